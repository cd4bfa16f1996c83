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
from collections.abc import Callable
from typing import Any

from astropy.table import Column, Table

__all__ = ["ecsv_data_lines", "json_rows_text"]

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


def _strs(col: Column) -> list[str]:
    """Each cell as astropy's ECSV writer formats it (``str`` of the cell), stripped of spaces
    and tabs at both ends as its writer's splitter does."""
    values = col.tolist()
    if col.dtype.kind == "U":
        return [v.strip(" \t") for v in values]
    return list(map(str, values))


class _Lines:
    """A file-like sink collecting each row the ``csv`` writer writes (one write per row)."""

    def __init__(self) -> None:
        self.lines: list[str] = []

    def write(self, text: str) -> None:
        self.lines.append(text)


def ecsv_data_lines(table: Table) -> list[str] | None:
    """The data lines of ``table`` as astropy's ECSV writer writes them (without line ends), or
    None for a table with other than plain 1-d columns."""
    if not _plain_columns(table):
        return None
    cells = [_strs(col) for col in table.itercols()]
    empty = [False] * len(table)
    for values in cells:
        for i, v in enumerate(values):
            if not v:
                values[i] = _SENTINEL
                empty[i] = True
    sink = _Lines()
    writer = csv.writer(sink, delimiter=" ", quotechar='"', doublequote=True, escapechar=None)
    writer.writerows(zip(*cells, strict=True))
    return [
        (line.replace(_SENTINEL, '""') if has else line).rstrip("\r\n")
        for line, has in zip(sink.lines, empty, strict=True)
    ]


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
    if not len(table):
        return "[]"
    pad = "  " * level
    keys = [json.dumps(str(name)) for name in table.colnames]
    cells = [list(map(_encoder(col.dtype.kind), col.tolist())) for col in table.itercols()]
    inner = f",\n{pad}    "
    rows = [
        "{\n" + pad + "    " + inner.join(f"{k}: {v}" for k, v in zip(keys, row, strict=True))
        for row in zip(*cells, strict=True)
    ]
    return f"[\n{pad}  " + f"\n{pad}  }},\n{pad}  ".join(rows) + f"\n{pad}  }}\n{pad}]"
