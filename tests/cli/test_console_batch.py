"""The CLI console's batched printing (issue 34): ``print_messages`` prints what one
``print(message, soft_wrap=True)`` per message printed, and ``print_table`` what a rich table
with one ``add_row`` per row printed, byte for byte: folded at the width with a hanging indent
or one line per message, in colour or not, at any width, under ``--quiet``.

The reference of each is rich's own one-call-each path, run in the same test.
"""

from __future__ import annotations

import io

from hypothesis import given
from hypothesis import strategies as st
from rich.cells import cell_len
from rich.markup import escape
from rich.table import Table as RichTable
from rich.text import Text

from ucbplan.cli._console import _Console, alert, rich_table

#: Characters of cells and messages: markup brackets and backslashes, spaces, accents, wide
#: (two-cell) characters, dashes, tabs; no newline (one logical line each).
_CHARS = st.sampled_from([*"ab Z09[]\\/:._-é★漢—\t", "  ", "[yellow]", "[/]"])
_TEXT = st.lists(_CHARS, max_size=30).map("".join)


def _console(width: int, fold: bool, colour: bool, quiet: bool = False) -> _Console:
    console = _Console(
        file=io.StringIO(),
        width=width,
        highlight=False,
        emoji=False,
        force_terminal=colour,
        color_system="standard" if colour else None,
    )
    console.fold, console.quiet_info = fold, quiet
    return console


def _printed(console: _Console) -> str:
    out = console.file
    assert isinstance(out, io.StringIO)
    return out.getvalue()


def _message(kind: str, text: str) -> str:
    return f"[yellow]{kind}:[/] {escape(text)}"


_MESSAGES = st.lists(
    st.tuples(st.sampled_from(["warning", "not placed", "note"]), _TEXT, _TEXT).map(
        lambda m: (m[0], m[1] + " " + m[2] * 4)
    ),
    max_size=8,
)


@given(
    messages=_MESSAGES,
    width=st.integers(20, 200),
    fold=st.booleans(),
    colour=st.booleans(),
    quiet=st.booleans(),
    as_text=st.booleans(),
)
def test_messages_print_as_one_print_each(
    messages: list[tuple[str, str]],
    width: int,
    fold: bool,
    colour: bool,
    quiet: bool,
    as_text: bool,
) -> None:
    """Markup messages, or :func:`alert`'s (a Text where the text is plain), print as each
    markup message printed on its own."""
    batched, each = (_console(width, fold, colour, quiet) for _ in range(2))
    markup = [_message(kind, text) for kind, text in messages]
    batched.print_messages([alert(*m) for m in messages] if as_text else markup)
    for message in markup:
        each.print(message, soft_wrap=True)
    assert _printed(batched) == _printed(each)


@given(kind=st.sampled_from(["warning", "not placed"]), text=_TEXT)
def test_an_alert_is_the_text_its_markup_renders_to(kind: str, text: str) -> None:
    console = _console(80, False, False)
    got = alert(kind, text)
    want = console.render_str(_message(kind, text), emoji=False, highlight=False)
    assert isinstance(got, Text) == ("[" not in text and "\\" not in text)
    got = console.render_str(got) if isinstance(got, str) else got
    assert (got.plain, got.spans) == (want.plain, want.spans)


def test_messages_fold_with_a_hanging_indent() -> None:
    """At 40 columns a long message wraps at words, its continuation lines indented by two; a
    short one stays as it is; pipes keep each on one line."""
    long = _message("not placed", "UCB09 (2040-01-08): never at airmass <= 2 during nautical night")
    folded, piped = _console(40, True, False), _console(40, False, False)
    for console in (folded, piped):
        console.print_messages([long, "[yellow]warning:[/] short"])
    lines = _printed(folded).splitlines()
    assert lines[0] == "not placed: UCB09 (2040-01-08): never at"
    assert len(lines) > 2 and all(line.startswith("  ") for line in lines[1:-1])
    assert lines[-1] == "warning: short"
    assert _printed(piped).splitlines() == [Text.from_markup(long).plain, "warning: short"]


def _fold_as_first_written(console: _Console, message: str, width: int) -> Text:
    """The hanging fold without shortcuts: rich wraps the message, then the rest narrower."""
    text = console.render_str(message, emoji=False, highlight=False)
    first = text.wrap(console, width)
    if len(first) <= 1:
        return text
    out, rest = first[0], text.divide([len(first[0].plain)])[1]
    for line in rest.wrap(console, max(width - 2, 20)):
        out.rstrip()
        out.append("\n  ")
        out.append_text(line)
    out.rstrip()
    return out


@given(text=_TEXT, words=_TEXT, width=st.integers(20, 120))
def test_the_fold_is_rich_wrap_with_a_hanging_indent(text: str, words: str, width: int) -> None:
    """The fold skips rich's wrap of a text that fits (no newline or tab, no wider): the same
    lines and styles as wrapping everything; no line is wider than the console."""
    console = _console(width, True, False)
    message = _message("warning", text + " " + words * 3)
    ours, reference = (
        console._hanging(message, None, width),
        _fold_as_first_written(console, message, width),
    )
    assert (ours.plain, ours.spans) == (reference.plain, reference.spans)
    if width >= 22 and "\t" not in ours.plain:
        assert max(map(cell_len, ours.plain.split("\n"))) <= width


def _cells(raw: str, styled: bool) -> str:
    return f"[bold]{escape(raw)}[/]" if styled and raw else escape(raw)


_ROWS = st.integers(1, 4).flatmap(
    lambda n: st.lists(
        st.lists(st.tuples(_TEXT, st.booleans()).map(lambda c: _cells(*c)), min_size=n, max_size=n),
        max_size=12,
    )
)


@given(
    rows=_ROWS,
    width=st.integers(10, 160),
    colour=st.booleans(),
    no_wrap=st.booleans(),
    title=_TEXT,
)
def test_tables_print_as_rows_added_one_by_one(
    rows: list[list[str]], width: int, colour: bool, no_wrap: bool, title: str
) -> None:
    columns = [f"col {k} [s]" for k in range(len(rows[0]) if rows else 2)]

    def make() -> RichTable:
        table = rich_table(title, columns)
        for column in table.columns[1:]:
            column.no_wrap = no_wrap
        return table

    batched, each = (_console(width, True, colour) for _ in range(2))
    batched.print_table(make, rows)
    reference = make()
    for row in rows:
        reference.add_row(*row)
    each.print(reference)
    assert _printed(batched) == _printed(each)


def test_a_long_table_is_printed_whole_and_quiet_prints_none() -> None:
    """183 rows (a semester's per-night summary) print as 183 lines between the rules; under
    ``--quiet`` no table is printed."""
    rows = [(f"2040-01-{k:03d}", str(k), f"{k / 7:.2f}") for k in range(183)]
    console, quiet = _console(100, True, False), _console(100, True, False, quiet=True)
    for c in (console, quiet):
        c.print_table(lambda: rich_table("per night", ["night", "visits", "hours"]), rows)
    lines = _printed(console).splitlines()
    assert sum(line.startswith("│") for line in lines) == 183
    assert lines[4] == "│ 2040-01-000 │      0 │  0.00 │"
    assert _printed(quiet) == ""


def test_a_table_too_wide_for_the_console_wraps_as_rich_wraps_rows() -> None:
    """A table wider than the console takes rich's path row by row (a wrapped cell makes its row
    taller): the second row's long cell wraps and the rows stay apart."""
    rows = [("a", "short"), ("b", "a long cell of several words")]
    make = lambda: rich_table("t", ["k", "v"])  # noqa: E731
    narrow, reference = _console(20, True, False), _console(20, True, False)
    narrow.print_table(make, rows)
    table = make()
    for row in rows:
        table.add_row(*row)
    reference.print(table)
    assert _printed(narrow) == _printed(reference)
    assert sum(line.startswith("│ b") for line in _printed(narrow).splitlines()) == 1


def test_no_markup_tag_spans_two_cells() -> None:
    """Text that is no tag in a cell stays text: ``x[b`` above ``c]`` (a tag if the cells'
    markup were read as one)."""
    rows = [("x[b", "[bold]1[/]"), ("c]", "2")]
    make = lambda: rich_table("t", ["k", "v"])  # noqa: E731
    console = _console(80, True, True)
    console.print_table(make, rows)
    lines = Text.from_ansi(_printed(console)).plain.splitlines()
    assert [line.split("│")[1].strip() for line in lines if line.startswith("│")] == ["x[b", "c]"]
