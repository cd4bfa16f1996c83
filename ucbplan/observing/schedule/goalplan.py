"""Goal-driven plans: how many exposures each target needs for a ``--goal``, and the shortfall.

For each target :func:`~ucbplan.observing.goals.spectra_for_goal` turns the goal into N spectra
from the regression's Fisher matrix with the target's Λ_K (of its exposure plan) and one σ_v per
exposure: ``--sigma-v``, else the instrument's σ_v at the airmass limit (every planned exposure
is at least as good, so the goal is reached), else the target file's σ_v. The visit planner then
plans exactly N exposures (:mod:`.visits`); if the nights given hold fewer, planning fails with
one line saying how far they fall short.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ucbplan.errors import InputError
from ucbplan.observing.blocks import Block
from ucbplan.observing.goals import GoalPlan, Shortfall, parse_goal, spectra_for_goal
from ucbplan.observing.instruments import MAX_AIRMASS
from ucbplan.observing.schedule.candidates import TargetRun
from ucbplan.observing.schedule.exposure import exposure_sigma_v
from ucbplan.observing.schedule.settings import PlanSettings

__all__ = ["check_goals", "goal_plans"]


def _goal_sigma_v(run: TargetRun, settings: PlanSettings) -> float:
    """σ_v per exposure the goal is computed with [km/s] (module notes)."""
    x = min(settings.airmass_max, MAX_AIRMASS)
    value = float(exposure_sigma_v(run.target, settings, run.exposure.plan.exptime_s, x))
    if not np.isfinite(value):
        raise InputError(
            f"--goal: {run.target.name}: sigma_v is unknown; pass --sigma-v KM_S, or an "
            "--instrument with sigma_ref and a magnitude in the target file"
        )
    return value


def goal_plans(runs: Sequence[TargetRun], settings: PlanSettings) -> dict[int, GoalPlan]:
    """The :class:`~ucbplan.observing.goals.GoalPlan` of every target (by sky-model index);
    empty without ``--goal``.

    Raises
    ------
    InputError
        A target without K1 (or K2 for a goal on q or the masses), unknown σ_v, or a mode
        whose anchors do not constrain K.
    """
    if settings.goal is None:
        return {}
    goal = parse_goal(settings.goal)
    out: dict[int, GoalPlan] = {}
    for run in runs:
        t, spec = run.target, run.target.spectroscopy
        k1 = (spec.K1_kms or spec.K_eff_kms) if spec is not None else None
        if k1 is None:
            raise InputError(
                f"--goal: {t.name}: expected spectroscopy.K1 (or K_eff) in the target file, "
                "got none; add it or plan without --goal"
            )
        k2 = spec.K2_kms if spec is not None and spec.lines == "SB2" else None
        sin_i = None
        cos_i = t.cos_inclination
        if cos_i is not None and np.isfinite(cos_i):
            sin_i = float(np.sqrt(max(0.0, 1.0 - cos_i**2))) or None
        out[run.index] = spectra_for_goal(
            goal,
            K1=k1,
            K2=k2,
            sigma_v_kms=_goal_sigma_v(run, settings),
            lambda_k=run.exposure.lambda_k,
            anchors=tuple(settings.spec.label.split("+")),
            period_s=t.period_s,
            sin_i=sin_i,
            e=t.params.eccentricity,
            exptime_s=run.exposure.plan.exptime_s,
            readout_s=run.exposure.plan.readout_s,
            acquisition_s=settings.overhead_s,
            visit_s=settings.visit_s,
        )
    return out


def check_goals(
    plans: dict[int, GoalPlan], runs: Sequence[TargetRun], blocks: Sequence[Block]
) -> None:
    """Refuse a plan that does not reach a target's goal (one line: the shortfall).

    Raises
    ------
    InputError
        Fewer exposures fit in the nights given than the goal needs.
    """
    for run in runs:
        plan = plans.get(run.index)
        if plan is None:
            continue
        got = sum(b.n_exp for b in blocks if b.target == run.target.name)
        if got < plan.n_spectra:
            short = Shortfall(plan.goal, plan.n_spectra, got, _reach(plan, got))
            raise InputError(f"{run.target.name}: {short.message()}")


def _reach(plan: GoalPlan, got: int) -> float:
    """σ of the goal quantity with ``got`` spectra (σ ∝ N^{-1/2})."""
    return plan.expected * float(np.sqrt(plan.n_spectra / got)) if got else float("inf")
