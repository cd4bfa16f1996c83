"""Output files: one atomic writer, the ``-o`` rule, JSON encoding.

Every file ucbplan writes goes through :func:`write_output`, so a failed run never leaves a partial
or changed file and nothing is overwritten without ``overwrite=True`` (``--overwrite``).
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

from ucbplan.errors import OutputExistsError, UcbplanError

__all__ = ["OUTPUT_FORMATS", "check_output_path", "dump_json", "json_default", "write_output"]

OUTPUT_FORMATS = ("table", "json", "ecsv", "csv")


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
