"""The master blocks table: the single source every export (p2, starlist, ICS, proposal) reads.

:data:`COLUMNS` declares the table once — name, type, unit, description, required — and the
writer (:func:`blocks_to_table`), the reader (:func:`read_blocks`), :data:`REQUIRED_COLUMNS` /
:data:`EXTRA_COLUMNS` and the block-table reference (:func:`column_reference`) derive from it.

Times are written as ISO-8601 strings (``YYYY-MM-DDTHH:MM:SS.sss``) so that ECSV, CSV and JSON
carry exactly the same text: ``t_*_utc`` columns are UTC at the site with millisecond precision,
``t_mid_tdb_bary`` is the barycentric TDB epoch with microsecond precision. Provenance (ucbplan
version, target files and their SHA-256, site, time base, phase convention, constraints) lives in
the table ``meta`` and is preserved by ECSV.
"""

from __future__ import annotations

import copy
import csv
import functools
import hashlib
import io
import itertools
import json
import math
import operator
import os
import threading
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from datetime import UTC, datetime, timedelta, timezone
from pathlib import Path
from typing import IO, Any
from zoneinfo import ZoneInfo

import erfa
import numpy as np
import yaml
from astropy import units as u
from astropy.coordinates import Angle
from astropy.table import Column as TableColumn
from astropy.table import Table
from astropy.time import Time

from ucbplan.errors import InputError, InputFileError, shorten
from ucbplan.inputs import MAX_ALIASES, read_text
from ucbplan.io import dump_json, dumps_json
from ucbplan.observing.blockcolumns import (
    BlockColumns,
    block_columns,
    isot_array,
    jd_parts,
    time_array,
)
from ucbplan.observing.blocks import MAX_BLOCK_S, MAX_N_EXP, MAX_READOUT_S, Block
from ucbplan.observing.tablewrite import (
    ecsv_data_lines,
    json_records_text,
    json_rows_text,
    yaml_flow_items,
)
from ucbplan.observing.timeconv import quiet_erfa
from ucbplan.target.values import one_line

__all__ = [
    "BLANK_OK",
    "COLUMNS",
    "COLUMN_BY_NAME",
    "EXTRA_COLUMNS",
    "KNOWN_COLUMNS",
    "MAX_TABLE_BYTES",
    "REQUIRED_COLUMNS",
    "TABLE_FORMATS",
    "USER_COLUMNS",
    "Column",
    "blocks_to_table",
    "check_blocks",
    "column_reference",
    "file_sha256",
    "jd_parts",
    "local_datetimes",
    "make_meta",
    "read_blocks",
    "table_to_json_rows",
    "time_array",
    "write_table",
]


@dataclass(frozen=True, slots=True)
class Column:
    """One column of the master blocks table: everything writers, readers and docs need.

    Attributes
    ----------
    name : str
        Column name.
    dtype : str
        Type of the values: ``str``, ``float64`` or ``int64``.
    unit : str or None
        Physical unit (astropy spelling); None for names, times and dimensionless numbers.
    description : str
        What the column holds (the block-table reference and, if ``in_header``, the ECSV header).
    required : bool
        Every reader needs it (:func:`read_blocks` checks); required columns come first.
    in_header : bool
        ``description`` is written into the file header. False for the columns whose files never
        carried one, so that tables stay byte-identical to those written before.
    kind : str
        How the value is made from a :class:`Block`: ``value`` (the attribute ``source``),
        ``utc`` / ``tdb`` (ISO time of ``source``, ms / µs), ``local`` (local civil time of
        ``source``), ``hms`` / ``dms`` (sexagesimal RA / Dec) or ``width`` (end − start).
    source : str
        The :class:`Block` attribute it comes from (default: ``name``).
    bounds : tuple of float, optional
        Smallest and largest value a reader accepts (in ``unit``); every value the planner
        writes lies well inside.
    nan_ok : bool
        NaN (unknown) is an accepted value.
    """

    name: str
    dtype: str
    unit: str | None
    description: str
    required: bool = False
    in_header: bool = True
    kind: str = "value"
    source: str = ""
    bounds: tuple[float, float] | None = None
    nan_ok: bool = False

    @property
    def attribute(self) -> str:
        """The :class:`Block` attribute the column is made from."""
        return self.source or self.name


#: Largest |u★| a table may hold [rad] (the planner writes 0 <= u★ < 2π).
_MAX_U = 4.0 * math.pi

#: The master blocks table, column by column, in file order: required columns first (issue 3).
COLUMNS: tuple[Column, ...] = (
    Column("target", "str", None, "target name", required=True),
    Column("block_id", "str", None, "unique block identifier", required=True),
    Column(
        "anchor",
        "str",
        None,
        "anchor name (quadrature, conjunction, zero-crossing, u=VALUE, fixed-u-pairs)",
        required=True,
    ),
    Column(
        "u_star_rad",
        "float64",
        "rad",
        "target argument of latitude of star 1",
        required=True,
        bounds=(-_MAX_U, _MAX_U),
    ),
    Column(
        "t_mid_utc",
        "str",
        None,
        "block centre, UTC at the site (light time removed), ISO ms",
        required=True,
        kind="utc",
    ),
    Column(
        "t_start_utc",
        "str",
        None,
        "block start (first exposure starts), UTC at the site, ISO ms",
        required=True,
        kind="utc",
    ),
    Column(
        "t_end_utc",
        "str",
        None,
        "block end (last exposure ends), UTC at the site, ISO ms",
        required=True,
        kind="utc",
    ),
    Column(
        "t_mid_tdb_bary",
        "str",
        None,
        "anchor epoch, TDB at the solar-system barycentre, ISO us",
        required=True,
        kind="tdb",
    ),
    Column(
        "sigma_t_s",
        "float64",
        "s",
        "1-sigma timing uncertainty of the anchor epoch (sigma_u / u_dot)",
        required=True,
        bounds=(0.0, 86400.0),
    ),
    Column(
        "t_alt_utc",
        "str",
        None,
        "phi_ref pi-mode alternative epoch (P_b/4 away), UTC at the site, ISO ms",
        required=True,
        kind="utc",
    ),
    Column(
        "exptime_s",
        "float64",
        "s",
        "single-exposure time",
        required=True,
        bounds=(0.0, MAX_BLOCK_S),
    ),
    Column(
        "n_exp",
        "int64",
        None,
        "number of exposures in the block",
        required=True,
        bounds=(1, MAX_N_EXP),
    ),
    Column(
        "lambda_k",
        "float64",
        None,
        "smearing attenuation of K over the block, sin(x)/x, x = n_b dt/2",
        required=True,
        bounds=(-1.0, 1.0),
    ),
    Column(
        "altitude_deg",
        "float64",
        "deg",
        "target altitude at block centre",
        required=True,
        bounds=(-90.0, 90.0),
    ),
    Column(
        "airmass",
        "float64",
        None,
        "airmass (sec z) at block centre",
        required=True,
        bounds=(1.0, 1000.0),
    ),
    Column(
        "moon_sep_deg",
        "float64",
        "deg",
        "smallest target-Moon separation over the block",
        required=True,
        bounds=(0.0, 180.0),
    ),
    Column(
        "ra_deg", "float64", "deg", "right ascension (ICRS)", in_header=False, bounds=(0.0, 360.0)
    ),
    Column(
        "dec_deg", "float64", "deg", "declination (ICRS)", in_header=False, bounds=(-90.0, 90.0)
    ),
    Column("ra_hms", "str", None, "right ascension, HH:MM:SS.sss", in_header=False, kind="hms"),
    Column("dec_dms", "str", None, "declination, +DD:MM:SS.ss", in_header=False, kind="dms"),
    Column("night", "str", None, "local date of the evening the night starts"),
    Column(
        "t_mid_local",
        "str",
        None,
        "block centre, local civil time at the site with UTC offset, ISO s",
        in_header=False,
        kind="local",
        source="t_mid_utc",
    ),
    Column(
        "t_start_local",
        "str",
        None,
        "block start, local civil time at the site with UTC offset, ISO s",
        in_header=False,
        kind="local",
        source="t_start_utc",
    ),
    Column(
        "t_end_local",
        "str",
        None,
        "block end, local civil time at the site with UTC offset, ISO s",
        in_header=False,
        kind="local",
        source="t_end_utc",
    ),
    Column("timezone", "str", None, "IANA time zone of the site", in_header=False),
    Column(
        "alt_start_deg",
        "float64",
        "deg",
        "target altitude at block start",
        in_header=False,
        bounds=(-90.0, 90.0),
    ),
    Column(
        "alt_end_deg",
        "float64",
        "deg",
        "target altitude at block end",
        in_header=False,
        bounds=(-90.0, 90.0),
    ),
    Column(
        "airmass_start",
        "float64",
        None,
        "airmass at block start",
        in_header=False,
        bounds=(1.0, 1000.0),
    ),
    Column(
        "airmass_end",
        "float64",
        None,
        "airmass at block end",
        in_header=False,
        bounds=(1.0, 1000.0),
    ),
    Column(
        "readout_s",
        "float64",
        "s",
        "dead time between exposures",
        in_header=False,
        bounds=(0.0, MAX_READOUT_S),
    ),
    Column(
        "block_width_s",
        "float64",
        "s",
        "block length, first exposure start to last exposure end",
        in_header=False,
        kind="width",
        bounds=(0.0, 86400.0),
    ),
    Column(
        "lambda_kappa",
        "float64",
        None,
        "attenuation of the eccentricity terms, sin(2x)/(2x)",
        bounds=(-1.0, 1.0),
    ),
    Column(
        "smear_kms",
        "float64",
        "km / s",
        "velocity smear K(1 - lambda_k); NaN if K unknown",
        bounds=(-1e5, 1e5),
        nan_ok=True,
    ),
    Column(
        "period_s",
        "float64",
        "s",
        "orbital period P_b",
        in_header=False,
        bounds=(1.0, 1e7),  # a zero period divided by zero in the exports (fuzz test)
        nan_ok=True,
    ),
    Column(
        "moon_illum",
        "float64",
        None,
        "illuminated fraction of the Moon at block centre",
        bounds=(0.0, 1.0),
    ),
    Column(
        "priority",
        "float64",
        None,
        "target priority (higher first)",
        in_header=False,
        bounds=(-1e9, 1e9),
    ),
    Column("session_id", "str", None, "blocks sharing a session (e.g. a quadrature pair)"),
    Column("pair_id", "str", None, "fixed-u pair identifier (same u at two epochs)"),
    Column(
        "delta_kappa",
        "float64",
        None,
        "predicted kappa change over the pair baseline (Eq. delta_kappa_rewrite)",
        bounds=(-2.0, 2.0),
        nan_ok=True,
    ),
    Column(
        "visit_id",
        "str",
        None,
        "visit (one acquisition followed by continuous exposures) the exposure belongs to",
    ),
    Column(
        "sigma_v_kms",
        "float64",
        "km / s",
        "RV precision of the exposure (--sigma-v, or instrument, magnitude and airmass); NaN "
        "if unknown",
        bounds=(0.0, 1e5),
        nan_ok=True,
    ),
)

#: Optional columns the planner does not write but exports read when a user adds them.
USER_COLUMNS: tuple[Column, ...] = (
    Column("vmag", "float64", "mag", "V magnitude", bounds=(-30.0, 40.0), nan_ok=True),
    Column(
        "acq_s", "float64", "s", "acquisition overhead before the block", bounds=(0.0, MAX_BLOCK_S)
    ),
    Column("tol_rad", "float64", "rad", "phase tolerance", bounds=(0.0, 10.0), nan_ok=True),
)

#: Columns by name.
COLUMN_BY_NAME: dict[str, Column] = {c.name: c for c in COLUMNS}

#: Every column a reader knows (planner columns and :data:`USER_COLUMNS`), by name.
KNOWN_COLUMNS: dict[str, Column] = {c.name: c for c in (*COLUMNS, *USER_COLUMNS)}

#: Columns whose cells may be empty: no π-mode alternative, no session, no pair, no visit.
BLANK_OK = frozenset(("t_alt_utc", "session_id", "pair_id", "visit_id"))

#: Largest blocks table [bytes] (a year of blocks of a 5-min binary is a few MB).
MAX_TABLE_BYTES = 100_000_000

#: Largest ECSV header [characters] (column declarations and provenance: a year-long plan writes
#: a few hundred kB).
MAX_HEADER_CHARS = 4_000_000

#: Years a blocks-table time may fall in (the planner plans nights in 1900-2100).
TIME_YEARS = (1900, 2101)

#: Columns every master table has, in this order; extras follow.
REQUIRED_COLUMNS: tuple[str, ...] = tuple(c.name for c in COLUMNS if c.required)

#: Extra columns (always present, in this order after the required ones).
EXTRA_COLUMNS: tuple[str, ...] = tuple(c.name for c in COLUMNS if not c.required)

TABLE_FORMATS = ("ecsv", "csv", "json")


def _iso(times: Sequence[Time | None], precision: int, scale: str) -> np.ndarray:
    """ISO strings of scalar Times (empty string for None) in ``scale``."""
    out = np.full(len(times), "", dtype=object)
    idx = [i for i, t in enumerate(times) if t is not None]
    if idx:
        out[idx] = _iso_of(time_array([times[i] for i in idx], scale), precision)
    return out.astype(str) if len(out) else np.array([], dtype="U1")


def _iso_of(times: Time, precision: int) -> np.ndarray:
    """ISO strings of an array Time, from its Julian dates as stored."""
    return isot_array(times, precision)


def _iso_column(times: Time, has: np.ndarray | None, precision: int) -> np.ndarray:
    """ISO strings of an array Time; empty where ``has`` is False."""
    if not len(times):
        return np.array([], dtype="U1")
    if has is None or bool(np.all(has)):
        return _iso_of(times, precision).astype(str)
    out = np.full(len(times), "", dtype=object)
    if np.any(has):
        out[has] = _iso_of(times[has], precision)
    return out.astype(str)


def local_datetimes(times: Sequence[Time], zones: Sequence[str]) -> list[datetime]:
    """Scalar UTC Times as aware local datetimes (µs), each in its IANA zone.

    One calendar conversion (erfa ``d2dtf``, as astropy's ``to_datetime`` makes it) for all
    times, then each is moved into its zone by :mod:`zoneinfo`, so DST changes are exact. A
    time inside a leap second takes astropy's own path (which refuses it)."""
    if not len(times):
        return []
    return _local_of(time_array(times, "utc"), zones)


def _local_of(utc: Time, zones: Sequence[str]) -> list[datetime]:
    """:func:`local_datetimes` of an array UTC Time (the Julian dates as stored)."""
    year, month, day, hmsf = erfa.d2dtf(b"UTC", 6, utc.jd1, utc.jd2)
    if np.any(hmsf["s"] >= 60):  # datetime has no leap second: astropy raises, as it always did
        return [
            t.utc.to_datetime(timezone=UTC).astimezone(ZoneInfo(z))
            for t, z in zip(utc, zones, strict=True)
        ]
    tz = {z: ZoneInfo(z) for z in dict.fromkeys(zones)}
    fields = zip(
        year.tolist(),
        month.tolist(),
        day.tolist(),
        hmsf["h"].tolist(),
        hmsf["m"].tolist(),
        hmsf["s"].tolist(),
        hmsf["f"].tolist(),
        zones,
        strict=True,
    )
    return [
        datetime(y, mo, d, h, mi, sec, us, tzinfo=UTC).astimezone(tz[z])
        for y, mo, d, h, mi, sec, us, z in fields
    ]


def _local_iso(times: Time | Sequence[Time], zones: Sequence[str]) -> np.ndarray:
    """Local civil time strings with UTC offset, second precision (of an array UTC Time or
    of scalar Times)."""
    if not len(times):
        return np.array([], dtype="U1")
    utc = times if isinstance(times, Time) else time_array(times, "utc")
    year, month, day, hmsf = erfa.d2dtf(b"UTC", 6, utc.jd1, utc.jd2)
    if np.any(hmsf["s"] >= 60) or np.any(year < 1970):  # a leap second (astropy's path refuses
        # it, as it always did) or a time before 1970 (not a POSIX time everywhere): time by time
        return np.array([dt.isoformat(timespec="seconds") for dt in _local_of(utc, zones)])
    # whole POSIX seconds: the seconds' fraction is cut by the format, and zones change their
    # offsets at whole seconds, so the zone's offset is that of the instant itself
    months = (year - 1970) * 12 + (month - 1)
    days = months.astype("datetime64[M]").astype("datetime64[D]").astype(np.int64) + (day - 1)
    posix = days * 86400 + hmsf["h"] * 3600 + hmsf["m"] * 60 + hmsf["s"]
    tz = {z: ZoneInfo(z) for z in dict.fromkeys(zones)}
    offsets = [
        datetime.fromtimestamp(t, tz[z]).utcoffset()
        for t, z in zip(posix.tolist(), zones, strict=True)
    ]
    found = {off: _offset_text(off) for off in dict.fromkeys(offsets)}
    text = {off: got for off, got in found.items() if got is not None}
    if len(text) < len(found):
        return np.array([dt.isoformat(timespec="seconds") for dt in _local_of(utc, zones)])
    shift = np.array([text[off][0] for off in offsets], dtype=np.int64)
    wall = np.datetime_as_string((posix + shift).astype("datetime64[s]"), unit="s").tolist()
    local = list(map(operator.add, wall, (text[off][1] for off in offsets)))
    return np.array(local, dtype=str)


def _offset_text(offset: timedelta | None) -> tuple[int, str] | None:
    """(seconds, ``+HH:MM`` as ``isoformat`` writes it) of a UTC offset of whole seconds."""
    if offset is None or offset.microseconds:
        return None
    zone = timezone(offset)
    return offset.days * 86400 + offset.seconds, datetime(2000, 1, 1, tzinfo=zone).isoformat()[19:]


def _per_distinct(values: np.ndarray, fmt: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
    """``fmt(values)``, formatting each distinct value (bit for bit: -0.0 is not 0.0) once: a
    target's coordinates repeat on every one of its blocks."""
    if len(values) == 0:
        return np.array([], dtype="U1")
    bits = np.ascontiguousarray(values, dtype=np.float64).view(np.int64)
    _, first, inverse = np.unique(bits, return_index=True, return_inverse=True)
    return fmt(values[first])[inverse.ravel()]


def _hms(ra_deg: np.ndarray) -> np.ndarray:
    ra = Angle(ra_deg, unit="deg").to_string(unit="hourangle", sep=":", precision=3, pad=True)
    return np.atleast_1d(ra).astype(str)


def _dms(dec_deg: np.ndarray) -> np.ndarray:
    dec = Angle(dec_deg, unit="deg").to_string(
        unit="deg", sep=":", precision=2, pad=True, alwayssign=True
    )
    return np.atleast_1d(dec).astype(str)


def _ra_hms(ra_deg: np.ndarray) -> np.ndarray:
    return _per_distinct(ra_deg, _hms)


def _dec_dms(dec_deg: np.ndarray) -> np.ndarray:
    return _per_distinct(dec_deg, _dms)


def _plain_values(column: Column, cols: BlockColumns) -> np.ndarray:
    values = cols.values[column.attribute]
    if column.dtype == "str":
        return values.astype(str) if len(values) else np.array([], dtype="U1")
    return np.asarray(values, dtype=column.dtype)


def _width_s(column: Column, cols: BlockColumns) -> np.ndarray:
    if not len(cols):
        return np.round(np.array([], dtype=float), 6)
    start, end = cols.times["t_start_utc"], cols.times["t_end_utc"]
    return np.round(np.asarray((end - start).to_value("s"), dtype=float), 6)


def _time_column(column: Column, cols: BlockColumns, precision: int) -> np.ndarray:
    has = cols.has_alt if column.attribute == "t_alt_utc" else None
    return _iso_column(cols.times[column.attribute], has, precision)


#: How each kind of column is made from the blocks' columns (see :attr:`Column.kind`).
_MAKERS: dict[str, Callable[[Column, BlockColumns], np.ndarray]] = {
    "value": _plain_values,
    "utc": lambda c, b: _time_column(c, b, 3),
    "tdb": lambda c, b: _time_column(c, b, 6),
    "local": lambda c, b: _local_iso(b.times[c.attribute], b.values["timezone"].tolist()),
    "hms": lambda c, b: _ra_hms(np.asarray(b.values["ra_deg"], dtype=float)),
    "dms": lambda c, b: _dec_dms(np.asarray(b.values["dec_deg"], dtype=float)),
    "width": _width_s,
}


def file_sha256(path: Path) -> str:
    """SHA-256 hex digest of a file's bytes (provenance of target files)."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def make_meta(
    *,
    site: Mapping[str, Any],
    targets: Sequence[Mapping[str, Any]],
    constraints: Sequence[str],
    mode: str,
    extra: Mapping[str, Any] | None = None,
) -> dict[str, Any]:
    """Provenance for the table ``meta``.

    Parameters
    ----------
    site : mapping
        Site description (name, lon_deg, lat_deg, height_m, timezone).
    targets : sequence of mapping
        One entry per target: name, file (path or None), sha256 (or None).
    constraints : sequence of str
        Human-readable constraint descriptions, e.g. ``"airmass <= 2.0"``.
    mode : str
        Planning mode (quadrature, conjunction, ...).
    extra : mapping, optional
        Further keys (alpha, nights, exposure plan, warnings ...).
    """
    from ucbplan._version import __version__

    meta: dict[str, Any] = {
        "ucbplan_version": __version__,
        "created_utc": datetime.now(UTC).isoformat(timespec="seconds"),
        "site": dict(site),
        "targets": [dict(t) for t in targets],
        "time_base": (
            "t_*_utc: UTC at the site (barycentric light time removed, astropy builtin "
            "ephemeris); t_mid_tdb_bary: TDB at the solar-system barycentre"
        ),
        "phase_convention": (
            "u = argument of latitude of star 1 (Eq. u_precessing_app); u=0 ascending node = "
            "maximum recession of star 1, v1 = gamma1 + K1 (cos u + kappa); quadrature u=0,pi; "
            "conjunction u=pi/2,3pi/2; block centre is the mid-exposure time"
        ),
        "constraints": list(constraints),
        "mode": mode,
    }
    if extra:
        meta.update(dict(extra))
    return meta


def blocks_to_table(blocks: Sequence[Block], meta: Mapping[str, Any]) -> Table:
    """Build the master table (required columns first, then extras) from blocks.

    Parameters
    ----------
    blocks : sequence of Block
        Planned blocks, in the order they should appear.
    meta : mapping
        Provenance stored in ``Table.meta`` (see :func:`make_meta`).

    Returns
    -------
    astropy.table.Table
        One row per block; ISO time strings, SI-ish floats with units.
    """
    with quiet_erfa():
        return _blocks_to_table(block_columns(blocks), meta)


def _blocks_to_table(cols: BlockColumns, meta: Mapping[str, Any]) -> Table:
    table = Table({c.name: _MAKERS[c.kind](c, cols) for c in COLUMNS})
    table.meta = _copy_meta(dict(meta))  # as Table(meta=...) would deep-copy it, but faster
    for c in COLUMNS:
        if c.unit is not None:
            table[c.name].unit = c.unit
        if c.in_header:
            table[c.name].description = c.description
    return table


def _copy_meta(value: Any, memo: dict[int, Any] | None = None) -> Any:
    """:func:`copy.deepcopy` of table meta, faster: dicts and lists copied level by level (a
    list of flat records of plain scalars, like a plan's visits, record by record), plain
    scalars kept (immutable), anything else by ``deepcopy``; an object met twice is copied once
    (``memo``, shared with ``deepcopy``), as the YAML header writes such an object once."""
    kind = type(value)
    if kind in _SCALARS:
        return value
    memo = {} if memo is None else memo
    if id(value) in memo:
        return memo[id(value)]
    out: Any
    if kind is dict:
        out = memo[id(value)] = {}
        out.update((k, _copy_meta(v, memo)) for k, v in value.items())
    elif kind is list:
        out = memo[id(value)] = []
        flat = itertools.chain.from_iterable(map(dict.values, value))
        if all(type(r) is dict for r in value) and _SCALARS.issuperset(map(type, flat)):
            out += [memo[id(r)] if id(r) in memo else _remember(memo, r, r.copy()) for r in value]
        else:
            out += [_copy_meta(v, memo) for v in value]
    else:
        return copy.deepcopy(value, memo)
    memo.setdefault(id(memo), []).append(value)  # the original kept alive, as deepcopy does
    return out


def _remember(memo: dict[int, Any], original: Any, copied: Any) -> Any:
    memo[id(original)] = copied
    return copied


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
    return type(col) is TableColumn and col.ndim == 1 and col.dtype.kind in "biufUS"


def _plain_meta(value: Any) -> Any:
    """Table meta as plain JSON values (NaN and infinities → null), recursively."""
    if isinstance(value, Mapping):
        return {str(k): _plain_meta(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        if _flat_records_safe(value) is not None and _finite(value):  # plain already: copied
            return [dict(zip(map(str, r), r.values(), strict=True)) for r in value]
        return [_plain_meta(v) for v in value]
    value = _plain(value)
    return value if isinstance(value, str | int | float | bool | type(None)) else str(value)


#: Characters every string of an ECSV header must be made of for libyaml to write it: libyaml
#: and PyYAML's pure-Python emitter write such headers byte for byte alike (tested on random
#: headers), not strings that need double quotes (other characters) nor empty mapping keys.
_LIBYAML_SAFE = frozenset(map(chr, range(0x20, 0x7F)))


def _libyaml_safe(value: Any) -> bool:
    """Whether every string in ``value`` (mapping keys, non-empty, and values, recursively) is
    printable ASCII; other values (numbers, booleans, None) are always safe."""
    if isinstance(value, str):
        return _LIBYAML_SAFE.issuperset(value)
    if isinstance(value, Mapping):
        return all(
            isinstance(k, str) and k != "" and _libyaml_safe(k) and _libyaml_safe(v)
            for k, v in value.items()
        )
    if isinstance(value, list | tuple):
        flat = _flat_records_safe(value)
        return flat if flat is not None else all(_libyaml_safe(v) for v in value)
    return isinstance(value, int | float | np.number | np.bool_ | type(None))


#: Kinds of value :func:`_flat_records_safe` checks at once (always safe but for ``str``).
_SCALARS = frozenset((str, int, float, bool, type(None)))


def _flat_records_safe(records: list[Any] | tuple[Any, ...]) -> bool | None:
    """:func:`_libyaml_safe` of a list of plain dicts of plain scalars (a plan's ``visits``),
    their keys and texts checked joined, or None for any other list."""
    if not records or any(type(r) is not dict for r in records):
        return None
    values = list(itertools.chain.from_iterable(map(dict.values, records)))
    if not _SCALARS.issuperset(map(type, values)):
        return None
    keys = set(itertools.chain.from_iterable(records))
    if not all(type(k) is str and k != "" for k in keys):
        return False
    texts = itertools.chain(keys, filter(str.__instancecheck__, values))
    return _LIBYAML_SAFE.issuperset("".join(texts))


def _header_safe(table: Table) -> bool:
    """Whether the whole ECSV header of ``table`` (meta, column names, units, descriptions,
    formats and column meta) is :func:`_libyaml_safe`."""
    if not _libyaml_safe(dict(table.meta)):
        return False
    for col in table.itercols():
        info = col.info
        unit = getattr(col, "unit", None)
        attrs = [info.name, info.description, info.format, None if unit is None else str(unit)]
        if not _libyaml_safe(attrs) or not _libyaml_safe(dict(info.meta or {})):
            return False
    return True


_LIBYAML_LOCK = threading.Lock()


def _represent_data(dumper: Any, data: Any) -> Any:
    """``represent_data`` of the libyaml dumper: a ``str`` becomes the node PyYAML's
    ``represent_str`` makes (no alias, default style) without the generic dispatch; the
    header of a long plan holds tens of thousands of strings."""
    if type(data) is str and dumper.yaml_representers.get(str) is _REPRESENT_STR:
        dumper.alias_key = None
        return yaml.ScalarNode("tag:yaml.org,2002:str", data, style=dumper.default_style)
    return yaml.representer.BaseRepresenter.represent_data(dumper, data)


def _resolve(dumper: Any, kind: Any, value: Any, implicit: Any) -> Any:
    """``resolve`` of the libyaml dumper, remembered per scalar text (the tag of a plain
    scalar depends on its text alone; a header repeats the same texts)."""
    if kind is not yaml.ScalarNode:
        return yaml.resolver.BaseResolver.resolve(dumper, kind, value, implicit)
    cache = dumper.__dict__.setdefault("_ucbplan_resolved", {})
    key = (value, implicit)
    if key not in cache:
        cache[key] = yaml.resolver.BaseResolver.resolve(dumper, kind, value, implicit)
    return cache[key]


#: PyYAML's representer of ``str`` (the one :func:`_represent_data` stands in for).
_REPRESENT_STR = yaml.representer.SafeRepresenter.represent_str


@contextmanager
def _libyaml_header(enabled: bool) -> Iterator[None]:
    """While active, astropy emits ECSV headers with libyaml (C) instead of PyYAML's emitter.

    astropy builds its table dumper on ``astropy.io.misc.yaml.AstropyDumper`` when it writes;
    swapping in a subclass with libyaml's emitter keeps astropy's representation (key order,
    styles, tags) and only replaces the emitter, ~20x faster on a semester's header. A no-op
    unless ``enabled`` and PyYAML has libyaml."""
    if not enabled or not yaml.__with_libyaml__:
        yield
        return
    import astropy.io.misc.yaml as astropy_yaml
    from yaml._yaml import CEmitter
    from yaml.cyaml import CSafeDumper

    base = astropy_yaml.AstropyDumper
    methods = {
        "__init__": CSafeDumper.__init__,
        "represent_data": _represent_data,
        "resolve": _resolve,
    }
    fast = type("LibyamlAstropyDumper", (CEmitter, base), methods)
    with _LIBYAML_LOCK:
        astropy_yaml.AstropyDumper = fast
        try:
            yield
        finally:
            astropy_yaml.AstropyDumper = base


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


def _write_csv(table: Table, handle: IO[str]) -> None:
    """CSV without meta as astropy writes it: its header line (written for no rows), then the
    rows column by column (:func:`.tablewrite.ecsv_data_lines`); for tables of other columns,
    astropy's whole writer."""
    plain = table.copy(copy_data=False)
    plain.meta = {}
    lines = ecsv_data_lines(plain, ",")
    if lines is None:
        plain.write(handle, format="ascii.csv")
        return
    plain[:0].write(handle, format="ascii.csv")
    handle.write("".join(line + os.linesep for line in lines))


def _write_ecsv(table: Table, handle: IO[str]) -> None:
    """ECSV as astropy writes it: its header (made from the columns and meta alone, so written
    for no rows; a plan's ``visits`` list written by :func:`.tablewrite.yaml_flow_items` when
    it can), then the rows column by column (:func:`.tablewrite.ecsv_data_lines`); for tables
    of other columns, astropy's whole writer."""
    lines = ecsv_data_lines(table)
    safe = _header_safe(table)
    with _libyaml_header(safe):
        if lines is None:
            table.write(handle, format="ascii.ecsv")
            return
        handle.write(_ecsv_header(table, safe))
    handle.write("".join(line + os.linesep for line in lines))


#: The ``visits`` entry of a plan's ECSV header while its items are written apart.
_NO_VISITS = f"{os.linesep}# - visits: []{os.linesep}"


def _ecsv_header(table: Table, libyaml: bool) -> str:
    """The ECSV header of ``table`` (for no rows), as astropy writes it."""
    visits = table.meta.get("visits") if libyaml else None
    items = None
    if isinstance(visits, list) and visits and all(isinstance(v, dict) for v in visits):
        items = yaml_flow_items(visits, _yaml_tag)
    buf = io.StringIO()
    if items is None:
        table[:0].write(buf, format="ascii.ecsv")
        return buf.getvalue()
    table.meta["visits"] = []  # written apart below (not copied with the table)
    try:
        empty = table[:0]
    finally:
        table.meta["visits"] = visits
    empty.write(buf, format="ascii.ecsv")
    text = buf.getvalue()
    if text.count(_NO_VISITS) != 1:  # never: meta keys are unique
        buf = io.StringIO()
        table[:0].write(buf, format="ascii.ecsv")
        return buf.getvalue()
    listed = "# " + f"{os.linesep}# ".join(items) + os.linesep
    return text.replace(_NO_VISITS, f"{os.linesep}# - visits:{os.linesep}{listed}")


@functools.lru_cache(maxsize=4096)
def _yaml_tag(text: str) -> str:
    """PyYAML's implicit tag of a plain scalar: ``str``, ``int``, ``float``, ``bool`` ..."""
    return str(yaml.SafeDumper.resolve(_RESOLVER, yaml.ScalarNode, text, (True, False))).rsplit(
        ":", 1
    )[-1]


_RESOLVER = yaml.resolver.Resolver()


def _write_json(table: Table, handle: IO[str], json_meta: bool) -> None:
    """The rows (with ``json_meta``: ``{"meta": ..., "rows": [...]}``) as :func:`dump_json`
    writes them, encoded column by column when the columns allow
    (:func:`.tablewrite.json_rows_text`)."""
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
    written key by key (:func:`.tablewrite.json_records_text`) where they allow."""
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
    with quiet_erfa():
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
            f"{where}: expected a JSON list of row objects (`ucbplan plan --format json`)"
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
        cells = [row[k] for row in rows]
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


def column_reference() -> str:
    """The block-table reference as a Markdown table (one row per column, in file order)."""
    lines = [
        "| column | type | unit | required | description |",
        "| --- | --- | --- | --- | --- |",
    ]
    for c in COLUMNS:
        required = "yes" if c.required else ""
        lines.append(f"| `{c.name}` | {c.dtype} | {c.unit or ''} | {required} | {c.description} |")
    return "\n".join(lines) + "\n"
