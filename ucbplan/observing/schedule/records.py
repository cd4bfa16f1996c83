"""Block records: placed sessions → named :class:`~ucbplan.observing.blocks.block.Block` rows.

Block and session identifiers are ``<target slug>-<YYYYMMDD>-NN`` and ``...-SNN``, numbered per
target and night in time order. UTC and TDB times come from one vectorised conversion per target
(:class:`~ucbplan.observing.observatory.time_axis.TimeAxis`); geometry from the run's sky model.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
from astropy.time import Time
from numpy.typing import NDArray

from ucbplan.core.constants import TWO_PI
from ucbplan.observing.blocks.arrays import BlockColumns, BlockList
from ucbplan.observing.constraints.checks import SAMPLE_STEP_S
from ucbplan.observing.observatory.sites import Site
from ucbplan.observing.observatory.sky import airmass_from_alt
from ucbplan.observing.precision.instruments import MAX_AIRMASS
from ucbplan.observing.schedule.candidates import PlanFrame, TargetRun
from ucbplan.observing.schedule.exposure import exposure_sigma_v
from ucbplan.observing.schedule.nights import NightSpan
from ucbplan.observing.schedule.placement import Session
from ucbplan.observing.schedule.settings import PlanSettings

FloatArray = NDArray[np.float64]


def slug(name: str) -> str:
    """A target name as an identifier part: runs of other characters → ``_``."""
    return re.sub(r"[^A-Za-z0-9]+", "_", name).strip("_") or "target"


class BlockLabels(NamedTuple):
    """Night labels, block, session and visit identifiers of blocks (text arrays)."""

    night: NDArray[np.str_]
    block_id: NDArray[np.str_]
    session_id: NDArray[np.str_]
    visit_id: NDArray[np.str_]


def _occurrence(keys: NDArray[np.int64]) -> NDArray[np.int64]:
    """1, 2, …: the how-many-th occurrence of its key each element is, in order."""
    order = np.argsort(keys, kind="stable")
    ordered = keys[order]
    new = np.flatnonzero(np.concatenate([[True], ordered[1:] != ordered[:-1]]))
    first = np.repeat(new, np.diff(np.append(new, keys.size)))
    out = np.empty_like(keys)
    out[order] = np.arange(keys.size) - first + 1
    return out


def _texts(prefix: NDArray[np.str_], tag: str, number: NDArray[np.int64]) -> NDArray[np.str_]:
    """``<prefix>-<tag><number, two digits at least>`` of each element."""
    digits = np.array([f"{k:02d}" for k in range(int(number.max()) + 1)])
    return np.char.add(np.char.add(prefix, f"-{tag}"), digits[number])


def _narrow(text: NDArray[np.str_]) -> NDArray[np.str_]:
    """``text`` as ``np.array(text.tolist(), dtype=str)`` makes it: as wide as its longest."""
    return text.astype(f"U{max(1, int(np.char.str_len(text).max()))}")


def _labels(
    placed: list[Session], runs: list[TargetRun], spans: list[NightSpan]
) -> dict[int, tuple[NDArray[np.int64], BlockLabels]]:
    """Candidate indices and labels of the placed blocks, per target (in target order):
    blocks and sessions numbered per target and night in the order of the session starts
    (equal starts in placement order)."""
    if not placed:
        return {}
    order = sorted(range(len(placed)), key=lambda k: (placed[k].target_i, placed[k].x0))
    sessions = [placed[k] for k in order]
    size = np.array([len(s.idx) for s in sessions], dtype=np.int64)
    key = np.array([s.target_i * len(spans) + s.night_i for s in sessions], dtype=np.int64)
    keys, inverse = np.unique(key, return_inverse=True)
    heads = [
        f"{slug(runs[k // len(spans)].target.name)}-{spans[k % len(spans)].label.replace('-', '')}"
        for k in keys.tolist()
    ]
    which = np.repeat(inverse.ravel(), size)  # per block: its target/night, as an index of keys
    prefix = np.array(heads)[which]
    number = np.repeat(_occurrence(key), size)
    nights = np.array([spans[k % len(spans)].label for k in keys.tolist()])[which]
    labels = BlockLabels(
        nights,
        _texts(prefix, "", _occurrence(key[np.repeat(np.arange(key.size), size)])),
        _texts(prefix, "S", number),
        _texts(prefix, "V", number),
    )
    js = np.fromiter((j for s in sessions for j in s.idx), dtype=np.int64, count=int(size.sum()))
    target = keys[which] // len(spans)
    out = {}
    for i in np.unique(target).tolist():
        mine = np.flatnonzero(target == i)
        out[i] = js[mine], BlockLabels(*(_narrow(text[mine]) for text in labels))
    return out


@dataclass(frozen=True)
class _Geometry:
    """Per-block arrays: altitude and airmass at start/middle/end, Moon, times."""

    alt: FloatArray  # (n, 3) [deg]
    airmass: FloatArray  # (n, 3)
    moon_sep: FloatArray  # smallest over the block [deg]
    moon_illum: FloatArray
    utc: Time  # (n, 4): start, middle, end, π-mode alternative
    tdb: Time  # (n,) barycentric anchor epochs
    sigma_v: FloatArray  # σ_v per exposure at the block-centre airmass [km/s]


def _geometry(
    run: TargetRun, js: NDArray[np.int64], frame: PlanFrame, settings: PlanSettings
) -> _Geometry:
    """Geometry and times of candidates ``js`` (one vectorised pass per target)."""
    c, sky, i, plan = run.cand, frame.sky, run.index, run.exposure.plan
    span_s = plan.span_s
    xs = np.stack([c.x_start[js], c.x_mid[js], c.x_end[js]], axis=1)
    alt = sky.target_alt_deg(i, xs)
    n_s = max(3, math.ceil(span_s / SAMPLE_STEP_S) + 1)
    fine = c.x_start[js][:, None] + np.linspace(0, 1, n_s)[None, :] * span_s
    # a timing ephemeris has no π-mode alternative (NaN): keep the time conversion finite
    x_alt = np.where(np.isfinite(c.x_alt[js]), c.x_alt[js], c.x_mid[js])
    x_all = np.concatenate([xs, x_alt[:, None]], axis=1)
    airmass = airmass_from_alt(alt)
    x_sigma = np.clip(airmass[:, 1], 1.0, MAX_AIRMASS)
    return _Geometry(
        alt=alt,
        airmass=airmass,
        moon_sep=np.min(sky.moon_sep_deg(i, fine), axis=1),
        moon_illum=sky.moon_illum(c.x_mid[js]),
        utc=frame.axis.utc(x_all),
        tdb=c.epochs.time(c.tau_origin_s, c.dt_s[js]),
        sigma_v=exposure_sigma_v(run.target, settings, plan.exptime_s, x_sigma),
    )


def _columns(
    run: TargetRun,
    g: _Geometry,
    js: NDArray[np.int64],
    labels: BlockLabels,
    anchor: str,
    site: Site,
) -> BlockColumns:
    """The placed blocks ``js`` of one target as columns (one array per Block field)."""
    t, sm, c, plan = run.target, run.smearing, run.cand, run.exposure.plan
    n = js.size

    def full(value: object, kind: type = float) -> NDArray[Any]:
        if kind is str:  # the string's own length (dtype=str would cut it to one character)
            return np.full(n, str(value))
        return np.full(n, value, dtype=kind)

    night, block_id, session_id, visit_id = labels
    values: dict[str, NDArray[Any]] = {
        "target": full(t.name, str),
        "block_id": block_id,
        "anchor": full(anchor, str),
        "u_star_rad": np.mod(c.u_star[js], TWO_PI),
        "sigma_t_s": np.asarray(c.sigma_t_s[js], dtype=float),
        "exptime_s": full(plan.exptime_s),
        "n_exp": full(plan.n_exp, int),
        "readout_s": full(plan.readout_s),
        "lambda_k": full(sm.lambda_k),
        "lambda_kappa": full(sm.lambda_kappa),
        "smear_kms": full(sm.smear_kms),
        "alt_start_deg": g.alt[:, 0],
        "altitude_deg": g.alt[:, 1],
        "alt_end_deg": g.alt[:, 2],
        "airmass_start": g.airmass[:, 0],
        "airmass": g.airmass[:, 1],
        "airmass_end": g.airmass[:, 2],
        "moon_sep_deg": np.asarray(g.moon_sep, dtype=float),
        "moon_illum": np.asarray(g.moon_illum, dtype=float),
        "ra_deg": full(t.ra_deg),
        "dec_deg": full(t.dec_deg),
        "night": night,
        "timezone": full(site.timezone, str),
        "period_s": full(t.period_s),
        "priority": full(t.priority),
        "session_id": session_id,
        "pair_id": full("", str),
        "delta_kappa": full(np.nan),
        "visit_id": visit_id,
        "sigma_v_kms": np.broadcast_to(np.asarray(g.sigma_v, dtype=float), (n,)).copy(),
    }
    times = {
        "t_mid_utc": g.utc[:, 1],
        "t_start_utc": g.utc[:, 0],
        "t_end_utc": g.utc[:, 2],
        "t_mid_tdb_bary": g.tdb,
        "t_alt_utc": g.utc[:, 3],
    }
    return BlockColumns(values, times, np.isfinite(c.x_alt[js]))


def block_records(
    placed: list[Session],
    runs: list[TargetRun],
    spans: list[NightSpan],
    frame: PlanFrame,
    site: Site,
    settings: PlanSettings,
) -> BlockList:
    """Block records of the placed sessions, grouped by target (in target order), as columns
    (:class:`~ucbplan.observing.blocks.arrays.BlockList`)."""
    parts: list[BlockColumns] = []
    for i, (js, labels) in _labels(placed, runs, spans).items():
        g = _geometry(runs[i], js, frame, settings)
        untargeted = runs[i].exposure.strategy == "untargeted"
        anchor = "untargeted" if untargeted else frame.mode.label
        parts.append(_columns(runs[i], g, js, labels, anchor, site))
    return BlockList(BlockColumns.concat(parts))
