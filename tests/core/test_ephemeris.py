"""Phase model and t★ inversion against independent references.

References: exact round trips u(t★) = u★; Appendix A closed-form epochs (node, zero crossing,
conjunction) to O(e²); an exact Kepler-equation orbit; the ELL1 Roemer-delay velocity
(Eq. roemer-ell1 differentiated); finite differences for the analytic rate.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq

from ucbplan.core.ephemeris import solve_u
from ucbplan.core.params import PhaseParams
from ucbplan.core.phase import (
    arg_latitude,
    arg_latitude_rate,
    ll_pair,
    phase_asc,
    radial_velocity,
    u_cycles,
)

YEAR = 365.25 * 86400.0
FID = PhaseParams(
    2.410235, 8.4062899940e-3, 1.640367e-15, 0.0, 8.249643e-3, 4.524585e-3, 1.496836e-6
)


def _resid(p: PhaseParams, k, dt, us, origin, star=1):
    m, g = u_cycles(p, dt, origin, star)
    return 2 * math.pi * ((m - k) + (g - us / (2 * math.pi)))


params_st = st.builds(
    lambda f, fdot, fddot, e, w, wdot, phase: PhaseParams(
        phase, f, fdot, fddot, e * math.sin(w), e * math.cos(w), wdot
    ),
    f=st.floats(1e-3, 2e-2),
    fdot=st.floats(-1e-15, 1e-14),
    fddot=st.floats(-1e-25, 1e-25),
    e=st.floats(0.0, 0.09),
    w=st.floats(0.0, 2 * math.pi),
    wdot=st.floats(0.0, 1e-5),
    phase=st.floats(0.0, 2 * math.pi),
)


@settings(max_examples=60, deadline=None)
@given(
    p=params_st,
    start_yr=st.floats(-3.0, 12.0),
    u_star=st.floats(0.0, 2 * math.pi),
    star=st.sampled_from([1, 2]),
)
def test_round_trip_u_of_t_star(p: PhaseParams, start_yr: float, u_star: float, star: int) -> None:
    """u(t★) = u★ to 1e-10 rad (docs/method.md), over e, ω, ω̇, ḟ, f̈ and epochs ±12 yr."""
    start = start_yr * YEAR
    k, dt, us, origin = solve_u(p, start, start + 6 * 3600.0, u_star, star)
    assert k.size > 0
    res = _resid(p, k, dt, us, origin, star)
    # 1e-10 rad: the bound; float64 offsets < 6 h keep the time grid at 1e-12 s
    assert np.max(np.abs(res)) < 1e-10
    # completeness: consecutive solutions are one orbit apart (no passage missed or doubled)
    period = 2 / p.f_gw
    gaps = np.diff(origin + dt)
    assert np.all(np.abs(gaps / period - 1) < 0.25)
    assert np.all(np.diff(k) == 1)


@settings(max_examples=30, deadline=None)
@given(p=params_st, start_yr=st.floats(-2.0, 10.0), branch=st.sampled_from(["+", "-"]))
def test_zero_crossing_solves_exact_condition(p: PhaseParams, start_yr: float, branch: str) -> None:
    """Zero crossing solves cos u = −κ(t) exactly (not its first-order form), to 1e-10."""
    start = start_yr * YEAR
    k, dt, us, origin = solve_u(p, start, start + 3600.0, f"zero-crossing{branch}")
    _, kap = ll_pair(p, origin + dt)
    assert np.max(np.abs(np.cos(us) + kap)) < 1e-12
    assert np.max(np.abs(_resid(p, k, dt, us, origin))) < 1e-10
    # first-order placement: π/2 + κ (branch +) and 3π/2 − κ (branch −), error O(κ³)
    approx = math.pi / 2 + kap if branch == "+" else 3 * math.pi / 2 - kap
    assert np.max(np.abs(us - approx)) < np.max(np.abs(kap)) ** 3 + 1e-12


def _t_asc(p: PhaseParams) -> float:
    """T_asc nearest the reference: Φ_asc = 0 (Appendix A1)."""
    return -p.phase / (2 * math.pi * p.f_gw)


@pytest.mark.parametrize("scale", [1.0, 0.5])
def test_appendix_a_epoch_formulas(scale: float) -> None:
    """Node, zero crossing and conjunction epochs of Appendix A1 agree with Newton to O(e²).

    Reference: T_asc + 2η/n̄ (u = 0), T_asc + π/(2n̄) − κ/n̄ (zero crossing),
    T_asc + π/(2n̄) − 2κ/n̄ (u = π/2). docs/method.md: ≤ 6 ms at e = 0.0096; we require ≤ 2 e²/n̄
    and check the error falls ∝ e² when e is halved.
    """
    # Table 3 midpoint (η, κ) of the fiducial source, e = 0.0094 (the docs/method.md check)
    p = PhaseParams(0.3, 8.4062899940e-3, 0.0, 0.0, 8.249643e-3 * scale, 4.524585e-3 * scale, 0.0)
    nbar = math.pi * p.f_gw
    e2 = p.eccentricity**2
    t_asc = _t_asc(p)
    w0 = t_asc - 30.0
    _, node, _, o = solve_u(p, w0, w0 + 200.0, 0.0)
    _, zc, _, _ = solve_u(p, w0, w0 + 200.0, "zero-crossing+")
    _, conj, _, _ = solve_u(p, w0, w0 + 200.0, math.pi / 2)
    err_node = abs(o + node[0] - (t_asc + 2 * p.eta / nbar))
    err_zc = abs(o + zc[0] - (t_asc + math.pi / (2 * nbar) - p.kappa / nbar))
    err_conj = abs(o + conj[0] - (t_asc + math.pi / (2 * nbar) - 2 * p.kappa / nbar))
    for err in (err_node, err_zc, err_conj):
        assert err < 2 * e2 / nbar
    if scale == 1.0:
        assert max(err_node, err_zc, err_conj) < 6e-3  # docs/method.md, "Phase model"


def _kepler_u(p: PhaseParams, tau: np.ndarray) -> np.ndarray:
    """Exact u = ω + ν from Kepler's equation with mean anomaly M = Φ_asc − ω (ω̇ = 0)."""
    e, w = p.eccentricity, p.omega_rad
    mean = phase_asc(p, tau) - w
    ecc_anom = mean.copy()
    for _ in range(50):
        ecc_anom = ecc_anom - (ecc_anom - e * np.sin(ecc_anom) - mean) / (1 - e * np.cos(ecc_anom))
    nu = 2 * np.arctan2(
        np.sqrt(1 + e) * np.sin(ecc_anom / 2), np.sqrt(1 - e) * np.cos(ecc_anom / 2)
    )
    return w + nu


@pytest.mark.parametrize("e", [0.0096, 0.03, 0.08])
def test_first_order_u_vs_exact_kepler(e: float) -> None:
    """First-order u differs from the exact Kepler ω + ν by ≤ 2e² rad (docs/method.md: ≈ 1.25e²)."""
    p = PhaseParams(1.0, 8.4e-3, 0.0, 0.0, e * math.sin(0.7), e * math.cos(0.7), 0.0)
    tau = np.linspace(0.0, 2 * 238.0, 2001)
    diff = np.angle(np.exp(1j * (arg_latitude(p, tau) - _kepler_u(p, tau))))
    assert np.max(np.abs(diff)) <= 2 * e**2
    assert np.max(np.abs(diff)) > 0.5 * e**2  # the residual really is the O(e²) term


def test_rate_matches_finite_difference() -> None:
    """Analytic du/dt vs a central difference (h = 1e-3 s; truncation ~u‴h²/6 ≪ 1e-9 rad/s)."""
    tau = np.linspace(-5e7, 2e8, 37)
    h = 1e-3
    fd = np.array(
        [
            2
            * math.pi
            * (
                (lambda a, b: (a[0] - b[0]) + (a[1] - b[1]))(
                    u_cycles(FID, np.array([h]), t), u_cycles(FID, np.array([-h]), t)
                )[0]
            )
            / (2 * h)
            for t in tau
        ]
    )
    rate = arg_latitude_rate(FID, tau)
    assert np.max(np.abs(rate - fd)) < 1e-9


def test_velocity_equals_ell1_roemer_derivative() -> None:
    """v1 = K(cos u + κ) equals the ELL1 velocity (d/dt of Eq. roemer-ell1) to O(e²K)."""
    p = PhaseParams(0.4, 8.4e-3, 0.0, 0.0, 0.0085, 0.0045, 0.0)
    tau = np.linspace(0, 500, 1001)
    phi = phase_asc(p, tau)
    k = 585.3
    ell1 = k * (np.cos(phi) + p.kappa * np.cos(2 * phi) + p.eta * np.sin(2 * phi))
    ours = radial_velocity(p, tau, k, gamma=0.0, star=1)
    assert np.max(np.abs(ours - ell1)) < 3 * p.eccentricity**2 * k
    v2 = radial_velocity(p, tau, 712.6, gamma=5.0, star=2)
    assert np.allclose(v2 - 5.0, -712.6 / k * ours)


def test_star_two_is_half_an_orbit_away() -> None:
    """ε_2 = π: u_2 = u_1 + π exactly."""
    tau = np.linspace(0, 1e6, 11)
    assert np.allclose(arg_latitude(FID, tau, star=2) - arg_latitude(FID, tau, star=1), math.pi)


def test_ll_rotation_preserves_e_and_advances_omega() -> None:
    """(η, κ) rotate rigidly: e constant, ω(τ) = ω_ref + ω̇τ (Eq. kappa_lisa_prediction)."""
    tau = np.linspace(-1e8, 1e8, 9)
    eta, kap = ll_pair(FID, tau)
    assert np.allclose(np.hypot(eta, kap), FID.eccentricity, rtol=1e-14)
    w = np.arctan2(eta, kap)
    assert np.allclose(
        np.angle(np.exp(1j * (w - FID.omega_rad - FID.omega_dot * tau))), 0, atol=1e-12
    )


def test_quadrature_epoch_is_velocity_extremum() -> None:
    """At u★ = 0 the predicted v1 is maximal: brute-force maximum of v1(t) agrees with t★."""
    p = FID
    _k, dt, _us, o = solve_u(p, 1e7, 1e7 + 300.0, 0.0)
    t_star = o + dt[0]

    def dv(t: float) -> float:
        h = 1e-3
        return float(radial_velocity(p, t + h, 1.0)[()] - radial_velocity(p, t - h, 1.0)[()])

    t_max = brentq(dv, t_star - 20, t_star + 20, xtol=1e-9)
    # v ∝ cos u + κ(t): the extremum is at u = 0 up to κ̇ ~ ω̇e terms (≪ 1 ms)
    assert abs(t_max - t_star) < 1e-3


def test_ascending_node_is_u_zero() -> None:
    """At T_asc (Appendix A1) a circular orbit has u = 0 mod 2π; σ(T_asc) = σ_φ/(2πf)."""
    from ucbplan.core.phase import ascending_node_s, sigma_ascending_node_s

    p = PhaseParams(2.3, 8.4e-3, 0.0, 0.0, 0.0, 0.0, 0.0)
    u = arg_latitude(p, np.array([ascending_node_s(p)]))[0]
    assert abs(np.angle(np.exp(1j * u))) < 1e-12
    cov = np.zeros((7, 7))
    cov[0, 0] = 0.03**2
    assert sigma_ascending_node_s(p, cov) == pytest.approx(0.03 / (2 * math.pi * 8.4e-3))


def test_find_epochs_takes_any_ephemeris_source() -> None:
    """The core asks only for params, covariance and t_obs_s: a plain record works (no Target)."""
    from types import SimpleNamespace

    from ucbplan.core.ephemeris import find_epochs

    cov = np.zeros((7, 7))
    cov[0, 0] = 1e-4  # σ_φ = 0.01 rad → σ_u ≈ 5e-3 rad at every epoch
    src = SimpleNamespace(params=FID, covariance=cov, t_obs_s=1e8)
    es = find_epochs(src, 1e6, 1e6 + 600.0, "quadrature")
    assert len(es) == pytest.approx(600 / 238 * 2, abs=2)
    u = arg_latitude(FID, es.tau_s)
    assert np.max(np.abs(np.angle(np.exp(1j * (u - es.u_star_rad))))) < 1e-9
    # σ_u = ½σ_φ(1 + O(e)) through the e-dependent ∂u/∂φ; σ_t = σ_u/|u̇| with |u̇| ≈ πf
    assert np.all(np.abs(es.sigma_u_rad - 5e-3) < 5e-3 * 3 * FID.eccentricity)
    assert np.allclose(es.sigma_t_s, 5e-3 / (math.pi * FID.f_gw), rtol=4 * FID.eccentricity)
    # π-mode alternative a quarter orbit (≈ P_b/4 ≈ 59.5 s) earlier
    assert np.allclose(es.tau_s - es.tau_alt_s, 0.25 * 2 / FID.f_gw, rtol=0.1)


def test_details_of_a_subset_equal_those_of_the_whole_set(
    hm_cnc_path: Path, eccentric_path: Path
) -> None:
    """σ_t, σ_u, u̇ and the π-mode alternative of chosen epochs (the planner's usable blocks)
    are bit for bit those that find_epochs computes for every epoch."""
    from ucbplan.core.ephemeris import find_epochs, with_details
    from ucbplan.targets import load_target

    for path in (hm_cnc_path, eccentric_path):
        target = load_target(path)
        for anchor in ("quadrature", "zero-crossing"):
            whole = find_epochs(target, 0.0, 30 * 86400.0, anchor)
            bare = find_epochs(target, 0.0, 30 * 86400.0, anchor, details=False)
            assert np.all(np.isnan(bare.sigma_t_s)) and np.array_equal(bare.dt_s, whole.dt_s)
            idx = np.sort(np.random.default_rng(3).choice(len(whole), 500, replace=False))
            part = with_details(target, bare, idx)
            for field in ("sigma_t_s", "sigma_u_rad", "tau_alt_s", "u_rate"):
                np.testing.assert_array_equal(getattr(part, field)[idx], getattr(whole, field)[idx])
                others = np.setdiff1d(np.arange(len(whole)), idx)
                assert np.all(np.isnan(getattr(part, field)[others]))


@settings(max_examples=30, deadline=None)
@given(p=params_st, start_yr=st.floats(-2.0, 10.0), branch=st.sampled_from(["+", "-"]))
def test_star2_zero_crossing_is_where_star2_velocity_is_gamma(
    p: PhaseParams, start_yr: float, branch: str
) -> None:
    """Star 2's zero crossings: v₂(t★) = γ₂ from the velocity model (issue 26, item 3).

    Reference: radial_velocity(star=2) = γ₂ − K₂(cos u₁ + κ), evaluated independently of the
    solver at the returned epochs; |cos u₁ + κ| < 1e-9 (the issue's bound; the Newton floor is
    1e-12 rad). Star 2's zero crossings are star 1's instants, so the epochs must agree too.
    """
    start = start_yr * YEAR
    k, dt, us, origin = solve_u(p, start, start + 3600.0, f"zero-crossing{branch}", star=2)
    assert k.size > 0
    # v₂ − γ₂ = −K₂(cos u₁ + κ) of Eq. v1v2_ecc_rv, u₁ evaluated with the window origin kept
    # separate and u₁ reduced to whole cycles + g (the unwrapped u ≈ 1e7 rad would cost 1e-9)
    _, g1 = u_cycles(p, dt, origin, 1)
    _, kap = ll_pair(p, origin + dt)
    assert np.max(np.abs(np.cos(2 * math.pi * g1) + kap)) < 1e-9
    # the velocity model itself (star=2 sign convention) at the returned epochs, 1e-6 of K₂
    v2 = radial_velocity(p, origin + dt, k=1.0, gamma=0.0, star=2)
    assert np.max(np.abs(v2)) < 1e-6
    assert np.max(np.abs(_resid(p, k, dt, us, origin, star=2))) < 1e-10
    _, dt1, _, o1 = solve_u(p, start, start + 3600.0, "zero-crossing+", star=1)
    _, dt1m, _, _ = solve_u(p, start, start + 3600.0, "zero-crossing-", star=1)
    star1 = np.sort(np.concatenate([o1 + dt1, o1 + dt1m]))
    # every star-2 epoch is one of star 1's (1e-6 s: the Newton floor over a 1-h window)
    near = np.min(np.abs((origin + dt)[:, None] - star1[None, :]), axis=1)
    assert np.max(near) < 1e-6


@settings(max_examples=300, deadline=None)
@given(st.lists(st.tuples(st.integers(-60, 60), st.integers(-5, 40)), min_size=1, max_size=12))
def test_integer_union_is_numpys_unique_of_the_ranges(ranges: list[tuple[int, int]]) -> None:
    # The orbit counts of sub-windows: every integer of [lo, lo + width] once, ascending (empty
    # ranges too), equal to np.unique of the concatenated ranges, dtype included.
    from ucbplan.core.ephemeris import integer_union

    lo = np.array([a for a, _ in ranges], dtype=np.int64)
    hi = lo + np.array([w for _, w in ranges], dtype=np.int64)
    parts = [np.arange(a, b + 1) for a, b in zip(lo, hi, strict=True)]
    expected = np.unique(np.concatenate(parts))
    got = integer_union(lo, hi)
    assert got.dtype == np.int64
    np.testing.assert_array_equal(got, expected.astype(np.int64))


class _OpaqueZero(float):
    """0.0 that does not compare equal to 0.0: drives u_state through its eccentric branch."""

    def __eq__(self, other: object) -> bool:
        return False

    __hash__ = float.__hash__


@pytest.mark.parametrize("star", [1, 2])
@pytest.mark.parametrize("origin", [0.0, -3.2e7, 1.3e8])
def test_circular_u_state_is_the_eccentric_formula_at_zero(star: int, origin: float) -> None:
    # The circular shortcut (η = κ = ω̇ = 0) gives the general formula's bits: m, g and u̇ over
    # both signs of τ, several origins, both stars (±0 terms add nothing).
    from ucbplan.core.phase import u_state

    circ = PhaseParams(1.3466, 8.379e-3, 7.07e-16, -1.07e-26)
    zero = _OpaqueZero(0.0)
    general = PhaseParams(1.3466, 8.379e-3, 7.07e-16, -1.07e-26, zero, zero, zero)
    assert not zero == 0.0
    dt = np.random.default_rng(5).uniform(-4e7, 4e7, 20000)
    for fast, slow in zip(
        u_state(circ, dt, origin, star), u_state(general, dt, origin, star), strict=True
    ):
        np.testing.assert_array_equal(fast, slow)


@pytest.mark.parametrize("shape", [(5, 7), (8192, 7), (8193, 7), (30011, 7), (3, 9000, 7)])
def test_jacobian_products_in_blocks_equal_one_product(shape: tuple[int, ...]) -> None:
    # σ_u's J·C in row blocks (mvnormal.rows_times, kept on the calling thread) gives the one
    # product's bits, whatever the stack's shape, and so does σ_u itself.
    from ucbplan.core.phase import _times, sigma_u_from_jacobian

    rng = np.random.default_rng(17)
    jac = rng.standard_normal(shape) * 10.0 ** rng.uniform(-6.0, 6.0, shape)
    root = rng.standard_normal((7, 7))
    cov = root @ root.T * 1e-12
    np.testing.assert_array_equal(_times(jac, cov), jac @ cov)
    whole = np.sqrt(np.maximum(np.sum((jac @ cov) * jac, axis=-1), 0.0))
    np.testing.assert_array_equal(sigma_u_from_jacobian(jac, cov), whole)


def _mean_seeds_all_steps(p: PhaseParams, origin_s: float, target_cycles: np.ndarray) -> np.ndarray:
    """The mean-phase seeds with all eight Newton steps on every offset (as before issue 34)."""
    nu0 = 0.5 * (p.f_gw + p.fdot * origin_s + p.fddot * origin_s**2 / 2)
    nu1 = 0.5 * (p.fdot + p.fddot * origin_s)
    nu2 = 0.5 * p.fddot
    dt = target_cycles / nu0
    for _ in range(8):
        val = nu0 * dt + nu1 * dt**2 / 2 + nu2 * dt**3 / 6 - target_cycles
        der = nu0 + nu1 * dt + nu2 * dt**2 / 2
        dt = dt - val / der
    return dt


@settings(max_examples=40, deadline=None)
@given(p=params_st, origin_yr=st.floats(-10.0, 30.0), n=st.integers(0, 3000), frac=st.floats(0, 1))
def test_mean_seeds_stepping_only_offsets_that_move_are_every_step(
    p: PhaseParams, origin_yr: float, n: int, frac: float
) -> None:
    """Seeds stepped only while a step still changes them (issue 34) are, bit for bit, those of
    all eight steps everywhere: a step that leaves an offset unchanged leaves it so forever."""
    from ucbplan.core.ephemeris import _mean_seeds

    cycles = np.arange(n) * (1.0 + 1e-3 * frac) - 2.0 + frac
    got = _mean_seeds(p, origin_yr * YEAR, cycles)
    want = _mean_seeds_all_steps(p, origin_yr * YEAR, cycles)
    assert got.dtype == np.float64 and got.tobytes() == want.tobytes()
