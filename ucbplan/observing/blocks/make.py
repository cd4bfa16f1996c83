"""The master blocks table made from planned blocks, with its provenance.

:func:`blocks_to_table` makes each column of :data:`~ucbplan.observing.blocks.schema.COLUMNS` from
the blocks' columns (:mod:`ucbplan.observing.blocks.arrays`) as its ``kind`` says — values as
they are, times and coordinates as text (:mod:`ucbplan.observing.blocks.cells`) — and
:func:`make_meta` gives the provenance the table's ``meta`` carries.
"""

from __future__ import annotations

import copy
import hashlib
import itertools
from collections.abc import Callable, Mapping, Sequence
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np
from astropy.table import Table

from ucbplan.observing.blocks.arrays import BlockColumns, block_columns
from ucbplan.observing.blocks.block import Block
from ucbplan.observing.blocks.cells import dec_dms_column, iso_column, local_iso, ra_hms_column
from ucbplan.observing.blocks.schema import COLUMNS, META_SCALARS, Column


def _plain_values(column: Column, cols: BlockColumns) -> np.ndarray:
    """A copy of the blocks' values (the table does not share the plan's arrays)."""
    values = cols.values[column.attribute]
    if column.dtype == "str":
        return values.astype(str) if len(values) else np.array([], dtype="U1")
    return np.array(values, dtype=column.dtype)


def _width_s(column: Column, cols: BlockColumns) -> np.ndarray:
    if not len(cols):
        return np.round(np.array([], dtype=float), 6)
    start, end = cols.times["t_start_utc"], cols.times["t_end_utc"]
    return np.round(np.asarray((end - start).to_value("s"), dtype=float), 6)


def _time_column(column: Column, cols: BlockColumns, precision: int) -> np.ndarray:
    has = cols.has_alt if column.attribute == "t_alt_utc" else None
    return iso_column(cols.times[column.attribute], has, precision)


#: How each kind of column is made from the blocks' columns (see :attr:`Column.kind`): each a
#: new array, which the table then holds without copying it again.
_MAKERS: dict[str, Callable[[Column, BlockColumns], np.ndarray]] = {
    "value": _plain_values,
    "utc": lambda c, b: _time_column(c, b, 3),
    "tdb": lambda c, b: _time_column(c, b, 6),
    "local": lambda c, b: local_iso(b.times[c.attribute], b.values["timezone"].tolist()),
    "hms": lambda c, b: ra_hms_column(np.asarray(b.values["ra_deg"], dtype=float)),
    "dms": lambda c, b: dec_dms_column(np.asarray(b.values["dec_deg"], dtype=float)),
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
    return _blocks_to_table(block_columns(blocks), meta)


def _blocks_to_table(cols: BlockColumns, meta: Mapping[str, Any]) -> Table:
    table = Table({c.name: _MAKERS[c.kind](c, cols) for c in COLUMNS}, copy=False)
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
    if kind in META_SCALARS:
        return value
    memo = {} if memo is None else memo
    if id(value) in memo:
        return memo[id(value)]
    out: Any
    if kind is dict and META_SCALARS.issuperset(map(type, value.values())):
        out = memo[id(value)] = value.copy()  # flat (a night's reasons): copied at once
    elif kind is dict:
        out = memo[id(value)] = {}
        out.update((k, _copy_meta(v, memo)) for k, v in value.items())
    elif kind is list:
        out = memo[id(value)] = []
        flat = itertools.chain.from_iterable(map(dict.values, value))
        if all(type(r) is dict for r in value) and META_SCALARS.issuperset(map(type, flat)):
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
