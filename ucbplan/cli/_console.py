"""The terminal side of the CLI: one stderr console and literal-text rich tables."""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import IO, Any

from rich.console import Console
from rich.markup import escape
from rich.table import Table as RichTable

from ucbplan.errors import InputError
from ucbplan.io import (
    check_output_path,
    dump_json,
    output_format,
    write_output,
)

__all__ = [
    "TABLE_FORMATS",
    "check_output_path",
    "dump_json",
    "err_console",
    "pick_format",
    "rich_table",
    "write_output",
    "write_table_output",
]


#: Markup tags, removed before deciding whether a message is an alert.
_TAG = re.compile(r"\[/?[a-z #]*\]")
#: Plain-text starts of the messages ``--quiet`` still prints.
ALERTS = ("warning", "error", "interrupted")


class _Console(Console):
    """A rich console that, with ``quiet_info`` set (``ucbplan --quiet``), prints only warnings
    and errors: tables, notes and "wrote …" lines are left out; machine output on stdout is not
    affected."""

    quiet_info = False

    def print(self, *objects: Any, **kwargs: Any) -> None:
        if self.quiet_info and not _is_alert(objects):
            return
        super().print(*objects, **kwargs)


def _is_alert(objects: tuple[Any, ...]) -> bool:
    first = objects[0] if objects else ""
    return isinstance(first, str) and _TAG.sub("", first).lstrip().startswith(ALERTS)


def _make_console() -> _Console:
    console = _Console(stderr=True, highlight=False)
    if not console.is_terminal and "COLUMNS" not in os.environ:
        # pipes and CI logs: wide enough that ISO times with microseconds are never cut
        console = _Console(stderr=True, highlight=False, width=180)
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


def pick_format(output: Path | None, fmt: str | None, formats: tuple[str, ...]) -> str:
    """The ``-o``/``--format`` rule of every command (see :func:`ucbplan.io.output_format`).

    ``table`` is the human table on the terminal; a file (``-o``) takes ``--format``, else its
    suffix, else the first machine format in ``formats``. ``--format table -o FILE`` and a
    ``--format`` that contradicts the suffix are errors.
    """
    fmt = fmt.lower() if fmt is not None else None
    machine = tuple(f for f in formats if f != "table")
    if output is None:
        return output_format(None, fmt, formats, formats[0])
    if fmt == "table":
        raise InputError(
            f"--format table prints to the terminal; for -o {output} use --format "
            f"{' | '.join(machine)} (or leave --format out: the suffix decides)"
        )
    return output_format(output, fmt, machine, machine[0])


#: Formats of the commands that print a table or write it (``--format``).
TABLE_FORMATS = ("table", "ecsv", "csv", "json")


def write_table_output(tab: Any, fmt: str, output: Path | None, overwrite: bool) -> None:
    """Write an astropy table as JSON (meta + rows), ECSV or CSV to ``output`` or stdout."""
    if fmt == "json":
        rows = [
            {
                c: (v.item() if hasattr(v, "item") else v)
                for c, v in zip(tab.colnames, row, strict=True)
            }
            for row in tab.iterrows()
        ]
        doc = {"meta": dict(tab.meta), "rows": rows}
        write_output(output, lambda h: dump_json(doc, h), overwrite=overwrite)
        return
    fmt_name = "ascii.ecsv" if fmt == "ecsv" else "ascii.csv"

    def _w(handle: IO[str]) -> None:
        tab.write(handle, format=fmt_name)

    write_output(output, _w, overwrite=overwrite)
