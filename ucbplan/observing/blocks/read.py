"""Reading a blocks table back: :func:`read_blocks` (ECSV, CSV or JSON, recognised by content)
and :func:`check_blocks`, which checks every cell against the columns' declaration
(:data:`~ucbplan.observing.blocks.schema.KNOWN_COLUMNS`: type, bounds, blanks, ISO times) so that
every export can rely on what it reads.
"""

from __future__ import annotations

import csv
import io
import itertools
import json
import math
from collections.abc import Mapping
from datetime import datetime
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from astropy import units as u
from astropy.table import Table
from astropy.time import Time

from ucbplan.errors import InputError, InputFileError, shorten
from ucbplan.inputs import MAX_ALIASES, read_text
from ucbplan.observing.blocks.schema import (
    BLANK_OK,
    KNOWN_COLUMNS,
    MAX_HEADER_CHARS,
    MAX_TABLE_BYTES,
    REQUIRED_COLUMNS,
    TIME_YEARS,
    Column,
)
from ucbplan.observing.blocks.write import csv_unsafe_text
from ucbplan.targets.values import one_line


def _bad_cell(where: str, row: int, column: str, expected: str, value: Any) -> InputFileError:
    return InputFileError(
        f"{where}: row {row + 1}, column {column}: expected {expected}, got {shorten(value, 60)}; "
        "regenerate the table with `ucbplan plan`"
    )


def _cells(col: Any) -> list[Any]:
    """Python values of a table column, None for masked (blank) cells."""
    mask = np.ma.getmaskarray(col) if hasattr(col, "mask") else np.zeros(len(col), dtype=bool)
    values = np.asarray(col).tolist() if not isinstance(col, Time) else list(col)
    return [None if m else v for v, m in zip(values, mask, strict=True)]


def _time_strings(col: Time, kind: str) -> list[str]:
    """ISO strings of an astropy Time column, in the scale of the column's kind."""
    return list(np.atleast_1d(getattr(col, "tdb" if kind == "tdb" else "utc").isot))


def _check_time(text: str, where: str, row: int, name: str) -> None:
    try:
        value = datetime.fromisoformat(text.strip()) if len(text) <= 64 else None
    except ValueError:
        value = None
    if value is None or not TIME_YEARS[0] <= value.year <= TIME_YEARS[1]:
        expected = f"an ISO time like 2037-01-15T01:02:03.400 in {TIME_YEARS[0]}-{TIME_YEARS[1]}"
        raise _bad_cell(where, row, name, expected, text)


def _text_column(c: Column, col: Any, where: str) -> np.ndarray:
    """A text column: every cell text (blank only where allowed), times parseable."""
    cells = _time_strings(col, c.kind) if isinstance(col, Time) else _cells(col)
    out: list[str] = []
    for i, v in enumerate(cells):
        if v is None or (isinstance(v, str) and not v.strip()):
            if c.name not in BLANK_OK:
                raise _bad_cell(where, i, c.name, "a value (blank cell)", "")
            v = ""
        if isinstance(v, bytes):
            v = v.decode("utf-8", "replace")
        if not isinstance(v, str):
            raise _bad_cell(where, i, c.name, "text", v)
        try:
            v.encode("utf-8")
        except UnicodeEncodeError:
            raise _bad_cell(where, i, c.name, "Unicode text", v) from None
        if v and c.kind in ("utc", "tdb"):
            _check_time(v, where, i, c.name)
        out.append(v)
    return np.array(out, dtype=str) if out else np.array([], dtype="U1")


def _number(v: Any) -> float | None:
    """A cell as a float (text is parsed), None if it is not a number."""
    if isinstance(v, bool | np.bool_) or v is None:
        return None
    if isinstance(v, int | float | np.integer | np.floating):
        return float(v)
    if isinstance(v, str | bytes) and len(v) <= 64:
        try:
            return float(v)
        except ValueError:
            return None
    return None


def _numeric_column(c: Column, col: Any, where: str) -> np.ndarray:
    """A number column: no blanks, finite (or NaN where allowed), inside ``c.bounds``."""
    scale = 1.0
    unit = getattr(col, "unit", None)
    if unit is not None and c.unit is not None:
        try:
            scale = float(u.Unit(unit).to(c.unit))
        except (u.UnitsError, ValueError, TypeError):
            raise InputFileError(
                f"{where}: column {c.name}: unit {shorten(str(unit), 40)} is not {c.unit}; "
                "regenerate the table with `ucbplan plan`"
            ) from None
    lo, hi = c.bounds if c.bounds is not None else (-math.inf, math.inf)
    whole = c.dtype == "int64"
    kind = "a whole number" if whole else "a number"
    expected = f"{kind} in [{lo:g}, {hi:g}]{f' {c.unit}' if c.unit else ''}"
    out: list[float] = []
    for i, v in enumerate(_cells(col)):
        if v is None or (isinstance(v, str) and not v.strip()):
            raise _bad_cell(where, i, c.name, f"{expected} (blank cell; write nan if unknown)", "")
        x = _number(v)
        if x is not None and math.isnan(x) and c.nan_ok:
            out.append(x)
            continue
        if x is None or not (math.isfinite(x) and lo <= x * scale <= hi):
            raise _bad_cell(where, i, c.name, expected, v)
        if whole and x != int(x):
            raise _bad_cell(where, i, c.name, expected, v)
        out.append(x)
    return np.array(out, dtype=np.int64 if whole else np.float64)


def _check_rows(table: Table, where: str) -> None:
    """Unique block ids; every block ends after it starts."""
    seen: dict[str, int] = {}
    for i, block in enumerate(table["block_id"]):
        first = seen.setdefault(str(block), i)
        if first != i:
            raise InputFileError(
                f"{where}: rows {first + 1} and {i + 1}: block_id {shorten(str(block), 60)} "
                "appears twice; block ids must be unique (calendar UIDs, OB names)"
            )
    for i, (t0, t1) in enumerate(zip(table["t_start_utc"], table["t_end_utc"], strict=True)):
        if datetime.fromisoformat(str(t1).strip()) < datetime.fromisoformat(str(t0).strip()):
            raise _bad_cell(where, i, "t_end_utc", f"a time after t_start_utc {t0}", str(t1))


def check_blocks(table: Table, where: str = "blocks table") -> Table:
    """A checked copy of a blocks table: the columns every reader relies on, cell by cell.

    Required columns present; every declared column (:data:`KNOWN_COLUMNS`) of its type, without
    blank cells (except :data:`BLANK_OK`), finite (or NaN where declared) and inside its bounds;
    times ISO in 1900-2101 (astropy Time columns become ISO strings); unique block ids; blocks
    that end after they start. Other columns are kept as they are.

    Raises
    ------
    InputFileError
        One line naming the row and the column, what was expected and what was found.
    """
    if not isinstance(table, Table):
        raise InputFileError(f"{where}: expected a table of blocks, got {shorten(table, 60)}")
    missing = [c for c in REQUIRED_COLUMNS if c not in table.colnames]
    if missing:
        raise InputFileError(
            f"{where}: blocks table lacks required columns {', '.join(missing)}; regenerate it "
            "with `ucbplan plan ... -o blocks.ecsv`"
        )
    out = Table(meta=dict(table.meta) if isinstance(table.meta, Mapping) else {})
    for name in table.colnames:
        col, c = table[name], KNOWN_COLUMNS.get(name)
        if c is None:
            out[name] = col
            continue
        check = _text_column if c.dtype == "str" else _numeric_column
        out[name] = check(c, col, where)
        out[name].unit = getattr(col, "unit", None) if c.dtype != "str" else None
        out[name].description = getattr(col, "description", None)
    _check_rows(out, where)
    return out


def _check_header(text: str, where: str) -> None:
    """Refuse an ECSV header larger than :data:`MAX_HEADER_CHARS` (astropy parses it in pure
    Python, ~1 MB/s) or with more YAML aliases than a target file may have (an alias bomb
    expands when the metadata is written out again)."""
    lines = itertools.takewhile(lambda ln: ln.startswith("#"), text.splitlines())
    header_lines: list[str] = []
    size = 0
    for line in lines:
        size += len(line) + 1
        if size > MAX_HEADER_CHARS:
            raise InputFileError(
                f"{where}: the ECSV header is larger than {MAX_HEADER_CHARS} characters, more "
                "than any plan writes; regenerate the table with `ucbplan plan`"
            )
        header_lines.append(line[2:] if line.startswith("# ") else line[1:])
    if header_lines and header_lines[0].startswith("%"):
        header_lines[0] = ""  # the "%ECSV 1.0" line: libyaml refuses unknown directives
    loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
    count = 0
    try:
        for event in yaml.parse("\n".join(header_lines), Loader=loader):
            count += isinstance(event, yaml.AliasEvent)
            if count > MAX_ALIASES:
                raise InputFileError(
                    f"{where}: the ECSV header uses more than {MAX_ALIASES} YAML aliases; "
                    "write the metadata out or regenerate the table with `ucbplan plan`"
                )
    except yaml.YAMLError:
        return  # astropy reports the malformed header


def _object_column(cells: list[Any], mask: list[bool]) -> np.ma.MaskedArray:
    """Cells as a 1-d masked object array (a cell holding a list stays one cell)."""
    data = np.empty(len(cells), dtype=object)
    data[:] = cells
    return np.ma.array(data, mask=mask)


def _json_table(text: str, where: str) -> Table:
    """A JSON list of row objects (``plan --format json``) as a table; null is NaN / blank."""
    try:
        rows = json.loads(text)
    except (ValueError, RecursionError) as exc:
        raise InputFileError(f"{where}: not valid JSON ({one_line(str(exc))[:120]})") from None
    if isinstance(rows, dict) and "rows" in rows:  # {"meta": ..., "rows": [...]}
        rows = rows["rows"]
    if not isinstance(rows, list) or not all(isinstance(r, dict) for r in rows):
        raise InputFileError(
            f"{where}: expected a JSON list of row objects (`Plan.write` to a .json path)"
        )
    names = list(dict.fromkeys(k for r in rows for k in r))
    columns: dict[str, Any] = {}
    for name in names:
        c = KNOWN_COLUMNS.get(name)
        cells = []
        for i, row in enumerate(rows):
            if name not in row:
                raise _bad_cell(where, i, name, "a value (the row lacks this column)", "")
            v = row[name]
            numeric = c is not None and c.dtype != "str"
            cells.append(math.nan if v is None and numeric else v)
        columns[name] = _object_column(cells, [v is None for v in cells])
    table = Table(columns) if columns else Table()
    for name in table.colnames:
        c = KNOWN_COLUMNS.get(name)
        if c is not None and c.unit is not None:
            table[name].unit = c.unit
    return table


def _csv_table(text: str, where: str) -> Table:
    """A CSV blocks table (``plan --format csv``): every cell read as text, then typed."""
    try:
        reader = csv.reader(io.StringIO(text, newline=""))
        header = next(reader, None)
        rows = list(reader)
    except csv.Error as exc:
        raise InputFileError(f"{where}: not valid CSV ({one_line(str(exc))[:120]})") from None
    if not header:
        raise InputFileError(f"{where}: empty file; pass a blocks table from `ucbplan plan -o`")
    if len(set(header)) != len(header):
        raise InputFileError(f"{where}: a column name appears twice in the CSV header")
    for i, row in enumerate(rows):
        if len(row) != len(header):
            raise InputFileError(
                f"{where}: row {i + 1}: {len(row)} cells for {len(header)} columns; "
                "regenerate the table with `ucbplan plan`"
            )
    columns = {}
    for k, name in enumerate(header):
        cells = [csv_unsafe_text(row[k]) for row in rows]  # the writer's ' before =, +, -, @
        columns[name] = _object_column(cells, [not v.strip() for v in cells])
    table = Table(columns) if rows else Table(names=header, dtype=[str] * len(header))
    for name in table.colnames:
        c = KNOWN_COLUMNS.get(name)
        if c is not None and c.unit is not None:
            table[name].unit = c.unit
    return table


def _ecsv_table(text: str, where: str) -> Table:
    _check_header(text, where)
    try:
        return Table.read(text.splitlines(), format="ascii.ecsv")
    except Exception as exc:  # astropy raises many types for a malformed ECSV file
        detail = one_line(f"{type(exc).__name__}: {exc}")[:160]
        raise InputFileError(
            f"{where}: not a readable ECSV blocks table ({detail}); write one with "
            "`ucbplan plan ... -o blocks.ecsv`"
        ) from None


def read_blocks(path: Path | str) -> Table:
    """Read a master blocks table written by ``ucbplan plan`` as ECSV, CSV or JSON.

    The file is read by :func:`ucbplan.inputs.read_text` (regular files only, size limit, UTF-8
    with or without a byte-order mark); its format is recognised by its content (``# %ECSV``,
    a JSON list, else CSV); then :func:`check_blocks` checks every cell.

    Raises
    ------
    InputFileError
        One line: unreadable file, malformed format, missing required columns, or a bad cell
        (with its row and column).
    """
    path = Path(path)
    where = shorten(str(path), 120).strip("'")
    try:
        text = read_text(path, "blocks table", limit=MAX_TABLE_BYTES)
    except InputError as exc:
        raise InputFileError(f"{exc}; pass a blocks table from `ucbplan plan -o`") from None
    head = text.lstrip()
    if head.startswith("# %ECSV"):
        table = _ecsv_table(text, where)
    elif head.startswith(("[", "{")):
        table = _json_table(text, where)
    else:
        table = _csv_table(text, where)
    return check_blocks(table, where)
