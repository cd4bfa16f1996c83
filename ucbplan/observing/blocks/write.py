"""Writing the blocks table: ECSV, CSV or JSON (:func:`write_table`), byte for byte as astropy's
ECSV/CSV writers and ``json``'s indented writer make it, only faster.

astropy's ECSV writer formats each cell on its own (``str(col[i])``, one numpy scalar each) and
``json.dumps(..., indent=2)`` encodes in pure Python: ~60 µs per row of the blocks table's 42
columns. Here each column is formatted at once (``str`` of the Python values of ``tolist()``,
which equals ``str`` of the numpy scalar for 1-d bool, integer, float and text columns) and the
rows are joined by the C ``csv`` writer and the C JSON string/number encoders. Tables with any
other kind of column (masked, multidimensional, object, bytes, mixins) take astropy's or
``json``'s own path. The ECSV header is :mod:`ucbplan.observing.blocks.ecsv_header`'s.
"""

from __future__ import annotations

import csv
import itertools
import json
import math
import operator
import os
import re
from collections.abc import Callable, Mapping
from typing import IO, Any

import numpy as np
from astropy.table import Column, Table

from ucbplan.errors import InputFileError
from ucbplan.io import dump_json, dumps_json
from ucbplan.observing.blocks.ecsv_header import ecsv_header, flat_records_safe
from ucbplan.observing.blocks.schema import TABLE_FORMATS


def _plain(value: Any) -> Any:
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, float) and not np.isfinite(value):
        return None
    return value


def table_to_json_rows(table: Table) -> list[dict[str, Any]]:
    """Rows as plain dicts (NaN -> null) for ``--format json``."""
    names = table.colnames
    if all(_plain_column(table[n]) for n in names):  # column by column: same values, faster
        cells = [[_plain(v) for v in table[n].tolist()] for n in names]
        return [dict(zip(names, row, strict=True)) for row in zip(*cells, strict=True)]
    rows = []
    for row in table:
        rows.append(
            {n: _plain(row[n].item() if hasattr(row[n], "item") else row[n]) for n in names}
        )
    return rows


def _finite(records: Any) -> bool:
    """Whether every float of a list of flat records is finite."""
    flat = itertools.chain.from_iterable(map(dict.values, records))
    return all(math.isfinite(v) for v in flat if type(v) is float)


def _plain_column(col: Any) -> bool:
    """A 1-d unmasked column of numbers or text: ``tolist()`` gives its cells as ``item()``
    does, one by one."""
    return type(col) is Column and col.ndim == 1 and col.dtype.kind in "biufUS"


def _plain_meta(value: Any) -> Any:
    """Table meta as plain JSON values (NaN and infinities → null), recursively."""
    if isinstance(value, Mapping):
        return {str(k): _plain_meta(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        if flat_records_safe(value) is not None and _finite(value):  # plain already: copied
            return [dict(zip(map(str, r), r.values(), strict=True)) for r in value]
        return [_plain_meta(v) for v in value]
    value = _plain(value)
    return value if isinstance(value, str | int | float | bool | type(None)) else str(value)


def write_table(table: Table, handle: IO[str], fmt: str, *, json_meta: bool = False) -> None:
    """Write ``table`` to an open text handle as ``ecsv``, ``csv`` or ``json``.

    JSON is the list of rows, or with ``json_meta`` ``{"meta": {...}, "rows": [...]}`` like
    every command's JSON (``plan --format json``: the meta holds ``visits`` and
    ``time_accounting``). :func:`read_blocks` reads both."""
    if fmt == "ecsv":
        _write_ecsv(table, handle)
    elif fmt == "csv":
        _write_csv(table, handle)
    elif fmt == "json":
        _write_json(table, handle, json_meta)
    else:
        raise InputFileError(f"unknown table format {fmt!r}; expected one of {TABLE_FORMATS}")


#: First characters that make a spreadsheet read a CSV cell as a formula (OWASP's list).
CSV_FORMULA_START = ("=", "+", "-", "@", "\t", "\r")
#: Text that starts so but is a number or a signed sexagesimal, which no spreadsheet runs.
_CSV_NUMBER = re.compile(r"[+-](?:\d+(?::\d+)*(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?")


def csv_safe_text(cell: str) -> str:
    """A CSV text cell a spreadsheet shows but never runs (issue 33; docs/blocks-table.md).

    A cell beginning with ``=``, ``+``, ``-``, ``@``, a tab or a carriage return gets a
    leading ``'`` (``=HYPERLINK(…)`` → ``'=HYPERLINK(…)``), as does one beginning with ``'``
    (so :func:`csv_unsafe_text` can always strip exactly one). A number or a signed
    sexagesimal (``-12.5``, ``+3e-4``, ``-23:12:34.5``, ``+01:00``) stays as it is: it is no
    formula and must stay a number. Numeric columns are never touched (:func:`csv_safe_table`).
    """
    if cell[:1] == "'" or (cell[:1] in CSV_FORMULA_START and not _CSV_NUMBER.fullmatch(cell)):
        return "'" + cell
    return cell


def csv_unsafe_text(cell: str) -> str:
    """The text :func:`csv_safe_text` neutralised (a reader's inverse: one leading ``'``
    stripped when the writer put it there)."""
    if cell[:1] == "'" and csv_safe_text(cell[1:]) == cell:
        return cell[1:]
    return cell


def csv_safe_table(table: Table) -> Table:
    """``table`` with each text cell through :func:`csv_safe_text` (a copy of the columns that
    change only); every CSV writer of ucbplan writes through it."""
    plain = table.copy(copy_data=False)
    for name in plain.colnames:
        col = plain[name]
        kind = getattr(getattr(col, "dtype", None), "kind", "")
        if kind not in ("U", "O") or getattr(col, "ndim", 1) != 1:
            continue
        cells = col.tolist()
        if not any(isinstance(c, str) and c[:1] in "'=+-@\t\r" for c in cells):
            continue
        safe = [csv_safe_text(c) if isinstance(c, str) else c for c in cells]
        plain[name] = Column(safe, name=name, unit=col.unit, description=col.description)
    return plain


def _write_csv(table: Table, handle: IO[str]) -> None:
    """CSV without meta as astropy writes it: its header line (written for no rows), then the
    rows column by column (:func:`ecsv_data_lines`); for tables of other columns,
    astropy's whole writer. Text cells are neutralised (:func:`csv_safe_table`)."""
    plain = csv_safe_table(table)
    plain.meta = {}
    lines = ecsv_data_lines(plain, ",")
    if lines is None:
        plain.write(handle, format="ascii.csv")
        return
    plain[:0].write(handle, format="ascii.csv")
    handle.write("".join(line + os.linesep for line in lines))


def _write_ecsv(table: Table, handle: IO[str]) -> None:
    """ECSV as astropy writes it: its header (made from the columns and meta alone, so written
    for no rows; a plan's ``visits`` list written by :func:`.ecsvheader.yaml_flow_items` when
    it can), then the rows column by column (:func:`ecsv_data_lines`); for tables
    of other columns, astropy's whole writer."""
    lines = ecsv_data_lines(table)
    if lines is None:
        table.write(handle, format="ascii.ecsv")
        return
    handle.write(ecsv_header(table))
    handle.write("".join(line + os.linesep for line in lines))


def _write_json(table: Table, handle: IO[str], json_meta: bool) -> None:
    """The rows (with ``json_meta``: ``{"meta": ..., "rows": [...]}``) as :func:`dump_json`
    writes them, encoded column by column when the columns allow
    (:func:`json_rows_text`)."""
    rows = json_rows_text(table, 1 if json_meta else 0)
    meta = {"meta": _plain_meta(dict(table.meta))} if json_meta else None
    if rows is None:
        listed = table_to_json_rows(table)
        dump_json(listed if meta is None else {**meta, "rows": listed}, handle)
        return
    if meta is None:
        handle.write(rows + "\n")
        return
    head, tail = _json_head(meta["meta"]), '"rows": []\n}'
    if not head.endswith(tail):  # never: the rows are the document's last value
        raise AssertionError(f"unexpected JSON layout: {head[-40:]!r}")
    handle.write(head[: -len("[]\n}")] + rows + "\n}\n")


#: Stands in for a plan's ``visits`` in the JSON meta while they are written apart.
_VISITS_MARK = "\x00ucbplan visits\x00"


def _json_head(meta: dict[str, Any]) -> str:
    """``{"meta": meta, "rows": []}`` as :func:`dumps_json` writes it, the meta's ``visits``
    written key by key (:func:`json_records_text`) where they allow."""
    visits = meta.get("visits")
    listed = json_records_text(visits, 2)
    if listed is None:
        return dumps_json({"meta": meta, "rows": []})
    meta["visits"] = _VISITS_MARK
    try:
        head = dumps_json({"meta": meta, "rows": []})
    finally:
        meta["visits"] = visits
    mark = json.dumps(_VISITS_MARK)
    if head.count(mark) != 1:  # never: the mark is no text of a plan
        return dumps_json({"meta": meta, "rows": []})
    return head.replace(mark, listed)


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
    """Whether a non-empty column of numbers or text holds one value, bit for bit (-0.0 is not
    0.0)."""
    if not len(col) or col.dtype.kind not in "biufU":
        return False
    data = col.data
    bits = data.view(f"u{data.itemsize}") if data.dtype.kind == "f" else data
    return bool((bits == bits[0]).all())


def _cell_texts(col: Column) -> list[str]:
    """Each cell as astropy's ECSV writer formats it (``str`` of the cell), stripped of spaces
    and tabs at both ends as its writer's splitter does."""
    if col.dtype.kind == "f":
        return _float_texts(col)
    values = col.tolist()
    if col.dtype.kind == "U":
        joined = "".join(values)
        if " " in joined or "\t" in joined:
            return [v.strip(" \t") for v in values]
        return values
    return list(map(str, values))


def _float_texts(col: Column) -> list[str]:
    """``str`` of each cell of a float column, each distinct value (bit for bit: -0.0 is not
    0.0) formatted once where at most half the cells are distinct: a target's coordinates,
    period and Λ_K repeat on each of its blocks, and ``float.__repr__`` costs ~0.35 µs."""
    data = col.data
    if not len(data):
        return []
    _, first, inverse = np.unique(
        data.view(f"u{data.itemsize}"), return_index=True, return_inverse=True
    )
    if 2 * len(first) > len(data):
        return list(map(str, data.tolist()))
    texts = np.array(list(map(str, data[first].tolist())), dtype=object)
    return list(texts[inverse.ravel()].tolist())


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
    rest are joined as they are; a column of one value (bit for bit) is formatted once."""
    if not _plain_columns(table) or (delimiter != " " and len(table.colnames) < 2):
        return None
    cells: list[list[str]] = []
    joined = False  # whether the last of ``cells`` holds one text (the columns before, joined)
    for col in table.itercols():
        one = _one_value(col)
        values = _cell_texts(col[:1] if one else col)
        if col.dtype.kind == "U" and _needs_csv(values, delimiter):
            values = _csv_cells(values, delimiter)  # a cell's text is its own
        if one and joined:  # columns of one value side by side: joined once
            cells[-1] = [cells[-1][0] + delimiter + values[0]]
        else:
            cells.append(values)
        joined = one
    n = len(table)
    return list(map(delimiter.join, zip(*(c * n if len(c) < n else c for c in cells), strict=True)))


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
