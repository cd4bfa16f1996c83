"""The regression's design variable per spectrum, from the LISA ephemeris (paper Sec. 3.1).

Window factors Λ_K, Λ_κ of each exposure, the orbit (Φ, η, κ, u) at mid-exposure, the
window-averaged orbital factor G (:func:`~ucbplan.reduce.regression.binned_design`) per component
(optionally at the emission time, for the light travel time across the orbit) and its analytic
Jacobian ∂G/∂θ for the phase-error propagation.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ucbplan.core.constants import C_KM_S
from ucbplan.core.smearing import lambda_k, lambda_kappa
from ucbplan.reduce.regression import binned_design, lambda_k_to_x

if TYPE_CHECKING:
    from ucbplan.core.params import PhaseParams
    from ucbplan.reduce.velocities import VelocityTable

__all__ = ["design_jacobian", "designs", "orbit", "window_factors"]

F64 = NDArray[np.float64]


def window_factors(table: VelocityTable, f_hz: float) -> tuple[F64, F64]:
    """Λ_K and Λ_κ per spectrum from the window widths (or the given Λ_K).

    Raises
    ------
    VelocityFileError
        A window as long as the orbital period P_b = 2π/n̄_b or longer (Λ_K ≤ 0).

    Notes
    -----
    Eqs. Lambda_K, Lambda_kappa with n̄_b = π f. Where only Λ_K is known, x = n̄_b Δt/2 is
    recovered by inverting sin x/x and Λ_κ = sin 2x/2x.
    """
    nbar = math.pi * f_hz
    w = table.window_s
    _check_windows(table, 2.0 * math.pi / nbar)
    lk = np.where(np.isfinite(w), lambda_k(np.nan_to_num(w), nbar), table.lambda_k)
    x = np.zeros_like(lk)
    given = ~np.isfinite(w)
    if np.any(given):
        x[given] = lambda_k_to_x(table.lambda_k[given])
    lkap = np.where(given, np.sinc(2.0 * x / np.pi), lambda_kappa(np.nan_to_num(w), nbar))
    return np.asarray(lk, float), np.asarray(lkap, float)


def _check_windows(table: VelocityTable, period_s: float) -> None:
    """Every window shorter than the orbital period: Λ_K = sin x/x > 0 (x = πΔt/P_b < π).

    A window of one period averages the velocity curve to zero (Λ_K = 0) and a longer one flips
    its sign: K = slope/Λ_K would blow up or change sign (K1 = −1e7 km/s was reported).
    """
    from ucbplan.errors import VelocityFileError

    w = table.window_s
    bad = np.flatnonzero(np.isfinite(w) & (w >= period_s))
    if bad.size:
        i = int(bad[0])
        raise VelocityFileError(
            f"{table.source}: row {i + 1}, column {table.window_column!r}: got {w[i]:.6g} s, "
            f"expected a window shorter than the orbital period P_b = {period_s:.6g} s (Λ_K = "
            f"sin x/x ≤ 0 there: the exposure averages the orbit away); split the exposure or "
            "give shorter co-add windows"
        )


def orbit(p: PhaseParams, tau: F64) -> tuple[F64, F64, F64, F64]:
    """(Φ_asc, η, κ, u of star 1) at ``tau`` [s since t_ref]."""
    from ucbplan.core.phase import orbit_state

    phi, eta, kap, u = orbit_state(p, tau)
    return phi, eta, kap, u


def design_jacobian(p: PhaseParams, tau: F64, lam_k: F64, lam_kap: F64) -> F64:
    """∂G_i/∂θ for θ in PARAM_NAMES order, shape (n, 7) (analytic, Eq. vbar_master).

    Notes
    -----
    Φ = φ_ref/2 + π(fτ + ḟτ²/2 + f̈τ³/6); (η, κ)(τ) rotated at ω̇ (Eq. kappa_lisa_prediction).
    """
    phi, eta, kap, _ = orbit(p, tau)
    dG_dphi = -lam_k * np.sin(phi) + 2.0 * lam_kap * (
        -kap * np.sin(2 * phi) + eta * np.cos(2 * phi)
    )
    dG_deta = lam_kap * np.sin(2 * phi)
    dG_dkap = lam_kap * np.cos(2 * phi)
    w = p.omega_dot * tau
    c, s = np.cos(w), np.sin(w)
    jac = np.empty((tau.size, 7))
    jac[:, 0] = 0.5 * dG_dphi
    jac[:, 1] = math.pi * tau * dG_dphi
    jac[:, 2] = math.pi * tau**2 / 2.0 * dG_dphi
    jac[:, 3] = math.pi * tau**3 / 6.0 * dG_dphi
    jac[:, 4] = dG_deta * c - dG_dkap * s  # ∂/∂η_ref
    jac[:, 5] = dG_deta * s + dG_dkap * c  # ∂/∂κ_ref
    jac[:, 6] = dG_deta * tau * kap - dG_dkap * tau * eta  # ∂/∂ω̇
    return jac


def designs(
    p: PhaseParams, tau: F64, lam_k: F64, lam_kap: F64, ncomp: int, K: tuple[float, ...] | None
) -> tuple[F64, ...]:
    """Design G per component; with K given, evaluated at the emission time τ − ΔR_j."""
    out = []
    u = orbit(p, tau)[3] if K is not None else tau
    for j in range(ncomp):
        t = tau
        if K is not None:
            nb = math.pi * p.f_gw - p.omega_dot
            sign = 1.0 if j == 0 else -1.0
            t = tau - sign * K[j] / (C_KM_S * nb) * np.sin(u)
        phi, eta, kap, _ = orbit(p, t)
        out.append(binned_design(phi, eta, kap, lam_k, lam_kap))
    return tuple(out)
