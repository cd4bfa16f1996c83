"""Block records: placed sessions → named :class:`~ucbplan.observing.blocks.block.Block` rows.

Block and session identifiers are ``<target slug>-<YYYYMMDD>-NN`` and ``...-SNN``, numbered per
target and night in time order. UTC and TDB times come from one vectorised conversion per target
(:class:`~ucbplan.observing.observatory.time_axis.TimeAxis`); geometry from the run's sky model.
"""

from __future__ import annotations

import math
import re
from collections import Counter
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


class BlockLabel(NamedTuple):
    """Night label, block, session and visit identifiers of one block."""

    night: str
    block_id: str
    session_id: str
    visit_id: str


def _labels(
    placed: list[Session], runs: list[TargetRun], spans: list[NightSpan]
) -> dict[int, tuple[list[int], list[BlockLabel]]]:
    """Candidate indices and labels of the placed blocks, per target (in target order)."""
    blocks: Counter[tuple[int, int]] = Counter()
    sessions: Counter[tuple[int, int]] = Counter()
    out: dict[int, tuple[list[int], list[BlockLabel]]] = {}
    prefixes: dict[tuple[int, int], str] = {}  # a dense night holds dozens of sessions
    for s in sorted(placed, key=lambda s: (s.target_i, s.x0)):
        key = (s.target_i, s.night_i)
        label = spans[s.night_i].label
        if key not in prefixes:
            prefixes[key] = f"{slug(runs[s.target_i].target.name)}-{label.replace('-', '')}"
        prefix = prefixes[key]
        js, labels = out.setdefault(s.target_i, ([], []))
        sessions[key] += 1
        session_id = f"{prefix}-S{sessions[key]:02d}"
        visit_id = f"{prefix}-V{sessions[key]:02d}"
        for j in s.idx:
            blocks[key] += 1
            js.append(j)
            labels.append(BlockLabel(label, f"{prefix}-{blocks[key]:02d}", session_id, visit_id))
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
    labels: list[BlockLabel],
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

    empty = np.array([], dtype="U1")
    texts = [np.array(v, dtype=str) for v in zip(*labels, strict=True)] if n else [empty] * 4
    night, block_id, session_id, visit_id = texts
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
    for i, (idx, labels) in _labels(placed, runs, spans).items():
        js = np.asarray(idx, dtype=np.int64)
        g = _geometry(runs[i], js, frame, settings)
        untargeted = runs[i].exposure.strategy == "untargeted"
        anchor = "untargeted" if untargeted else frame.mode.label
        parts.append(_columns(runs[i], g, js, labels, anchor, site))
    return BlockList(BlockColumns.concat(parts))
