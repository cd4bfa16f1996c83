"""Exposures per target: the smearing floor, the visit cadence and σ_v per exposure.

Every target of a run gets its own exposure plan, because the smearing factor Λ_K (Eq. Lambda_K,
:func:`ucbplan.core.smearing.comb_attenuation`) depends on its orbital rate n̄_b:

- **Smearing floor.** Λ_K of a block must be at least ``min_lambda_k`` (default 0.9). An exposure
  time the user gave is refused below it; a default or chosen one (phase-locked cadence) is
  capped at the longest exposure that keeps the floor, with a one-line note. ``allow_smeared``
  lifts both.
- **Cadence.** Anchors of a mode are P_b/m apart (m = 2 for quadratures u = 0, π or conjunctions,
  1 for a single u★). With the ``anchor`` cadence an exposure costs exptime + readout and the next
  one waits for the next anchor it can reach: step = ⌈cost/(P_b/m)⌉·P_b/m. With ``phase-locked``
  exptime = step − readout, so consecutive exposures centre on consecutive anchors with no wait;
  the duty cycle is exptime/step.
- **Chosen for information per hour** (:func:`optimised_exposure`): when σ_v follows the
  exposure time (``--sigma-v 30km/s@600s``, or an instrument's σ_ref) and no ``--exptime`` is
  given, the exposure time and the strategy (targeted, phase-locked, untargeted) are those with
  the most information on K per visit (:mod:`ucbplan.observing.precision.strategy`); ``--cadence``
  may force a strategy. Sessions (no visits) take the exposure time with the most information per
  hour of a session.
- **σ_v per exposure** (:func:`exposure_sigma_v`): the exposure-time law of ``--sigma-v``, else a
  fixed ``--sigma-v``, else the instrument's σ_ref scaled with magnitude, exposure time and
  airmass (:func:`ucbplan.observing.precision.instruments.sigma_v_kms`), else the target file's σ_v.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ucbplan.core.smearing import comb_attenuation
from ucbplan.errors import InputError
from ucbplan.observing.blocks.block import ExposurePlan
from ucbplan.observing.precision.goals import goal_info_needed, parse_goal
from ucbplan.observing.precision.instruments import instrument_magnitude, sigma_v_kms
from ucbplan.observing.precision.observed import collected_information
from ucbplan.observing.precision.sigma_v import SigmaVModel
from ucbplan.observing.precision.strategy import (
    LOCK_MARGIN_S,
    StrategyResult,
    VisitShape,
    best_strategy,
    compare_strategies,
    goal_times,
    session_result,
)
from ucbplan.observing.schedule.settings import QUEUE_CADENCES, QUEUE_WAIT_S, PlanSettings

if TYPE_CHECKING:
    from ucbplan.targets import Target

#: Shortest exposure the smearing floor may cap to [s].
_SHORTEST_S = 0.1
#: Relative precision of the floor exposure time found by bisection.
_FLOOR_RTOL = 1e-9


@dataclass(frozen=True)
class TargetCadence:
    """One target's exposure plan and visit cadence.

    Attributes
    ----------
    plan : ExposurePlan
        Exposures of one block (one exposure per block inside a visit).
    spacing_s : float
        Time between consecutive anchors, P_b/m [s].
    step_s : float
        Time from one exposure centre to the next inside a visit [s].
    lambda_k : float
        Smearing factor Λ_K of one block.
    notes : tuple of str
        One-line notes (exposure capped at the floor, phase-locked duty cycle).
    floor_ok : bool
        False when no exposure of the target keeps the smearing floor (nothing is planned).
    strategy : str
        ``targeted``, ``phase-locked`` or ``untargeted`` (back-to-back, any phase).
    results : tuple of StrategyResult
        Every strategy's best exposure time when it was chosen for information per hour (the
        chosen one among them); empty otherwise.
    visit_s : float or None
        Longest visit of this target, acquisition included [s] (None: sessions).
    goal_hours : tuple of float
        With a goal: the hours each of ``results`` needs to reach it (the exposure time of each
        is then the one with the fewest hours).
    """

    plan: ExposurePlan
    spacing_s: float
    step_s: float
    lambda_k: float
    notes: tuple[str, ...] = ()
    floor_ok: bool = True
    strategy: str = "targeted"
    results: tuple[StrategyResult, ...] = ()
    visit_s: float | None = None
    goal_hours: tuple[float, ...] = ()

    @property
    def chosen(self) -> StrategyResult | None:
        """The chosen strategy's result (None when the exposure time was not optimised)."""
        return next((r for r in self.results if r.name == self.strategy), None)

    @property
    def optimum(self) -> StrategyResult | None:
        """The best strategy: the fewest hours to the goal, else the most information per
        visit (None: not optimised)."""
        possible = [r for r in self.results if r.possible]
        if not possible:
            return None
        if self.goal_hours:
            return min(zip(self.results, self.goal_hours, strict=True), key=lambda p: p[1])[0]
        return max(possible, key=lambda r: r.info_per_visit)

    @property
    def duty_cycle(self) -> float:
        """Shutter-open fraction of a visit's exposure sequence, exptime / step."""
        return self.plan.exptime_s / self.step_s if self.step_s > 0 else 1.0


def _lambda_k(plan: ExposurePlan, n_bar: float) -> float:
    return comb_attenuation(plan.exptime_s, plan.readout_s, plan.n_exp, n_bar, 1)


def floor_exptime(plan: ExposurePlan, n_bar: float, floor: float) -> float | None:
    """Longest exposure time ≤ ``plan.exptime_s`` whose block keeps Λ_K ≥ ``floor`` [s].

    Bisection on the exposure time (Λ_K falls monotonically from the shortest exposure to the
    first zero of sin x/x); None if even a vanishing exposure misses the floor (a comb of many
    exposures spread over the orbit).
    """
    if _lambda_k(plan, n_bar) >= floor and floor > 0:
        return plan.exptime_s
    lo, hi = 0.0, plan.exptime_s
    if _lambda_k(replace(plan, exptime_s=hi * 1e-9), n_bar) < floor:
        return None
    while hi - lo > _FLOOR_RTOL * plan.exptime_s:
        mid = 0.5 * (lo + hi)
        if _lambda_k(replace(plan, exptime_s=mid), n_bar) >= floor:
            lo = mid
        else:
            hi = mid
    return lo


def _capped(
    target: Target, plan: ExposurePlan, settings: PlanSettings, why: str
) -> tuple[ExposurePlan, list[str]]:
    """``plan`` held to the smearing floor: refused if explicit, else capped with a note."""
    n_bar, floor = target.params.n_bar, settings.lambda_k_floor
    lam = _lambda_k(plan, n_bar)
    if settings.allow_smeared or (lam >= floor and lam > 0):
        return plan, []
    best = floor_exptime(plan, n_bar, floor)
    period = f"P_b = {target.period_s:.1f} s"
    if best is not None and best < _SHORTEST_S:
        best = None  # only a vanishing exposure would keep the floor
    if not settings.exptime_given and best is None:
        return plan, [
            f"{target.name}: no exposure keeps Lambda_K >= {floor:g} ({period}): not planned; "
            "lower --min-lambda-k or pass --allow-smeared"
        ]
    if settings.exptime_given or best is None:
        fix = f"use `exptime` <= {math.floor(best * 10) / 10:g} s" if best else "fewer `n_exp`"
        raise InputError(
            f"exptime: {target.name}: {plan.exptime_s:g} s gives Lambda_K = {lam:.3f} "
            f"({period}), below `min_lambda_k` {floor:g}; {fix}, or pass `allow_smeared`"
        )
    capped = replace(plan, exptime_s=math.floor(best * 1000) / 1000)
    note = (
        f"{target.name}: {why} exposure capped at {capped.exptime_s:.1f} s (from "
        f"{plan.exptime_s:g} s) to keep Lambda_K >= {floor:g} ({period}); --allow-smeared keeps it"
    )
    return capped, [note]


def _phase_locked(target: Target, settings: PlanSettings, spacing: float) -> ExposurePlan:
    """Exposure + readout = the smallest whole number of anchor spacings with exptime > 0 (and
    at least the instrument's minimum exposure).

    The anchors of an eccentric orbit are not evenly spaced (to first order in e the shortest
    gap is ≥ (1 − 2e)·P_b/m) and the light time moves them by ≤ 0.02 s per minute, so the
    exposure is shortened by that much (and :data:`LOCK_MARGIN_S`) to keep every readout.
    """
    plan = settings.exposure
    inst = settings.instrument
    low = inst.min_exptime_s if inst is not None and inst.min_exptime_s is not None else 0.0
    short = spacing * (1.0 - 2.0 * target.params.eccentricity) - LOCK_MARGIN_S
    k = max(1, math.ceil((plan.readout_s + max(low, 1e-3)) / short * (1 - 1e-12)))
    exptime = math.floor((k * short - plan.readout_s) * 10) / 10
    if exptime <= 0:
        raise InputError(
            f"cadence phase-locked: {target.name}: no exposure fits between anchors "
            f"{spacing:.1f} s apart with {plan.readout_s:g} s readout; use `cadence` anchor"
        )
    return replace(plan, exptime_s=exptime)


def _check_queue_wait(
    target: Target, settings: PlanSettings, plan: ExposurePlan, wait_s: float
) -> None:
    """``--service-mode``: a phase-locked exposure shortened below the anchor spacing (the
    smearing floor) waits after each readout, which a queue cannot.

    Raises
    ------
    InputError
        With ``service_mode`` and a wait above :data:`QUEUE_WAIT_S`.
    """
    if settings.service_mode and wait_s > QUEUE_WAIT_S:
        raise InputError(
            f"service_mode: {target.name}: phase-locked {plan.exptime_s:.1f} s exposures "
            f"(capped for Lambda_K) wait {wait_s:.1f} s after each readout, which a queue "
            "cannot; use `cadence=untargeted` (or auto), or pass `allow_smeared`"
        )


def _visit_length(settings: PlanSettings) -> float | None:
    """Longest visit [s]: ``--visit``, else ``--max-visit`` for a goal, else None (sessions)."""
    if settings.visit_s is not None:
        return settings.visit_s
    return settings.max_visit_s if settings.goal is not None else None


def _check_visit(target: Target, settings: PlanSettings, plan: ExposurePlan) -> None:
    """A visit must hold acquisition + one exposure + readout."""
    visit = _visit_length(settings)
    cost = plan.exptime_s + plan.readout_s
    if visit is not None and settings.overhead_s + cost > visit:
        option = "visit" if settings.visit_s is not None else "max_visit"
        raise InputError(
            f"{option}: expected at least acquisition + one exposure + readout = "
            f"{(settings.overhead_s + cost) / 60:.1f} min, got {visit / 60:.1f} min; "
            f"lengthen `{option}` or shorten the exposure"
        )


def check_visit_holds_an_exposure(target: Target, settings: PlanSettings) -> ExposurePlan:
    """The shortest exposure the instrument allows, checked to fit a visit with its
    acquisition and readout (``plan`` and ``feasibility`` before any work or output).

    Raises
    ------
    InputError
        The visit (``--visit``, else ``--max-visit``) is shorter; one line naming the option.
    """
    low = visit_shape(target, settings, 0.0).min_exptime_s
    shortest = replace(settings.exposure, exptime_s=low)
    _check_visit(target, settings, shortest)
    return shortest


def target_exposure(target: Target, settings: PlanSettings) -> TargetCadence:
    """Exposure plan and cadence of ``target`` (module notes).

    Raises
    ------
    InputError
        An explicit exposure below the smearing floor; a visit shorter than acquisition + one
        exposure + readout (one line each, naming the option to change).
    """
    if settings.optimises_exposure and settings.spec.label != "fixed-u-pairs":
        return optimised_exposure(target, settings)
    m = len(settings.spec.u_values)
    spacing = target.period_s / m
    cadence = settings.cadence
    if settings.service_mode and cadence == "auto":
        cadence = "untargeted"  # the given exposure time, back to back
    if cadence == "phase-locked":
        plan, why = _phase_locked(target, settings, spacing), "phase-locked"
    else:
        plan, why = settings.exposure, "default" if not settings.exptime_given else "given"
    plan, notes = _capped(target, plan, settings, why)
    lam = _lambda_k(plan, target.params.n_bar)
    floor_ok = settings.allow_smeared or (lam >= settings.lambda_k_floor and lam > 0)
    cost = plan.exptime_s + plan.readout_s
    step = math.ceil(cost / spacing * (1.0 - 1e-12)) * spacing
    _check_visit(target, settings, plan)
    strategy = "phase-locked" if cadence == "phase-locked" else "targeted"
    if cadence == "untargeted":
        strategy, spacing, step = "untargeted", cost, cost
    if cadence == "phase-locked":
        wait = step - cost
        _check_queue_wait(target, settings, plan, wait)
        notes.append(
            f"{target.name}: phase-locked cadence: {plan.exptime_s:.1f} s exposures every "
            f"{step:.1f} s (P_b/{m} x {round(step / spacing)}), duty cycle "
            f"{plan.exptime_s / step:.1%}"
            + (f"; the OB must wait {wait:.1f} s after each readout" if wait > QUEUE_WAIT_S else "")
        )
    if settings.sigma_v_kms is not None and settings.sigma_model is None:
        notes.append(
            f"{target.name}: sigma_v {settings.sigma_v_kms:g} km/s fixed per exposure: exposure "
            f"time not optimised (--sigma-v {settings.sigma_v_kms:g}km/s@600s would)"
        )
    visit = _visit_length(settings)
    return TargetCadence(plan, spacing, step, lam, tuple(notes), floor_ok, strategy, (), visit)


def sigma_law(target: Target, settings: PlanSettings) -> SigmaVModel | None:
    """The σ_v law that follows the exposure time: ``--sigma-v …@…``, else the instrument's
    σ_ref (with its extinction) unless a fixed ``--sigma-v`` overrides it; None otherwise."""
    if settings.sigma_model is not None:
        return settings.sigma_model if settings.sigma_model.follows_exposure else None
    inst = settings.instrument
    if settings.sigma_v_kms is not None or inst is None or inst.sigma_ref is None:
        return None
    ref = inst.sigma_ref
    return SigmaVModel(
        ref.sigma_v_kms,
        ref.exptime_s,
        ref.band,
        ref.mag,
        extinction_k=inst.extinction_k or 0.0,
        option=f"instrument {inst.name}",
    )


def visit_shape(target: Target, settings: PlanSettings, visit_s: float) -> VisitShape:
    """What one visit of ``visit_s`` allows ``target`` under ``settings``."""
    inst = settings.instrument
    low = inst.min_exptime_s if inst is not None and inst.min_exptime_s is not None else 1.0
    step = inst.exptime_step_s if inst is not None and inst.exptime_step_s is not None else 1.0
    return VisitShape(
        period_s=target.period_s,
        n_bar=target.params.n_bar,
        pattern_u=settings.spec.u_values,
        readout_s=settings.exposure.readout_s,
        acquisition_s=settings.overhead_s,
        visit_s=visit_s,
        min_lambda_k=0.0 if settings.allow_smeared else settings.lambda_k_floor,
        min_exptime_s=max(low, step),
        granularity_s=step,
        eccentricity=target.params.eccentricity,
    )


def _forced(
    results: tuple[StrategyResult, ...],
    cadence: str,
    hours: tuple[float, ...] = (),
    service_mode: bool = False,
) -> StrategyResult:
    """The strategy ``--cadence`` names, or the best (``auto``; with ``service_mode`` the best
    of :data:`QUEUE_CADENCES`): the fewest ``hours`` to a goal when given, else the most
    information per visit.

    Raises
    ------
    InputError
        The forced strategy plans nothing (its reason); no strategy plans anything.
    """
    if cadence == "auto":
        keep = [k for k, r in enumerate(results) if not service_mode or r.name in QUEUE_CADENCES]
        best = best_strategy([results[k] for k in keep])
        if hours:
            best = min(((results[k], hours[k]) for k in keep), key=lambda p: p[1])[0]
        return best
    name = "targeted" if cadence == "anchor" else cadence
    pick = next(r for r in results if r.name == name)
    if not pick.possible:
        raise InputError(f"cadence {cadence}: {pick.note or 'no exposure fits'}; use another")
    return pick


def _strategy_results(
    target: Target,
    settings: PlanSettings,
    sigma: Callable[[NDArray[np.float64]], NDArray[np.float64]],
    visit: float | None,
) -> tuple[tuple[StrategyResult, ...], tuple[float, ...]]:
    """Every strategy's best exposure time, and with a goal the hours each needs: sessions
    (no visit) take the pattern's blocks after one acquisition; a goal minimises hours; visits
    otherwise maximise the information per visit."""
    if visit is None:
        n = len(settings.spec.u_values) if settings.spec.paired else 1
        shape = visit_shape(target, settings, settings.overhead_s + 43200.0)
        return (session_result(shape, sigma, n),), ()
    shape = visit_shape(target, settings, visit)
    if settings.goal is None:
        return tuple(compare_strategies(shape, sigma)), ()
    need = goal_info_needed(parse_goal(settings.goal), target)
    # the spectra already taken (observed) leave less to collect: the hours are the rest's
    taken = collected_information(settings.observed, target.name, target.params, settings.star)
    need = max(0.0, need - taken)
    times = goal_times(need, shape, sigma, settings.goal)
    return tuple(g.strategy for g in times), tuple(g.hours for g in times)


def optimised_exposure(target: Target, settings: PlanSettings) -> TargetCadence:
    """Exposure time and cadence with the most information on K per visit (module notes).

    The σ_v law is evaluated at airmass 1; per-exposure airmasses enter the planned σ_v.

    Raises
    ------
    InputError
        No strategy plans an exposure in the visit; the forced ``--cadence`` plans none; the
        target has no magnitude in the band of the σ_v reference.
    """
    law = sigma_law(target, settings)
    assert law is not None  # settings.optimises_exposure
    mag = law.target_mag(target.magnitudes, target.name)

    def sigma(t: NDArray[np.float64]) -> NDArray[np.float64]:
        return law.sigma(t, 1.0, mag) * settings.sigma_v_scale

    visit = _visit_length(settings)
    shortest = check_visit_holds_an_exposure(target, settings)
    results, hours = _strategy_results(target, settings, sigma, visit)
    pick = _forced(results, settings.cadence, hours, settings.service_mode)
    plan = replace(settings.exposure, exptime_s=pick.exptime_s)
    spacing = target.period_s / len(settings.spec.u_values)
    if pick.name == "untargeted":
        spacing = pick.step_s
    notes: tuple[str, ...] = ()
    if pick.exptime_s <= shortest.exptime_s and plan.readout_s == 0:
        notes = (
            f"{target.name}: with no readout the shortest exposure ({pick.exptime_s:g} s) wins "
            "(the σ_v law has no read noise); give --readout or an --instrument",
        )
    if settings.readout_assumed:
        notes = (
            f"{target.name}: no readout given: {plan.readout_s:g} s assumed (the shortest of the "
            "bundled spectrographs) to choose the exposure time; give --readout or an --instrument",
        )
    return TargetCadence(
        plan,
        spacing,
        pick.step_s,
        _lambda_k(plan, target.params.n_bar),
        notes,
        True,
        pick.name,
        results,
        visit,
        hours,
    )


def exposure_sigma_v(
    target: Target, settings: PlanSettings, exptime_s: float, airmass: ArrayLike
) -> NDArray[np.float64]:
    """σ_v per exposure [km/s]: the exposure-time law (:func:`sigma_law`), else ``--sigma-v``,
    else the instrument's scaling, else the target file's σ_v (NaN if none of them is known),
    times ``settings.sigma_v_scale``.

    Raises
    ------
    InputError
        An instrument without σ_ref (pass --sigma-v), or a target without a magnitude in its
        band.
    """
    return _law_sigma_v(target, settings, exptime_s, airmass) * settings.sigma_v_scale


def _law_sigma_v(
    target: Target, settings: PlanSettings, exptime_s: float, airmass: ArrayLike
) -> NDArray[np.float64]:
    """:func:`exposure_sigma_v` before ``settings.sigma_v_scale``."""
    x = np.asarray(airmass, dtype=np.float64)
    law = sigma_law(target, settings)
    if law is not None and settings.sigma_model is not None:
        return law.sigma(exptime_s, x, law.target_mag(target.magnitudes, target.name))
    inst = settings.instrument
    if settings.sigma_v_kms is None and inst is not None:
        mag = instrument_magnitude(inst, target.magnitudes)
        return sigma_v_kms(inst, mag, exptime_s, x)
    spec = target.spectroscopy
    value = settings.sigma_v_kms or (spec.sigma_v_kms if spec else None)
    return np.full(x.shape, np.nan if value is None else float(value))


def strategy_facts(te: TargetCadence, collected: float) -> dict[str, Any]:
    """The exposure-strategy choice of a target as plain values (table meta, reports, JSON):
    every strategy's exposure time, Λ_K, exposures and information per visit and per hour,
    the chosen one's fraction of the best, and the information the plan's rows collect."""
    top = max((r.info_per_visit for r in te.results), default=0.0)
    rows = {
        r.name: {
            "exptime_s": r.exptime_s if r.possible else None,
            "lambda_k": round(r.lambda_k, 6) if r.possible else None,
            "exposures_per_visit": r.n_exposures,
            "info_per_visit": r.info_per_visit,
            "info_per_hour": r.info_per_hour,
            "fraction_of_best": r.info_per_visit / top if top > 0 else 0.0,
            "note": r.note,
        }
        for r in te.results
    }
    for row, hours in zip(rows.values(), te.goal_hours, strict=False):
        row["goal_hours"] = hours if math.isfinite(hours) else None
    return {"chosen": te.strategy, "strategies": rows, "collected_info": collected}
