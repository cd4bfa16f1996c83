"""The terminal side of the CLI: one stderr console and literal-text rich tables."""

from __future__ import annotations

import itertools
import os
import re
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import IO, Any

from rich.cells import cell_len
from rich.console import Console
from rich.markup import escape
from rich.measure import Measurement
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
                objects = (self._hanging(objects[0], kwargs.pop("markup", None), self.width),)
        super().print(*objects, **kwargs)

    def print_messages(self, messages: Sequence[str | Text], markup: bool | None = None) -> None:
        """Each of ``messages`` (one logical line each: a warning, a note; markup, or a Text
        as :func:`alert` makes it) as ``print(message, soft_wrap=True, markup=markup)``
        prints it, all in one print: a long plan's hundreds of "not placed" lines cost one
        render and one write, not one each."""
        shown = [m for m in messages if not self.quiet_info or _is_alert((m,))]
        if not shown:
            return
        if self.fold:
            width = self.width  # read once: rich finds it anew at each call
            texts = [self._hanging(m, markup, width) for m in shown]
        else:
            texts = [self._text(m, markup) for m in shown]
        super().print(Text("\n").join(texts), soft_wrap=True)

    def _text(self, message: str | Text, markup: bool | None) -> Text:
        """A message as rich renders it (a Text as it is)."""
        if isinstance(message, Text):
            return message
        return self.render_str(message, markup=markup, emoji=False, highlight=False)

    def print_table(self, make: Callable[[], RichTable], rows: Sequence[Sequence[str]]) -> None:
        """Print the table ``make()`` (of :func:`rich_table`, without rows) with ``rows`` of
        text cells (markup, as ``add_row`` takes them), as rich prints it.

        Where that prints the same bytes, the rows are printed as one row whose cells hold
        each column's lines: rich measures and renders a cell at a time, so a 183-night summary
        costs 4 cells, not 732. That is so when the rows only stack (:func:`_stacks`) and no
        line wraps: when the table's natural width fits the console (:func:`_fits`). Else the
        rows are added one by one."""
        if self.quiet_info:
            return  # --quiet prints no tables
        table = make()
        if rows and _stacks(table, rows):
            table.add_row(*(_stacked(self, cells) for cells in zip(*rows, strict=True)))
            if _fits(self, table):
                self.print(table)
                return
            table = make()
        for row in rows:
            table.add_row(*row)
        self.print(table)

    def _hanging(self, message: str | Text, markup: bool | None, width: int) -> Text:
        """``message`` as text wrapped to ``width`` (the console's), with a hanging indent."""
        text = self._text(message, markup)
        if _one_line(text, width):
            return text
        first = text.wrap(self, width)
        if len(first) <= 1:
            return text
        rest = text.divide([len(first[0].plain)])[1]
        narrower = max(width - HANGING_INDENT, 20)
        out = first[0]
        for line in [rest] if _one_line(rest, narrower) else rest.wrap(self, narrower):
            out.rstrip()
            out.append("\n" + " " * HANGING_INDENT)
            out.append_text(line)
        out.rstrip()
        return out


def _one_line(text: Text, width: int) -> bool:
    """Whether rich's wrap at ``width`` leaves ``text`` as it is, one line (no newline, no
    tab to expand, no wider): then the fold need not run it."""
    plain = text.plain
    return "\n" not in plain and "\t" not in plain and cell_len(plain) <= width


def _stacks(table: RichTable, rows: Sequence[Sequence[str]]) -> bool:
    """Whether ``rows`` printed as one row of stacked cells look as rows in ``table`` would
    (when no cell wraps): text cells of one line without tabs (rich measures a tab before
    expanding it), no rule, space or style between rows."""
    plain = not (table.show_lines or table.leading or table.row_styles or table.expand)
    if not plain or table.width is not None or table.min_width is not None:
        return False
    width = len(table.columns)
    return all(len(row) == width and all(type(c) is str for c in row) for row in rows) and (
        not {"\n", "\t"} & set("".join(itertools.chain.from_iterable(rows)))
    )


def _stacked(console: Console, cells: Sequence[str]) -> str | Text:
    """A column's cells as one cell of lines: their text joined when they hold no markup, else
    each rendered as rich renders a table's text cell and the texts joined (so that no tag can
    span two cells)."""
    if not any("[" in cell for cell in cells):
        return Text("\n".join(cells), no_wrap=True)
    text = Text("\n").join(console.render_str(cell, highlight=False) for cell in cells)
    text.no_wrap = True
    return text


#: A width [columns] no table reaches: its natural width is measured within it.
_UNBOUNDED = 1_000_000


def _fits(console: Console, table: RichTable) -> bool:
    """Whether ``table`` at its natural width (each column as wide as its widest line) fits
    ``console``, so that rich neither shrinks a column nor wraps a line."""
    options = console.options
    natural = Measurement.get(console, options.update_width(_UNBOUNDED), table).maximum
    return natural <= options.max_width


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


def alert(kind: str, text: str, markup: str | None = None) -> str | Text:
    """The message ``[yellow]{kind}:[/] {markup}`` for :meth:`_Console.print_messages`, where
    ``markup`` is ``text`` as markup (default ``escape(text)``; a caller that escapes its parts
    one by one gives its own). Where ``text`` holds no ``[`` nor ``\\`` the markup is ``text``
    itself and the message is the Text rich makes of it, so that hundreds of them are not
    parsed one by one."""
    if "[" in text or "\\" in text:
        return f"[yellow]{kind}:[/] {escape(text) if markup is None else markup}"
    return Text.assemble((f"{kind}:", "yellow"), f" {text}")


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
