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

import hashlib
import json
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import IO, Any
from zoneinfo import ZoneInfo

import numpy as np
from astropy.coordinates import Angle
from astropy.table import Table
from astropy.time import Time

from ucbplan.errors import InputFileError
from ucbplan.observing.blocks import Block
from ucbplan.observing.timeconv import quiet_erfa

__all__ = [
    "COLUMNS",
    "COLUMN_BY_NAME",
    "EXTRA_COLUMNS",
    "REQUIRED_COLUMNS",
    "TABLE_FORMATS",
    "Column",
    "blocks_to_table",
    "column_reference",
    "file_sha256",
    "make_meta",
    "read_blocks",
    "table_to_json_rows",
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
    """

    name: str
    dtype: str
    unit: str | None
    description: str
    required: bool = False
    in_header: bool = True
    kind: str = "value"
    source: str = ""

    @property
    def attribute(self) -> str:
        """The :class:`Block` attribute the column is made from."""
        return self.source or self.name


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
    Column("u_star_rad", "float64", "rad", "target argument of latitude of star 1", required=True),
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
    ),
    Column(
        "t_alt_utc",
        "str",
        None,
        "phi_ref pi-mode alternative epoch (P_b/4 away), UTC at the site, ISO ms",
        required=True,
        kind="utc",
    ),
    Column("exptime_s", "float64", "s", "single-exposure time", required=True),
    Column("n_exp", "int64", None, "number of exposures in the block", required=True),
    Column(
        "lambda_k",
        "float64",
        None,
        "smearing attenuation of K over the block, sin(x)/x, x = n_b dt/2",
        required=True,
    ),
    Column("altitude_deg", "float64", "deg", "target altitude at block centre", required=True),
    Column("airmass", "float64", None, "airmass (sec z) at block centre", required=True),
    Column(
        "moon_sep_deg",
        "float64",
        "deg",
        "smallest target-Moon separation over the block",
        required=True,
    ),
    Column("ra_deg", "float64", "deg", "right ascension (ICRS)", in_header=False),
    Column("dec_deg", "float64", "deg", "declination (ICRS)", in_header=False),
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
    Column("alt_start_deg", "float64", "deg", "target altitude at block start", in_header=False),
    Column("alt_end_deg", "float64", "deg", "target altitude at block end", in_header=False),
    Column("airmass_start", "float64", None, "airmass at block start", in_header=False),
    Column("airmass_end", "float64", None, "airmass at block end", in_header=False),
    Column("readout_s", "float64", "s", "dead time between exposures", in_header=False),
    Column(
        "block_width_s",
        "float64",
        "s",
        "block length, first exposure start to last exposure end",
        in_header=False,
        kind="width",
    ),
    Column("lambda_kappa", "float64", None, "attenuation of the eccentricity terms, sin(2x)/(2x)"),
    Column("smear_kms", "float64", "km / s", "velocity smear K(1 - lambda_k); NaN if K unknown"),
    Column("period_s", "float64", "s", "orbital period P_b", in_header=False),
    Column("moon_illum", "float64", None, "illuminated fraction of the Moon at block centre"),
    Column("priority", "float64", None, "target priority (higher first)", in_header=False),
    Column("session_id", "str", None, "blocks sharing a session (e.g. a quadrature pair)"),
    Column("pair_id", "str", None, "fixed-u pair identifier (same u at two epochs)"),
    Column(
        "delta_kappa",
        "float64",
        None,
        "predicted kappa change over the pair baseline (Eq. delta_kappa_rewrite)",
    ),
)

#: Columns by name.
COLUMN_BY_NAME: dict[str, Column] = {c.name: c for c in COLUMNS}

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
        jd1 = np.array([getattr(times[i], scale).jd1 for i in idx])
        jd2 = np.array([getattr(times[i], scale).jd2 for i in idx])
        t = Time(jd1, jd2, format="jd", scale=scale, precision=precision)
        out[idx] = t.isot
    return out.astype(str) if len(out) else np.array([], dtype="U1")


def _local_iso(times: Sequence[Time], zones: Sequence[str]) -> np.ndarray:
    """Local civil time strings with UTC offset, second precision."""
    out = []
    for t, zone in zip(times, zones, strict=True):
        dt = t.utc.to_datetime(timezone=UTC).astimezone(ZoneInfo(zone))
        out.append(dt.isoformat(timespec="seconds"))
    return np.array(out, dtype=str) if out else np.array([], dtype="U1")


def _ra_hms(ra_deg: np.ndarray) -> np.ndarray:
    if len(ra_deg) == 0:
        return np.array([], dtype="U1")
    ra = Angle(ra_deg, unit="deg").to_string(unit="hourangle", sep=":", precision=3, pad=True)
    return np.atleast_1d(ra).astype(str)


def _dec_dms(dec_deg: np.ndarray) -> np.ndarray:
    if len(dec_deg) == 0:
        return np.array([], dtype="U1")
    dec = Angle(dec_deg, unit="deg").to_string(
        unit="deg", sep=":", precision=2, pad=True, alwayssign=True
    )
    return np.atleast_1d(dec).astype(str)


def _attribute(column: Column, blocks: list[Block]) -> list[Any]:
    return [getattr(b, column.attribute) for b in blocks]


def _plain_values(column: Column, blocks: list[Block]) -> np.ndarray:
    if column.dtype == "str" and not blocks:
        return np.array([], dtype="U1")
    return np.array(
        _attribute(column, blocks), dtype=str if column.dtype == "str" else column.dtype
    )


def _width_s(column: Column, blocks: list[Block]) -> np.ndarray:
    if not blocks:
        return np.round(np.array([], dtype=float), 6)
    start = Time([b.t_start_utc for b in blocks])
    end = Time([b.t_end_utc for b in blocks])
    return np.round(np.asarray((end - start).to_value("s"), dtype=float), 6)


#: How each kind of column is made from the blocks (see :attr:`Column.kind`).
_MAKERS: dict[str, Callable[[Column, list[Block]], np.ndarray]] = {
    "value": _plain_values,
    "utc": lambda c, b: _iso(_attribute(c, b), 3, "utc"),
    "tdb": lambda c, b: _iso(_attribute(c, b), 6, "tdb"),
    "local": lambda c, b: _local_iso(_attribute(c, b), [x.timezone for x in b]),
    "hms": lambda c, b: _ra_hms(np.array([x.ra_deg for x in b], dtype=float)),
    "dms": lambda c, b: _dec_dms(np.array([x.dec_deg for x in b], dtype=float)),
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
    from ucbplan import __version__

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
        return _blocks_to_table(list(blocks), meta)


def _blocks_to_table(blocks: list[Block], meta: Mapping[str, Any]) -> Table:
    table = Table({c.name: _MAKERS[c.kind](c, blocks) for c in COLUMNS}, meta=dict(meta))
    for c in COLUMNS:
        if c.unit is not None:
            table[c.name].unit = c.unit
        if c.in_header:
            table[c.name].description = c.description
    return table


def _plain(value: Any) -> Any:
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, float) and not np.isfinite(value):
        return None
    return value


def table_to_json_rows(table: Table) -> list[dict[str, Any]]:
    """Rows as plain dicts (NaN -> null) for ``--format json``."""
    names = table.colnames
    rows = []
    for row in table:
        rows.append(
            {n: _plain(row[n].item() if hasattr(row[n], "item") else row[n]) for n in names}
        )
    return rows


def write_table(table: Table, handle: IO[str], fmt: str) -> None:
    """Write ``table`` to an open text handle as ``ecsv``, ``csv`` or ``json`` (list of rows)."""
    if fmt == "ecsv":
        table.write(handle, format="ascii.ecsv")
    elif fmt == "csv":
        plain = table.copy(copy_data=False)
        plain.meta = {}
        plain.write(handle, format="ascii.csv")
    elif fmt == "json":
        json.dump(table_to_json_rows(table), handle, indent=2, allow_nan=False)
        handle.write("\n")
    else:
        raise InputFileError(f"unknown table format {fmt!r}; expected one of {TABLE_FORMATS}")


def read_blocks(path: Path | str) -> Table:
    """Read a master blocks table written as ECSV and check its required columns.

    Raises
    ------
    InputFileError
        If the file cannot be read as ECSV or lacks required columns.
    """
    path = Path(path)
    try:
        table = Table.read(path, format="ascii.ecsv")
    except FileNotFoundError as exc:
        raise InputFileError(
            f"{path}: file not found; pass a blocks table from `ucbplan plan -o`"
        ) from exc
    except Exception as exc:
        raise InputFileError(
            f"{path}: not a readable ECSV blocks table ({exc}); write one with "
            "`ucbplan plan ... -o blocks.ecsv`"
        ) from exc
    for name in table.colnames:
        column = table[name]
        if column.dtype.kind in "US" and getattr(column, "mask", None) is not None:
            table[name] = column.filled("")  # ECSV reads empty strings (no t_alt_utc) as masked
    missing = [c for c in REQUIRED_COLUMNS if c not in table.colnames]
    if missing:
        raise InputFileError(
            f"{path}: blocks table lacks required columns {missing}; "
            "regenerate it with `ucbplan plan`"
        )
    return table


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
