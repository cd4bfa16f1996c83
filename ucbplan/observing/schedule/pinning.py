"""Visits a replan keeps: the old plan's visits on the surviving nights, placed before any new one.

An observer prefers a schedule that moves little (issue 32). A replan gives the old plan's visits
on the nights it plans again (``PlanSettings.pinned``: per visit, its target and the UTC starts of
its exposures); each one whose exposures are still candidate exposures of the new plan (the same
anchors, within :data:`_MATCH_S`) is placed first, at the same start, and its information counts
toward the goal. Pinned visits a goal does not need are dropped, the least information per hour
first, only while the others still reach it; new visits add what is still missing.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from astropy.time import Time

from ucbplan.observing.schedule.candidates import PlanFrame, TargetRun
from ucbplan.observing.schedule.nights import NightSpan
from ucbplan.observing.schedule.placement import Allowance, Session, Timeline
from ucbplan.observing.schedule.settings import PlanSettings

#: How far a kept exposure's start may lie from a candidate exposure's of the new plan [s]
#: (the same anchor: anchors are a step of ≥ 1 min apart; rounding of the text table is 1 ms).
_MATCH_S = 1.0


def _session(
    run: TargetRun, starts: Sequence[str], spans: list[NightSpan], frame: PlanFrame, acq: float
) -> Session | None:
    """The session of a kept visit (its exposures matched to candidates), or None when one of
    them is no candidate exposure of the new plan."""
    c = run.cand
    x = np.atleast_1d((Time(list(starts), scale="utc") - frame.axis.origin).to_value("s"))
    j = np.clip(np.searchsorted(c.x_start, x), 1, c.x_start.size - 1)
    j = np.where(np.abs(c.x_start[j - 1] - x) < np.abs(c.x_start[j] - x), j - 1, j)
    good = (run.ok > 0) & run.valid
    if np.any(np.abs(c.x_start[j] - x) > _MATCH_S) or not np.all(good[j]):
        return None
    x0, x1 = float(c.x_start[j[0]]) - acq, float(c.x_end[j[-1]]) + run.exposure.plan.readout_s
    night = [n for n, sp in enumerate(spans) if sp.x0 <= x0 < sp.x1]
    return Session(run.index, night[0], tuple(int(k) for k in j), x0, x1) if night else None


def _needed(run: TargetRun, sessions: list[Session], allowance: Allowance) -> list[Session]:
    """``sessions`` less those a goal reached without them does not need (least information
    per hour first)."""
    if allowance.info is None:
        return sessions
    info = {s: float(np.nansum(run.weight[list(s.idx)])) for s in sessions}
    total = sum(info.values())
    kept = list(sessions)
    for s in sorted(sessions, key=lambda s: info[s] / max(s.x1 - s.x0, 1e-9)):
        if total - info[s] >= allowance.info:
            kept.remove(s)
            total -= info[s]
    return kept


def pin_visits(
    runs: Sequence[TargetRun],
    spans: list[NightSpan],
    frame: PlanFrame,
    settings: PlanSettings,
    timeline: Timeline,
    allowances: Mapping[int, Allowance] | None,
) -> None:
    """Place the kept visits of ``settings.pinned`` in ``timeline`` and charge their targets'
    allowances (module notes)."""
    for run in runs:
        visits = [starts for name, starts in settings.pinned if name == run.target.name]
        sessions = [_session(run, s, spans, frame, settings.overhead_s) for s in visits]
        allowance = (allowances or {}).get(run.index) or Allowance()
        for s in _needed(run, [s for s in sessions if s], allowance):
            if timeline.add(s):
                allowance.charge(len(s.idx), s.x1 - s.x0, float(np.nansum(run.weight[list(s.idx)])))
