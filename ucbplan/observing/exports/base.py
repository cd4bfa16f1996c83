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
import os
import stat
import unicodedata
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from datetime import UTC, datetime, timedelta
from pathlib import Path
from typing import Any

import numpy as np
from astropy.coordinates import Angle
from astropy.table import Table
from astropy.time import Time

from ucbplan.errors import InputError, InputFileError, UcbplanError, shorten
from ucbplan.inputs import MAX_YAML_BYTES, check_range, is_number, load_yaml
from ucbplan.observing.blocks import MAX_BLOCK_S
from ucbplan.observing.blocktable import EXTRA_COLUMNS, REQUIRED_COLUMNS
from ucbplan.observing.blocktable import USER_COLUMNS as USER_COLUMN_DECLS
from ucbplan.observing.semesters import semester_dates
from ucbplan.observing.timeconv import quiet_erfa
from ucbplan.target import target_from_dict

__all__ = [
    "DEFAULT_ACQUISITION_S",
    "KECK_ROTMODES",
    "MAX_TOLERANCE_SIGMA",
    "USER_COLUMNS",
    "ExportOptions",
    "ExportResult",
    "Exporter",
    "ObStartWindow",
    "acquisition_s",
    "ascii_name",
    "ascii_names",
    "ascii_text",
    "clean_meta",
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

#: Largest window half-width in units of σ_t.
MAX_TOLERANCE_SIGMA = 100.0
#: Rotator modes a Keck starlist takes (``rotmode=``; ``vertical`` keeps the slit parallactic).
KECK_ROTMODES = ("pa", "vertical", "stationary")

#: Optional columns the planner does not write but the exports read when a user adds them:
#: ``vmag`` [mag], ``acq_s`` (acquisition overhead per block) [s], ``tol_rad`` (phase tolerance);
#: declared (type, unit, range) in :data:`ucbplan.observing.blocktable.USER_COLUMNS`.
USER_COLUMNS = tuple(c.name for c in USER_COLUMN_DECLS)

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
    force : bool
        Write a format even when the plan's site is not one of its observatory's sites.
    semester : str or None
        Proposal semester ``2041A``/``2041B`` or ESO period ``P147``; None = the one containing
        the plan.
    seeing_arcsec : float
        Seeing limit of the ESO constraint set [arcsec].
    instrument : str or None
        Instrument configuration (``ucbplan instruments``) whose readout mode and overheads go
        into the ESO OB templates; None = the exposure numbers of the plan only.
    eso_templates : str or None
        YAML file naming the ESO p2 acquisition and science templates and their keywords.
    """

    acquisition_s: float | None = None
    tolerance_sigma: float = 3.0
    tolerance_floor_s: float = 10.0
    rounding_warn_fraction: float = 0.1
    merge_overlaps: bool = False
    proposal_format: str = "ecsv"
    keck_rotmode: str = "vertical"
    force: bool = False
    semester: str | None = None
    seeing_arcsec: float = 1.0
    instrument: str | None = None
    eso_templates: str | None = None

    def __post_init__(self) -> None:
        why = "acquisition before the first exposure; a block must fit in one night"
        if self.acquisition_s is not None:
            check_range("--acquisition", self.acquisition_s, 0.0, MAX_BLOCK_S, "s", why)
        why = "window half-width in units of the block's 1-sigma timing error"
        check_range("--tolerance-sigma", self.tolerance_sigma, 0.0, MAX_TOLERANCE_SIGMA, "", why)
        why = "smallest window half-width; a day at most"
        check_range("--tolerance-floor", self.tolerance_floor_s, 0.0, 86400.0, "s", why)
        check_range("rounding_warn_fraction", self.rounding_warn_fraction, 0.0, 1.0)
        why = "seeing limit of the ESO constraint set"
        check_range("--seeing", self.seeing_arcsec, 0.0, 5.0, "arcsec", why, low_open=True)
        if self.semester is not None:
            semester_dates(self.semester)  # refuses anything but 2041A, 2041B, P147
        if not isinstance(self.keck_rotmode, str) or self.keck_rotmode not in KECK_ROTMODES:
            raise InputError(
                f"--rotmode: expected {', '.join(KECK_ROTMODES)} (Keck starlist rotator "
                f"modes), got {shorten(self.keck_rotmode, 40)}"
            )


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
    """Spaces → underscores, control characters dropped (optionally truncated), for catalogue
    and OB names."""
    text = "_".join("".join(ch for ch in name if ch.isprintable() or ch.isspace()).split())
    return text[:max_len] if max_len else text


#: Dash-like characters written as ``-`` in ASCII names (hyphens, en/em dashes, minus signs).
_DASHES = dict.fromkeys(
    map(ord, "\u2010\u2011\u2012\u2013\u2014\u2015\u2212\ufe58\ufe63\uff0d"), "-"
)
#: Letters NFKD does not decompose, spelled in ASCII.
_LETTERS = str.maketrans(
    {
        "ß": "ss",
        "æ": "ae",
        "Æ": "AE",
        "œ": "oe",
        "Œ": "OE",
        "ø": "o",
        "Ø": "O",
        "đ": "d",
        "Đ": "D",
        "ł": "l",
        "Ł": "L",
        "þ": "th",
        "Þ": "Th",
        "ı": "i",
        "ð": "d",
        "Ð": "D",
    }
)


def ascii_name(name: str) -> str:
    """``name`` in printable ASCII: dashes → ``-``, accents dropped (Unicode NFKD), a few
    letters spelled out (ß → ss, ø → o), any other non-ASCII character → ``_``; control
    characters dropped."""
    text = unicodedata.normalize("NFKD", name.translate(_DASHES).translate(_LETTERS))
    text = "".join(ch for ch in text if not unicodedata.combining(ch))
    text = "".join(ch if ch.isascii() else "_" for ch in text.translate(_DASHES))
    return "".join(ch for ch in text if ch.isprintable() or ch.isspace())


def ascii_text(text: str) -> str:
    """Free text (a site name, an anchor) as one line of printable ASCII (see
    :func:`ascii_name`)."""
    return " ".join(ascii_name(text).split())


def ascii_names(
    names: list[str],
    fmt: str,
    notes: list[str],
    max_len: int | None = None,
    drop: str = "",
    what: str = "target",
) -> dict[str, str]:
    """The ASCII catalogue name of each distinct target name for a format that takes ASCII only.

    Names are transliterated (:func:`ascii_name`, with a note), characters in ``drop`` become
    ``_``, white space ``_`` (:func:`safe_name`) and names are cut to ``max_len`` (with a note).

    Raises
    ------
    InputFileError
        A name without any ASCII letter or digit, or two names that become the same (both named).
    """
    out: dict[str, str] = {}
    owner: dict[str, str] = {}
    for name in dict.fromkeys(names):
        text = ascii_name(name)
        for ch in drop:
            text = text.replace(ch, "_")
        text = safe_name(text)
        if not any(ch.isalnum() for ch in text):
            raise InputFileError(
                f"{fmt}: {what} {shorten(name, 60)} has no ASCII spelling ({fmt} takes ASCII "
                "names only); give it an ASCII name in its target file"
            )
        if text != safe_name(name):
            notes.append(f"{fmt}: {what} {shorten(name, 60)} written as {text!r} (ASCII only)")
        if max_len and len(text) > max_len:
            notes.append(f"{fmt}: name {shorten(text, 60)} truncated to {max_len} characters")
            text = text[:max_len]
        if owner.setdefault(text, name) != name:
            raise InputFileError(
                f"{fmt}: {what}s {shorten(owner[text], 60)} and {shorten(name, 60)} both become "
                f"{text!r}"
                + (f" ({max_len}-character limit)" if max_len else "")
                + "; rename one in its target file"
            )
        out[name] = text
    return out


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
    """Orbital period per row [s]: ``period_s``, else (empty cells, no column) 4 |t_alt − t_mid|
    to a few ms (the times are written to 1 ms), else NaN."""
    given = has_column(table, "period_s")
    values = floats(table, "period_s", unit="s") if given else np.full(len(table), math.nan)
    empty = ~np.isfinite(values)
    if not np.any(empty):
        return values
    mids = required_times(table, "t_mid_utc")
    alts = times_utc(table, "t_alt_utc", required=False)
    estimate = np.array(
        [
            4.0 * abs((a - m).total_seconds()) if a is not None else math.nan
            for a, m in zip(alts, mids, strict=True)
        ]
    )
    what = (
        f"period_s empty in {int(empty.sum())} of {len(table)} rows"
        if given
        else "no period_s column"
    )
    notes.append(f"{what}: P_b estimated as 4|t_alt_utc - t_mid_utc| (to a few ms)")
    return np.where(empty, estimate, values)


def acquisition_s(table: Table, options: ExportOptions, notes: list[str]) -> np.ndarray:
    """Acquisition overhead per row [s]: option, else ``acq_s`` column, else the default."""
    if options.acquisition_s is not None:
        return np.full(len(table), float(options.acquisition_s))
    if has_column(table, "acq_s"):
        return floats(table, "acq_s", unit="s")
    value = meta(table).get("overhead_s")
    planned = float(value) if is_number(value) else math.nan
    if 0 <= planned <= MAX_BLOCK_S:
        notes.append(
            f"acquisition overhead {planned:.0f} s from the plan's overhead_s (the time "
            "`ucbplan plan` reserved before each session); pass --acquisition S to change it"
        )
        return np.full(len(table), planned)
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


def _regular_file_bytes(path: Path, limit: int) -> bytes:
    """The bytes of ``path`` if it is a regular file of at most ``limit`` bytes.

    Opened without blocking and checked on the open descriptor, so a FIFO, a device or a folder
    named in a table's provenance is refused at once instead of hanging the export.

    Raises
    ------
    OSError
        Not a regular file, too large, or unreadable (``strerror`` says which).
    """
    fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise OSError(0, "not a regular file")
        if info.st_size > limit:
            raise OSError(0, f"larger than {limit} bytes")
        with os.fdopen(os.dup(fd), "rb") as handle:
            data = handle.read(limit + 1)
        if len(data) > limit:
            raise OSError(0, f"larger than {limit} bytes")
        return data
    finally:
        os.close(fd)


def _file_vmag(entry: dict[str, Any]) -> tuple[float | None, str | None]:
    """``vmag`` of the target file named in the table's provenance, and a note when the file
    cannot be used (missing, not a regular file, changed since planning, not a target file)."""
    path = entry.get("file")
    if not path:
        return None, None
    if not isinstance(path, str) or len(path) > 4096 or "\x00" in path:
        return None, f"target file {shorten(path, 80)} in the table's provenance is not a path"
    label = shorten(path, 120)
    try:
        data = _regular_file_bytes(Path(path), MAX_YAML_BYTES)
    except (OSError, ValueError) as exc:
        why = exc.strerror if isinstance(exc, OSError) and exc.strerror else "cannot be read"
        return None, f"target file {label} ({why}): its magnitude is not read"
    digest = hashlib.sha256(data).hexdigest()
    if entry.get("sha256") and digest != entry["sha256"]:
        return (
            None,
            f"target file {label} changed since planning (SHA-256 differs): its magnitude is "
            "not read",
        )
    try:
        doc = load_yaml(Path(path), "target file", text=data.decode("utf-8-sig"))
        return target_from_dict(doc, Path(path)).vmag, None
    except (UcbplanError, UnicodeDecodeError, RecursionError, ValueError, TypeError):
        return None, f"target file {label} is not a valid target file: its magnitude is not read"


def _meta_vmag(entry: dict[str, Any], notes: list[str]) -> float | None:
    """The magnitude of one ``meta['targets']`` entry: its ``vmag``, else its target file's."""
    value = entry.get("vmag")
    if value is not None:
        if is_number(value) and -30.0 <= float(value) <= 40.0:
            return float(value)
        notes.append(
            f"meta targets: vmag {shorten(value, 40)} of {shorten(entry.get('name'), 60)} is "
            "not a magnitude: ignored"
        )
        return None
    vmag, note = _file_vmag(entry)
    if note:
        notes.append(note)
    return vmag


def vmags(table: Table, notes: list[str] | None = None) -> np.ndarray:
    """V magnitude per row: ``vmag`` column, else ``meta['targets'][*]`` (its ``vmag`` or the
    ``vmag`` of the target file it names, read only if it is a regular file whose SHA-256 still
    matches), else NaN. Why a file could not be used goes to ``notes``."""
    out = floats(table, "vmag", default=math.nan)
    if np.all(np.isfinite(out)):
        return out
    items = meta(table).get("targets", [])
    items = items if isinstance(items, list) else []
    wanted = {n for n, v in zip(strings(table, "target"), out, strict=True) if not math.isfinite(v)}
    found = notes if notes is not None else []
    by_name: dict[str, float | None] = {}
    for t in items:
        if (
            isinstance(t, dict)
            and str(t.get("name")) in wanted
            and str(t.get("name")) not in by_name
        ):
            by_name[str(t.get("name"))] = _meta_vmag(t, found)
    for i, name in enumerate(strings(table, "target")):
        value = by_name.get(name)
        if not math.isfinite(out[i]) and value is not None:
            out[i] = float(value)
    return out


# --------------------------------------------------------------------------------------------
# Provenance
# --------------------------------------------------------------------------------------------


def meta(table: Table) -> dict[str, Any]:
    """The table's ``meta`` as a dict (empty when absent or not a mapping)."""
    return dict(table.meta) if isinstance(table.meta, Mapping) else {}


def _meta_text(value: Any, default: str) -> str:
    """A provenance value as one short line of text (``default`` unless it is a plain value)."""
    if isinstance(value, str | int | float) and not isinstance(value, bool):
        text = " ".join(_utf8(str(value)).split())
        return text[:200] if text else default
    return default


def _utf8(text: str) -> str:
    """``text`` without lone surrogates (a YAML ``"\\ud800"`` escape cannot be written)."""
    return text.encode("utf-8", "replace").decode("utf-8")


def clean_meta(value: Any, budget: list[int] | None = None, depth: int = 0) -> Any:
    """A copy of provenance metadata that can be written again: plain dicts, lists, numbers and
    UTF-8 strings, at most 8 levels deep and 10 000 values in all (shared references, as a YAML
    alias makes them, cannot expand without limit). A table's own metadata comes back equal."""
    budget = [10_000] if budget is None else budget
    budget[0] -= 1
    if depth > 8 or budget[0] < 0:
        return "..."
    if isinstance(value, Mapping):
        return {_utf8(str(k)): clean_meta(v, budget, depth + 1) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [clean_meta(v, budget, depth + 1) for v in value]
    if isinstance(value, str):
        return _utf8(value)
    if value is None or isinstance(value, bool | int | float):
        return value
    return _utf8(str(value))


def created_utc(table: Table) -> str:
    """The table's ``meta['created_utc']`` ('' when absent)."""
    return _meta_text(meta(table).get("created_utc"), "")


def site_name(table: Table) -> str:
    """The observing site's name from the table ``meta`` ('unknown site' when absent)."""
    site = meta(table).get("site")
    if isinstance(site, Mapping):
        return _meta_text(site.get("name"), "unknown site")
    return _meta_text(site, "unknown site")


def version() -> str:
    """The ucbplan version written into every export."""
    from ucbplan._version import __version__

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
