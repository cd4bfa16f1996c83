"""Eclipse-time tables: full-precision barycentric epochs, their σ, kind and optional cycle.

A table (CSV, or ECSV with units) has the columns

- ``bjd_tdb`` (barycentric Julian date, TDB) or ``bmjd_tdb`` (= BJD − 2400000.5): the epoch, read
  from its text as an exact decimal, never through one float64 (which keeps ~40 µs at JD 2.46e6);
- ``sigma_s``: its 1σ error in seconds (in ECSV any time unit, e.g. ``d``, converted);
- ``kind`` (optional): ``primary`` (default) or ``secondary`` eclipse;
- ``cycle`` (optional): the cycle number, an integer for primaries and a half-integer for
  secondaries; without it the cycles are counted from the times (:mod:`ucbplan.timing.cycles`);
- ``instrument``, ``reference``, ``note`` (optional text, ignored).

Epochs are held as exact decimals and, for the arithmetic, as float64 seconds since a reference
epoch taken from the data (the subtraction is exact, so the seconds keep ~10 ns over decades).
Rows are numbered from 1 = the first data row; every bad row is a one-line
:class:`~ucbplan.errors.InputFileError` naming the row and column.
"""

from __future__ import annotations

import csv
import decimal
import difflib
import math
import re
from dataclasses import dataclass
from decimal import Decimal
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from numpy.typing import NDArray

from ucbplan.core.constants import DAY_S
from ucbplan.core.timing_epochs import (
    DECIMAL_CONTEXT,
    JD_RANGE,
    MJD_OFFSET,
    jd_to_seconds,
    parse_decimal,
)
from ucbplan.errors import InputFileError, SchemaError, shorten
from ucbplan.inputs import MAX_ALIASES, MAX_YAML_BYTES, blank_comments, read_text

F64 = NDArray[np.float64]


#: Time columns and the offset that turns them into a JD.
TIME_COLUMNS = {"bjd_tdb": Decimal(0), "bmjd_tdb": MJD_OFFSET}
#: Text columns that may be present and are ignored.
TEXT_COLUMNS = ("instrument", "reference", "note")
KNOWN_COLUMNS = (*TIME_COLUMNS, "sigma_s", "kind", "cycle", *TEXT_COLUMNS)
#: Accepted σ of one time [s]: from 1 ns (below any clock) to a day (no eclipse timing).
MIN_SIGMA_S = 1e-9
MAX_SIGMA_S = DAY_S
#: Largest |cycle| accepted.
MAX_CYCLE = 1e12


@dataclass(frozen=True)
class EclipseTimes:
    """Eclipse times sorted by epoch, each with the data row it came from.

    Attributes
    ----------
    source : Path
        The table.
    ref_jd : Decimal
        Reference epoch (exact JD, TDB) of ``t_s``.
    jd : tuple of Decimal
        The epochs as read (exact JD, TDB).
    t_s : array
        Seconds since ``ref_jd`` (float64; exact to ~1e-8 s).
    sigma_s : array
        1σ timing errors [s].
    secondary : array of bool
        True for secondary eclipses (half-integer cycles).
    cycle : array or None
        Cycle numbers from the table, or None (count them).
    rows : array of int
        Data row of each time (1 = first data row).
    """

    source: Path
    ref_jd: Decimal
    jd: tuple[Decimal, ...]
    t_s: F64
    sigma_s: F64
    secondary: NDArray[np.bool_]
    cycle: F64 | None
    rows: NDArray[np.int64]

    @property
    def n(self) -> int:
        """Number of times."""
        return int(self.t_s.size)

    def label(self) -> str:
        """The file name used in messages."""
        return self.source.name


# ---------------------------------------------------------------------------------------------
# reading


class _Reader:
    def __init__(self, path: Path) -> None:
        self.path = path

    def fail(self, where: str, msg: str) -> InputFileError:
        return InputFileError(f"{self.path.name}: {where}: {msg}")


def _csv_rows(r: _Reader, text: str) -> tuple[list[str], list[tuple[int, list[str]]]]:
    """Header and (row number, cells) of a CSV; ``#`` comments and blank lines skipped."""
    try:
        text = blank_comments(text, Path(r.path.name))
    except SchemaError as exc:
        raise InputFileError(str(exc)) from None
    lines = [ln for ln in text.splitlines() if ln.strip()]
    if not lines:
        raise r.fail(
            "header", "empty table; expected a header line like bjd_tdb,sigma_s[,kind][,cycle]"
        )
    try:
        parsed = list(csv.reader(lines))
    except csv.Error as exc:
        raise r.fail("table", f"not readable as CSV ({exc})") from None
    header = [h.strip().lower() for h in parsed[0]]
    body = [(k, [c.strip() for c in cells]) for k, cells in enumerate(parsed[1:], start=1)]
    for k, cells in body:
        if len(cells) != len(header):
            raise r.fail(
                f"row {k}", f"has {len(cells)} fields, expected {len(header)} like the header"
            )
    return header, body


def _ecsv_rows(
    r: _Reader, text: str
) -> tuple[list[str], list[tuple[int, list[str]]], dict[str, Any]]:
    """Header, raw cells per row and astropy's column metadata (units) of an ECSV table.

    Astropy reads the header (units, data types, Time columns); the cells are re-read as text so
    that an epoch with more digits than a float64 keeps them.
    """
    from astropy.table import Table

    _check_ecsv_header(r, text)
    try:
        tab = Table.read(text if "\n" in text else text + "\n", format="ascii.ecsv")
    except Exception as exc:  # astropy raises many types for malformed ECSV
        msg = " ".join(str(exc).split())[:200]
        raise r.fail("table", f"not a readable ECSV table ({msg}); check the header") from None
    meta, time_cols = _ecsv_columns(r, tab)
    header, body = _ecsv_cells(text)
    names = [c.strip().lower() for c in tab.colnames]
    if header != names:  # Time columns serialised as jd1/jd2: take the exact two parts
        return names, _ecsv_time_rows(tab, names, time_cols), meta
    if len(body) != len(tab):
        raise r.fail("table", "the ECSV data lines do not match its header; check the file")
    for k, cells in body:
        if len(cells) != len(header):
            raise r.fail(f"row {k}", f"has {len(cells)} fields, expected {len(header)}")
    native = {"bjd_tdb": "jd", "bmjd_tdb": "mjd"}
    for key, col in time_cols.items():
        if col.format != native[key]:  # e.g. ISO text: the exact two parts, not the text
            i = header.index(key)
            exact = _ecsv_time_rows(tab, names, {key: col})
            for (_, cells), (_, ex) in zip(body, exact, strict=True):
                cells[i] = ex[i]
    return header, body, meta


def _ecsv_columns(r: _Reader, tab: Any) -> tuple[dict[str, Any], dict[str, Any]]:
    """Unit per column (None for Time columns) and the Time columns of an astropy table.

    Raises
    ------
    InputFileError
        A Time column not named bjd_tdb/bmjd_tdb or not in TDB, or a blank cell.
    """
    from astropy.time import Time

    meta: dict[str, Any] = {}
    time_cols: dict[str, Any] = {}
    for name in tab.colnames:
        col = tab[name]
        key = name.strip().lower()
        if isinstance(col, Time):
            if key not in TIME_COLUMNS:
                raise r.fail(f"column {name!r}", "unknown Time column; name it bjd_tdb")
            if col.scale != "tdb":
                raise r.fail(
                    f"column {name!r}",
                    f"expected barycentric TDB times, got scale {col.scale}; convert to BJD_TDB",
                )
            time_cols[key] = col
            meta[key] = None
            continue
        meta[key] = getattr(col, "unit", None)
        mask = getattr(col, "mask", None)
        if mask is not None and np.any(mask):
            k = int(np.flatnonzero(np.asarray(mask))[0]) + 1
            raise r.fail(f"row {k}, column {name!r}", "blank cell; every row needs a value")
    return meta, time_cols


def _ecsv_cells(text: str) -> tuple[list[str], list[tuple[int, list[str]]]]:
    """Header and raw cells per row (row number from 1) of the data lines of an ECSV text."""
    delim = " "
    m = re.search(r"^#\s*delimiter:\s*['\"]?(,|\s)['\"]?\s*$", text, flags=re.MULTILINE)
    if m and m.group(1) == ",":
        delim = ","
    lines = [
        ln.strip() for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")
    ]
    parsed = list(csv.reader(lines, delimiter=delim, quotechar='"', skipinitialspace=True))
    header = [h.strip().lower() for h in parsed[0]] if parsed else []
    body = [(k, [c.strip() for c in cells]) for k, cells in enumerate(parsed[1:], start=1)]
    return header, body


def _check_ecsv_header(r: _Reader, text: str) -> None:
    """Count the aliases of the ECSV's YAML header before astropy constructs it: astropy's own
    loader would expand an alias bomb ("billion laughs") into gigabytes."""
    lines = []
    for ln in text.splitlines():
        if not ln.startswith("#"):
            break
        body = ln[2:] if ln.startswith("# ") else ln[1:]
        if not body.startswith("%ECSV"):
            lines.append(body)
    header = "\n".join(lines)
    if len(header) > MAX_YAML_BYTES:
        raise r.fail("header", f"ECSV header larger than {MAX_YAML_BYTES} bytes; check the file")
    try:
        aliases = sum(
            isinstance(ev, yaml.AliasEvent) for ev in yaml.parse(header, Loader=yaml.SafeLoader)
        )
    except yaml.YAMLError as exc:
        msg = " ".join(str(exc).split())[:200]
        raise r.fail("header", f"not a valid ECSV header ({msg})") from None
    if aliases > MAX_ALIASES:
        raise r.fail(
            "header", f"more than {MAX_ALIASES} YAML aliases; write the header out without anchors"
        )


def _ecsv_time_rows(
    tab: Any, names: list[str], time_cols: dict[str, Any]
) -> list[tuple[int, list[str]]]:
    """Rows of an ECSV as text, the Time columns from their exact two-part JDs."""
    body = []
    for k in range(len(tab)):
        cells = []
        for name, key in zip(tab.colnames, names, strict=True):
            if key in time_cols:
                col = time_cols[key]
                jd = DECIMAL_CONTEXT.add(Decimal(float(col.jd1[k])), Decimal(float(col.jd2[k])))
                rel = DECIMAL_CONTEXT.subtract(
                    jd, TIME_COLUMNS[key]
                )  # 1e-18 d = 1e-13 s resolution
                cells.append(str(rel.quantize(Decimal("1e-18"), context=DECIMAL_CONTEXT)))
            else:
                cells.append(str(tab[name][k]).strip())
        body.append((k + 1, cells))
    return body


def _check_header(r: _Reader, header: list[str]) -> str:
    for h in header:
        if h not in KNOWN_COLUMNS:
            near = difflib.get_close_matches(h, KNOWN_COLUMNS, n=1)
            hint = f" (did you mean {near[0]!r}?)" if near else ""
            raise r.fail(
                f"column {shorten(h, 40)}",
                f"unknown column{hint}; expected bjd_tdb (or bmjd_tdb), sigma_s and optionally "
                f"kind, cycle, {', '.join(TEXT_COLUMNS)}",
            )
    dups = [h for h in header if header.count(h) > 1]
    if dups:
        raise r.fail(f"column {dups[0]!r}", "appears twice; keep one")
    times = [h for h in header if h in TIME_COLUMNS]
    if len(times) != 1:
        raise r.fail(
            "header",
            f"expected exactly one time column, bjd_tdb or bmjd_tdb, got {times or 'none'}",
        )
    if "sigma_s" not in header:
        raise r.fail("header", "column sigma_s is missing (1σ timing error of each time, s)")
    return times[0]


def _sigma_factor(r: _Reader, unit: Any) -> float:
    """Seconds per unit of an ECSV ``sigma_s`` column (1 without a unit)."""
    if unit is None:
        return 1.0
    from astropy import units as u

    try:
        return float((1.0 * unit).to_value(u.s))
    except (u.UnitsError, TypeError, ValueError):
        raise r.fail(
            "column 'sigma_s'", f"expected a time unit (s, min, d), got unit {unit}"
        ) from None


def _epoch(r: _Reader, k: int, col: str, cell: str) -> Decimal:
    where = f"row {k}, column {col!r}"
    if not cell:
        raise r.fail(where, "blank cell; every row needs an epoch")
    try:
        jd = parse_decimal(cell) + TIME_COLUMNS[col]
    except (ValueError, decimal.InvalidOperation):
        raise r.fail(
            where, f"expected a number like 2458305.6827886, got {shorten(cell, 60)}"
        ) from None
    if not (JD_RANGE[0] <= jd <= JD_RANGE[1]):
        hint = (
            "; a modified or reduced JD? use the column bmjd_tdb (BJD − 2400000.5)"
            if col == "bjd_tdb" and jd < JD_RANGE[0]
            else ""
        )
        raise r.fail(
            where,
            f"expected an epoch between JD {JD_RANGE[0]} and {JD_RANGE[1]}, got "
            f"{shorten(cell, 60)}{hint}",
        )
    return jd


def _sigma(r: _Reader, k: int, cell: str, factor: float) -> float:
    where = f"row {k}, column 'sigma_s'"
    try:
        val = float(parse_decimal(cell)) * factor
    except (ValueError, decimal.InvalidOperation, OverflowError):
        raise r.fail(
            where, f"expected a positive number of seconds, got {shorten(cell, 60)}"
        ) from None
    if not (math.isfinite(val) and MIN_SIGMA_S <= val <= MAX_SIGMA_S):
        raise r.fail(
            where,
            f"expected a positive timing error from {MIN_SIGMA_S:g} to {MAX_SIGMA_S:g} s, got "
            f"{shorten(cell, 60)}",
        )
    return val


def _kind(r: _Reader, k: int, cell: str) -> bool:
    word = cell.strip().lower()
    if word not in ("primary", "secondary"):
        raise r.fail(
            f"row {k}, column 'kind'", f"expected primary or secondary, got {shorten(cell, 40)}"
        )
    return word == "secondary"


def _cycle(r: _Reader, k: int, cell: str, secondary: bool) -> float:
    where = f"row {k}, column 'cycle'"
    try:
        val = parse_decimal(cell)
    except (ValueError, decimal.InvalidOperation):
        raise r.fail(where, f"expected a cycle number, got {shorten(cell, 40)}") from None
    if abs(val) > Decimal(MAX_CYCLE):
        raise r.fail(where, f"expected |cycle| ≤ {MAX_CYCLE:g}, got {shorten(cell, 40)}")
    twice = val * 2
    if twice != twice.to_integral_value() or (abs(twice) % 2 == 1) != secondary:
        want = (
            "a half-integer (n + 0.5) for a secondary" if secondary else "an integer for a primary"
        )
        raise r.fail(where, f"expected {want} eclipse, got {shorten(cell, 40)}")
    return float(val)


def read_times(path: Path | str) -> EclipseTimes:
    """Read an eclipse-time table (ECSV by the ``.ecsv`` suffix, else CSV); see the module notes.

    Raises
    ------
    InputFileError
        Unreadable file, unknown/missing/duplicate column, bad cell (the row and column named),
        non-positive σ, or cycle numbers that do not increase with time.
    """
    path = Path(path)
    text = read_text(path, "table of eclipse times")
    return _parse(path, text, path.suffix.lower() == ".ecsv")


def read_times_table(table: Any, label: str = "<Table>") -> EclipseTimes:
    """The eclipse times of an astropy ``Table`` (columns and rules as :func:`read_times`; a
    ``Time`` column keeps its two-part JD, a text column every digit).

    Raises
    ------
    InputFileError
        As :func:`read_times`, naming ``label``.
    """
    import io

    buf = io.StringIO()
    try:
        table.write(buf, format="ascii.ecsv")
    except Exception as exc:  # astropy raises many types for columns ECSV cannot hold
        msg = " ".join(str(exc).split())[:200]
        raise InputFileError(f"{label}: not writable as a table of eclipse times ({msg})") from None
    return _parse(Path(label), buf.getvalue(), True)


def _parse(path: Path, text: str, ecsv: bool) -> EclipseTimes:
    """:func:`read_times` of a table's text (ECSV or CSV); ``path`` names it in messages."""
    r = _Reader(path)
    units: dict[str, Any] = {}
    if ecsv:
        header, body, units = _ecsv_rows(r, text)
    else:
        header, body = _csv_rows(r, text)
    tcol = _check_header(r, header)
    if not body:
        raise r.fail("table", "no data rows; add one line per eclipse time")
    idx = {h: i for i, h in enumerate(header)}
    unit = units.get(tcol)
    if unit is not None and str(unit) not in ("d", "day"):
        raise r.fail(f"column {tcol!r}", f"expected days (a Julian date), got unit {unit}")
    factor = _sigma_factor(r, units.get("sigma_s"))
    jds, sig, sec, cyc, rows = [], [], [], [], []
    for k, cells in body:
        jds.append(_epoch(r, k, tcol, cells[idx[tcol]]))
        sig.append(_sigma(r, k, cells[idx["sigma_s"]], factor))
        is_sec = _kind(r, k, cells[idx["kind"]]) if "kind" in idx else False
        sec.append(is_sec)
        if "cycle" in idx:
            cyc.append(_cycle(r, k, cells[idx["cycle"]], is_sec))
        rows.append(k)
    order = sorted(range(len(jds)), key=lambda i: (jds[i], rows[i]))
    jd_sorted = tuple(jds[i] for i in order)
    ref = jd_sorted[len(jd_sorted) // 2].to_integral_value(rounding=decimal.ROUND_FLOOR)
    times = EclipseTimes(
        source=path,
        ref_jd=ref,
        jd=jd_sorted,
        t_s=np.array([jd_to_seconds(j, ref) for j in jd_sorted]),
        sigma_s=np.array([sig[i] for i in order]),
        secondary=np.array([sec[i] for i in order], dtype=bool),
        cycle=np.array([cyc[i] for i in order]) if cyc else None,
        rows=np.array([rows[i] for i in order], dtype=np.int64),
    )
    if times.cycle is not None:
        check_monotonic(times, times.cycle)
    return times


def check_monotonic(times: EclipseTimes, cycle: F64) -> None:
    """Cycle numbers must not decrease as time increases (equal cycles: the same eclipse).

    Raises
    ------
    InputFileError
        Naming the two rows whose order disagrees.
    """
    dn = np.diff(cycle)
    dt = np.diff(times.t_s)
    bad = np.flatnonzero((dn < 0) | ((dn > 0) & (dt <= 0)))
    if bad.size:
        i = int(bad[0])
        a, b = int(times.rows[i]), int(times.rows[i + 1])
        raise InputFileError(
            f"{times.label()}: rows {a} and {b}, column 'cycle': cycle numbers must increase with "
            f"time, got cycle {cycle[i]:g} at BJD_TDB {times.jd[i]} and {cycle[i + 1]:g} at "
            f"BJD_TDB {times.jd[i + 1]}; fix the cycle column (or leave it out to count cycles)"
        )
