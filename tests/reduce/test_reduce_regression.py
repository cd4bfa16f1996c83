"""Regression kernels of ``ucbplan reduce`` vs independent values (paper, numpy, brute force)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ucbplan.core.smearing import lambda_k, lambda_kappa
from ucbplan.reduce.regression import (
    OUTLIER_NSIGMA,
    ComponentFit,
    binned_design,
    fit_component,
    lambda_k_to_x,
    line_slope,
    line_weights,
    paper_recipe,
    phase_sensitivity,
    two_spectrum_solution,
    weighted_line,
    wilson_fit,
)

NBAR = math.pi * 8.4062899940e-3  # fiducial n̄_b [rad/s]
P_MEAN = 2.0 * math.pi / NBAR


def test_lambda_factors_match_reference_values() -> None:
    """Λ_K(P/8) = 0.97450, 1/Λ_K(P/3) = 1.2092, Λ_κ(P/3) = 0.4135 (docs/method.md, "Smearing").

    Tolerance 5e-5: the printed precision of the reference values.
    """
    assert float(lambda_k(P_MEAN / 8, NBAR)) == pytest.approx(0.97450, abs=5e-5)
    assert 1.0 / float(lambda_k(P_MEAN / 3, NBAR)) == pytest.approx(1.2092, abs=5e-5)
    assert float(lambda_kappa(P_MEAN / 3, NBAR)) == pytest.approx(0.4135, abs=5e-5)
    # the paper's "Λ_K = sinc(π/8) = 0.974" (Sec. 5) and "Λ_K ≃ 0.83" at P/3 (Appendix B)
    assert float(lambda_k(P_MEAN / 8, NBAR)) == pytest.approx(0.974, abs=5e-4)
    assert float(lambda_k(P_MEAN / 3, NBAR)) == pytest.approx(0.83, abs=5e-3)
    assert float(lambda_k(0.0, NBAR)) == 1.0


def test_lambda_k_matches_brute_force_average() -> None:
    """Λ_K equals the numerical window average of cos(n̄t) centred on a maximum (1e-10)."""
    dt = P_MEAN / 5
    t = np.linspace(-dt / 2, dt / 2, 200001)
    brute = np.trapezoid(np.cos(NBAR * t), t) / dt
    assert float(lambda_k(dt, NBAR)) == pytest.approx(brute, abs=1e-10)
    brute2 = np.trapezoid(np.cos(2 * NBAR * t), t) / dt
    assert float(lambda_kappa(dt, NBAR)) == pytest.approx(brute2, abs=1e-10)


@settings(max_examples=50, deadline=None)
@given(st.floats(min_value=0.0, max_value=3.0))
def test_lambda_k_inversion_round_trip(x: float) -> None:
    """x → Λ_K = sin x/x → x recovers x to 1e-7 rad (Newton on a smooth monotone function)."""
    lam = math.sin(x) / x if x > 0 else 1.0
    assert float(lambda_k_to_x(lam)[0]) == pytest.approx(x, abs=1e-7)


def test_weighted_line_matches_numpy_polyfit() -> None:
    """Slope/intercept and formal covariance equal numpy.polyfit(w=1/σ, cov='unscaled') (1e-10)."""
    rng = np.random.default_rng(3)
    x = rng.uniform(-1, 1, 60)
    s = rng.uniform(5, 20, 60)
    y = 12.0 + 600.0 * x + rng.normal(0, s)
    fit = weighted_line(x, y, s, scale=False)
    coef, cov = np.polyfit(x, y, 1, w=1.0 / s, cov="unscaled")
    assert fit.slope == pytest.approx(coef[0], rel=1e-10)
    assert fit.intercept == pytest.approx(coef[1], rel=1e-10)
    assert fit.cov[1, 1] == pytest.approx(cov[0, 0], rel=1e-8)
    assert fit.cov[0, 0] == pytest.approx(cov[1, 1], rel=1e-8)
    assert fit.cov[0, 1] == pytest.approx(cov[0, 1], rel=1e-8)


def test_outliers_are_flagged_not_dropped() -> None:
    """A 10σ point is flagged; the slope still includes it (differs from the fit without it)."""
    x = np.linspace(-1, 1, 41)
    y = 3.0 + 100.0 * x
    y[7] += 10 * 15.0
    s = np.full(x.size, 15.0)
    fit = weighted_line(x, y, s)
    assert fit.outliers[7] and fit.outliers.sum() == 1
    assert abs(fit.normalized[7]) > OUTLIER_NSIGMA
    clean = weighted_line(np.delete(x, 7), np.delete(y, 7), np.delete(s, 7))
    assert fit.slope != pytest.approx(clean.slope, abs=1e-9)
    assert fit.scaled  # χ²/dof > 1 → errors inflated


def test_paper_sigma_k_480_spectra() -> None:
    """Sec. 5: N = 480, σ_v = 15 km/s, 8 exposures/orbit → σ_slope = σ_v√(2/N) ≈ 0.97 km/s.

    With u spread uniformly (8 phases) Σcos²u = N/2 exactly, so σ_slope = 15·√(2/480) = 0.968;
    dividing by Λ_K(P/8) gives σ_K = 0.993. At the two quadratures only, σ = σ_v/√N = 0.685
    (Appendix C, "a factor of √2 better").
    """
    u = (np.arange(480) % 8 + 0.5) * math.pi / 4
    G = binned_design(u, 0.0, 0.0, lambda_k(P_MEAN / 8, NBAR), 1.0)
    fit = fit_component(G, 100.0 + 585.3 * G, np.full(480, 15.0), star=1)
    assert fit.line.sigma_slope * float(lambda_k(P_MEAN / 8, NBAR)) == pytest.approx(
        15 * math.sqrt(2 / 480), rel=1e-12
    )
    assert fit.sigma_K == pytest.approx(0.968 / 0.9745, abs=1e-3)
    uq = (np.arange(480) % 2) * math.pi
    fq = fit_component(np.cos(uq), 585.3 * np.cos(uq), np.full(480, 15.0), star=1)
    assert fq.sigma_K == pytest.approx(15 / math.sqrt(480), rel=1e-12)


@pytest.mark.parametrize("eta,kappa", [(0.0, 0.0), (0.0068, 0.0068), (-0.008, 0.0045)])
def test_two_spectrum_quadrature_limit_agrees_with_fit(eta: float, kappa: float) -> None:
    """Two spectra at u = 0, π: the regression equals Eqs. sb2_half_diff / sb2_half_sum_ecc.

    Data from the first-order model with u★ = 0, π mapped to Φ_c by Eq. Phi_c. The two agree to
    O(e²K): tolerance 3e²K + 1e-9 km/s (0.0 for circular).
    """
    phi = np.array([2 * eta, math.pi - 2 * eta])  # Eq. Phi_c at u★ = 0, π
    G = binned_design(phi, eta, kappa)
    K1, K2, g1, g2 = 585.3, 712.6, 30.0, 10.0
    v1, v2 = g1 + K1 * G, g2 - K2 * G
    s = np.ones(2)
    f1, f2 = fit_component(G, v1, s, 1), fit_component(G, v2, s, 2)
    k1, gg1 = two_spectrum_solution(v1[0], v1[1], 1, kappa_s=kappa)
    k2, gg2 = two_spectrum_solution(v2[0], v2[1], 2, kappa_s=kappa)
    e2 = eta**2 + kappa**2
    for a, b, K in ((f1.K, k1, K1), (f1.gamma, gg1, K1), (f2.K, k2, K2), (f2.gamma, gg2, K2)):
        assert a == pytest.approx(b, abs=3 * e2 * K + 1e-9)
    assert f1.K == pytest.approx(K1, abs=1e-9) and f2.gamma == pytest.approx(g2, abs=1e-9)


def test_paper_recipe_equals_design_fit_for_common_window() -> None:
    """Regressing on F then K = slope/Λ_K, γ with the Λ_κ κ_s K term equals the design fit.

    Common window P/3, quadrature sampling (where Eq. vbar_quad is exact to O(e²)), e = 0.0096:
    the two estimators agree to 2e²K (≈ 0.1 km/s ≪ σ).
    """
    eta, kappa = 0.0068, 0.0068
    lk, lkap = float(lambda_k(P_MEAN / 3, NBAR)), float(lambda_kappa(P_MEAN / 3, NBAR))
    u = (np.arange(200) % 2) * math.pi
    phi = u - 2 * kappa * np.sin(u) + 2 * eta * np.cos(u)
    G = binned_design(phi, eta, kappa, lk, lkap)
    F = np.cos(u) + kappa
    v = 30.0 + 585.3 * G
    s = np.full(u.size, 15.0)
    fit = fit_component(G, v, s, 1)
    K, gamma = paper_recipe(F, v, s, 1, lk, lkap, kappa)
    tol = 2 * (eta**2 + kappa**2) * 585.3
    assert K == pytest.approx(fit.K, abs=tol)
    assert gamma == pytest.approx(fit.gamma, abs=tol)
    # and the uncorrected intercept is biased by K κ (Λ_κ − Λ_K) ≈ −1.7 km/s: the correction matters
    raw = weighted_line(F, v, s).intercept
    assert abs(raw - 30.0) > 1.5


def test_wilson_fit_recovers_q_and_intercept() -> None:
    """WIL41 line on noise-free pairs: q = K1/K2 and γ1 + qγ2 exactly (1e-9)."""
    u = np.linspace(0, 2 * math.pi, 37)
    v1, v2 = 30 + 585.3 * np.cos(u), 10 - 712.6 * np.cos(u)
    w = wilson_fit(v1, np.full(37, 15.0), v2, np.full(37, 15.0))
    q = 585.3 / 712.6
    assert w.q == pytest.approx(q, rel=1e-9)
    assert w.intercept == pytest.approx(30 + q * 10, abs=1e-7)


@pytest.mark.parametrize(("s1", "s2"), [(100.0, 100.0), (60.0, 140.0), (140.0, 60.0)])
def test_wilson_q_unbiased_over_noise_realisations(s1: float, s2: float) -> None:
    """WIL41 q unbiased with errors on both velocities (issue 26, item 2).

    Reference: the true q = K1/K2 of the simulated pairs (v1 = γ1 + K1 cos u, v2 = γ2 − K2 cos u,
    40 phases, σ ~ 0.1–0.2 K: a plain regression of v1 on v2 is diluted by Var(v2)/(Var(v2) +
    σ2²), ≈ 0.8σ per data set here). Over 1500 seeded realisations the mean of q must sit within
    0.1σ_q of the truth (σ_q = the scatter of q; the Monte-Carlo error of the mean is 0.026σ_q,
    so 0.1σ_q is a 4σ bound), and the reported σ_q must match the scatter to 10 % (Monte-Carlo
    error of a standard deviation from 1500 draws: 1.8 %; the σ_q formula is first order).
    Runs in ~1 s.
    """
    rng = np.random.default_rng(2611)
    K1, K2, g1, g2 = 585.3, 712.6, 30.0, -10.0
    q_true = K1 / K2
    u = np.linspace(0.0, 2 * math.pi, 40, endpoint=False)
    qs, sq = [], []
    for _ in range(1500):
        v1 = g1 + K1 * np.cos(u) + rng.normal(0.0, s1, u.size)
        v2 = g2 - K2 * np.cos(u) + rng.normal(0.0, s2, u.size)
        w = wilson_fit(v1, np.full(u.size, s1), v2, np.full(u.size, s2), q0=1.0)
        qs.append(w.q)
        sq.append(w.sigma_q)
    scatter = float(np.std(qs))
    assert abs(float(np.mean(qs)) - q_true) < 0.1 * scatter
    assert float(np.median(sq)) == pytest.approx(scatter, rel=0.10)


def test_phase_sensitivity_matches_brute_force_refit() -> None:
    """∂K/∂θ and ∂γ/∂θ agree with refitting on the design of a perturbed θ.

    θ here is a generic phase offset δ = 1e-3 rad added to Φ (∂G/∂δ = −Λ_K sin Φ − …); the
    re-regression shift is −(∂K/∂θ)δ (docstring of phase_sensitivity). Noise-free data (the
    linearisation drops noise×δ terms); tolerance 3 %: the O(δ²K) term is 1 % of the linear one.
    """
    rng = np.random.default_rng(5)
    phi = rng.uniform(0, 2 * math.pi, 300)
    eta, kappa, lk, lkap = 0.0068, 0.0068, 0.97, 0.9
    G = binned_design(phi, eta, kappa, lk, lkap)
    s = rng.uniform(10, 20, 300)
    v1 = 30 + 585.3 * G
    f = fit_component(G, v1, s, 1)
    d = 1e-4
    dG = (
        binned_design(phi + d, eta, kappa, lk, lkap) - binned_design(phi - d, eta, kappa, lk, lkap)
    ) / (2 * d)
    dK, dg = phase_sensitivity(G, s, dG[:, None], f.K, 1.0)
    delta = 1e-3
    f2 = fit_component(binned_design(phi + delta, eta, kappa, lk, lkap), v1, s, 1)
    assert f2.K - f.K == pytest.approx(-dK[0] * delta, rel=3e-2)
    assert f2.gamma - f.gamma == pytest.approx(-dg[0] * delta, rel=3e-2)


def test_wilson_fit_is_the_chi2_minimum_with_q_in_the_variance() -> None:
    """The WIL41 q minimises Σ(v1 − a + q v2)²/(σ1² + q²σ2²) over (a, q) (Deming/York).

    Reference: scipy's bounded scalar minimiser on the profile χ²(q) (a eliminated as its
    weighted mean); tolerance 1e-6 in q, the minimiser's xatol (χ² is flat to second order).
    """
    from scipy.optimize import minimize_scalar

    rng = np.random.default_rng(7)
    u = rng.uniform(0, 2 * math.pi, 25)
    s1, s2 = rng.uniform(20, 80, 25), rng.uniform(40, 160, 25)
    v1 = 5 + 400 * np.cos(u) + rng.normal(0, s1)
    v2 = -3 - 650 * np.cos(u) + rng.normal(0, s2)

    def chi2(q: float) -> float:
        w = 1 / (s1**2 + q * q * s2**2)
        a = float((w * (v1 + q * v2)).sum() / w.sum())
        return float((w * (v1 - a + q * v2) ** 2).sum())

    ref = minimize_scalar(chi2, bounds=(0.2, 1.5), method="bounded", options={"xatol": 1e-9})
    fit = wilson_fit(v1, s1, v2, s2, q0=1.0)
    assert fit.q == pytest.approx(ref.x, abs=1e-6)
    assert fit.chi2 == pytest.approx(chi2(fit.q), rel=1e-12)


def _scattered_fit(extra: float, n: int = 400) -> ComponentFit:
    """A star-1 fit of n spectra whose scatter is σ·extra (σ = 10 km/s given)."""
    rng = np.random.default_rng(11)
    g = np.cos(np.linspace(0.0, 40.0, n))
    v = 30.0 + 300.0 * g + rng.normal(0.0, 10.0 * extra, n)
    return fit_component(g, v, np.full(n, 10.0), 1)


@pytest.mark.parametrize("extra", [1.0, 1.2, 1.6])
def test_sigma_k_scaling_is_reported_and_warned_by_one_rule(extra: float) -> None:
    """Issue 33: σ(K) was scaled by √(χ²/dof) whenever χ²/dof > 1, the warning fired only
    above 2 and the report gave the scaled σ alone. Now the fit carries the scale, the
    statistical σ from the given σ_v alone is kept beside the scaled one, and the warning fires
    whenever the excess is significant (χ² above its 99th percentile for the dof), independent
    closed form: σ_K = σ/√Σ(G − Ḡ)², times √(χ²/dof)."""
    from scipy.stats import chi2 as chi2_dist

    from ucbplan.reduce.pipeline import _fit_warnings

    f = _scattered_fit(extra)
    g = np.cos(np.linspace(0.0, 40.0, 400))
    closed = 10.0 / math.sqrt(float(((g - g.mean()) ** 2).sum()))
    ratio = f.line.chi2 / f.line.dof
    assert f.sigma_K_input == pytest.approx(closed, rel=1e-12)
    assert f.line.scale == pytest.approx(math.sqrt(ratio) if ratio > 1 else 1.0, rel=1e-12)
    assert f.sigma_K == pytest.approx(f.sigma_K_input * f.line.scale, rel=1e-12)
    warned = [w for w in _fit_warnings((f,)) if "χ²/dof" in w]
    significant = f.line.chi2 > chi2_dist.ppf(0.99, f.line.dof)
    assert bool(warned) == significant
    assert significant == (extra > 1.1)  # 1.2 (χ²/dof ≈ 1.44) is significant, unlike 1.0
    if warned:
        assert f"σ(K) {f.sigma_K_input:.3g} → {f.sigma_K:.3g} km/s" in warned[0], warned


@pytest.mark.parametrize("n", [2, 3, 8191, 8192, 8193, 3 * 8192 + 5])
def test_phase_sensitivity_block_sums_are_the_whole_products(n: int) -> None:
    """phase_sensitivity sums its (n, 7) products block by block; the result is the sum of the
    whole products bit for bit (numpy's row-after-row order carried across blocks), on values
    spread over 40 decades so that any other order of the additions would show."""
    from ucbplan.reduce import regression

    rng = np.random.default_rng(n)
    x, s = rng.standard_normal(n), rng.uniform(5, 20, n)
    dG = rng.standard_normal((n, 7)) * np.exp(rng.uniform(-46, 46, (n, 7)))
    w = 1.0 / s**2
    for weights in (w, w * (x - 0.3)):
        whole = (weights[:, None] * dG).sum(axis=0)
        np.testing.assert_array_equal(regression._weighted_column_sums(weights, dG), whole)
    sw = w.sum()
    xm = (w * x).sum() / sw
    sxx = (w * (x - xm) ** 2).sum()
    slope = -1.0 * 585.3 * ((w * (x - xm))[:, None] * dG).sum(axis=0) / sxx
    intercept = -1.0 * 585.3 * (w[:, None] * dG).sum(axis=0) / sw - xm * slope
    dK, dg = phase_sensitivity(x, s, dG, 585.3, -1.0)
    np.testing.assert_array_equal(dK, -1.0 * slope)
    np.testing.assert_array_equal(dg, intercept)


def _line_as_written(x: np.ndarray, y: np.ndarray, sa: np.ndarray) -> list[object]:
    """weighted_line's numbers as its formulas read, one fresh array per operation (the code
    before its products shared a scratch array)."""
    w = 1.0 / sa**2
    sw = w.sum()
    xm = float((w * x).sum() / sw)
    ym = float((w * y).sum() / sw)
    dx = x - xm
    sxx = float((w * dx * dx).sum())
    b = float((w * dx * (y - ym)).sum() / sxx)
    a = ym - b * xm
    res = y - (a + b * x)
    norm = res / sa
    cov = [1.0 / sw + xm * xm / sxx, -xm / sxx, 1.0 / sxx]
    rms = float(np.sqrt(np.mean(res * res)))
    return [b, a, cov, float((norm * norm).sum()), rms, res, norm, np.abs(norm) > OUTLIER_NSIGMA]


@pytest.mark.parametrize(("n", "seed"), [(2, 0), (3, 1), (1000, 2), (100_003, 3)])
def test_weighted_line_and_line_slope_are_the_formulas_bit_for_bit(n: int, seed: int) -> None:
    """weighted_line (its products written into one scratch array) and line_slope (slope and
    intercept alone, from line_weights) give the doubles of the formulas written out."""
    rng = np.random.default_rng(seed)
    x = rng.uniform(-1.0, 1.0, n)
    sa = rng.uniform(5.0, 20.0, n)
    y = 30.0 + 585.3 * x + sa * rng.standard_normal(n) * 3.0
    fit = weighted_line(x, y, sa, scale=False)
    c = fit.cov
    got = [fit.slope, fit.intercept, [c[0, 0], c[0, 1], c[1, 1]], fit.chi2, fit.rms,
           fit.residuals, fit.normalized, fit.outliers]  # fmt: skip
    ref = _line_as_written(x, y, sa)
    for a, b in zip(got, ref, strict=True):
        assert np.asarray(a).tobytes() == np.asarray(b).tobytes()
    assert line_slope(x, y, line_weights(sa)) == (fit.slope, fit.intercept)


def test_line_slope_refuses_what_weighted_line_refuses() -> None:
    """One point, equal abscissae and a bad σ raise the same ValueError in both."""
    one, flat = np.ones(1), np.ones(5)
    with pytest.raises(ValueError, match="two points"):
        line_slope(one, one, one)
    with pytest.raises(ValueError, match="abscissae are equal"):
        line_slope(flat, np.arange(5.0), flat)
    with pytest.raises(ValueError, match="positive and finite"):
        line_weights(np.array([1.0, 0.0]))


def _wilson_as_written(v1: np.ndarray, s1: np.ndarray, v2: np.ndarray, s2: np.ndarray) -> tuple:
    """wilson_fit's York iteration as its formulas read, one fresh array per operation."""
    x, y, wx, wy = v2, v1, 1.0 / s2**2, 1.0 / s1**2

    def terms(b: float) -> tuple:
        W = wx * wy / (wx + b * b * wy)
        xm = float((W * x).sum() / W.sum())
        ym = float((W * y).sum() / W.sum())
        U, V = x - xm, y - ym
        return W, xm, U, V, W * (U / wy + b * V / wx)

    b = -1.0
    for _ in range(200):
        W, _xm, U, V, beta = terms(b)
        b_new = float((W * beta * V).sum() / (W * beta * U).sum())
        done = abs(b_new - b) <= 1e-13 * max(1.0, abs(b_new))
        b = b_new
        if done:
            break
    W, xm, _U, _V, beta = terms(b)
    a = float((W * y).sum() / W.sum()) - b * xm
    xa = xm + beta
    ua = xa - float((W * xa).sum() / W.sum())
    var_b = 1.0 / float((W * ua * ua).sum())
    var_a = 1.0 / float(W.sum()) + float((W * xa).sum() / W.sum()) ** 2 * var_b
    res = y - a - b * x
    return -b, math.sqrt(var_b), a, math.sqrt(var_a), float((W * res * res).sum())


@pytest.mark.parametrize(("n", "seed"), [(3, 0), (500, 1), (100_001, 2)])
def test_wilson_fit_is_york_as_written_bit_for_bit(n: int, seed: int) -> None:
    """The WIL41 fit (York's arrays rewritten in one work array per call) gives the doubles of
    the iteration written out with fresh arrays."""
    rng = np.random.default_rng(seed)
    g = rng.uniform(-1.0, 1.0, n)
    s1, s2 = rng.uniform(5.0, 20.0, n), rng.uniform(5.0, 20.0, n)
    v1 = 30.0 + 585.3 * g + s1 * rng.standard_normal(n)
    v2 = 10.0 - 712.6 * g + s2 * rng.standard_normal(n)
    w = wilson_fit(v1, s1, v2, s2)
    assert (w.q, w.sigma_q, w.intercept, w.sigma_intercept, w.chi2) == _wilson_as_written(
        v1, s1, v2, s2
    )
