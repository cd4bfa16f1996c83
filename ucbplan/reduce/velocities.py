"""Read measured radial velocities (CSV or ECSV) into a validated :class:`VelocityTable`.

Accepted columns (one time column, one window column, SB1 or SB2 velocities):

=====================  =========================================================================
column                 meaning
=====================  =========================================================================
``bjd_tdb``            mid-exposure barycentric Julian date, TDB  (or ``bmjd_tdb`` / ``mjd_tdb``:
                       barycentric MJD in TDB)
``jd_utc``/``mjd_utc`` mid-exposure UTC at the telescope (needs ``--site``; converted with
                       :func:`ucbplan.observing.observatory.barycentric.site_utc_to_bary_tdb`)
``exptime_s``          exposure or co-add window Δt_bin [s] (alias ``window_s``), ≥ 0
``lambda_k``           Λ_K of the window as written by ``ucbplan plan`` (instead of exptime_s)
``v1, sigma_v1``       star 1 velocity and 1σ [km/s]; with ``v2, sigma_v2`` for SB2
``v, sigma_v``         SB1 velocity and 1σ [km/s]
``session``            optional session label (default: spectra separated by > 0.5 d split)
``u_star``             optional targeted argument of latitude of star 1 [rad] (plan anchor)
=====================  =========================================================================

Velocities are positive when receding. ECSV columns may carry units (velocity → km/s, window →
s). Times are mid-exposure (ESO's MJD-OBS is the exposure *start*: add half the exposure).

Files are UTF-8 (a byte-order mark is accepted; other encodings are refused with the fix, see
:func:`ucbplan.inputs.read_text`). Every cell must hold a value: a blank cell, a non-finite
number, a date outside 1858–2500, a negative or zero σ, |v| ≥ c or a duplicate column is a
one-line :class:`~ucbplan.errors.VelocityFileError` naming the file, row and column. The
reduction then needs at least :data:`MIN_SPECTRA` spectra at different phases, and refuses
windows as long as the orbit (:func:`ucbplan.reduce.design.window_factors`: it needs the
target's period).

Validity (:func:`check_validity`): every time must lie between the start of the LISA observation
and :data:`HORIZON_S` (20 Julian years) after its end; beyond that the u(t) extrapolation is not
something ucbplan will stand behind.
"""

from __future__ import annotations

import csv
import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from astropy.time import Time
from numpy.typing import NDArray

from ucbplan.core.constants import C_KM_S, DAY_S, YEAR_S
from ucbplan.core.kepler import row_chunks
from ucbplan.errors import SchemaError, VelocityFileError, shorten
from ucbplan.inputs import blank_comments, read_text

if TYPE_CHECKING:
    from astropy.coordinates import EarthLocation, SkyCoord

    from ucbplan.targets import Target

F64 = NDArray[np.float64]

#: Latest accepted epoch after the end of the LISA observation [s] (20 Julian years).
HORIZON_S = 20.0 * YEAR_S
#: Without a session column, consecutive spectra further apart than this start a new session [s].
SESSION_GAP_S = 0.5 * DAY_S
#: Fewest spectra the fit v = γ ± K F̄ accepts (two unknowns per star).
MIN_SPECTRA = 2
#: Accepted range of each time column (JD or MJD): years 1858 … 2500, far wider than LISA's.
_TIME_RANGE = {
    "bjd_tdb": (2400000.5, 2634166.5),
    "bmjd_tdb": (0.0, 234166.0),
    "mjd_tdb": (0.0, 234166.0),
    "jd_utc": (2400000.5, 2634166.5),
    "mjd_utc": (0.0, 234166.0),
}

_TIME_COLS = {
    "bjd_tdb": 0.0,
    "bmjd_tdb": 2400000.5,
    "mjd_tdb": 2400000.5,
    "jd_utc": 0.0,
    "mjd_utc": 2400000.5,
}
_NUM_COLS = (
    "exptime_s",
    "window_s",
    "lambda_k",
    "v1",
    "sigma_v1",
    "v2",
    "sigma_v2",
    "v",
    "sigma_v",
    "u_star",
)
KNOWN_COLUMNS: tuple[str, ...] = (*_TIME_COLS, *_NUM_COLS, "session")
_VEL_UNIT = {
    "v1": "km/s",
    "sigma_v1": "km/s",
    "v2": "km/s",
    "sigma_v2": "km/s",
    "v": "km/s",
    "sigma_v": "km/s",
    "exptime_s": "s",
    "window_s": "s",
    "u_star": "rad",
}


@dataclass(frozen=True, slots=True)
class VelocityTable:
    """Validated velocities, one entry per spectrum, in input order.

    Attributes
    ----------
    source : Path or None
        File read.
    time : astropy.time.Time
        Mid-exposure epochs, TDB at the barycentre.
    window_s : ndarray
        Exposure/co-add window Δt_bin [s]; NaN where only ``lambda_k`` was given.
    lambda_k : ndarray
        Λ_K given in the file; NaN where ``window_s`` was given.
    v, sigma : tuple of ndarray
        (v1,) for SB1 or (v1, v2) for SB2 and their 1σ [km/s].
    session : tuple of str
        Session label of each spectrum.
    u_star : ndarray or None
        Targeted u★ per spectrum [rad] if the file has it.
    site_utc : bool
        True while ``time`` is UTC at the (not yet known) telescope; :func:`to_barycentric`
        converts it.
    window_column : str
        The file's window column (``exptime_s``, ``window_s`` or ``lambda_k``), for messages.
    """

    source: Path | None
    time: Time
    window_s: F64
    lambda_k: F64
    v: tuple[F64, ...]
    sigma: tuple[F64, ...]
    session: tuple[str, ...]
    u_star: F64 | None
    site_utc: bool = False
    window_column: str = "exptime_s"

    @property
    def lines(self) -> str:
        """ "SB1" or "SB2"."""
        return "SB2" if len(self.v) == 2 else "SB1"

    @property
    def n(self) -> int:
        """Number of spectra."""
        return int(self.v[0].size)


def _fail(path: Path, where: str, msg: str) -> VelocityFileError:
    return VelocityFileError(f"{path}: {where}: {msg}")


def _col(name: str) -> str:
    """A column name quoted for a message (cut to a sane length)."""
    return shorten(name, 60)


def _text(path: Path) -> str:
    """The file's text (UTF-8, BOM accepted), or a one-line VelocityFileError."""
    try:
        return read_text(path, "velocity table")
    except SchemaError as exc:
        raise VelocityFileError(str(exc)) from None


def _read_csv(path: Path) -> tuple[list[str], list[tuple[int, list[str]]]]:
    try:
        text = blank_comments(_text(path), path)
    except SchemaError as exc:
        raise VelocityFileError(str(exc)) from None
    lines = [(i + 1, ln) for i, ln in enumerate(text.splitlines()) if ln.strip()]
    if not lines:
        raise VelocityFileError(
            f"{path}: empty velocity file; expected a header line like "
            "bjd_tdb,exptime_s,v1,sigma_v1,v2,sigma_v2"
        )
    try:
        rows = list(csv.reader([ln for _, ln in lines]))
    except csv.Error as exc:
        raise VelocityFileError(f"{path}: not a readable CSV table ({exc})") from None
    header = [h.strip().lower() for h in rows[0]]
    body = [(lines[k][0], [c.strip() for c in r]) for k, r in enumerate(rows[1:], start=1)]
    return header, body


def _read_ecsv(path: Path) -> tuple[list[str], dict[str, list[object]], list[int]]:
    from astropy.table import Table

    text = _text(path)
    try:
        tab = Table.read(text.splitlines(), format="ascii.ecsv")
    except Exception as exc:  # astropy raises many types for malformed ECSV
        why = " ".join(str(exc).split())[:200]
        raise VelocityFileError(f"{path}: not a readable ECSV table ({why})") from None
    return _table_columns(path, tab)


def _table_columns(path: Path, tab: Any) -> tuple[list[str], dict[str, list[object]], list[int]]:
    """Header (lower case), columns (velocities in km/s) and row numbers of an astropy table."""
    header = [name.strip().lower() for name in tab.colnames]
    cols: dict[str, list[object]] = {}
    for name, key in zip(tab.colnames, header, strict=True):
        col = tab[name]
        mask = np.asarray(getattr(col, "mask", False))
        if mask.any():
            row = int(np.flatnonzero(mask.reshape(len(col), -1).any(axis=1))[0]) + 1
            raise _fail(
                path,
                f"row {row}, column {_col(name)}",
                "blank cell, expected a value (every spectrum needs one)",
            )
        if col.ndim > 1:
            raise _fail(
                path, f"column {_col(name)}", f"has shape {col.shape}, expected one value per row"
            )
        unit = getattr(col, "unit", None)
        if key in _VEL_UNIT and unit is not None:
            try:
                vals = col.quantity.to_value(_VEL_UNIT[key])
            except Exception:  # astropy: UnitConversionError, TypeError for strings, …
                raise _fail(
                    path,
                    f"column {_col(name)}",
                    f"unit {shorten(str(unit), 60)} is not convertible to {_VEL_UNIT[key]}",
                ) from None
            cols[key] = list(vals)
        elif isinstance(col, Time):
            raise _fail(
                path,
                f"column {_col(name)}",
                "Time columns are not accepted; write "
                "bjd_tdb as a plain number (barycentric JD, TDB)",
            )
        else:
            cols[key] = list(col)
    return header, cols, list(range(1, len(tab) + 1))


def _parse_float(path: Path, row: int, col: str, raw: object) -> float:
    where = f"row {row}, column {_col(col)}"
    if isinstance(raw, str) and not raw.strip():
        raise _fail(path, where, "blank cell, expected a number (every spectrum needs one)")
    try:
        val = float(raw)  # type: ignore[arg-type]
    except (TypeError, ValueError, OverflowError):
        raise _fail(path, where, f"got {shorten(raw)}, expected a number") from None
    if not math.isfinite(val):
        raise _fail(path, where, f"got {shorten(raw)}, expected a finite number")
    return val


def _check_header(path: Path, header: list[str]) -> tuple[str, tuple[str, ...]]:
    if len(set(header)) != len(header):
        dup = next(h for h in header if header.count(h) > 1)
        raise _fail(
            path, f"column {_col(dup)}", "appears twice (column names ignore case); keep one"
        )
    unknown = [h for h in header if h not in KNOWN_COLUMNS]
    if unknown:
        raise _fail(
            path,
            f"column {_col(unknown[0])}",
            f"unknown column; expected some of {', '.join(KNOWN_COLUMNS)}",
        )
    times = [h for h in header if h in _TIME_COLS]
    if len(times) != 1:
        raise _fail(
            path,
            "header",
            f"expected exactly one time column of {', '.join(_TIME_COLS)}, got {times or 'none'}",
        )
    if {"v1", "v2"} <= set(header):
        comps: tuple[str, ...] = ("v1", "v2")
    elif "v" in header and "v1" not in header and "v2" not in header:
        comps = ("v",)
    elif "v1" in header and "v2" not in header and "v" not in header:
        comps = ("v1",)
    else:
        raise _fail(path, "header", "expected v1,sigma_v1,v2,sigma_v2 (SB2) or v,sigma_v (SB1)")
    for c in comps:
        if f"sigma_{c}" not in header:
            raise _fail(path, "header", f"column sigma_{c} is missing (1σ of {c} in km/s)")
    windows = [h for h in header if h in ("exptime_s", "window_s", "lambda_k")]
    if len(windows) != 1:
        raise _fail(
            path,
            "header",
            "expected exactly one of exptime_s, window_s, lambda_k "
            f"(exposure window in s, or Λ_K from the plan), got {windows or 'none'}",
        )
    return times[0], comps


def read_velocities(path: Path | str) -> VelocityTable:
    """Read and validate a velocity table (format from the suffix: ``.ecsv`` or CSV otherwise).

    Parameters
    ----------
    path : Path or str
        The table.

    Returns
    -------
    VelocityTable

    Raises
    ------
    VelocityFileError
        Unreadable or non-UTF-8 file, unknown/missing/duplicate columns, blank cells, malformed,
        non-finite or out-of-range values, no rows; one line naming the row and column.
    """
    path = Path(path)
    fast = None if path.suffix.lower() == ".ecsv" else _fast_csv(path)
    if fast is not None:
        header, num, colmap, rownums = fast
        return _assemble(path, header, colmap, rownums, num)
    if path.suffix.lower() == ".ecsv":
        return _assemble(path, *_read_ecsv(path))
    return _assemble(path, *_csv_columns(path))


def velocities_from_table(table: Any, source: Path) -> VelocityTable:
    """Validate an astropy ``Table`` with the columns of a velocity file (as
    :func:`read_velocities`; velocity columns with units are converted to km/s).

    Raises
    ------
    VelocityFileError
        As :func:`read_velocities`, naming ``source`` in place of a file.
    """
    return _assemble(source, *_table_columns(source, table))


def _assemble(
    path: Path,
    header: list[str],
    colmap: dict[str, list[object]],
    rownums: Sequence[int],
    num: dict[str, Any] | None = None,
) -> VelocityTable:
    """The checked :class:`VelocityTable` of parsed columns (``num``: already numeric)."""
    tcol, comps = _check_header(path, header)
    if num is None:
        if not rownums:
            raise VelocityFileError(f"{path}: no data rows; add one line per spectrum")
        num = {
            h: np.array(
                [_parse_float(path, r, h, x) for r, x in zip(rownums, colmap[h], strict=True)]
            )
            for h in header
            if h != "session"
        }
    _check_ranges(path, num, comps, rownums)
    jd = num[tcol] + _TIME_COLS[tcol]
    scale = "utc" if tcol.endswith("_utc") else "tdb"
    nan = np.full(jd.shape, np.nan)
    day = np.floor(jd)
    return VelocityTable(
        source=path,
        time=Time(day, jd - day, format="jd", scale=scale),
        window_s=num.get("exptime_s", num.get("window_s", nan)),
        lambda_k=num.get("lambda_k", nan),
        v=tuple(num[c] for c in comps),
        sigma=tuple(num[f"sigma_{c}"] for c in comps),
        session=_sessions(path, colmap, rownums, jd),
        u_star=num.get("u_star"),
        site_utc=scale == "utc",
        window_column=next(h for h in ("exptime_s", "window_s", "lambda_k") if h in num),
    )


def _fast_csv(
    path: Path,
) -> tuple[list[str], dict[str, F64], dict[str, list[object]], Sequence[int]] | None:
    """The columnar reading of a CSV (:func:`ucbplan.reduce.columnar.read_columns`), or None
    when the strict reader must read it."""
    from ucbplan.reduce.columnar import read_columns

    return read_columns(path, KNOWN_COLUMNS)


def _csv_columns(path: Path) -> tuple[list[str], dict[str, list[object]], list[int]]:
    """Header, cells per column and data-row numbers of a CSV (rows of the wrong width fail)."""
    header, body = _read_csv(path)
    colmap: dict[str, list[object]] = {h: [] for h in header}
    rownums = []
    for k, (line_no, cells) in enumerate(body, start=1):
        if len(cells) != len(header):
            raise _fail(
                path,
                f"row {k} (line {line_no})",
                f"has {len(cells)} fields, expected {len(header)} like the header",
            )
        for h, c in zip(header, cells, strict=True):
            colmap[h].append(c)
        rownums.append(k)
    return header, colmap, rownums


#: Accepted range of the window columns: (low, high, what the message asks for).
_WINDOW_RANGES = (
    ("exptime_s", 0.0, math.inf, "a window ≥ 0 s"),
    ("window_s", 0.0, math.inf, "a window ≥ 0 s"),
    ("lambda_k", 1e-6, 1.0, "Λ_K in (0, 1]"),
)


def _check_ranges(
    path: Path, num: dict[str, F64], comps: tuple[str, ...], rownums: Sequence[int]
) -> None:
    """Times in range, positive σ_v, |v| < c and windows in range; names the first bad row."""
    for h, (lo, hi) in _TIME_RANGE.items():
        if h in num:
            bad = np.flatnonzero((num[h] < lo) | (num[h] > hi))
            if bad.size:
                raise _fail(
                    path,
                    f"row {rownums[int(bad[0])]}, column {h!r}",
                    f"got {num[h][bad[0]]:.10g}, expected a date in [{lo:.10g}, {hi:.10g}] "
                    "(years 1858–2500); check the column's scale (JD vs MJD)",
                )
    for c in comps:
        bad = np.flatnonzero(~(num[f"sigma_{c}"] > 0))
        if bad.size:
            r = rownums[int(bad[0])]
            raise _fail(
                path,
                f"row {r}, column 'sigma_{c}'",
                f"got {num[f'sigma_{c}'][bad[0]]}, expected a positive 1σ in km/s",
            )
        for h in (c, f"sigma_{c}"):
            bad = np.flatnonzero(np.abs(num[h]) >= C_KM_S)
            if bad.size:
                raise _fail(
                    path,
                    f"row {rownums[int(bad[0])]}, column {h!r}",
                    f"got {num[h][bad[0]]:.6g}, expected less than the speed of light in km/s "
                    "(is the column in m/s?)",
                )
    for h, lo, hi, what in _WINDOW_RANGES:
        if h in num:
            bad = np.flatnonzero((num[h] < lo) | (num[h] > hi))
            if bad.size:
                raise _fail(
                    path,
                    f"row {rownums[int(bad[0])]}, column {h!r}",
                    f"got {num[h][bad[0]]}, expected {what}",
                )


def _sessions(
    path: Path, colmap: dict[str, list[object]], rownums: Sequence[int], jd: F64
) -> tuple[str, ...]:
    """Session labels from the column (non-empty) or from gaps in time (:func:`_auto_sessions`)."""
    if "session" not in colmap:
        return _auto_sessions(jd)
    sess = tuple(str(s).strip() for s in colmap["session"])
    empty = [r for r, s in zip(rownums, sess, strict=True) if not s]
    if empty:
        raise _fail(
            path, f"row {empty[0]}, column 'session'", "blank cell, expected a session label"
        )
    return sess


def _auto_sessions(jd: F64) -> tuple[str, ...]:
    """Label spectra by gaps > :data:`SESSION_GAP_S` in time order ("S1", "S2", …)."""
    order = np.argsort(jd, kind="stable")
    gaps = np.diff(jd[order]) * DAY_S > SESSION_GAP_S
    number = np.empty(jd.size, dtype=np.int64)
    number[order] = 1 + np.concatenate([[0], np.cumsum(gaps)])
    names = np.array([f"S{k}" for k in range(1, int(number.max(initial=1)) + 1)], dtype=object)
    return tuple(names[number - 1].tolist())  # one str object per session, gathered in C


def to_barycentric(table: VelocityTable, coord: SkyCoord, location: EarthLocation) -> VelocityTable:
    """Convert site-UTC mid-exposure times to barycentric TDB (no-op for barycentric tables).

    Notes
    -----
    t_bary = t.tdb + Δ(t), Δ the barycentric light travel time (astropy builtin ephemeris, within
    ~12 µs of DE421; docs/method.md "Barycentric and site time").
    """
    if not table.site_utc:
        return table
    from ucbplan.observing.observatory.barycentric import site_utc_to_bary_tdb

    bary = site_utc_to_bary_tdb(table.time, coord, location)
    return dataclasses.replace(table, time=Time(bary, scale="tdb"), site_utc=False)


def _seconds_since(time: Time, t_ref: Time) -> F64:
    """``(time - t_ref).to_value("s")`` as float64, chunk by chunk: astropy's arithmetic is
    elementwise, so the same doubles, with its temporaries in cache instead of ~20 fresh arrays
    of the table's length."""
    if time.ndim != 1:
        return np.asarray((time - t_ref).to_value("s"), dtype=np.float64)
    out = np.empty(time.shape)
    for sl in row_chunks(out.size):
        out[sl] = (time[sl] - t_ref).to_value("s")
    return out


def check_validity(table: VelocityTable, target: Target) -> F64:
    """Seconds since ``target.t_ref`` of each spectrum, after checking the validity window.

    Raises
    ------
    VelocityFileError
        UTC site times that were not converted (give ``--site``); a time before the LISA start
        or more than :data:`HORIZON_S` after its end, or, for a timing ephemeris, more than
        :data:`HORIZON_S` from T0 on either side (names the first offending row).
    """
    if table.site_utc:
        raise VelocityFileError(
            f"{table.source}: times are UTC at the telescope (jd_utc/mjd_utc); give the site with "
            "`site` NAME so they can be converted to barycentric TDB"
        )
    tau = _seconds_since(table.time, target.t_ref)
    timing = getattr(target, "kind", "lisa") == "timing"
    # a timing ephemeris holds on both sides of T0; a LISA posterior from the mission start on
    lo = -HORIZON_S if timing else -0.5 * target.t_obs_s
    hi = 0.5 * target.t_obs_s + HORIZON_S
    bad = np.flatnonzero((tau < lo) | (tau > hi))
    if bad.size:
        i = int(bad[0])
        if timing:
            when = "more than 20 yr from the ephemeris epoch T0"
            span = f"T0 = {target.t_ref.tdb.isot} TDB"
        else:
            when = (
                "before the LISA observation start"
                if tau[i] < lo
                else "more than 20 yr after the LISA observation end"
            )
            span = f"{target.t_start.isot} – {target.t_end.isot} TDB"
        raise VelocityFileError(
            f"{table.source}: row {i + 1}: time {table.time[i].tdb.isot} TDB is {when} "
            f"({span}); check the time column and scale"
        )
    return tau
