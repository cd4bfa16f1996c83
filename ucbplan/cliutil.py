"""Shared helpers for the command-line shell: offline astropy, safe outputs, output formats.

Every command module uses these so that errors, overwrites and machine output behave the same way.
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO, Any

from rich.console import Console
from rich.markup import escape
from rich.table import Table as RichTable

from ucbplan.errors import OutputExistsError, UcbplanError

__all__ = [
    "OUTPUT_FORMATS",
    "check_output_path",
    "configure_offline",
    "err_console",
    "json_default",
    "rich_table",
    "write_output",
]


def _make_console() -> Console:
    console = Console(stderr=True, highlight=False)
    if not console.is_terminal and "COLUMNS" not in os.environ:
        # pipes and CI logs: wide enough that ISO times with microseconds are never cut
        console = Console(stderr=True, highlight=False, width=180)
    return console


#: Console for humans: rich tables and warnings go to stderr so stdout stays machine-readable.
#: Unit brackets like "[s]" in table headers must go through :func:`rich_table` (no markup).
err_console = _make_console()


def rich_table(title: str, columns: list[str], **kwargs: Any) -> RichTable:
    """A rich table whose title and headers are literal text (``[s]`` is a unit, not markup)."""
    table = RichTable(title=escape(title), **kwargs)
    for name in columns:
        table.add_column(escape(name), justify="right")
    return table


OUTPUT_FORMATS = ("table", "json", "ecsv", "csv")

_OFFLINE_DONE = False


def configure_offline() -> None:
    """Configure astropy so that nothing ever touches the network (SCIENCE.md recipe).

    Called once at CLI start, never on import. Uses the IERS-A/B tables and leap seconds bundled
    with ``astropy-iers-data``; nights past their coverage are warned about by the planner.
    """
    global _OFFLINE_DONE
    if _OFFLINE_DONE:
        return
    from astropy.utils import data, iers

    iers.conf.auto_download = False
    iers.conf.auto_max_age = None
    data.conf.allow_internet = False
    _OFFLINE_DONE = True


def check_output_path(path: Path, overwrite: bool) -> None:
    """Refuse to clobber an existing file unless ``overwrite``; make sure the folder exists.

    Raises
    ------
    OutputExistsError
        If ``path`` exists and ``overwrite`` is false.
    UcbplanError
        If the parent folder does not exist.
    """
    if path.exists() and not overwrite:
        raise OutputExistsError(
            f"{path}: output file exists; pass --overwrite to replace it or choose another -o path"
        )
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.is_dir():
        raise UcbplanError(f"{path}: folder {parent} does not exist; create it first")


@contextmanager
def _atomic_handle(path: Path, mode: str) -> Iterator[IO[Any]]:
    parent = path.parent if str(path.parent) else Path(".")
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=parent)
    try:
        with os.fdopen(fd, mode) as handle:
            yield handle
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_output(
    path: Path | None,
    writer: Callable[[IO[Any]], None],
    *,
    overwrite: bool = False,
    binary: bool = False,
) -> None:
    """Write with ``writer(handle)`` to ``path`` atomically, or to stdout when ``path`` is None.

    The file appears only if ``writer`` finished without error: no partial outputs, ever.
    """
    if path is None:
        if binary:
            writer(sys.stdout.buffer)
            sys.stdout.buffer.flush()
        else:
            writer(sys.stdout)
            sys.stdout.flush()
        return
    check_output_path(path, overwrite)
    with _atomic_handle(path, "wb" if binary else "w") as handle:
        writer(handle)


def json_default(obj: Any) -> Any:
    """``json.dumps`` fallback for numpy scalars/arrays."""
    import numpy as np

    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.floating):
        return float(obj)
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")


def dump_json(doc: Any, handle: IO[str]) -> None:
    """Write one JSON document (with trailing newline)."""
    json.dump(doc, handle, indent=2, default=json_default, allow_nan=False)
    handle.write("\n")
