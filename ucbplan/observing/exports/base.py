"""What every export format shares: options, result, column access, text formats, time windows.

Every time written is UTC at the site (from the ``t_*_utc`` columns) and carries its 1σ
uncertainty ``sigma_t_s`` (docs/exports.md). Column names are those declared by
:mod:`ucbplan.observing.blocktable`; the accessors here refuse any other name except the few
optional inputs a user may add by hand (:data:`USER_COLUMNS`), so a renamed schema column fails
loudly instead of silently reading a default.

Missing optional columns get documented defaults, each reported once in ``ExportResult.notes``:
no ``acq_s`` column → the plan's ``meta['overhead_s']``, else :data:`DEFAULT_ACQUISITION_S` (or
``--acquisition``); no ``vmag`` → the target file named in ``meta['targets']``; no ``period_s`` →
P_b ≈ 4 |t_alt − t_mid| (the φ_ref π-mode alternative epoch lies a quarter orbit away); no
``readout_s`` → the dead time inside the block, (t_end − t_start) − n_exp·exptime.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from datetime import UTC, datetime, timedelta
from pathlib import Path
from typing import Any

import numpy as np
from astropy.coordinates import Angle
from astropy.table import Table
from astropy.time import Time

from ucbplan.errors import InputFileError, UcbplanError
from ucbplan.observing.blocktable import EXTRA_COLUMNS, REQUIRED_COLUMNS
from ucbplan.observing.timeconv import quiet_erfa
from ucbplan.target import load_target

__all__ = [
    "DEFAULT_ACQUISITION_S",
    "USER_COLUMNS",
    "ExportOptions",
    "ExportResult",
    "Exporter",
    "ObStartWindow",
    "acquisition_s",
    "coordinates",
    "created_utc",
    "floats",
    "fmt_sigma",
    "has_column",
    "iso_minute",
    "iso_ms",
    "ob_start_window",
    "parse_utc",
    "period_s",
    "readout_total_s",
    "required_times",
    "safe_name",
    "sexagesimal",
    "site_name",
    "strings",
    "time_order",
    "times_utc",
    "version",
    "vmags",
]

#: Acquisition overhead assumed when neither ``--acquisition`` nor an ``acq_s`` column is given [s]
#: (a typical VLT/Keck slit acquisition of a faint target: pointing, acquisition image, centring).
DEFAULT_ACQUISITION_S = 600.0

#: Optional columns the planner does not write but the exports read when a user adds them:
#: ``vmag`` [mag], ``acq_s`` (acquisition overhead per block) [s], ``tol_rad`` (phase tolerance).
USER_COLUMNS = ("vmag", "acq_s", "tol_rad")

_KNOWN_COLUMNS = frozenset((*REQUIRED_COLUMNS, *EXTRA_COLUMNS, *USER_COLUMNS))


@dataclass(frozen=True, slots=True)
class ExportOptions:
    """Knobs shared by the export formats.

    Attributes
    ----------
    acquisition_s : float or None
        Acquisition overhead before the first exposure [s]; None → ``acq_s`` column, else the
        plan's ``meta['overhead_s']``, else :data:`DEFAULT_ACQUISITION_S`.
    tolerance_sigma : float
        Window half-width in units of σ_t (k in k·σ_t).
    tolerance_floor_s : float
        Smallest window half-width [s] (an operator cannot start an OB to better than this).
    rounding_warn_fraction : float
        Warn when minute rounding widens an ESO window by more than this fraction of P_b.
    merge_overlaps : bool
        Merge overlapping ESO windows of one target into one OB instead of raising.
    proposal_format : str
        ``ecsv``, ``csv`` or ``latex`` for the proposal table.
    keck_rotmode : str
        Keck ``rotmode=`` value (``vertical`` = parallactic slit, right for spectroscopy).
    """

    acquisition_s: float | None = None
    tolerance_sigma: float = 3.0
    tolerance_floor_s: float = 10.0
    rounding_warn_fraction: float = 0.1
    merge_overlaps: bool = False
    proposal_format: str = "ecsv"
    keck_rotmode: str = "vertical"


@dataclass(frozen=True, slots=True)
class ExportResult:
    """Bytes to write plus notes for the user (defaults taken, rounding warnings)."""

    content: bytes
    suffix: str
    notes: tuple[str, ...] = field(default_factory=tuple)


#: One export format: ``(blocks table, options) -> ExportResult``.
Exporter = Callable[[Table, ExportOptions], ExportResult]


# --------------------------------------------------------------------------------------------
# Column access, robust to missing optional columns
# --------------------------------------------------------------------------------------------


def _declared(column: str) -> str:
    """``column`` if the blocks-table schema (or :data:`USER_COLUMNS`) declares it."""
    if column not in _KNOWN_COLUMNS:
        raise LookupError(
            f"exports read column {column!r}, which ucbplan.observing.blocktable does not declare"
        )
    return column


def has_column(table: Table, column: str) -> bool:
    """Whether ``table`` has the declared blocks-table column ``column``."""
    return _declared(column) in table.colnames


def parse_utc(text: str, column: str, row: int) -> datetime:
    """UTC datetime of an ISO text (naive = UTC); ``column``/``row`` name it in the error."""
    try:
        value = datetime.fromisoformat(text.strip())
    except ValueError as exc:
        raise InputFileError(
            f"blocks table: column {column} row {row}: got {text!r}, expected ISO UTC "
            "like 2037-01-15T01:02:03.400; regenerate the table with `ucbplan plan`"
        ) from exc
    return value.replace(tzinfo=UTC) if value.tzinfo is None else value.astimezone(UTC)


def _time_texts(table: Table, column: str) -> list[str]:
    col = table[column]
    if isinstance(col, Time):
        with quiet_erfa():  # future dates: ERFA's "dubious year" is about leap seconds only
            return list(np.atleast_1d(col.utc.isot))
    return [str(v) if v is not np.ma.masked else "" for v in col]


def times_utc(table: Table, column: str, required: bool = True) -> list[datetime | None]:
    """UTC datetimes (µs resolution) of an ISO string or astropy Time column; None for blanks."""
    if not has_column(table, column):
        if required:
            raise InputFileError(f"blocks table lacks column {column}; regenerate it")
        return [None] * len(table)
    out: list[datetime | None] = []
    for i, text in enumerate(_time_texts(table, column)):
        if not text or text in ("--", "nan", "None"):
            if required:
                raise InputFileError(f"blocks table: column {column} row {i}: empty time")
            out.append(None)
        else:
            out.append(parse_utc(text, column, i))
    return out


def required_times(table: Table, column: str) -> list[datetime]:
    """Like :func:`times_utc` for a required column: every row must hold a time."""
    return [t for t in times_utc(table, column) if t is not None]


def floats(table: Table, column: str, default: float | None = None, unit: str = "") -> np.ndarray:
    """Column as float64 (in ``unit`` if the column has one); ``default`` when it is missing."""
    if not has_column(table, column):
        if default is None:
            raise InputFileError(f"blocks table lacks column {column}; regenerate it")
        return np.full(len(table), float(default))
    col = table[column]
    if unit and getattr(col, "unit", None) is not None:
        values = col.quantity.to_value(unit)
    else:
        values = np.ma.filled(np.ma.asarray(col, dtype=float), np.nan)
    return np.asarray(values, dtype=float)


def strings(table: Table, column: str, default: str = "") -> list[str]:
    """Column as str (masked → ``default``); all ``default`` when missing."""
    if not has_column(table, column):
        return [default] * len(table)
    return [default if v is np.ma.masked else str(v) for v in table[column]]


def time_order(table: Table) -> list[int]:
    """Row indices sorted by ``t_mid_utc`` (ties keep table order)."""
    mids = required_times(table, "t_mid_utc")
    return sorted(range(len(table)), key=lambda i: (mids[i], i))


# --------------------------------------------------------------------------------------------
# Text formats
# --------------------------------------------------------------------------------------------


def iso_minute(t: datetime) -> str:
    """``YYYY-MM-DDTHH:MM`` (UTC)."""
    return t.strftime("%Y-%m-%dT%H:%M")


def iso_ms(t: datetime, decimals: int = 3) -> str:
    """``YYYY-MM-DDTHH:MM:SS.sss`` (UTC) rounded to ``decimals`` ≤ 6 digits of the second."""
    step = 10 ** (6 - decimals)
    micro = t.microsecond + t.second * 1_000_000
    rounded = (micro + step // 2) // step * step  # half up
    t = t.replace(second=0, microsecond=0) + timedelta(microseconds=rounded)
    text = t.strftime("%Y-%m-%dT%H:%M:%S")
    if decimals > 0:
        text += f".{t.microsecond:06d}"[: decimals + 1]
    return text


def sexagesimal(value: float, decimals: int, sep: str, signed: bool, width: int = 2) -> str:
    """Sexagesimal string with correct carry (never ``60.00``) and ``-00`` for small negatives.

    ``value`` is in hours (RA) or degrees (Dec).
    """
    scale = 10**decimals
    total = round(abs(value) * 3600.0 * scale)
    if not signed:
        total %= 24 * 3600 * scale  # RA: 23 59 59.999 rounds to 00 00 00.00, not 24
    sign = "-" if (value < 0 and total > 0) else "+"
    whole, frac = divmod(total, scale)
    minutes_total, seconds = divmod(whole, 60)
    units, minutes = divmod(minutes_total, 60)
    sec = f"{seconds:02d}" + (f".{frac:0{decimals}d}" if decimals else "")
    head = f"{units:0{width}d}"
    return (sign if signed else "") + sep.join([head, f"{minutes:02d}", sec])


def safe_name(name: str, max_len: int | None = None) -> str:
    """Spaces → underscores (optionally truncated), for catalogue and OB names."""
    text = "_".join(name.split())
    return text[:max_len] if max_len else text


def fmt_sigma(sigma_s: float) -> str:
    """σ with two significant figures (``0.6``, ``0.63``, ``12``) [s]."""
    if not math.isfinite(sigma_s):
        return "nan"
    return f"{sigma_s:.0f}" if sigma_s >= 10 else f"{sigma_s:.2g}"


# --------------------------------------------------------------------------------------------
# Derived per-row quantities with documented defaults
# --------------------------------------------------------------------------------------------


def coordinates(table: Table) -> tuple[np.ndarray, np.ndarray]:
    """ICRS RA, Dec [deg] from ``ra_deg``/``dec_deg`` or the sexagesimal ``ra_hms``/``dec_dms``."""
    if has_column(table, "ra_deg") and has_column(table, "dec_deg"):
        return floats(table, "ra_deg", unit="deg"), floats(table, "dec_deg", unit="deg")
    if has_column(table, "ra_hms") and has_column(table, "dec_dms"):
        ra = Angle(strings(table, "ra_hms"), unit="hourangle").deg
        dec = Angle(strings(table, "dec_dms"), unit="deg").deg
        return np.asarray(ra, dtype=float), np.asarray(dec, dtype=float)
    raise InputFileError(
        "blocks table has neither ra_deg/dec_deg nor ra_hms/dec_dms columns; regenerate it with "
        "`ucbplan plan`"
    )


def period_s(table: Table, notes: list[str]) -> np.ndarray:
    """Orbital period per row [s]: ``period_s`` column, else 4 |t_alt − t_mid|, else NaN."""
    if has_column(table, "period_s"):
        values = floats(table, "period_s", unit="s")
        if np.all(np.isfinite(values)):
            return values
    mids = required_times(table, "t_mid_utc")
    alts = times_utc(table, "t_alt_utc", required=False)
    out = np.array(
        [
            4.0 * abs((a - m).total_seconds()) if a is not None else math.nan
            for a, m in zip(alts, mids, strict=True)
        ]
    )
    notes.append("no period_s column: P_b estimated as 4|t_alt_utc - t_mid_utc|")
    return out


def acquisition_s(table: Table, options: ExportOptions, notes: list[str]) -> np.ndarray:
    """Acquisition overhead per row [s]: option, else ``acq_s`` column, else the default."""
    if options.acquisition_s is not None:
        return np.full(len(table), float(options.acquisition_s))
    if has_column(table, "acq_s"):
        return floats(table, "acq_s", unit="s")
    planned = (table.meta or {}).get("overhead_s")
    if isinstance(planned, int | float) and math.isfinite(planned) and planned >= 0:
        notes.append(
            f"acquisition overhead {float(planned):.0f} s from the plan's overhead_s (the time "
            "`ucbplan plan` reserved before each session); pass --acquisition S to change it"
        )
        return np.full(len(table), float(planned))
    notes.append(
        f"no acq_s column: assuming {DEFAULT_ACQUISITION_S:.0f} s acquisition overhead; "
        "pass --acquisition S with your instrument's value"
    )
    return np.full(len(table), DEFAULT_ACQUISITION_S)


def readout_total_s(table: Table, notes: list[str]) -> np.ndarray:
    """Dead time inside each block [s]: n_exp·readout_s, else (t_end − t_start) − n_exp·exptime."""
    n_exp = floats(table, "n_exp")
    if has_column(table, "readout_s"):
        return n_exp * floats(table, "readout_s", unit="s")
    starts = required_times(table, "t_start_utc")
    ends = required_times(table, "t_end_utc")
    width = np.array([(e - s).total_seconds() for s, e in zip(starts, ends, strict=True)])
    notes.append("no readout_s column: readout taken as block width minus exposure time")
    return np.maximum(width - n_exp * floats(table, "exptime_s", unit="s"), 0.0)


def _file_vmag(entry: dict[str, Any]) -> float | None:
    """``vmag`` of the target file named in the table's provenance, if it is still readable."""
    path = entry.get("file")
    if not path:
        return None
    try:
        digest = hashlib.sha256(Path(str(path)).read_bytes()).hexdigest()
        if entry.get("sha256") and digest != entry["sha256"]:
            return None  # the file changed since planning: do not trust it
        return load_target(str(path)).vmag
    except (UcbplanError, OSError):
        return None


def vmags(table: Table) -> np.ndarray:
    """V magnitude per row: ``vmag`` column, else ``meta['targets'][*]`` (its ``vmag`` or the
    ``vmag`` of the target file it names), else NaN."""
    out = floats(table, "vmag", default=math.nan)
    if np.all(np.isfinite(out)):
        return out
    items = table.meta.get("targets", []) if table.meta else []
    by_name = {
        str(t.get("name")): t.get("vmag") if t.get("vmag") is not None else _file_vmag(t)
        for t in items
        if isinstance(t, dict)
    }
    for i, name in enumerate(strings(table, "target")):
        value = by_name.get(name)
        if not math.isfinite(out[i]) and value is not None:
            out[i] = float(value)
    return out


# --------------------------------------------------------------------------------------------
# Provenance
# --------------------------------------------------------------------------------------------


def created_utc(table: Table) -> str:
    """The table's ``meta['created_utc']`` ('' when absent)."""
    return str(table.meta.get("created_utc", "")) if table.meta else ""


def site_name(table: Table) -> str:
    """The observing site's name from the table ``meta`` ('unknown site' when absent)."""
    site = table.meta.get("site") if table.meta else None
    if isinstance(site, dict):
        return str(site.get("name", "unknown site"))
    return str(site) if site else "unknown site"


def version() -> str:
    """The ucbplan version written into every export."""
    from ucbplan import __version__

    return __version__


# --------------------------------------------------------------------------------------------
# Time window on the OB start (ESO p2, LCO)
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class ObStartWindow:
    """Window on an observation's start: the block start minus the acquisition, ± half-width.

    Attributes
    ----------
    ob_start : datetime
        Nominal OB start, t_start − acquisition (UTC).
    half_width_s : float
        max(k·σ_t, floor) [s].
    lo, hi : datetime
        ob_start ∓ half_width (UTC, µs resolution, not rounded).
    """

    ob_start: datetime
    half_width_s: float
    lo: datetime
    hi: datetime


def ob_start_window(
    start: datetime, acquisition: float, sigma_s: float, options: ExportOptions
) -> ObStartWindow:
    """Window on the OB start of a block starting at ``start`` (UTC).

    Parameters
    ----------
    start : datetime
        Block start (first exposure starts), UTC.
    acquisition : float
        Acquisition overhead before the first exposure [s].
    sigma_s : float
        1σ timing uncertainty of the block [s].
    options : ExportOptions
        ``tolerance_sigma`` (k) and ``tolerance_floor_s`` of the half-width max(k·σ_t, floor).
    """
    half = max(options.tolerance_sigma * sigma_s, options.tolerance_floor_s)
    ob_start = start - timedelta(seconds=acquisition)
    return ObStartWindow(
        ob_start=ob_start,
        half_width_s=half,
        lo=ob_start - timedelta(seconds=half),
        hi=ob_start + timedelta(seconds=half),
    )
