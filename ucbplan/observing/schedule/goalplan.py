"""Goal-driven plans: the information on K each target needs for a ``--goal``, in balanced visits.

A goal on σ_K, K1, K2, q or a mass is a goal on the information I = Σ_i w_i on K of the spectra,
w_i = (Λ_K,i cos u_i)²/σ_v,i² (γ's, 1/σ_v,i², for anchors at cos u = 0): every goal quantity's σ
scales as I^{-½} (:mod:`ucbplan.observing.precision.goals`), so the goal needs I = (σ_goal(I =
1)/goal)². Each exposure's σ_v at its own airmass and exposure time enters its w_i exactly; the
visit planner (:mod:`.visits`) plans visits until the information is collected.

Visits are balanced: the spectra a goal is expected to need (at the mean information of the
target's usable exposures) are split as evenly as whole anchor patterns allow over the fewest
visits of at most ``--visit`` (else ``--max-visit``), and each visit is given the length its
share needs. If the nights given hold less, planning fails with one line saying how far short
they fall.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from astropy.time import TimeDelta
from numpy.typing import NDArray

from ucbplan.core.constants import HOUR_S
from ucbplan.errors import InputError
from ucbplan.observing.blocks.arrays import BlockColumns, block_columns
from ucbplan.observing.blocks.block import Block
from ucbplan.observing.precision.goals import (
    Goal,
    GoalPlan,
    Shortfall,
    TimeBudget,
    check_goal_spectra,
    goal_info_needed,
    parse_goal,
    target_k,
)
from ucbplan.observing.precision.observed import ObservedFisher, observed_fisher, target_spectra
from ucbplan.observing.precision.strategy import balanced_counts, constrains_k, information
from ucbplan.observing.schedule.candidates import TargetRun
from ucbplan.observing.schedule.placement import INFO_RTOL
from ucbplan.observing.schedule.settings import PlanSettings

#: Fraction of a goal's information a replan that changes the plan (lost nights, spectra taken
#: given) may leave uncollected (``PlanSettings.goal_slack``): σ within
#: 0.5 % of the goal rather than a whole anchor pattern more (observers replan to the goal, and
#: a knife-edge pattern costs an acquisition's worth of hours for 0.05 % in σ).
REPLAN_INFO_SLACK = 0.01

#: Time added to a balanced visit so that the light-time drift of its anchors (≤ 0.02 s/min)
#: never drops its last exposure [s].
_VISIT_SLACK_S = 1.0


def _per_spectrum(run: TargetRun) -> float:
    """Mean information of one of the target's usable exposures [(km/s)⁻²].

    Raises
    ------
    InputError
        σ_v is unknown (no --sigma-v, instrument reference or target-file σ_v).
    """
    usable = (run.ok > 0) & run.valid & np.isfinite(run.weight)
    w = run.weight[usable] if np.any(usable) else run.weight
    value = float(np.nanmean(w)) if np.any(np.isfinite(w)) else math.nan
    if not math.isfinite(value) or value <= 0:
        raise InputError(
            f"goal: {run.target.name}: sigma_v is unknown; pass `sigma_v` KM_S, or an "
            "`instrument` with sigma_ref and a magnitude in the target file"
        )
    return value


def _max_per_visit(run: TargetRun, settings: PlanSettings) -> tuple[int, float]:
    """(most exposures one visit holds, step between them [s])."""
    te = run.exposure
    visit = te.visit_s if te.visit_s is not None else settings.max_visit_s
    cost = te.plan.exptime_s + te.plan.readout_s
    science = visit - settings.overhead_s - cost
    return max(1, int(science // te.step_s + 1e-9) + 1), te.step_s


def _gamma_ratio(run: TargetRun) -> float:
    """γ-to-K information ratio r = Σ 1/σ_v² / Σ (Λ_K cos u)²/σ_v² of the target's usable
    exposures (:mod:`ucbplan.observing.precision.observed`; ≈ 1/Λ_K² at quadrature anchors)."""
    g2 = (run.exposure.lambda_k * np.cos(run.cand.u_star)) ** 2
    usable = (run.ok > 0) & run.valid & np.isfinite(run.weight) & (g2 > 1e-12)
    if not np.any(usable):
        return 0.0
    return float(np.sum(run.weight[usable] / g2[usable]) / np.sum(run.weight[usable]))


def _collected(run: TargetRun, settings: PlanSettings) -> tuple[ObservedFisher, int]:
    """(Fisher matrix, number) of the target's spectra already taken (``--observed``), each at
    its own u, Λ_K and σ_v (:mod:`ucbplan.observing.precision.observed`).

    Raises
    ------
    InputError
        A spectrum outside the validity window of the target's ephemeris.
    """
    spectra = target_spectra(settings.observed, run.target.name)
    if spectra is None:
        return ObservedFisher(), 0
    t_ref = run.target.t_ref
    lo, hi = ((t - t_ref).to_value("s") for t in (run.since, run.until))
    bad = np.flatnonzero((spectra.tau_s < lo) | (spectra.tau_s > hi))
    if bad.size:
        when = (t_ref + TimeDelta(float(spectra.tau_s[bad[0]]), format="sec")).tdb.isot
        raise InputError(
            f"observed: {spectra.source}: {run.target.name}: spectrum {int(bad[0]) + 1} at "
            f"{when} TDB is outside the validity of its ephemeris ({run.since.tdb.isot} – "
            f"{run.until.tdb.isot} TDB); remove it or update the target file"
        )
    fisher = observed_fisher(spectra, run.target.params, _gamma_ratio(run), settings.star)
    return fisher, spectra.n


def _reached(
    goal: Goal, run: TargetRun, need: float, collected: tuple[ObservedFisher, int]
) -> GoalPlan:
    """The goal plan of a target whose spectra already taken reach the goal: no spectra."""
    fisher, n_taken = collected
    sigma_k = 1.0 / math.sqrt(fisher.alone)
    _, k2, _ = target_k(run.target)
    return GoalPlan(
        goal=goal,
        n_spectra=0,
        per_anchor=(),
        expected=math.sqrt(need) * goal.value * sigma_k,
        sigma_K1_kms=sigma_k,
        sigma_K2_kms=sigma_k if k2 is not None else None,
        time=TimeBudget(0, 0, run.exposure.step_s, 0.0, 0.0, 0.0, 0.0),
        cycles=0,
        info_needed=0.0,
        collected_info=fisher.alone,
        collected_spectra=n_taken,
        collected_fisher=_as_tuple(fisher),
    )


def _as_tuple(fisher: ObservedFisher) -> tuple[float, float, float, float]:
    return (fisher.f_gg, fisher.f_gk, fisher.f_kk, fisher.ratio)


def _target_goal_plan(goal: Goal, run: TargetRun, settings: PlanSettings) -> GoalPlan:
    """Spectra, balanced visits and time of one target's goal (less what was observed)."""
    need_all = goal_info_needed(goal, run.target)
    collected = _collected(run, settings)
    fisher = collected[0]
    # a replan may leave REPLAN_INFO_SLACK of the information (σ within ½ of it of the goal)
    need = fisher.needed(need_all * (1.0 - settings.goal_slack))
    if collected[1] and math.isfinite(need_all) and need <= need_all * INFO_RTOL:
        return _reached(goal, run, need_all, collected)
    w = _per_spectrum(run)
    te = run.exposure
    pattern = len(settings.spec.u_values) if te.strategy != "untargeted" else 1
    check_goal_spectra(goal.text, need / w)
    n = max(1, math.ceil(need / w * (1.0 - 1e-12)))
    n_max, step = _max_per_visit(run, settings)
    counts = balanced_counts(n, n_max, pattern)
    n = sum(counts)
    cost = te.plan.exptime_s + te.plan.readout_s
    walls = [settings.overhead_s + (c - 1) * step + cost for c in counts]
    shutter, readout = n * te.plan.exptime_s, n * te.plan.readout_s
    overhead = len(counts) * settings.overhead_s + readout
    total = sum(walls)
    time = TimeBudget(
        n_visits=len(counts),
        spectra_per_visit=max(counts),
        step_s=step,
        shutter_h=shutter / HOUR_S,
        overhead_h=overhead / HOUR_S,
        idle_h=(total - shutter - overhead) / HOUR_S,
        total_h=total / HOUR_S,
    )
    sigma_k = 1.0 / math.sqrt(fisher.joint(n * w))
    _, k2, _ = target_k(run.target)
    return GoalPlan(
        goal=goal,
        n_spectra=n,
        per_anchor=((settings.spec.label if pattern > 1 else te.strategy, n),),
        expected=math.sqrt(need_all) * goal.value * sigma_k,
        sigma_K1_kms=sigma_k,
        sigma_K2_kms=sigma_k if k2 is not None else None,
        time=time,
        cycles=max(1, n // pattern),
        info_needed=need,
        visit_s=min(max(walls) + _VISIT_SLACK_S, te.visit_s or settings.max_visit_s),
        collected_info=fisher.alone,
        collected_spectra=collected[1],
        collected_fisher=_as_tuple(fisher),
    )


def goal_plans(runs: Sequence[TargetRun], settings: PlanSettings) -> dict[int, GoalPlan]:
    """The :class:`~ucbplan.observing.precision.goals.GoalPlan` of every target (by sky-model
    index); empty without ``--goal``.

    Raises
    ------
    InputError
        A target without K1 (or K2 for a goal on q or the masses), unknown σ_v.
    """
    if settings.goal is None:
        return {}
    goal = parse_goal(settings.goal)
    if not constrains_k(settings.spec.u_values):
        raise InputError(
            f"goal: the anchors of `mode` {settings.spec.label} do not constrain K "
            "(cos u = 0); use `mode` quadrature"
        )
    return {run.index: _target_goal_plan(goal, run, settings) for run in runs}


def balanced_runs(runs: Sequence[TargetRun], plans: dict[int, GoalPlan]) -> list[TargetRun]:
    """``runs`` with each goal target's visit length set to its balanced visit."""
    out = []
    for run in runs:
        plan = plans.get(run.index)
        if plan is not None and plan.visit_s is not None:
            run = replace(run, exposure=replace(run.exposure, visit_s=plan.visit_s))
        out.append(run)
    return out


def info_of_blocks(blocks: Sequence[Block], pattern_u: Sequence[float]) -> float:
    """Information on K of planned blocks, Σ (Λ_K cos u)²/σ_v² (γ's, Σ 1/σ_v², for anchors at
    cos u = 0) [(km/s)⁻²]."""
    return info_of_columns(block_columns(blocks), pattern_u)


def info_of_columns(
    cols: BlockColumns, pattern_u: Sequence[float], rows: NDArray[np.bool_] | None = None
) -> float:
    """:func:`info_of_blocks` of the blocks' columns (``rows``: of those rows only)."""
    pick = slice(None) if rows is None else rows
    lam = np.asarray(cols.values["lambda_k"][pick], dtype=np.float64)
    u = np.asarray(cols.values["u_star_rad"][pick], dtype=np.float64)
    sig = np.asarray(cols.values["sigma_v_kms"][pick], dtype=np.float64)
    untargeted = bool(np.any(cols.values["anchor"][pick] == "untargeted"))
    if not constrains_k(pattern_u) and not untargeted:
        return float(np.nansum(1.0 / sig**2))
    return information(lam, u, sig)


def check_goals(
    plans: dict[int, GoalPlan],
    runs: Sequence[TargetRun],
    blocks: Sequence[Block],
    pattern_u: Sequence[float],
    longer: tuple[float, float, Callable[[], Sequence[Block]]] | None = None,
) -> None:
    """Refuse a plan that does not reach a target's goal (one line: the shortfall).

    ``longer``: (``max_visit`` [s], the longest visit the nights allow [s], a function planning
    with it): when visits were capped by ``max_visit``, the line also gives what visits as long
    as the nights allow collect.

    Raises
    ------
    InputError
        The exposures that fit in the nights given collect less information than the goal needs.
    """
    for run, short in _shortfalls(plans, runs, blocks, pattern_u):
        text = short.message()
        if longer is not None:
            cap_s, long_s, replan = longer
            more = dict(_shortfalls(plans, runs, replan(), pattern_u, by_name=True))
            text = _with_longer_visits(short, more.get(run.target.name), cap_s, long_s)
        raise InputError(f"{run.target.name}: {text}")


@dataclass(frozen=True)
class GoalShortfall:
    """A goal the nights cannot reach, planned as far as they go (a replan states it instead of
    failing).

    Attributes
    ----------
    target : str
        Target name.
    goal : Goal
        The goal.
    reachable : float
        σ of the goal quantity the spectra taken and planned reach (the goal's unit).
    got, needed : float
        Information the planned spectra collect, and would need (Σ (Λ_K cos u)²/σ_v²,
        balanced visits: :meth:`~ucbplan.observing.precision.observed.ObservedFisher.joint`)
        [(km/s)⁻²].
    """

    target: str
    goal: Goal
    reachable: float
    got: float
    needed: float

    def line(self, booked_s: float, n_nights: int) -> str:
        """One line (≤ 100 columns for names up to 24 characters): the σ the nights reach, and
        the hours (at the information per hour of the ``booked_s`` of visits planned on
        ``n_nights``) and nights more that would reach the goal."""
        value = float(f"{self.reachable:.3g}")
        reach = Goal(self.goal.quantity, value, self.goal.relative, "").describe()
        head = f"{self.target[:24]}: {self.goal.text} not reached: {reach.replace(' ≤', ' =')}"
        if self.got <= 0 or booked_s <= 0:
            return f"{head}; no visit fits: add nights"
        hours = (self.needed - self.got) / self.got * booked_s / HOUR_S
        nights = math.ceil(hours / (booked_s / HOUR_S / max(1, n_nights)) - 1e-9)
        return f"{head}; needs {hours:.2g} h (~{nights} night(s)) more"


def goal_shortfalls(
    plans: dict[int, GoalPlan],
    runs: Sequence[TargetRun],
    blocks: Sequence[Block],
    pattern_u: Sequence[float],
) -> list[GoalShortfall]:
    """The goals the planned ``blocks`` do not reach (a replan's statement, not an error)."""
    return [
        GoalShortfall(run.target.name, short.goal, reach, got, need)
        for run, short, got, need, reach in _short_goals(plans, runs, blocks, pattern_u)
    ]


def as_planned(
    plans: dict[int, GoalPlan], runs: Sequence[TargetRun], shortfalls: Sequence[GoalShortfall]
) -> dict[int, GoalPlan]:
    """``plans`` with each goal out of reach expecting the σ its planned spectra reach."""
    reach = {x.target: x.reachable for x in shortfalls}
    out = dict(plans)
    for run in runs:
        plan = plans.get(run.index)
        if plan is not None and run.target.name in reach:
            out[run.index] = _scaled(plan, reach[run.target.name] / plan.expected)
    return out


def as_placed(
    plans: dict[int, GoalPlan],
    runs: Sequence[TargetRun],
    blocks: Sequence[Block],
    pattern_u: Sequence[float],
) -> dict[int, GoalPlan]:
    """``plans`` with each goal expecting what its placed spectra give with those taken (a
    replan places the fewest that reach it, not the estimated count): σ_K = 1/√(F_KK) of the
    joint Fisher matrix at the placed information, the goal's σ scaled alike."""
    cols = block_columns(blocks) if plans else None
    out = dict(plans)
    for run in runs:
        plan = plans.get(run.index)
        if plan is None or plan.info_needed is None or cols is None or not plan.n_spectra:
            continue
        mine = cols.values["target"] == run.target.name
        got = float(
            ObservedFisher(*plan.collected_fisher).joint(info_of_columns(cols, pattern_u, mine))
        )
        if got <= 0:
            continue
        f = got**-0.5 / plan.sigma_K1_kms
        out[run.index] = _scaled(plan, f, n_spectra=int(np.sum(mine)))
    return out


def _scaled(plan: GoalPlan, f: float, **fields: Any) -> GoalPlan:
    """``plan`` with its expected σ, σ_K1 and σ_K2 scaled by ``f`` (and ``fields`` replaced)."""
    k2 = plan.sigma_K2_kms * f if plan.sigma_K2_kms is not None else None
    return replace(
        plan,
        expected=f * plan.expected,
        sigma_K1_kms=f * plan.sigma_K1_kms,
        sigma_K2_kms=k2,
        **fields,
    )


def _shortfalls(
    plans: dict[int, GoalPlan],
    runs: Sequence[TargetRun],
    blocks: Sequence[Block],
    pattern_u: Sequence[float],
    by_name: bool = False,
) -> list[tuple[Any, Shortfall]]:
    """(run, or its target's name with ``by_name``; shortfall) of each goal not reached."""
    return [
        (run.target.name if by_name else run, short)
        for run, short, *_ in _short_goals(plans, runs, blocks, pattern_u)
    ]


def _short_goals(
    plans: dict[int, GoalPlan],
    runs: Sequence[TargetRun],
    blocks: Sequence[Block],
    pattern_u: Sequence[float],
) -> list[tuple[TargetRun, Shortfall, float, float, float]]:
    """(run, shortfall, information got, information needed, σ reached) of each goal not
    reached."""
    cols = block_columns(blocks) if plans else None
    out: list[tuple[TargetRun, Shortfall, float, float, float]] = []
    for run in runs:
        plan = plans.get(run.index)
        if plan is None or plan.info_needed is None or cols is None:
            continue
        mine = cols.values["target"] == run.target.name
        got = info_of_columns(cols, pattern_u, mine)
        if got < plan.info_needed * (1.0 - 1e-9):
            joint = ObservedFisher(*plan.collected_fisher)
            got_all, goal_all = float(joint.joint(got)), float(joint.joint(plan.info_needed))
            # the goal quantity's σ scales as I^-½; the error scales the promise, the replan's
            # statement the goal itself (exact: the goal's value at the goal's I)
            ratio = math.sqrt(goal_all / got_all) if got_all > 0 else math.inf
            available = math.floor(plan.n_spectra * got / plan.info_needed)
            short = Shortfall(
                plan.goal, plan.n_spectra, min(available, int(np.sum(mine))), plan.expected * ratio
            )
            out.append((run, short, got, plan.info_needed, plan.goal.value * ratio))
    return out


def _with_longer_visits(
    short: Shortfall, longer: Shortfall | None, cap_s: float, long_s: float
) -> str:
    """The shortfall line with what visits as long as the nights allow would collect."""
    cap_h = cap_s / HOUR_S
    reach = Goal(short.goal.quantity, short.reachable, short.goal.relative, "").describe()
    head = (
        f"`goal` {short.goal.text}: needs {short.needed_spectra} spectra, the nights given allow "
        f"{short.available_spectra} in visits of at most {cap_h:.3g} h (`max_visit`; {reach})"
    )
    if longer is None:
        return (
            f"{head}; visits as long as the nights allow ({long_s / HOUR_S:.3g} h) reach it: "
            "raise `max_visit`"
        )
    far = Goal(short.goal.quantity, longer.reachable, short.goal.relative, "").describe()
    return (
        f"{head}, {longer.available_spectra} in visits as long as the nights allow "
        f"({long_s / HOUR_S:.3g} h; {far}); add nights or relax the goal"
    )
