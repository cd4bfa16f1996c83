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
- **σ_v per exposure** (:func:`exposure_sigma_v`): ``--sigma-v``, else the instrument's σ_ref
  scaled with magnitude, exposure time and airmass (:func:`ucbplan.observing.instruments.
  sigma_v_kms`), else the target file's σ_v.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ucbplan.core.smearing import comb_attenuation
from ucbplan.errors import InputError
from ucbplan.observing.blocks import ExposurePlan
from ucbplan.observing.instruments import instrument_magnitude, sigma_v_kms
from ucbplan.observing.schedule.settings import PlanSettings

if TYPE_CHECKING:
    from ucbplan.target import Target

__all__ = ["TargetExposure", "exposure_sigma_v", "floor_exptime", "target_exposure"]

#: Time kept free in each step of a phase-locked cadence besides the readout [s].
_LOCK_MARGIN_S = 0.2
#: Shortest exposure the smearing floor may cap to [s].
_SHORTEST_S = 0.1
#: Relative precision of the floor exposure time found by bisection.
_FLOOR_RTOL = 1e-9


@dataclass(frozen=True)
class TargetExposure:
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
    """

    plan: ExposurePlan
    spacing_s: float
    step_s: float
    lambda_k: float
    notes: tuple[str, ...] = ()
    floor_ok: bool = True

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
    if not settings.exptime_explicit and best is None:
        return plan, [
            f"{target.name}: no exposure keeps Lambda_K >= {floor:g} ({period}): not planned; "
            "lower --min-lambda-k or pass --allow-smeared"
        ]
    if settings.exptime_explicit or best is None:
        fix = f"use --exptime <= {math.floor(best * 10) / 10:g} s" if best else "fewer --n-exp"
        raise InputError(
            f"--exptime: {target.name}: {plan.exptime_s:g} s gives Lambda_K = {lam:.3f} "
            f"({period}), below --min-lambda-k {floor:g}; {fix}, or pass --allow-smeared"
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
    exposure is shortened by that much (and :data:`_LOCK_MARGIN_S`) to keep every readout.
    """
    plan = settings.exposure
    inst = settings.instrument
    low = inst.min_exptime_s if inst is not None and inst.min_exptime_s is not None else 0.0
    short = spacing * (1.0 - 2.0 * target.params.eccentricity) - _LOCK_MARGIN_S
    k = max(1, math.ceil((plan.readout_s + max(low, 1e-3)) / short * (1 - 1e-12)))
    exptime = math.floor((k * short - plan.readout_s) * 10) / 10
    if exptime <= 0:
        raise InputError(
            f"--cadence phase-locked: {target.name}: no exposure fits between anchors "
            f"{spacing:.1f} s apart with {plan.readout_s:g} s readout; use --cadence anchor"
        )
    return replace(plan, exptime_s=exptime)


def target_exposure(target: Target, settings: PlanSettings) -> TargetExposure:
    """Exposure plan and cadence of ``target`` (module notes).

    Raises
    ------
    InputError
        An explicit exposure below the smearing floor; a visit shorter than acquisition + one
        exposure + readout (one line each, naming the option to change).
    """
    m = len(settings.spec.u_values)
    spacing = target.period_s / m
    if settings.cadence == "phase-locked":
        plan, why = _phase_locked(target, settings, spacing), "phase-locked"
    else:
        plan, why = settings.exposure, "default" if not settings.exptime_explicit else "given"
    plan, notes = _capped(target, plan, settings, why)
    lam = _lambda_k(plan, target.params.n_bar)
    floor_ok = settings.allow_smeared or (lam >= settings.lambda_k_floor and lam > 0)
    cost = plan.exptime_s + plan.readout_s
    step = math.ceil(cost / spacing * (1.0 - 1e-12)) * spacing
    if settings.visit_s is not None and settings.overhead_s + cost > settings.visit_s:
        raise InputError(
            f"--visit: expected at least acquisition + one exposure + readout = "
            f"{(settings.overhead_s + cost) / 60:.1f} min, got {settings.visit_s / 60:.1f} min; "
            "lengthen --visit or shorten the exposure"
        )
    if settings.cadence == "phase-locked":
        wait = step - cost
        notes.append(
            f"{target.name}: phase-locked cadence: {plan.exptime_s:.1f} s exposures every "
            f"{step:.1f} s (P_b/{m} x {round(step / spacing)}), duty cycle "
            f"{plan.exptime_s / step:.1%}"
            + (f"; the OB must wait {wait:.1f} s after each readout" if wait > 1.0 else "")
        )
    return TargetExposure(plan, spacing, step, lam, tuple(notes), floor_ok)


def exposure_sigma_v(
    target: Target, settings: PlanSettings, exptime_s: float, airmass: ArrayLike
) -> NDArray[np.float64]:
    """σ_v per exposure [km/s]: ``--sigma-v``, else the instrument's scaling, else the target
    file's σ_v (NaN if none of them is known).

    Raises
    ------
    InputError
        An instrument without σ_ref (pass --sigma-v), or a target without a magnitude in its
        band.
    """
    x = np.asarray(airmass, dtype=np.float64)
    inst = settings.instrument
    if settings.sigma_v_kms is None and inst is not None:
        mag = instrument_magnitude(inst, target.magnitudes)
        return sigma_v_kms(inst, mag, exptime_s, x)
    spec = target.spectroscopy
    value = settings.sigma_v_kms or (spec.sigma_v_kms if spec else None)
    return np.full(x.shape, np.nan if value is None else float(value))
