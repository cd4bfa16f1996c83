"""Exact-Keplerian synthetic velocities for the reduce tests (and checks of the generator itself).

Truth model (independent of the first-order u(t) of the ephemeris): the binary's mean phase from
the ascending node Φ_asc = Φ_GW/2 advances at n̄ = n_b + ω̇; star 1's mean anomaly is
M = Φ_asc − ω(t) with ω(t) = atan2(η, κ) rotated at ω̇; Kepler's equation E − e sin E = M is
solved by Newton iteration; u = ω + ν; v1 = γ1 + K1[cos u + e cos ω], v2 = γ2 − K2[cos u + e cos ω]
(the exact Keplerian RV formula). Finite exposures are integrated with 24-node Gauss–Legendre
quadrature over the window (exact to < 1e-12 for the smooth orbit at Δt ≤ P_b/3).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from support.reduce_synth import (
    exact_factor,
    exposure_factor,
    session_times,
    solve_kepler,
)

from ucbplan.core import ephemeris
from ucbplan.core.params import PhaseParams

# ------------------------------------------------------------------------------------------------
# checks of the generator itself
# ------------------------------------------------------------------------------------------------


def test_kepler_solver_residual_and_circular_limit() -> None:
    """E − e sin E = M to 1e-13 rad; e = 0 returns E = M exactly."""
    M = np.linspace(-10, 10, 1001)
    E = solve_kepler(M, 0.3)
    assert np.max(np.abs(E - 0.3 * np.sin(E) - M)) < 1e-13
    assert np.array_equal(solve_kepler(M, 0.0), M)


def fid_params() -> PhaseParams:
    """The fiducial phase parameters without the YAML parser."""
    return PhaseParams(
        phase=2.410235,
        f_gw=8.4062899940e-3,
        fdot=1.640367e-15,
        eta=8.249643e-3,
        kappa=4.524585e-3,
        omega_dot=1.496836e-6,
    )


@pytest.mark.parametrize("tau0", [0.0, 7.0e7, 3.0e8])
def test_exact_factor_second_order(tau0: float) -> None:
    """max |exact − (cos u₁ + κ)| over an orbit is O(e²): within [0.5e², 3e²] (second order)."""
    p = fid_params()
    tau = tau0 + np.linspace(0, 240, 2001)
    first = np.cos(ephemeris.arg_latitude(p, tau)) + ephemeris.ll_pair(p, tau)[1]
    diff = np.max(np.abs(exact_factor(p, tau) - first))
    e2 = p.eccentricity**2
    assert 0.5 * e2 < diff < 3.0 * e2


def test_exposure_average_matches_lambda_k_circular() -> None:
    """Circular orbit, window P/8: numerical average = Λ_K cos Φ_c, Λ_K = sinc(π/8) (to 1e-9)."""
    p = PhaseParams(phase=0.3, f_gw=8.4e-3, fdot=0.0)
    tau, dt = session_times(p, 1000.0, n_orbits=2)
    avg = exposure_factor(p, tau, dt)
    lam = math.sin(math.pi / 8) / (math.pi / 8)
    np.testing.assert_allclose(avg, lam * np.cos(ephemeris.phase_asc(p, tau)), atol=1e-9)
