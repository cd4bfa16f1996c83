"""Column-by-column text of a table's rows, byte for byte as astropy's ECSV and ``json``'s
indented writers make it.

astropy's ECSV writer formats each cell on its own (``str(col[i])``, one numpy scalar each) and
``json.dumps(..., indent=2)`` encodes in pure Python: ~60 µs per row of the blocks table's 42
columns. Here each column is formatted at once (``str`` of the Python values of ``tolist()``,
which equals ``str`` of the numpy scalar for 1-d bool, integer, float and text columns) and the
rows are joined by the C ``csv`` writer and the C JSON string/number encoders. Tables with any
other kind of column (masked, multidimensional, object, bytes, mixins) return None: the caller
takes astropy's or ``json``'s own path.
"""

from __future__ import annotations

import csv
import json
import math
import operator
from collections.abc import Callable
from typing import Any

from astropy.table import Column, Table

__all__ = ["ecsv_data_lines", "json_records_text", "json_rows_text"]

#: Column dtype kinds the fast paths take (bool, integers, floats, Unicode text).
_PLAIN_KINDS = "biufU"

#: What astropy's ``CsvWriter`` puts in place of an empty cell before the ``csv`` writer runs
#: (then replaced by ``""``): the same sentinel, so that the same rows come out.
_SENTINEL = "2b=48Av%0-V3p>bX"


def _plain_columns(table: Table) -> bool:
    return all(
        type(col) is Column and col.ndim == 1 and col.dtype.kind in _PLAIN_KINDS
        for col in table.itercols()
    )


def _one_value(col: Column) -> bool:
    """Whether a non-empty column of numbers holds one value, bit for bit (-0.0 is not 0.0)."""
    if not len(col) or col.dtype.kind not in "biuf":
        return False
    data = col.data
    bits = data.view(f"u{data.itemsize}") if data.dtype.kind == "f" else data
    return bool((bits == bits[0]).all())


def _strs(col: Column) -> list[str]:
    """Each cell as astropy's ECSV writer formats it (``str`` of the cell), stripped of spaces
    and tabs at both ends as its writer's splitter does; a column of one value (bit for bit)
    formatted once."""
    if _one_value(col):
        return [str(col.data[:1].tolist()[0])] * len(col)
    values = col.tolist()
    if col.dtype.kind == "U":
        joined = "".join(values)
        if " " in joined or "\t" in joined:
            return [v.strip(" \t") for v in values]
        return values
    return list(map(str, values))


def _needs_csv(values: list[str], delimiter: str) -> bool:
    """Whether some cell of a text column is empty or one the ``csv`` writer may quote."""
    joined = "".join(values)
    odd = not joined.isprintable() or " " in joined or '"' in joined or delimiter in joined
    return odd or "" in values


class _Lines:
    """A file-like sink collecting each row the ``csv`` writer writes (one write per row)."""

    def __init__(self) -> None:
        self.lines: list[str] = []

    def write(self, text: str) -> None:
        self.lines.append(text)


def _csv_cells(values: list[str], delimiter: str) -> list[str]:
    """Each cell as astropy's writer puts it on a line: an empty one as ``""`` (space-delimited)
    or nothing (else), others as the ``csv`` writer quotes a field (on its own: its quoting
    depends on the field alone; a column whose only odd cells are empty, without it)."""
    empty = '""' if delimiter == " " else ""
    full = [v for v in values if v]
    if not _needs_csv(full, delimiter):
        return [v or empty for v in values]
    sink = _Lines()
    writer = csv.writer(sink, delimiter=delimiter, quotechar='"', doublequote=True, escapechar=None)
    writer.writerows([v or _SENTINEL] for v in values)
    return [line.rstrip("\r\n").replace(_SENTINEL, empty) for line in sink.lines]


def ecsv_data_lines(table: Table, delimiter: str = " ") -> list[str] | None:
    """The data lines of ``table`` as astropy's ECSV writer (or, ``delimiter=","``, its CSV
    writer) writes them, without line ends; None for a table with other than plain 1-d columns
    (or a CSV table of one column: the ``csv`` writer quotes a row of one empty field). Column
    by column: a text column with a cell to quote goes through the ``csv`` writer alone, the
    rest are joined as they are."""
    if not _plain_columns(table) or (delimiter != " " and len(table.colnames) < 2):
        return None
    cells = []
    for col in table.itercols():
        values = _strs(col)
        text = col.dtype.kind == "U"
        if text and _needs_csv(values, delimiter):
            values = _csv_cells(values, delimiter)
        cells.append(values)
    return list(map(delimiter.join, zip(*cells, strict=True)))


def _float_text(v: float) -> str:
    return float.__repr__(v) if math.isfinite(v) else "null"


def _encoder(kind: str) -> Callable[[Any], str]:
    """JSON text of one cell of a column of dtype ``kind`` (NaN and infinities → null)."""
    if kind == "f":
        return _float_text
    if kind == "b":
        return lambda v: "true" if v else "false"
    if kind in "iu":
        return int.__repr__
    return json.encoder.encode_basestring_ascii


def json_rows_text(table: Table, level: int) -> str | None:
    """The rows of ``table`` as ``json.dumps(rows, indent=2)`` writes the list at nesting
    ``level`` (0: the document; 1: a value of the top-level object), or None for a table with
    other than plain 1-d columns."""
    if not _plain_columns(table) or not table.colnames:
        return None
    cells = [
        [_encoder(col.dtype.kind)(col.data[:1].tolist()[0])] * len(col)
        if _one_value(col)
        else list(map(_encoder(col.dtype.kind), col.tolist()))
        for col in table.itercols()
    ]
    return _records_text([str(name) for name in table.colnames], cells, len(table), level)


def _records_text(names: list[str], cells: list[list[str]], n: int, level: int) -> str:
    """``n`` objects of the keys ``names`` (each key's encoded values in ``cells``) as
    ``json.dumps(..., indent=2)`` writes their list at nesting ``level``."""
    if not n:
        return "[]"
    pad = "  " * level
    keys = [json.encoder.encode_basestring_ascii(name) + ": " for name in names]
    inner = f",\n{pad}    "
    rows = [
        "{\n" + pad + "    " + inner.join(map(operator.add, keys, row))
        for row in zip(*cells, strict=True)
    ]
    return f"[\n{pad}  " + f"\n{pad}  }},\n{pad}  ".join(rows) + f"\n{pad}  }}\n{pad}]"


#: JSON text of a plain value, by its exact type (a float here is finite).
_JSON_TEXT: dict[type, Callable[[Any], str]] = {
    str: json.encoder.encode_basestring_ascii,
    int: int.__repr__,
    float: _float_text,
    bool: lambda v: "true" if v else "false",
    type(None): lambda v: "null",
}


def json_records_text(records: Any, level: int) -> str | None:
    """A list of flat records (a plan's ``visits``) as ``json.dumps(records, indent=2)`` writes
    it at nesting ``level``, key by key; None unless every record is a dict of the same text
    keys in the same order, of strings, integers, finite floats, booleans and None."""
    if not isinstance(records, list) or not records or any(type(r) is not dict for r in records):
        return None
    names = list(records[0])
    if (
        not names
        or any(type(k) is not str for k in names)
        or any(list(r) != names for r in records)
    ):
        return None
    cells = []
    for name in names:
        column = [r[name] for r in records]
        kinds = set(map(type, column))
        if not kinds.issubset(_JSON_TEXT):
            return None
        if float in kinds and not all(math.isfinite(v) for v in column if type(v) is float):
            return None
        one = _JSON_TEXT[kinds.pop()] if len(kinds) == 1 else None
        cells.append(list(map(one, column)) if one else [_JSON_TEXT[type(v)](v) for v in column])
    return _records_text(names, cells, len(records), level)


#: Characters of a text value the fast ECSV header path writes itself (others: PyYAML's path).
_YAML_TEXT = frozenset("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_.()/+- :")
#: The column after which libyaml breaks a line (astropy writes ECSV headers at width 130).
_YAML_WIDTH = 130
#: Indentation of a flow mapping's continuation lines in the ``visits`` list: before a key,
#: and inside a scalar (libyaml indents a scalar one step, 2, deeper).
_YAML_INDENT, _YAML_SCALAR_INDENT = 4, 6


def _yaml_scalar(value: Any, tags: Callable[[str], str]) -> tuple[str, bool] | None:
    """(text, breakable at spaces) of one scalar of a flow mapping as libyaml emits PyYAML's
    node for it, or None where this path does not know (the caller takes PyYAML's)."""
    if isinstance(value, bool) or value is None:
        return None
    if isinstance(value, int):
        text = str(value)
        return (text, False) if tags(text) == "int" else None
    if isinstance(value, float):
        if not math.isfinite(value):
            return None
        text = repr(value).lower()
        if "." not in text and "e" in text:
            text = text.replace("e", ".0e", 1)
        return (text, False) if tags(text) == "float" else None
    if not isinstance(value, str) or not value or not _YAML_TEXT.issuperset(value):
        return None
    if not (value[0].isalnum() or value[0] in "_(") or value[-1] == " " or "  " in value:
        return None
    if tags(value) != "str":  # a date, a number, true/null ...: single-quoted, if unbroken
        return None if " " in value else (f"'{value}'", False)
    if ":" in value:  # a plain ':' is a flow indicator for libyaml
        return None
    return value, True


def yaml_flow_items(items: list[dict[str, Any]], tags: Callable[[str], str]) -> list[str] | None:
    """Lines of a block sequence (indent 2) of flow mappings with sorted keys, as astropy's ECSV
    header writer emits them through libyaml (:mod:`ucbplan.observing.blocktable`); None if
    any key or value is of a kind this path does not write (the caller then takes PyYAML's).
    ``tags(text)``: PyYAML's implicit tag of a plain scalar (``str``, ``int``, ``float``, ...).

    libyaml breaks a flow mapping before a key once the column passes the width, and a plain
    value at a space once the column passes it; the tests compare with libyaml's own output.
    Items of the same keys are written key by key: each distinct value's text found once, and
    each mapping made from a ``%`` template of its texts' lengths (where the lines break)."""
    keys = sorted(items[0]) if items else []
    if (
        not keys
        or any(map(items[0].keys().__ne__, map(dict.keys, items)))
        or not all(
            isinstance(key, str) and " " not in key and _yaml_scalar(key, tags) == (key, True)
            for key in keys
        )
    ):
        return _flow_items_one_by_one(items, tags)
    columns = []
    for key in keys:
        texts = _column_texts([item[key] for item in items], tags)
        if texts is None:
            return None
        columns.append(texts)
    rows = list(zip(*columns, strict=True))
    widths = list(zip(*(list(map(len, col)) for col in columns), strict=True))
    templates = {w: _template(keys, w) for w in set(widths)}
    if not any(_Words in map(type, col) for col in columns):
        return "\n".join(map(operator.mod, map(templates.__getitem__, widths), rows)).split("\n")
    lines: list[str] = []
    for item, row, width in zip(items, rows, widths, strict=True):
        if _Words in map(type, row):  # a value that may break at its spaces
            lines += _flow_item(item, tags) or []
        else:
            lines += (templates[width] % row).split("\n")
    return lines


class _Words(str):
    """A value's text that libyaml may break at its spaces (a plain string with spaces)."""


def _column_texts(values: list[Any], tags: Callable[[str], str]) -> list[str] | None:
    """Each value's text (a :class:`_Words` where it may break): in a column of one kind, each
    distinct number's text (a function of its ``repr``) found once and each string's style once
    per :func:`_shapes`; None if a value is of a kind this path does not write."""
    kinds = set(map(type, values))
    if kinds == {str}:
        return _text_column(values, _shapes(values), tags)
    if kinds != {int} and kinds != {float}:
        # one by one: a string's text (its own shape), a number's (never breakable)
        each = [
            _text_column([v], [v], tags) if type(v) is str else _yaml_scalar(v, tags)
            for v in values
        ]
        return None if None in each else [got[0] for got in each if got is not None]
    reprs = list(map(repr, values))
    known = {}
    for text, v in dict(zip(reprs, values, strict=True)).items():
        got = _yaml_scalar(v, tags)
        if got is None:
            return None
        known[text] = got[0]
    return list(map(known.__getitem__, reprs))


def _text_column(
    values: list[str], shapes: list[str], tags: Callable[[str], str]
) -> list[str] | None:
    """The texts of strings (see :func:`_column_texts`), each style found once per shape."""
    styles = {}
    for shape, v in dict(zip(shapes, values, strict=True)).items():
        style = styles[shape] = _style(v, tags)
        if style is None:
            return None
    if len(set(styles.values())) == 1 and style != "words":  # one style: the column at once
        return list(values) if style == "plain" else list(map("'{}'".format, values))
    return [
        v if s == "plain" else f"'{v}'" if s == "quoted" else _Words(v)
        for v, s in zip(values, map(styles.__getitem__, shapes), strict=True)
    ]


#: Every character of PyYAML's implicit ``int`` and ``float`` patterns (digits, signs, ``_.:``,
#: hexadecimal letters, ``0b``/``0x``, ``inf``/``nan`` in their cases).
_NUMBER_CHARS = frozenset("0123456789_+-.:xXbBaAcCdDeEfFiInN")
#: Every ASCII digit as ``0`` (in UTF-8, whose other characters hold no ASCII byte).
_DIGITS_AS_0 = bytes.maketrans(b"123456789", b"000000000")


def _shapes(values: list[str]) -> list[str]:
    """Per string, the text whose :func:`_style` is its own: itself if it might be a number,
    else with every digit as ``0``. A text with a character outside :data:`_NUMBER_CHARS`
    cannot be an ``int`` or a ``float``, and PyYAML's other patterns (timestamps) take any
    digit alike, as every digit starts the same resolvers: a header's times and visit ids share
    a handful of shapes."""
    joined = "\x00".join(values)
    if joined.count("\x00") != len(values) - 1:  # a NUL inside a value
        return list(values)
    coarse_bytes = joined.encode("utf-8", "surrogatepass").translate(_DIGITS_AS_0)
    coarse = coarse_bytes.decode("utf-8", "surrogatepass").split("\x00")
    # digits map to digits: a text and its shape are alike made of :data:`_NUMBER_CHARS` or not
    numeric = {c for c in set(coarse) if _NUMBER_CHARS.issuperset(c)}
    if not numeric:
        return coarse
    return [v if c in numeric else c for v, c in zip(values, coarse, strict=True)]


def _style(text: str, tags: Callable[[str], str]) -> str | None:
    """How :func:`_yaml_scalar` writes the string ``text``: ``plain``, ``quoted`` (in single
    quotes), ``words`` (plain, breakable at its spaces), or None (not by this path)."""
    got = _yaml_scalar(text, tags)
    if got is None:
        return None
    if got[0] != text:
        return "quoted"
    return "words" if got[1] and " " in text else "plain"


def _template(keys: list[str], widths: tuple[int, ...]) -> str:
    """The ``%`` template of a flow mapping of ``keys`` whose value texts have ``widths`` (none
    breakable), its lines joined by newlines: a line breaks before a key past the width."""
    parts, col = ["  - {"], 5
    for k, (key, width) in enumerate(zip(keys, widths, strict=True)):
        if k:
            col += 1
            if col > _YAML_WIDTH:
                parts.append(",\n" + " " * _YAML_INDENT)
                col = _YAML_INDENT
            else:
                parts.append(", ")
                col += 1
        parts.append(f"{key}: %s")
        col += len(key) + 2 + width
    return "".join(parts) + "}"


def _flow_items_one_by_one(
    items: list[dict[str, Any]], tags: Callable[[str], str]
) -> list[str] | None:
    """:func:`yaml_flow_items` of mappings of differing keys, one mapping at a time."""
    lines: list[str] = []
    for item in items:
        got = _flow_item(item, tags)
        if got is None:
            return None
        lines += got
    return lines


def _flow_item(item: dict[str, Any], tags: Callable[[str], str]) -> list[str] | None:
    """The lines of one flow mapping (see :func:`yaml_flow_items`), or None."""
    lines: list[str] = []
    line, col = "  - {", 5
    for k, key in enumerate(sorted(item)):
        if not isinstance(key, str) or _yaml_scalar(key, tags) != (key, True) or " " in key:
            return None
        got = _yaml_scalar(item[key], tags)
        if got is None:
            return None
        text, breakable = got
        if k:
            line += ","
            col += 1
            if col > _YAML_WIDTH:
                lines.append(line)
                line, col = " " * _YAML_INDENT, _YAML_INDENT
            else:
                line += " "
                col += 1
        line += f"{key}: "
        col += len(key) + 2
        words = text.split(" ") if breakable else [text]
        for w, word in enumerate(words):
            if w:
                if col > _YAML_WIDTH:
                    lines.append(line)
                    line, col = " " * _YAML_SCALAR_INDENT, _YAML_SCALAR_INDENT
                else:
                    line += " "
                    col += 1
            line += word
            col += len(word)
    lines.append(line + "}")
    return lines
