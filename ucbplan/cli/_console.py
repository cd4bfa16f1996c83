"""The terminal side of the CLI: one stderr console and literal-text rich tables."""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import IO, Any

from rich.console import Console
from rich.markup import escape
from rich.table import Table as RichTable
from rich.text import Text

from ucbplan.api import terminal
from ucbplan.api.terminal import (
    check_output_path,
    dump_json,
    output_format,
    write_output,
)
from ucbplan.errors import InputError

#: Markup tags, removed before deciding whether a message is an alert.
_TAG = re.compile(r"\[/?[a-z #]*\]")
#: Plain-text starts of the messages ``--quiet`` still prints.
ALERTS = ("warning", "error", "interrupted")


#: Indent [columns] of the continuation lines of a message wrapped at the terminal width.
HANGING_INDENT = 2


class _Console(Console):
    """A rich console for the messages of the CLI.

    With ``quiet_info`` set (``ucbplan --quiet``) it prints only warnings and errors: tables,
    notes and "wrote …" lines are left out; machine output on stdout is not affected. With
    ``fold`` set (a terminal, or ``COLUMNS`` given), a message printed with ``soft_wrap=True``
    (one logical line: a warning, an error, a note) is wrapped at a word to the terminal width,
    its continuation lines indented by :data:`HANGING_INDENT`; without it (pipes and logs) it
    stays on one line, so that ``grep`` finds it whole.
    """

    quiet_info = False
    fold = True

    def print(self, *objects: Any, **kwargs: Any) -> None:
        if self.quiet_info and not _is_alert(objects):
            return
        if self.fold and kwargs.get("soft_wrap") and len(objects) == 1:
            if isinstance(objects[0], str):
                objects = (self._hanging(objects[0], kwargs.pop("markup", None)),)
        super().print(*objects, **kwargs)

    def _hanging(self, message: str, markup: bool | None) -> Text:
        """``message`` as text wrapped to the console width, with a hanging indent."""
        text = self.render_str(message, markup=markup, emoji=False, highlight=False)
        first = text.wrap(self, self.width)
        if len(first) <= 1:
            return text
        rest = text.divide([len(first[0].plain)])[1]
        out = first[0]
        for line in rest.wrap(self, max(self.width - HANGING_INDENT, 20)):
            out.rstrip()
            out.append("\n" + " " * HANGING_INDENT)
            out.append_text(line)
        out.rstrip()
        return out


def _is_alert(objects: tuple[Any, ...]) -> bool:
    first = objects[0] if objects else ""
    if isinstance(first, Text):
        first = first.plain
    return isinstance(first, str) and _TAG.sub("", first).lstrip().startswith(ALERTS)


def _make_console() -> _Console:
    console = _Console(stderr=True, highlight=False, emoji=False)
    if not console.is_terminal and not os.environ.get("COLUMNS", "").strip():
        # pipes and CI logs: wide enough that ISO times with microseconds are never cut, and
        # one line per message
        console = _Console(stderr=True, highlight=False, emoji=False, width=180)
        console.fold = False
    return console


def literal(text: object) -> str:
    """``text`` (a file name, a target name) escaped so that rich prints it as it is spelled:
    ``hmcnc[draft].yaml`` stays ``hmcnc[draft].yaml``, never a style tag."""
    return escape(str(text))


#: Console for humans: rich tables and warnings go to stderr so stdout stays machine-readable.
#: Unit brackets like "[s]" in table headers must go through :func:`rich_table` (no markup).
err_console = _make_console()


def rich_table(title: str, columns: list[str], **kwargs: Any) -> RichTable:
    """A rich table whose title and headers are literal text (``[s]`` is a unit, not markup)."""
    table = RichTable(title=escape(title), **kwargs)
    for name in columns:
        table.add_column(escape(name), justify="right")
    return table


def check_output_and_plot(output: Path | None, plot: Path | None, overwrite: bool) -> None:
    """Refuse an -o and a --plot naming one file, or either existing, before any work is done."""
    if output is not None and plot is not None and output.resolve() == plot.resolve():
        raise InputError(f"-o, --plot: both name {output}; give two different files")
    if output is not None:
        check_output_path(output, overwrite)
    if plot is not None:
        terminal.check_figure_path(plot, overwrite)


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
    if fmt == "csv":
        tab = terminal.csv_safe_table(tab)  # no formula cells (issue 33)

    def _w(handle: IO[str]) -> None:
        tab.write(handle, format=fmt_name)

    write_output(output, _w, overwrite=overwrite)
