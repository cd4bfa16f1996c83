"""Visits: one acquisition, then continuous exposures, each centred on an anchor epoch.

A visit of length D (``--visit``, acquisition included) starts with the acquisition (slew +
acquisition + set-up, ``overhead_s``) that ends when the first exposure starts; each exposure is
centred on an anchor epoch, and the next exposure is the first anchor whose exposure starts at
least one readout after the previous one ends (:mod:`.exposure` gives the cadence). The visit
ends with the readout of its last exposure, at most D after it started. Every exposure satisfies
every constraint over its whole length and lies inside the validity window; the acquisition is
in the night, within the airmass and altitude limits and outside the zenith hole too; a visit
stops at the first anchor that fails.

Targets are taken in priority order; in each night a target gets its best visits (most
exposures, then lowest mean airmass) that keep clear of everything placed before, up to
``sessions_per_night`` visits, or until its quota of exposures (a ``--goal``) is planned. A
replan that changes the plan (``goal_slack`` > 0) fills a goal's nights in the order of the
information per hour of their best visit, not in date order: the fewest hours for what is
still missing.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from numpy.typing import NDArray

from ucbplan.observing.constraints.checks import evaluate_window
from ucbplan.observing.schedule.candidates import PlanFrame, TargetRun
from ucbplan.observing.schedule.nights import NightSpan
from ucbplan.observing.schedule.pinning import pin_visits
from ucbplan.observing.schedule.placement import (
    INFO_RTOL,
    Allowance,
    NightTask,
    Session,
    Timeline,
    Unplaced,
    night_usable,
    place_by_priority,
)
from ucbplan.observing.schedule.settings import PlanSettings

#: Slack on the readout between two exposures [s]: the light time moves anchors by up to ~0.02 s
#: per minute, so a phase-locked cadence may find the next exposure starting a hair early.
_READOUT_SLACK_S = 0.1


def _chain(
    j: int,
    nxt: NDArray[np.int64],
    good: NDArray[np.bool_],
    x_start: NDArray[np.float64],
    x_end: NDArray[np.float64],
    end_limit: float,
    readout_s: float,
    cap: int,
) -> list[int]:
    """Exposures of the visit whose first exposure is anchor ``j`` (anchor indices)."""
    out = [j]
    n = x_start.size
    while len(out) < cap:
        k = int(nxt[out[-1]])
        if k >= n or not good[k] or x_end[k] + readout_s > end_limit:
            break
        out.append(k)
    return out


def _goal_cut(exps: list[int], weight: NDArray[np.float64], need: float, pattern: int) -> None:
    """Drop the exposures a goal does not need: keep the fewest whose information reaches
    ``need``, in whole anchor patterns (``pattern`` > 1) when the visit has that many."""
    cum = np.cumsum(np.nan_to_num(weight[exps]))
    keep = int(np.searchsorted(cum, need * (1.0 - INFO_RTOL))) + 1
    if pattern > 1 and keep % pattern:
        keep += pattern - keep % pattern
    del exps[keep:]


def _whole_patterns(exps: list[int], pattern: int) -> None:
    """Drop the exposures past the last whole anchor pattern (a visit of more than one)."""
    if len(exps) > pattern:
        del exps[len(exps) - len(exps) % pattern :]


def _visit_key(run: TargetRun, exps: list[int]) -> tuple[float, float]:
    """How good a visit is: its information for back-to-back exposures (their phases differ),
    else its number of exposures; then the lower mean airmass."""
    airmass = -float(np.mean(run.cand.airmass_mid[exps]))
    if run.exposure.strategy == "untargeted":
        return round(float(np.nansum(run.weight[exps])), 12), airmass
    return float(len(exps)), airmass


def _replan_key(
    run: TargetRun, exps: list[int], allowance: Allowance, wall_s: float
) -> tuple[float, float, float]:
    """How good a visit of a replan's goal is: the information it brings toward what is still
    missing, then the shorter visit to the second (a visit that reaches the goal with fewer
    exposures beats a longer one, which :func:`_visit_key` would prefer), then the lower mean
    airmass (a σ_v fixed per exposure ties the information)."""
    info = float(np.nansum(run.weight[exps]))
    if allowance.info is not None:
        info = min(info, allowance.info * (1.0 - INFO_RTOL))
    return round(info, 12), -round(wall_s), -float(np.mean(run.cand.airmass_mid[exps]))


def _best_visit(
    run: TargetRun,
    span: NightSpan,
    timeline: Timeline,
    frame: PlanFrame,
    settings: PlanSettings,
    allowance: Allowance,
) -> tuple[tuple[int, ...], float, float] | None:
    """The best free visit of ``run`` in a night within its allowance: (exposures, start,
    end) or None."""
    c, te = run.cand, run.exposure
    acq, r, visit_s = settings.overhead_s, te.plan.readout_s, float(te.visit_s or 0.0)
    j0, j1 = np.searchsorted(c.x_mid, [span.x0, span.x1])
    if j1 == j0:
        return None
    good = (run.ok > 0) & run.valid
    js = np.arange(j0, j1)
    acq_cs = frame.constraints.pointing  # the zenith hole too (issue 33)
    acq_ok, _ = evaluate_window(
        acq_cs, frame.sky, run.index, c.x_start[js] - acq, c.x_start[js], frame.night
    )
    starts = js[good[js] & acq_ok]
    nxt = np.searchsorted(c.x_start, c.x_end + r - _READOUT_SLACK_S, side="left")
    best: tuple[tuple[int, ...], float, float] | None = None
    best_key: tuple[float, ...] = (0.0, 0.0)
    pattern = len(settings.spec.u_values) if te.strategy != "untargeted" else 1
    cap = c.x_mid.size if allowance.exposures is None else allowance.exposures
    cap = min(cap, allowance.share(pattern) or cap)
    length = visit_s if allowance.seconds is None else min(visit_s, allowance.seconds)
    fastest = settings.goal_slack > 0 and allowance.info is not None
    for j in starts:
        x0 = float(c.x_start[j]) - acq
        exps = _chain(int(j), nxt, good, c.x_start, c.x_end, x0 + length, r, cap)
        if exps and float(c.x_end[exps[-1]]) + r > x0 + length:
            exps = []  # not even one exposure fits the time budget left
        while exps and not timeline.free(x0, float(c.x_end[exps[-1]]) + r):
            exps.pop()
        if allowance.info is not None and exps:
            _goal_cut(exps, run.weight, allowance.info, 1 if fastest else pattern)
        elif allowance.exposures is not None:
            _whole_patterns(exps, pattern)  # an exposure cap: whole patterns
        if not exps:
            continue
        x1 = float(c.x_end[exps[-1]]) + r
        key = _replan_key(run, exps, allowance, x1 - x0) if fastest else _visit_key(run, exps)
        if best is None or key > best_key:
            best, best_key = (tuple(exps), x0, x1), key
    return best


def _place_night(run: TargetRun, night: NightTask) -> str | None:
    """Place one target's visits in a night within its allowance; the reason if fewer."""
    n, span, timeline, frame, settings, allowance, sun = night
    usable = night_usable(run, span, frame, settings, sun)
    if isinstance(usable, str):
        return usable
    wanted = settings.sessions_per_night
    placed = 0  # a replan's kept visits of this night count (sessions_per_night)
    if settings.pinned:
        placed = sum(1 for s in timeline.placed if s.target_i == run.index and s.night_i == n)
    while placed < wanted and not allowance.spent:
        pick = _best_visit(run, span, timeline, frame, settings, allowance)
        if pick is None:
            break
        idx, x0, x1 = pick
        timeline.add(Session(run.index, n, idx, x0, x1))
        allowance.charge(len(idx), x1 - x0, float(np.nansum(run.weight[list(idx)])))
        placed += 1
    if allowance.spent and (allowance.exposures is not None or allowance.info is not None):
        return None  # the goal is planned
    if allowance.spent or (placed < wanted and allowance.seconds is not None and placed > 0):
        return f"time budget spent after {placed} visit(s)"
    if placed == 0:
        return (
            "every usable visit overlaps higher-priority visits (or its acquisition falls in "
            "twilight or above the airmass limit)"
        )
    if placed < wanted:
        return f"only {placed} of {wanted} visits fit"
    return None


def _cheapest_first(run: TargetRun, tasks: Sequence[NightTask]) -> list[int]:
    """A goal's nights, the one whose best free visit collects the most information per hour
    first (a replan books the fewest hours for what is still missing; ties in night order)."""
    rate = []
    for task in tasks:
        _, span, timeline, frame, settings, allowance, sun = task
        pick = None
        if allowance.info is not None and not isinstance(
            night_usable(run, span, frame, settings, sun), str
        ):
            pick = _best_visit(run, span, timeline, frame, settings, allowance)
        info = float(np.nansum(run.weight[list(pick[0])])) if pick else 0.0
        rate.append(info / (pick[2] - pick[1]) if pick else 0.0)
    return sorted(range(len(tasks)), key=lambda n: -rate[n])


def place_visits(
    runs: list[TargetRun],
    spans: list[NightSpan],
    frame: PlanFrame,
    settings: PlanSettings,
    busy: Sequence[tuple[float, float]] = (),
    allowances: Mapping[int, Allowance] | None = None,
) -> tuple[list[Session], list[Unplaced]]:
    """Greedy visit schedule: targets by priority, each night's best visits (module notes).

    Parameters
    ----------
    allowances : mapping of int to Allowance, optional
        Exposures (a ``--goal``) and wall time (``--budget``) per target index over all nights;
        planning of a target stops when its allowance is spent (it is spent in place).

    Returns
    -------
    placed : list of Session
        One per visit; ``x0`` is the acquisition start and ``x1`` the end of the last readout.
    unplaced : list of Unplaced
        One entry per target and night that got fewer visits than asked.
    """
    timeline = Timeline(0.0)
    if settings.pinned:  # a replan's kept visits first
        pin_visits(runs, spans, frame, settings, timeline, allowances)
    return place_by_priority(
        runs,
        spans,
        frame,
        settings,
        timeline,
        busy,
        allowances,
        _place_night,
        quiet_goals=True,
        order=_cheapest_first if settings.goal_slack > 0 else None,
    )
