"""The Fourier-series Kepler velocity and its window average vs a brute-force Kepler solution.

Reference: Newton's solution of Kepler's equation E − e sin E = M, ν from E, h = cos(ω + ν) +
e cos ω (the exact Keplerian RV formula), averaged over a window with 96-node Gauss–Legendre
quadrature while ω advances at ω̇ (so M advances at n_b = n̄ − ω̇). Independent of the Bessel
series and its recurrences.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ucbplan.core.kepler import harmonics, n_harmonics, window_average

NBAR = math.pi * 8.4062899940e-3
PB = 2 * math.pi / NBAR


def _kepler_h(mean: np.ndarray, om: np.ndarray, e: float) -> np.ndarray:
    ecc = mean + e * np.sin(mean)
    for _ in range(60):
        ecc = ecc - (ecc - e * np.sin(ecc) - mean) / (1 - e * np.cos(ecc))
    nu = 2 * np.arctan2(math.sqrt(1 + e) * np.sin(ecc / 2), math.sqrt(1 - e) * np.cos(ecc / 2))
    return np.cos(om + nu) + e * np.cos(om)


def _brute_average(phi, om, e, wdot, window):  # type: ignore[no-untyped-def]
    x, w = np.polynomial.legendre.leggauss(96)
    s = 0.5 * window * x  # offsets from mid-exposure [s]
    ph = phi[:, None] + NBAR * s[None, :]
    o = om[:, None] + wdot * s[None, :]
    return (_kepler_h(ph - o, o, e) * w).sum(axis=1) / 2


@pytest.mark.parametrize("e", [0.0, 0.0094, 0.05, 0.1, 0.5])
@pytest.mark.parametrize("frac", [0.0, 1 / 8, 1 / 3, 0.9])
def test_window_average_matches_brute_force_kepler(e: float, frac: float) -> None:
    """⟨h⟩ to 1e-13 (the series is cut at 1e-14; the quadrature is exact to ~1e-15 here).

    ω̇ = 1e-3 rad/s (700× the fiducial's) so the ω̇ terms of the window rates are tested."""
    rng = np.random.default_rng(3)
    phi = rng.uniform(0, 2 * math.pi, 200)
    om = rng.uniform(0, 2 * math.pi, 200)
    wdot = 1e-3
    got = window_average(phi, om, e, NBAR - wdot, wdot, frac * PB).h
    np.testing.assert_allclose(got, _brute_average(phi, om, e, wdot, frac * PB), atol=1e-13)


def test_circular_limit_is_lambda_k_cos_phi() -> None:
    """e = 0: ⟨h⟩ = Λ_K cos Φ with Λ_K = sin x/x, x = n̄Δt/2 (Eq. Lambda_K), to 1e-15."""
    phi = np.linspace(0, 2 * math.pi, 50)
    x = NBAR * PB / 6
    got = window_average(phi, 0.0, 0.0, NBAR, 0.0, PB / 3).h
    np.testing.assert_allclose(got, math.sin(x) / x * np.cos(phi), atol=1e-15)


def test_first_order_is_eq_vbar_master() -> None:
    """⟨h⟩ − [Λ_K cos Φ + Λ_κ(κ cos 2Φ + η sin 2Φ)] is O(e²): within [0.1e², 2e²] (Eq.
    vbar_master is the first order)."""
    phi = np.linspace(0, 2 * math.pi, 400)
    for e in (0.01, 0.02):
        om = 0.7
        x = NBAR * PB / 6
        lk, lkap = math.sin(x) / x, math.sin(2 * x) / (2 * x)
        first = lk * np.cos(phi) + lkap * e * (
            math.cos(om) * np.cos(2 * phi) + math.sin(om) * np.sin(2 * phi)
        )
        diff = np.max(np.abs(window_average(phi, om, e, NBAR, 0.0, PB / 3).h - first))
        assert 0.1 * e**2 < diff < 2 * e**2


@settings(max_examples=40, deadline=None)
@given(e=st.floats(1e-6, 0.3), om=st.floats(0, 2 * math.pi), phi=st.floats(0, 2 * math.pi))
def test_partials_match_finite_differences(e: float, om: float, phi: float) -> None:
    """∂⟨h⟩/∂Φ, ∂/∂ω, ∂/∂e vs central differences of ⟨h⟩ (step 1e-6: truncation ~1e-12,
    rounding ~1e-10; tolerance 1e-8)."""
    win = PB / 4

    def h(p: float, o: float, ee: float) -> float:
        return float(window_average(np.array([p]), np.array([o]), ee, NBAR, 0.0, win).h[0])

    got = window_average(np.array([phi]), np.array([om]), e, NBAR, 0.0, win)
    d = 1e-6
    assert got.d_phase[0] == pytest.approx(
        (h(phi + d, om, e) - h(phi - d, om, e)) / (2 * d), abs=1e-8
    )
    assert got.d_omega[0] == pytest.approx(
        (h(phi, om + d, e) - h(phi, om - d, e)) / (2 * d), abs=1e-8
    )
    de = min(d, 0.5 * e)
    assert got.d_e[0] == pytest.approx(
        (h(phi, om, e + de) - h(phi, om, e - de)) / (2 * de), abs=1e-6
    )


def test_harmonics_limits_and_count() -> None:
    """P₁ → 1, P₂/e → 1 as e → 0 (first order); n_harmonics grows as e grows; e ≥ 1 refused."""
    p, q, dp, dq = harmonics(1e-6)
    assert abs(dq[0]) < 1e-5  # Q₁ = −e²/8 + …: dQ₁/de = −e/4
    assert p[0] == pytest.approx(1.0, abs=1e-11) and p[1] / 1e-6 == pytest.approx(1.0, rel=1e-6)
    assert abs(q[0]) < 1e-12 and dp[1] == pytest.approx(1.0, rel=1e-6)
    assert n_harmonics(0.0) == 1 < n_harmonics(0.0094) < n_harmonics(0.1) <= 20
    with pytest.raises(ValueError, match="eccentricity"):
        harmonics(1.0)


@pytest.mark.parametrize("ecc", [0.0, 1e-9, 0.0094, 0.08])
def test_design_jacobian_matches_finite_differences_of_the_design(ecc: float) -> None:
    """∂G/∂θ of reduce's design vs central differences of G over each of the 7 parameters.

    Steps: 1e-6 of each parameter's natural scale (φ: 1e-6 rad, ḟ: 1e-6/τ², …, η, κ: 1e-6,
    f and ω̇: 1e-4/τ, against the rounding of f·τ and of G); tolerance 1e-6 of the
    column's largest entry: the Jacobian leaves out the window rates' own dependence on ḟτ and
    ω̇ (2e-7 relative). e = 0 and 1e-9 use Eq. vbar_master's Jacobian (exact at e = 0).
    """
    from ucbplan.core.params import PARAM_NAMES, PhaseParams
    from ucbplan.reduce.design import design_jacobian, designs

    p = PhaseParams(
        2.41, 8.406e-3, 1.64e-15, 1e-27, ecc * math.sin(1.2), ecc * math.cos(1.2), 1.5e-6
    )
    tau = 6.3e7 + np.linspace(0.0, 3 * PB, 40)
    win = np.full(tau.size, PB / 5)
    jac = design_jacobian(p, tau, win)
    scale = {"phase": 1.0, "f_gw": 1 / 6.3e7, "fdot": 1 / 6.3e7**2, "fddot": 1 / 6.3e7**3}
    scale |= {"eta": 1.0, "kappa": 1.0, "omega_dot": 1 / 6.3e7}
    for k, name in enumerate(PARAM_NAMES):
        h = (1e-4 if name in ("f_gw", "omega_dot") else 1e-6) * scale[name]
        vals = p.as_array()
        up = PhaseParams(*(vals + h * (np.arange(7) == k)))
        dn = PhaseParams(*(vals - h * (np.arange(7) == k)))
        fd = (designs(up, tau, win, 1, None)[0] - designs(dn, tau, win, 1, None)[0]) / (2 * h)
        # + the rounding floor of G (a few ulp) over the step, where the derivative is ~0
        floor = 4e-16 / h
        np.testing.assert_allclose(jac[:, k], fd, rtol=0, atol=1e-6 * np.max(np.abs(fd)) + floor)


@settings(max_examples=25, deadline=None)
@given(st.sampled_from([0.0, 1e-9, 0.0094, 0.05, 0.3, 0.7]), st.integers(0, 2**32 - 1))
def test_h_is_the_same_with_and_without_derivatives(e: float, seed: int) -> None:
    """Issue 23: reduce takes the plain design G from the derivative pass of the Jacobian, so
    ⟨h⟩ must not depend on ``derivatives`` by a single bit (the derivative-only terms, whose
    coefficient is below 1e-15, stay out of it)."""
    rng = np.random.default_rng(seed)
    n = 300
    args = (
        rng.uniform(0, 2 * math.pi, n),
        rng.uniform(0, 2 * math.pi, n),
        e,
        rng.uniform(0.01, 0.03, n),
        1.5e-6,
        rng.uniform(0.0, 60.0, n),
    )
    with_d = window_average(*args, derivatives=True)
    plain = window_average(*args, derivatives=False)
    assert with_d.h.tobytes() == plain.h.tobytes()
    assert not np.any(plain.d_phase)
