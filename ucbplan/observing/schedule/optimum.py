"""Exact optimum of a small scheduling instance (a MILP) and the greedy placement rule on it.

An :class:`Instance` is what the planner's placement sees once candidates are built: candidate
sessions (target, night, start, end on one time axis [s], a score the greedy sorts by and a
scientific value), the target priorities, at most ``per_night`` sessions per target and night, a
time budget per target, and the slew/acquisition overhead that must separate any two sessions.

:func:`optimum` solves it exactly with :func:`scipy.optimize.milp`: maximise Σ vᵢ xᵢ over
xᵢ ∈ {0, 1} subject to

* non-overlap: each session occupies [x0, x1 + overhead) (half-open, the rule of
  :mod:`.placement`); sessions conflict when these intervals overlap. The conflict graph is an
  interval graph, so one clique constraint Σ xᵢ ≤ 1 per start point (all sessions whose interval
  holds it) is exact;
* Σ xᵢ ≤ ``per_night`` over each target's sessions in each night;
* Σ (x1 − x0)ᵢ xᵢ ≤ ``budget_s`` over each target's sessions.

:func:`greedy` applies the planner's placement rule to the same instance (targets by priority,
ties in input order; nights in order; a night's sessions by increasing score; a session is taken
when it keeps the overhead clear of everything taken and fits the night cap and the budget), so
the two can be compared (docs/scheduling.md).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy import sparse
from scipy.optimize import Bounds, LinearConstraint, milp

from ucbplan.core.constants import DAY_S
from ucbplan.errors import NumericalError
from ucbplan.observing.schedule.placement import Timeline

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: Largest instance :func:`optimum` accepts (candidate sessions): the MILP is exact, not fast.
MAX_MILP_SESSIONS = 5000


@dataclass(frozen=True)
class Instance:
    """Candidate sessions of several targets over several nights (one entry per session).

    Attributes
    ----------
    target, night : ndarray of int
        Target index (into ``priority`` and ``budget_s``) and night index of each session.
    x0, x1 : ndarray of float
        Session start and end [s on one time axis].
    score : ndarray of float
        What the greedy sorts a night's sessions by, lowest first (the worst airmass).
    value : ndarray of float
        Scientific value of each session (any non-negative unit; summed).
    priority : ndarray of float
        Per target; higher is placed first by the greedy.
    budget_s : ndarray of float
        Per target, the most time its sessions may take [s] (``inf``: no budget).
    per_night : int
        Most sessions per target and night.
    overhead_s : float
        Slew/acquisition time kept clear before every session [s].
    """

    target: IntArray
    night: IntArray
    x0: FloatArray
    x1: FloatArray
    score: FloatArray
    value: FloatArray
    priority: FloatArray
    budget_s: FloatArray
    per_night: int
    overhead_s: float

    @property
    def size(self) -> int:
        """Number of candidate sessions."""
        return int(self.x0.size)


@dataclass(frozen=True)
class Solution:
    """Chosen sessions (boolean mask over the instance) and their total value."""

    chosen: NDArray[np.bool_]
    value: float


def _conflict_rows(inst: Instance) -> sparse.csr_array:
    """One clique row per session start: every session whose [x0, x1 + overhead) holds it."""
    gap = max(inst.overhead_s, 0.0)
    starts, ends = inst.x0, inst.x1 + gap
    holds = (starts[None, :] <= starts[:, None]) & (starts[:, None] < ends[None, :])
    rows = np.unique(holds, axis=0)  # identical cliques once
    return sparse.csr_array(rows[rows.sum(axis=1) > 1].astype(np.float64))


def _group_rows(keys: IntArray, weights: FloatArray) -> sparse.csr_array:
    """One row per distinct key, holding ``weights`` on its sessions."""
    uniq, inv = np.unique(keys, return_inverse=True)
    cols = np.arange(keys.size)
    return sparse.csr_array((weights, (inv, cols)), shape=(uniq.size, keys.size))


def optimum(inst: Instance) -> Solution:
    """The exact best schedule of ``inst`` (largest total value), by mixed-integer programming.

    Raises
    ------
    NumericalError
        If the instance is larger than :data:`MAX_MILP_SESSIONS` or the solver fails.
    """
    n = inst.size
    if n == 0:
        return Solution(np.zeros(0, dtype=bool), 0.0)
    if n > MAX_MILP_SESSIONS:
        raise NumericalError(
            f"optimum: {n} candidate sessions is more than {MAX_MILP_SESSIONS}; the exact "
            "schedule is for small instances (fewer targets or nights)"
        )
    nights = int(inst.night.max()) + 1
    cap = _group_rows(inst.target * nights + inst.night, np.ones(n))
    budget = _group_rows(inst.target, inst.x1 - inst.x0)
    constraints = [
        LinearConstraint(cap, -np.inf, float(inst.per_night)),
        LinearConstraint(budget, -np.inf, inst.budget_s[np.unique(inst.target)]),
    ]
    conflicts = _conflict_rows(inst)
    if conflicts.shape[0]:
        constraints.append(LinearConstraint(conflicts, -np.inf, 1.0))
    res = milp(
        -inst.value,
        constraints=constraints,
        integrality=np.ones(n),
        bounds=Bounds(0.0, 1.0),
    )
    if res.x is None or not res.success:
        raise NumericalError(f"optimum: the MILP solver failed ({res.message})")
    chosen = np.asarray(res.x > 0.5)
    return Solution(chosen, float(inst.value[chosen].sum()))


def greedy(inst: Instance) -> Solution:
    """The planner's placement rule (:func:`~.placement.place_sessions`) applied to ``inst``,
    with the per-target time budget: a session that would exceed it is skipped."""
    timeline = Timeline(inst.overhead_s)
    chosen = np.zeros(inst.size, dtype=bool)
    for t in sorted(range(inst.priority.size), key=lambda k: -inst.priority[k]):
        used = 0.0
        for n in np.unique(inst.night):
            js = np.flatnonzero((inst.target == t) & (inst.night == n))
            js = js[np.argsort(inst.x0[js], kind="stable")]
            count = 0
            for j in js[np.argsort(inst.score[js], kind="stable")]:
                dur = float(inst.x1[j] - inst.x0[j])
                if count >= inst.per_night or used + dur > inst.budget_s[t]:
                    continue
                if timeline.free(float(inst.x0[j]), float(inst.x1[j])):
                    timeline.take(float(inst.x0[j]), float(inst.x1[j]))
                    chosen[j], count, used = True, count + 1, used + dur
    return Solution(chosen, float(inst.value[chosen].sum()))


def is_feasible(inst: Instance, chosen: NDArray[np.bool_]) -> bool:
    """Whether the sessions ``chosen`` keep every rule of ``inst`` (checked pairwise)."""
    idx = np.flatnonzero(chosen)
    gap = max(inst.overhead_s, 0.0)
    for a in idx:
        for b in idx:
            if a < b and inst.x0[b] < inst.x1[a] + gap and inst.x0[a] < inst.x1[b] + gap:
                return False
    for t in np.unique(inst.target):
        mine = idx[inst.target[idx] == t]
        if float((inst.x1[mine] - inst.x0[mine]).sum()) > inst.budget_s[t] * (1 + 1e-12):
            return False
        if mine.size and np.bincount(inst.night[mine]).max() > inst.per_night:
            return False
    return True


#: Extinction used by :func:`random_instance` to turn airmass into value [mag per airmass]: a
#: photon-limited spectrum's RV information scales with the flux, 10^(−0.4 k (X − 1)).
_EXTINCTION_MAG = 0.2


def random_instance(seed: int, n_targets: int = 3, n_nights: int = 2) -> Instance:
    """A random small instance (seeded): phase-locked candidates of binaries with 5-25 min
    orbits, one candidate per half orbit inside each target's 2-4 h window per night.

    The value of a session is its target's priority (1, 2 or 3) times the RV information kept
    after extinction, 10^(−0.4·0.2·(X − 1)); the score is the airmass X (a parabola in time from
    1 at the window centre to 2.2 at its edges). Budgets are 40-100 % of what the caps allow
    (none for a third of the targets); overhead 0-600 s; 2-8 sessions per target and night.
    """
    rng = np.random.default_rng(seed)
    cols: dict[str, list[FloatArray]] = {k: [] for k in ("t", "n", "x0", "x1", "X")}
    durations = np.zeros(n_targets)
    for t in range(n_targets):
        period = rng.uniform(300.0, 1500.0)
        durations[t] = rng.uniform(60.0, 0.45 * period)
        for n in range(n_nights):
            width = rng.uniform(7200.0, 14400.0)
            centre = n * DAY_S + rng.uniform(width / 2, 28800.0 - width / 2)
            mids = np.arange(centre - width / 2, centre + width / 2, period / 2)
            mids = mids + rng.uniform(0.0, period / 2)
            mids = mids[mids < centre + width / 2]
            cols["t"].append(np.full(mids.size, t, dtype=np.float64))
            cols["n"].append(np.full(mids.size, n, dtype=np.float64))
            cols["x0"].append(mids - durations[t] / 2)
            cols["x1"].append(mids + durations[t] / 2)
            cols["X"].append(1.0 + 1.2 * ((mids - centre) / (width / 2)) ** 2)
    target = np.concatenate(cols["t"]).astype(np.int64)
    airmass = np.concatenate(cols["X"])
    priority = rng.integers(1, 4, n_targets).astype(np.float64)
    per_night = int(rng.integers(2, 9))
    budget = rng.uniform(0.4, 1.0, n_targets) * per_night * n_nights * durations
    budget[rng.random(n_targets) < 1 / 3] = np.inf
    return Instance(
        target=target,
        night=np.concatenate(cols["n"]).astype(np.int64),
        x0=np.concatenate(cols["x0"]),
        x1=np.concatenate(cols["x1"]),
        score=airmass,
        value=priority[target] * 10 ** (-0.4 * _EXTINCTION_MAG * (airmass - 1.0)),
        priority=priority,
        budget_s=budget,
        per_night=per_night,
        overhead_s=float(rng.uniform(0.0, 600.0)),
    )
