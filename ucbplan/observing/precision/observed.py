"""What was observed counts: the information on K that spectra already taken collect.

A spectrum taken at mid-exposure time τ (TDB seconds since the target's reference epoch), with
exposure (or co-add window) T and measured σ_v, measures v = γ + K Λ_K cos u + noise, with its
own argument of latitude u = u(τ) from the target's ephemeris (Eq. u_precessing_app) and its own
smearing factor Λ_K = sin x/x, x = n̄_b T/2 (Eq. Lambda_K). The spectra's (γ, K) Fisher matrix is

    F = Σ_i (1, Λ_K,i cos u_i)ᵀ (1, Λ_K,i cos u_i) / σ_v,i²,

and the information on K with γ free is its Schur complement I = F_KK − F_γK²/F_γγ, so that
σ_K = I^{-½} = √[(F⁻¹)_KK] (:attr:`ObservedFisher.alone`; 0 when the spectra do not separate
γ and K).

γ is one number per target, shared by the spectra taken and the spectra still to plan (a plan
has one instrument; an observed file is taken to be from it). The goal is reached when the
Schur complement of the *sum* F_obs + F_plan reaches I_goal
(:func:`ucbplan.observing.precision.goals.goal_info_needed`), not when the two complements add up:
spectra taken at one anchor alone give no information on K, but with planned spectra that fix γ they
do. The planned visits are balanced (Σ Λ cos u/σ² ≈ 0: anchors in whole patterns), so their Fisher
matrix is diag(r P, P) with P = Σ (Λ cos u)²/σ² the information the planner counts and r = Σ 1/σ² /
P their γ-to-K ratio (≈ 1/Λ² for quadrature anchors), and

    I(P) = O_KK + P − O_γK²/(O_γγ + r P)                         (:meth:`ObservedFisher.joint`)

with O = F_obs. The planner collects the P that solves I(P) = I_goal, the positive root of a
quadratic (:meth:`ObservedFisher.needed`).

The measured σ_v of the spectra also say whether the plan's σ_v law holds: the median of
measured / predicted (:func:`sigma_v_ratio`) rescales the law for the remainder.

Velocities in km/s, times in seconds, angles in radians (plain floats and numpy arrays).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ucbplan.core.params import PhaseParams
from ucbplan.core.phase import arg_latitude
from ucbplan.core.smearing import lambda_k as smearing_factor

F64 = NDArray[np.float64]

#: Relative difference of the measured σ_v from the law's below which the law is kept (the
#: median of a few spectra scatters by several per cent).
SIGMA_V_RATIO_TOL = 0.05


@dataclass(frozen=True, eq=False)
class ObservedSpectra:
    """The spectra of one target already taken (compared by identity: the settings that hold
    them stay hashable).

    Attributes
    ----------
    target : str
        Target name (as its file names it).
    tau_s : ndarray
        Mid-exposure epochs, TDB seconds since the target's reference epoch [s].
    lambda_k : ndarray
        Smearing factor Λ_K of each spectrum.
    sigma_v_kms : ndarray
        Measured σ_v of each spectrum [km/s].
    predicted_kms : ndarray
        σ_v the plan's law predicts for each spectrum's exposure time and airmass (unscaled)
        [km/s]; NaN where unknown.
    source : str
        The file they were read from (for messages).
    """

    target: str
    tau_s: F64
    lambda_k: F64
    sigma_v_kms: F64
    predicted_kms: F64
    source: str = ""

    @property
    def n(self) -> int:
        """Number of spectra."""
        return int(self.tau_s.size)


def spectra_u(params: PhaseParams, tau_s: ArrayLike, star: int = 1) -> F64:
    """Argument of latitude of each spectrum at its mid-exposure epoch ``tau_s`` [rad]."""
    return np.asarray(arg_latitude(params, tau_s, star), dtype=np.float64)


def window_lambda_k(window_s: ArrayLike, n_bar: float) -> F64:
    """Λ_K = sin x/x, x = n̄_b T/2 of exposures (windows) of ``window_s`` [s]."""
    return np.asarray(smearing_factor(window_s, n_bar), dtype=np.float64)


def observed_information(spectra: ObservedSpectra, params: PhaseParams, star: int = 1) -> float:
    """Information on K [(km/s)⁻²] the ``spectra`` collect (γ free), each at its own u."""
    return observed_fisher(spectra, params, 0.0, star).alone


@dataclass(frozen=True)
class ObservedFisher:
    """The (γ, K) Fisher matrix of a target's spectra already taken [(km/s)⁻²] and the γ-to-K
    information ratio ``ratio`` of the spectra still to plan (module notes)."""

    f_gg: float = 0.0
    f_gk: float = 0.0
    f_kk: float = 0.0
    ratio: float = 0.0

    @property
    def alone(self) -> float:
        """Information on K of the spectra taken alone (γ free; 0 when they cannot separate γ
        and K) [(km/s)⁻²]."""
        det = self.f_gg * self.f_kk - self.f_gk**2
        if self.f_gg <= 0 or det <= 1e-12 * max(self.f_gg * self.f_kk, 1e-300):
            return 0.0
        return det / self.f_gg

    def joint(self, planned: ArrayLike) -> F64 | float:
        """Information on K of the spectra taken with balanced planned ones collecting
        ``planned`` [(km/s)⁻²] (γ free, one γ for both)."""
        p = np.asarray(planned, dtype=np.float64)
        gamma = self.f_gg + self.ratio * p
        safe = np.where(gamma > 0, gamma, 1.0)
        out = self.f_kk + p - np.where(gamma > 0, self.f_gk**2 / safe, 0.0)
        return float(out) if out.ndim == 0 else out

    def needed(self, goal: float) -> float:
        """The planned information P [(km/s)⁻²] with :meth:`joint` (P) = ``goal`` (0 when the
        spectra taken reach it alone)."""
        a, c, o, r = goal - self.f_kk, self.f_gk**2, self.f_gg, self.ratio
        if self.alone >= goal or not math.isfinite(goal):
            return 0.0 if math.isfinite(goal) else goal
        if r <= 0 or c == 0:
            return max(0.0, a + (c / o if o > 0 else 0.0))
        b = o - a * r  # r P² + b P − (a o + c) = 0, positive root (a o + c > 0 here)
        return (-b + math.sqrt(b * b + 4.0 * r * (a * o + c))) / (2.0 * r)


def observed_fisher(
    spectra: ObservedSpectra | None, params: PhaseParams, ratio: float, star: int = 1
) -> ObservedFisher:
    """The :class:`ObservedFisher` of ``spectra`` (None: nothing taken), each at its own u, Λ_K
    and σ_v, with the planned spectra's γ-to-K ratio ``ratio``."""
    if spectra is None or spectra.n == 0:
        return ObservedFisher(ratio=ratio)
    g = spectra.lambda_k * np.cos(spectra_u(params, spectra.tau_s, star))
    w = 1.0 / spectra.sigma_v_kms**2
    ok = np.isfinite(g) & np.isfinite(w)
    g, w = g[ok], w[ok]
    return ObservedFisher(
        float(np.sum(w)), float(np.sum(w * g)), float(np.sum(w * g * g)), ratio=ratio
    )


def collected_information(
    observed: Sequence[ObservedSpectra], name: str, params: PhaseParams, star: int = 1
) -> float:
    """Information on K [(km/s)⁻²] the spectra of target ``name`` among ``observed`` collect
    (0 when none was taken)."""
    spectra = target_spectra(observed, name)
    return observed_information(spectra, params, star) if spectra is not None else 0.0


def target_spectra(observed: Sequence[ObservedSpectra], name: str) -> ObservedSpectra | None:
    """The spectra of target ``name`` among ``observed`` (None when it has none)."""
    return next((s for s in observed if s.target == name and s.n > 0), None)


def sigma_v_ratio(measured_kms: ArrayLike, predicted_kms: ArrayLike) -> float:
    """Median of measured / predicted σ_v over the spectra whose prediction is known (NaN if
    none is)."""
    m = np.asarray(measured_kms, dtype=np.float64)
    p = np.asarray(predicted_kms, dtype=np.float64)
    ok = np.isfinite(p) & (p > 0) & np.isfinite(m)
    return float(np.median(m[ok] / p[ok])) if np.any(ok) else math.nan
