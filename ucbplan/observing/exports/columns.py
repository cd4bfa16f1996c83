"""Reading a blocks table for the exports: declared columns only, times, numbers, defaults.

Every time written is UTC at the site (from the ``t_*_utc`` columns) and carries its 1σ
uncertainty ``sigma_t_s`` (docs/exports.md). Column names are those declared by
:mod:`ucbplan.observing.blocks.schema`; the accessors here refuse any other name except the few
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
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np
from astropy.coordinates import Angle
from astropy.table import Table
from astropy.time import Time

from ucbplan.errors import InputFileError, UcbplanError, shorten
from ucbplan.inputs import MAX_YAML_BYTES, is_number, load_yaml
from ucbplan.observing.blocks.block import MAX_BLOCK_S
from ucbplan.observing.blocks.schema import EXTRA_COLUMNS, REQUIRED_COLUMNS
from ucbplan.observing.blocks.schema import USER_COLUMNS as USER_COLUMN_DECLS
from ucbplan.observing.exports.interface import DEFAULT_ACQUISITION_S, ExportOptions
from ucbplan.observing.exports.provenance import meta
from ucbplan.targets import target_from_dict

#: Optional columns the planner does not write but the exports read when a user adds them:
#: ``vmag`` [mag], ``acq_s`` (acquisition overhead per block) [s], ``tol_rad`` (phase tolerance);
#: declared (type, unit, range) in :data:`ucbplan.observing.blocks.schema.USER_COLUMNS`.
USER_COLUMNS = tuple(c.name for c in USER_COLUMN_DECLS)

_KNOWN_COLUMNS = frozenset((*REQUIRED_COLUMNS, *EXTRA_COLUMNS, *USER_COLUMNS))

# --------------------------------------------------------------------------------------------
# Column access, robust to missing optional columns
# --------------------------------------------------------------------------------------------


def _declared(column: str) -> str:
    """``column`` if the blocks-table schema (or :data:`USER_COLUMNS`) declares it."""
    if column not in _KNOWN_COLUMNS:
        raise LookupError(
            f"exports read column {column!r}, which ucbplan.observing.blocks.schema does not "
            "declare"
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
