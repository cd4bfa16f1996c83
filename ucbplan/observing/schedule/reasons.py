"""Why anchor epochs were not planned: counts per target, night and reason, kept apart.

Only night-time candidates count: anchor epochs whose centre falls while the Sun is below the
twilight limit (daytime epochs are no loss). Each one that was not planned is counted under the
first reason that applies, in this order:

1. ``outside validity`` — σ_u(t) > α·δu_tol at its own epoch (before or after the reference);
2. ``smearing floor`` — no exposure of the target keeps Λ_K ≥ the floor;
3. the first constraint it fails over its exposure: ``daylight/twilight`` (it runs into
   twilight), ``altitude/airmass``, ``zenith hole``, ``Moon separation``, ``Moon illumination``,
   ``other constraint`` (one of the user's own or astroplan's);
4. ``taken by a higher-priority target`` — it overlaps a visit or session of another target
   (with the acquisition before it);
5. ``time budget spent`` — the target's ``--budget`` was used up;
6. ``not needed`` — usable, but the night's visits/sessions (or the goal) were already planned.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from ucbplan.observing.constraints.checks import evaluate_window
from ucbplan.observing.schedule.candidates import PlanFrame, TargetRun
from ucbplan.observing.schedule.nights import NightSpan
from ucbplan.observing.schedule.placement import Session, Unplaced

#: The reasons, in the order they are tried.
REASONS = (
    "outside validity",
    "smearing floor",
    "daylight/twilight",
    "altitude/airmass",
    "zenith hole",
    "Moon separation",
    "Moon illumination",
    "other constraint",
    "taken by a higher-priority target",
    "time budget spent",
    "not needed",
)
#: Constraint name → reason.
_BY_CONSTRAINT = {
    "night": "daylight/twilight",
    "airmass": "altitude/airmass",
    "altitude": "altitude/airmass",
    "zenith-hole": "zenith hole",
    "moon-sep": "Moon separation",
    "moon-illum": "Moon illumination",
}


def _overlaps(
    x0: NDArray[np.float64], x1: NDArray[np.float64], taken: list[tuple[float, float]]
) -> NDArray[np.bool_]:
    """Whether each [x0, x1] overlaps one of the ``taken`` intervals."""
    if not taken:
        return np.zeros(x0.shape, dtype=bool)
    ordered = sorted(taken)
    starts = np.array([a for a, _ in ordered])
    ends = np.maximum.accumulate(np.array([b for _, b in ordered]))
    k = np.searchsorted(starts, x1, side="left")  # intervals starting before our end
    return (k > 0) & (ends[np.maximum(k - 1, 0)] > x0)


def _reason_codes(run: TargetRun, frame: PlanFrame) -> NDArray[np.int64]:
    """Index into :data:`REASONS` of the first reason up to 'taken' for every candidate of
    ``run`` (−1: usable; module notes), in one vectorised pass."""
    c = run.cand
    tau = c.tau_origin_s + c.dt_s
    valid = (tau >= c.epochs.tau(run.since)) & (tau <= c.epochs.tau(run.until))
    names = [con.name for con in frame.constraints.active]
    by_index = np.array(
        [REASONS.index(_BY_CONSTRAINT.get(n, "other constraint")) for n in names] or [-1],
        dtype=np.int64,
    )
    code = np.where(c.ok, -1, by_index[np.maximum(c.first_failed, 0)])
    if not run.exposure.floor_ok:
        code = np.full(code.shape, REASONS.index("smearing floor"), dtype=np.int64)
    return np.where(valid, code, REASONS.index("outside validity")).astype(np.int64)


def _counts_per_night(
    x_mid: NDArray[np.float64],
    counted: NDArray[np.bool_],
    codes: NDArray[np.int64],
    spans: Sequence[NightSpan],
) -> NDArray[np.int64]:
    """(night, reason) counts of the ``counted`` candidates (time-sorted): column
    ``len(REASONS)`` counts the usable ones (code −1). Nights in order and apart hold each
    candidate at most once: one count per (night, reason) cell; others by running sums."""
    klass = np.where(codes < 0, len(REASONS), codes)
    j0 = np.searchsorted(x_mid, [sp.x0 for sp in spans])
    j1 = np.searchsorted(x_mid, [sp.x1 for sp in spans])
    if not np.all(j0[1:] >= j1[:-1]):
        return _counts_by_sums(counted, klass, j0, j1)
    at = np.flatnonzero(counted)
    night = np.searchsorted(j0, at, side="right") - 1  # the last night starting at or before
    keep = (night >= 0) & (at < j1[np.maximum(night, 0)])
    cells = night[keep] * (len(REASONS) + 1) + klass[at[keep]]
    table = np.bincount(cells, minlength=len(spans) * (len(REASONS) + 1))
    return np.asarray(table.reshape(len(spans), len(REASONS) + 1), dtype=np.int64)


def _counts_by_sums(
    counted: NDArray[np.bool_],
    klass: NDArray[np.int64],
    j0: NDArray[np.intp],
    j1: NDArray[np.intp],
) -> NDArray[np.int64]:
    """:func:`_counts_per_night` of the candidates ``j0[k]`` … ``j1[k] − 1`` of each night k,
    from running sums over the candidates (nights that overlap)."""
    onehot = np.zeros((klass.size + 1, len(REASONS) + 1), dtype=np.int64)
    at = np.flatnonzero(counted)
    onehot[at + 1, klass[at]] = 1
    prefix = np.cumsum(onehot, axis=0)
    return np.asarray(prefix[j1] - prefix[j0], dtype=np.int64)


def not_planned(
    runs: Sequence[TargetRun],
    spans: Sequence[NightSpan],
    frame: PlanFrame,
    placed: Sequence[Session],
    unplaced: Sequence[Unplaced],
    gap_s: float,
) -> dict[str, dict[str, dict[str, int]]]:
    """{target: {night: {reason: count}}} of the night-time anchor epochs not planned.

    ``gap_s`` is the time kept free before a session of another target (its acquisition);
    visits include their acquisition already (0).
    """
    out: dict[str, dict[str, dict[str, int]]] = {}
    budget = {(m.target, m.night) for m in unplaced if m.reason.startswith("time budget spent")}
    night = frame.constraints.night
    order = [r.index for r in sorted(runs, key=lambda r: -r.target.priority)]
    taken_code, last = REASONS.index("taken by a higher-priority target"), len(REASONS)
    by_target: dict[int, list[Session]] = {}
    for s in placed:
        by_target.setdefault(s.target_i, []).append(s)
    for run in runs:
        c, per_night, mine = run.cand, {}, by_target.get(run.index, [])
        free = np.ones(c.x_mid.size, dtype=bool)
        free[[j for s in mine for j in s.idx]] = False
        before = order[: order.index(run.index)]  # placed before this target
        taken = [(s.x0 - gap_s, s.x1) for t in before for s in by_target.get(t, [])]
        dark = (
            free & evaluate_window([night], frame.sky, run.index, c.x_mid, c.x_mid, frame.night)[0]
        )
        others = _overlaps(c.x_start - gap_s, c.x_end + gap_s, taken)
        codes = _reason_codes(run, frame)
        codes = np.where((codes < 0) & others, taken_code, codes)
        table = _counts_per_night(c.x_mid, dark, codes, spans)
        spent = np.array([(run.target.name, sp.label) in budget for sp in spans], dtype=bool)
        usable = table[:, last]
        table = table[:, :last]
        table[spent, REASONS.index("time budget spent")] += usable[spent]
        table[~spent, REASONS.index("not needed")] += usable[~spent]
        for span, row in zip(spans, table.tolist(), strict=True):
            if any(row):
                per_night[span.label] = {r: k for r, k in zip(REASONS, row, strict=True) if k}
        out[run.target.name] = per_night
    return out
