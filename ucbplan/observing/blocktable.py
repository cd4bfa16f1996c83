"""The master blocks table: the single source every export (p2, starlist, ICS, proposal) reads.

Times are written as ISO-8601 strings (``YYYY-MM-DDTHH:MM:SS.sss``) so that ECSV, CSV and JSON
carry exactly the same text: ``t_*_utc`` columns are UTC at the site with millisecond precision,
``t_mid_tdb_bary`` is the barycentric TDB epoch with microsecond precision. Provenance (ucbplan
version, target files and their SHA-256, site, time base, phase convention, constraints) lives in
the table ``meta`` and is preserved by ECSV.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping, Sequence
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
    "REQUIRED_COLUMNS",
    "TABLE_FORMATS",
    "blocks_to_table",
    "file_sha256",
    "make_meta",
    "read_blocks",
    "table_to_json_rows",
    "write_table",
]

#: Columns every master table has, in this order (issue 3); extras follow.
REQUIRED_COLUMNS = (
    "target",
    "block_id",
    "anchor",
    "u_star_rad",
    "t_mid_utc",
    "t_start_utc",
    "t_end_utc",
    "t_mid_tdb_bary",
    "sigma_t_s",
    "t_alt_utc",
    "exptime_s",
    "n_exp",
    "lambda_k",
    "altitude_deg",
    "airmass",
    "moon_sep_deg",
)

#: Extra columns (always present, in this order after the required ones).
EXTRA_COLUMNS = (
    "ra_deg",
    "dec_deg",
    "ra_hms",
    "dec_dms",
    "night",
    "t_mid_local",
    "t_start_local",
    "t_end_local",
    "timezone",
    "alt_start_deg",
    "alt_end_deg",
    "airmass_start",
    "airmass_end",
    "readout_s",
    "block_width_s",
    "lambda_kappa",
    "smear_kms",
    "period_s",
    "moon_illum",
    "priority",
    "session_id",
    "pair_id",
    "delta_kappa",
)

TABLE_FORMATS = ("ecsv", "csv", "json")

_UNITS = {
    "u_star_rad": "rad",
    "sigma_t_s": "s",
    "exptime_s": "s",
    "altitude_deg": "deg",
    "moon_sep_deg": "deg",
    "ra_deg": "deg",
    "dec_deg": "deg",
    "alt_start_deg": "deg",
    "alt_end_deg": "deg",
    "readout_s": "s",
    "block_width_s": "s",
    "smear_kms": "km / s",
    "period_s": "s",
}

_DESCRIPTIONS = {
    "target": "target name",
    "block_id": "unique block identifier",
    "anchor": "anchor name (quadrature, conjunction, zero-crossing, u=VALUE, fixed-u-pairs)",
    "u_star_rad": "target argument of latitude of star 1",
    "t_mid_utc": "block centre, UTC at the site (light time removed), ISO ms",
    "t_start_utc": "block start (first exposure starts), UTC at the site, ISO ms",
    "t_end_utc": "block end (last exposure ends), UTC at the site, ISO ms",
    "t_mid_tdb_bary": "anchor epoch, TDB at the solar-system barycentre, ISO us",
    "sigma_t_s": "1-sigma timing uncertainty of the anchor epoch (sigma_u / u_dot)",
    "t_alt_utc": "phi_ref pi-mode alternative epoch (P_b/4 away), UTC at the site, ISO ms",
    "exptime_s": "single-exposure time",
    "n_exp": "number of exposures in the block",
    "lambda_k": "smearing attenuation of K over the block, sin(x)/x, x = n_b dt/2",
    "altitude_deg": "target altitude at block centre",
    "airmass": "airmass (sec z) at block centre",
    "moon_sep_deg": "smallest target-Moon separation over the block",
    "night": "local date of the evening the night starts",
    "lambda_kappa": "attenuation of the eccentricity terms, sin(2x)/(2x)",
    "smear_kms": "velocity smear K(1 - lambda_k); NaN if K unknown",
    "moon_illum": "illuminated fraction of the Moon at block centre",
    "session_id": "blocks sharing a session (e.g. a quadrature pair)",
    "pair_id": "fixed-u pair identifier (same u at two epochs)",
    "delta_kappa": "predicted kappa change over the pair baseline (Eq. delta_kappa_rewrite)",
}


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


def _sexagesimal(ra_deg: np.ndarray, dec_deg: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    if len(ra_deg) == 0:
        return np.array([], dtype="U1"), np.array([], dtype="U1")
    ra = Angle(ra_deg, unit="deg").to_string(unit="hourangle", sep=":", precision=3, pad=True)
    dec = Angle(dec_deg, unit="deg").to_string(
        unit="deg", sep=":", precision=2, pad=True, alwayssign=True
    )
    return np.atleast_1d(ra).astype(str), np.atleast_1d(dec).astype(str)


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


def _blocks_to_table(b: list[Block], meta: Mapping[str, Any]) -> Table:
    def col(name: str, dtype: Any) -> np.ndarray:
        return np.array([getattr(x, name) for x in b], dtype=dtype)

    ra = col("ra_deg", float)
    dec = col("dec_deg", float)
    ra_hms, dec_dms = _sexagesimal(ra, dec)
    zones = [x.timezone for x in b]
    starts = [x.t_start_utc for x in b]
    ends = [x.t_end_utc for x in b]
    t_start = Time(starts) if b else None
    t_end = Time(ends) if b else None
    width = (t_end - t_start).to_value("s") if b else np.array([], dtype=float)  # type: ignore[operator]
    data: dict[str, Any] = {
        "target": col("target", str) if b else np.array([], dtype="U1"),
        "block_id": col("block_id", str) if b else np.array([], dtype="U1"),
        "anchor": col("anchor", str) if b else np.array([], dtype="U1"),
        "u_star_rad": col("u_star_rad", float),
        "t_mid_utc": _iso([x.t_mid_utc for x in b], 3, "utc"),
        "t_start_utc": _iso(starts, 3, "utc"),
        "t_end_utc": _iso(ends, 3, "utc"),
        "t_mid_tdb_bary": _iso([x.t_mid_tdb_bary for x in b], 6, "tdb"),
        "sigma_t_s": col("sigma_t_s", float),
        "t_alt_utc": _iso([x.t_alt_utc for x in b], 3, "utc"),
        "exptime_s": col("exptime_s", float),
        "n_exp": col("n_exp", np.int64),
        "lambda_k": col("lambda_k", float),
        "altitude_deg": col("altitude_deg", float),
        "airmass": col("airmass", float),
        "moon_sep_deg": col("moon_sep_deg", float),
        "ra_deg": ra,
        "dec_deg": dec,
        "ra_hms": ra_hms,
        "dec_dms": dec_dms,
        "night": col("night", str) if b else np.array([], dtype="U1"),
        "t_mid_local": _local_iso([x.t_mid_utc for x in b], zones),
        "t_start_local": _local_iso(starts, zones),
        "t_end_local": _local_iso(ends, zones),
        "timezone": np.array(zones, dtype=str) if b else np.array([], dtype="U1"),
        "alt_start_deg": col("alt_start_deg", float),
        "alt_end_deg": col("alt_end_deg", float),
        "airmass_start": col("airmass_start", float),
        "airmass_end": col("airmass_end", float),
        "readout_s": col("readout_s", float),
        "block_width_s": np.round(np.asarray(width, dtype=float), 6),
        "lambda_kappa": col("lambda_kappa", float),
        "smear_kms": col("smear_kms", float),
        "period_s": col("period_s", float),
        "moon_illum": col("moon_illum", float),
        "priority": col("priority", float),
        "session_id": col("session_id", str) if b else np.array([], dtype="U1"),
        "pair_id": col("pair_id", str) if b else np.array([], dtype="U1"),
        "delta_kappa": col("delta_kappa", float),
    }
    table = Table(data, meta=dict(meta))
    for name, unit in _UNITS.items():
        table[name].unit = unit
    for name, text in _DESCRIPTIONS.items():
        table[name].description = text
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
