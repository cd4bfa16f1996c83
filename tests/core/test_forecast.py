"""σ_u, tolerances and T_valid against the paper's tables and closed-form answers."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from ucbplan.core.forecast import anchor_sigma_u, horizon_table, sigma_u, t_valid, tolerance
from ucbplan.core.params import PARAM_NAMES, PhaseParams, shift_reference
from ucbplan.core.phase import u_cycles, u_jacobian
from ucbplan.targets import load_target

DAY = 86400.0
YEAR = 365.25 * DAY
T4 = 4 * 31558149.7635  # 4 sidereal years (docs/method.md, "Time scales")
FID = PhaseParams(
    2.410235, 8.4062899940e-3, 1.640367e-15, 2e-27, 8.249643e-3, 4.524585e-3, 1.496836e-6
)


def test_tolerances_match_paper_to_four_digits() -> None:
    """Tables 4 and 7 (docs/method.md, "Forecast"): conj σ_v/K_eff, quad (√2σ_v/K_eff)^½ (N = 2)."""
    assert tolerance("conjunction", 15.0, 1298.0, 2) == pytest.approx(0.0115562, rel=1e-4)
    assert tolerance("quadrature", 15.0, 1298.0, 2) == pytest.approx(0.127840, rel=1e-4)
    sv = math.sqrt(2) * 40.0  # σ_v = √2 σ_K (Table 7)
    assert tolerance("conjunction", sv, 390.0, 2) == pytest.approx(0.145048, rel=1e-4)
    assert tolerance("quadrature", sv, 390.0, 2) == pytest.approx(0.452911, rel=1e-4)
    # N = 1 quadrature (2σ_v/K)^½ is larger than N = 2 by 2^(1/4) (Appendix C summary)
    ratio = tolerance("quadrature", 15.0, 1298.0, 1) / tolerance("quadrature", 15.0, 1298.0, 2)
    assert ratio == pytest.approx(2**0.25, rel=1e-12)
    # generic σ_v/(K|sin u★|), capped by the quadrature form near u★ = 0
    assert tolerance("generic", 15.0, 1298.0, 1, u_star=math.pi / 6) == pytest.approx(
        2 * 15 / 1298, rel=1e-12
    )
    assert tolerance("generic", 15.0, 1298.0, 1, u_star=1e-6) == tolerance(
        "quadrature", 15.0, 1298.0, 1
    )


@pytest.mark.parametrize("name", PARAM_NAMES)
def test_jacobian_matches_finite_differences(name: str) -> None:
    """Analytic ∂u/∂θ vs central differences of the exact model (relative 1e-6)."""
    tau = np.array([-3e7, 1e6, 8.3e7, 2.5e8])
    i = PARAM_NAMES.index(name)
    base = FID.as_array()
    step = {
        "phase": 1e-6,
        "f_gw": 1e-13,
        "fdot": 1e-21,
        "fddot": 1e-29,
        "eta": 1e-7,
        "kappa": 1e-7,
        "omega_dot": 1e-12,
    }[name]

    def u_at(v: np.ndarray) -> np.ndarray:
        m, g = u_cycles(PhaseParams.from_array(v), tau)
        m0, _ = u_cycles(FID, tau)
        return 2 * math.pi * ((m - m0) + g)

    plus, minus = base.copy(), base.copy()
    plus[i] += step
    minus[i] -= step
    fd = (u_at(plus) - u_at(minus)) / (2 * step)
    an = u_jacobian(FID, tau)[:, i]
    assert np.allclose(an, fd, rtol=1e-6, atol=1e-6 * np.max(np.abs(an)))


def test_sigma_u_closed_forms() -> None:
    """Single-parameter covariances give σ_u = |∂u/∂θ|σ_θ (Eq. sigma_PhiGW_quartic terms)."""
    p = replace(FID, eta=0.0, kappa=0.0, omega_dot=0.0)
    tau = np.linspace(0, 3e8, 7)
    for i, expect in [
        (0, 0.5 * np.ones_like(tau)),
        (1, math.pi * tau),
        (2, math.pi * tau**2 / 2),
        (3, math.pi * tau**3 / 6),
    ]:
        cov = np.zeros((7, 7))
        cov[i, i] = 1.0
        assert np.allclose(sigma_u(p, cov, tau), expect, rtol=1e-12)


def test_t_valid_closed_form_fdot_only() -> None:
    """Only σ(ḟ): σ_u = πτ²σ/2, so T_valid = √(2·α·tol/(πσ)) − T/2."""
    cov = np.zeros((7, 7))
    sig = 3.41e-19
    cov[2, 2] = sig**2
    p = replace(FID, eta=0.0, kappa=0.0, omega_dot=0.0)
    tol = 0.12784
    for alpha in (0.5, 1.0):
        expect = math.sqrt(2 * alpha * tol / (math.pi * sig)) - T4 / 2
        got = t_valid((p, cov, T4), tol, 0.0, alpha)
        assert got == pytest.approx(expect, rel=1e-6)


def test_t_valid_zero_when_never_admissible() -> None:
    """σ_u above the tolerance from the end of LISA onward → T_valid = 0 (Eq. T_valid_alpha)."""
    cov = np.zeros((7, 7))
    cov[0, 0] = 1.0  # σ_u = 0.5 rad forever
    assert t_valid((FID, cov, T4), 0.1, 0.0, 1.0) == 0.0


def test_t_valid_oscillating_closed_form() -> None:
    """Only σ(κ) with ω̇ ≠ 0: at conjunction σ_u = 2σ_κ|cos ω̇τ| (to O(e)); the first window
    closes where |cos ω̇τ| = tol/(2σ_κ) — the apsidal oscillation must be resolved."""
    p = PhaseParams(0.0, 8.4e-3, 0.0, 0.0, 0.0, 0.0, 1.5e-6)  # e = 0 keeps the form exact
    cov = np.zeros((7, 7))
    sk = 5e-3
    cov[5, 5] = sk**2
    tol = 1.2 * sk  # admissible while |cos ω̇τ| ≤ 0.6
    t_end = T4 / 2
    # first τ ≥ t_end where |cos(ω̇τ)| rises through 0.6, or where it is ≤ 0.6 then rises
    grid = t_end + np.linspace(0, 2 * math.pi / p.omega_dot, 2_000_001)
    c = np.abs(np.cos(p.omega_dot * grid))
    ok = c <= 0.6
    start = int(np.argmax(ok))
    close = start + int(np.argmax(~ok[start:]))
    expect = grid[close] - t_end
    got = t_valid((p, cov, T4), tol, math.pi / 2, 1.0)
    assert got == pytest.approx(expect, abs=60.0)  # grid refined to P_aps/32 then bisected


def test_anchor_sigma_matches_sigma_at_true_epochs(eccentric_path) -> None:
    """σ_u at virtual anchor epochs equals σ_u at the solved t★ (same anchor) to 1e-6 relative."""
    from ucbplan.core.ephemeris import solve_u

    t = load_target(eccentric_path)
    _k, dt, _us, o = solve_u(t.params, 9e7, 9e7 + 600, 0.0)
    tau = o + dt
    direct = sigma_u(t.params, t.covariance, tau)
    virt = anchor_sigma_u(t.params, t.covariance, tau, 0.0)
    assert np.allclose(direct, virt, rtol=1e-6)


TABLE7 = {  # anchor, α → (T_valid [d], δt_u [s])
    ("conjunction", 0.5): (2554, 3.7),
    ("conjunction", 1.0): (3646, 7.4),
    ("quadrature", 0.5): (4481, 11.6),
    ("quadrature", 1.0): (6036, 23.2),
}


def test_hm_cnc_reproduces_table7(hm_cnc_path) -> None:
    """Table 7 within 3 % in T_valid and δt_u (issue 2); σ_u(end) = 11.76 mrad within 3 %."""
    t = load_target(hm_cnc_path)
    rows = horizon_table(t, math.sqrt(2) * 40.0, 390.0)
    for r in rows:
        tv, dt = TABLE7[(r.anchor, r.alpha)]
        assert r.t_valid_days == pytest.approx(tv, rel=0.03)
        assert r.dt_u_s == pytest.approx(dt, rel=0.03)
    assert rows[0].sigma_u_end_rad == pytest.approx(11.76e-3, rel=0.03)


def test_hm_cnc_without_fddot_is_12_to_28_percent_longer(hm_cnc_path) -> None:
    """Removing f̈ lengthens the horizons; Table 7 is 12–28 % shorter (paper Sec. 4.2)."""
    t = load_target(hm_cnc_path)
    with_f = horizon_table(t, math.sqrt(2) * 40.0, 390.0)
    names = t.cov_names[:3]
    t0 = replace(
        t, params=replace(t.params, fddot=0.0), cov_names=names, cov_matrix=t.cov_matrix[:3, :3]
    )
    without = horizon_table(t0, math.sqrt(2) * 40.0, 390.0)
    shorter = [1 - a.t_valid_days / b.t_valid_days for a, b in zip(with_f, without, strict=True)]
    assert min(shorter) == pytest.approx(0.12, abs=0.015)
    assert max(shorter) == pytest.approx(0.28, abs=0.015)


TABLE4 = {
    ("conjunction", 0.5): 390,
    ("conjunction", 1.0): 920,
    ("quadrature", 0.5): 3194,
    ("quadrature", 1.0): 4844,
}


def test_eccentric_quadrature_horizons_match_table4(eccentric_path) -> None:
    """Quadrature horizons within 3 % of Table 4 (insensitive to unpublished correlations);
    conjunction ones depend on them: we only require the right order (±15 %)."""
    t = load_target(eccentric_path)
    rows = horizon_table(t, 15.0, 1298.0)
    for r in rows:
        ref = TABLE4[(r.anchor, r.alpha)]
        rel = 0.03 if r.anchor == "quadrature" else 0.15
        assert r.t_valid_days == pytest.approx(ref, rel=rel)


def test_midpoint_transform_reproduces_table2() -> None:
    """Eq. ecc_mcmc_inj (start epoch) → Table 2 (midpoint) with T = 4 sidereal years."""
    z = 30.097462
    wdot = 2 * math.pi * z / T4
    # ḟ from Table 2 (1.6404897e-15; Eq. ecc_mcmc_inj's log10 ḟ = −14.7850265 agrees to 3e-7).
    # The printed inputs limit the check: the 8-digit log10 ḟ alone moves φ_mid by ~5e-6 rad
    # through 2π ḟ (T/2)²/2 ≈ 20 rad, so we require 1e-5 rad (0.5 % of Table 3's σ_φ = 2e-3 rad);
    # f, η, κ are checked to 1e-12/1e-6.
    p0 = PhaseParams(4.6100488, 8.406186457145e-3, 1.6404897e-15, 0.0, 0.0068, 0.0068, wdot)
    pm, _ = shift_reference(p0, np.zeros((7, 7)), T4 / 2)
    assert pm.phase == pytest.approx(2.4102573, abs=1e-5)
    assert pm.f_gw == pytest.approx(8.406289998784e-3, rel=1e-12)
    assert pm.fdot == pytest.approx(1.6404897e-15, rel=1e-7)
    # z_ω has 8 digits: ω̇T/2 = 94.6 rad known to ~1.6e-6 rad → (η, κ) to ~3e-6 relative
    assert pm.eta == pytest.approx(8.5334116e-3, rel=5e-6)
    assert pm.kappa == pytest.approx(4.4340597e-3, rel=5e-6)
    assert pm.omega_dot == pytest.approx(1.49809106e-6, rel=1e-8)  # Table 2's ω̇, unchanged


def test_shift_covariance_matches_monte_carlo() -> None:
    """Covariance propagation of the reference shift vs 20 000 seeded draws (3 % on σ's)."""
    rng = np.random.default_rng(42)
    sig = np.array([2e-3, 5.5e-12, 3.4e-19, 0.0, 5.4e-4, 5.4e-4, 1.5e-9])
    cov = np.diag(sig**2)
    _, new_cov = shift_reference(FID, cov, -T4 / 2)
    draws = rng.multivariate_normal(FID.as_array(), cov, size=20000)
    shifted = np.array(
        [
            shift_reference(PhaseParams.from_array(d), cov, -T4 / 2)[0].as_array()
            for d in draws[:4000]
        ]
    )
    shifted[:, 0] = np.unwrap(shifted[:, 0])
    mc = np.std(shifted, axis=0)
    an = np.sqrt(np.diag(new_cov))
    for i in (0, 1, 2, 4, 5):
        assert mc[i] == pytest.approx(an[i], rel=0.05)  # 4000 draws: σ of σ ≈ 1.1 %


def test_shift_columns_equals_scalar_shift() -> None:
    """Sample-wise shift (with f̈ and a fixed, unsampled ω̇) equals shift_reference per row (1e-9)."""
    from ucbplan.core.params import shift_columns

    rng = np.random.default_rng(3)
    base = FID.as_array()
    rows = base + rng.normal(size=(50, 7)) * np.array([1e-3, 5e-12, 3e-19, 1e-28, 5e-4, 5e-4, 0])
    cols = {n: rows[:, i] for i, n in enumerate(PARAM_NAMES) if n != "omega_dot"}
    cols["cos_inclination"] = np.full(50, 0.09)
    out = shift_columns(cols, -T4 / 2, defaults={"omega_dot": FID.omega_dot})
    assert "omega_dot" not in out and np.all(out["cos_inclination"] == 0.09)
    for i, row in enumerate(rows):
        ref, _ = shift_reference(PhaseParams.from_array(row), np.zeros((7, 7)), -T4 / 2)
        for n in ("f_gw", "fdot", "eta", "kappa"):
            assert out[n][i] == pytest.approx(getattr(ref, n), rel=1e-12)
        dphi = np.angle(np.exp(1j * (out["phase"][i] - ref.phase)))
        assert abs(dphi) < 1e-9  # float64 f·T/2 ≈ 5e5 cycles: ~1e-10 cycle rounding


def test_horizon_s_closed_form_fdot_only() -> None:
    """horizon_s = √(2α δu_tol/(πσ_ḟ)) − T/2 with the N = 2 quadrature tolerance (√2σ_v/K)^½."""
    from ucbplan.core.forecast import horizon_s

    cov = np.zeros((7, 7))
    sig = 3.41e-19
    cov[2, 2] = sig**2
    p = replace(FID, eta=0.0, kappa=0.0, omega_dot=0.0)
    tol = math.sqrt(math.sqrt(2) * 15.0 / 1298.0)
    expect = math.sqrt(2 * 0.5 * tol / (math.pi * sig)) - T4 / 2
    assert horizon_s((p, cov, T4), 15.0, 1298.0, "quadrature", alpha=0.5) == pytest.approx(
        expect, rel=1e-6
    )


def test_sigma_u_end_phase_only() -> None:
    """Only σ(φ_ref): σ_u = σ_φ/2 at every epoch and anchor (∂u/∂φ_ref = 1/2 for e = 0)."""
    from ucbplan.core.forecast import sigma_u_end

    cov = np.zeros((7, 7))
    cov[0, 0] = 0.02**2
    p = replace(FID, eta=0.0, kappa=0.0, omega_dot=0.0)
    for anchor in ("quadrature", "conjunction", 0.7):
        assert sigma_u_end((p, cov, T4), anchor) == pytest.approx(0.01, rel=1e-12)
