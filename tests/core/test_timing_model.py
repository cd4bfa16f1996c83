"""core/timing: a timing ephemeris (T0, P, Ṗ, P̈) as the phase model, checked independently.

References: the polynomial t(n) = T0 + P n + ½PṖn² + ⅙P²P̈n³ itself (exact rational arithmetic),
its series inversion, central finite differences, and the first-order eclipse condition solved
with a bracketing root finder. Numbers are the issue's ZTF J1539+5027 values (test input).
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest
from scipy.optimize import brentq

from ucbplan.core.constants import YEAR_S
from ucbplan.core.ephemeris import solve_u
from ucbplan.core.params import PARAM_NAMES, PhaseParams
from ucbplan.core.phase import arg_latitude, u_cycles
from ucbplan.core.timing import (
    MARKS,
    TIMING_NAMES,
    TimingEphemeris,
    cycle_time_s,
    mark_phase_asc,
    period_sign_change,
    phase_covariance,
    phase_jacobian,
    to_phase_params,
    truncation_s,
)

P_S = 414.7915404  # s, ZTF J1539+5027 (issue text)
PDOT = -2.373e-11
ZTF = TimingEphemeris("primary_eclipse", P_S, PDOT)


def _poly_s(eph: TimingEphemeris, n: Fraction) -> Fraction:
    """t(n) − T0 in exact rational arithmetic (the floats taken as exact binary values)."""
    p, pd, pdd = Fraction(eph.period_s), Fraction(eph.pdot), Fraction(eph.pddot)
    return p * n + p * pd * n * n / 2 + p * p * pdd * n**3 / 6


def _u1(p: PhaseParams, tau: float) -> float:
    m, g = u_cycles(p, np.array([tau]))
    return float(2 * math.pi * (m[0] + g[0]))


def test_frequency_model_is_the_series_inversion() -> None:
    """f = 2/P, ḟ = −2Ṗ/P², f̈ = 2(3Ṗ²/P³ − P̈/P²) (module docstring), by hand."""
    eph = TimingEphemeris("primary_eclipse", P_S, PDOT, 3e-20)
    p = to_phase_params(eph)
    assert p.f_gw == pytest.approx(2 / P_S, rel=1e-15)
    assert p.fdot == pytest.approx(-2 * PDOT / P_S**2, rel=1e-15)
    assert p.fddot == pytest.approx(2 * (3 * PDOT**2 / P_S**3 - 3e-20 / P_S**2), rel=1e-12)


@pytest.mark.parametrize("pddot", [0.0, 2e-20, -2e-20])
def test_model_matches_the_polynomial_to_fourth_order(pddot: float) -> None:
    """Events of the polynomial (integer n, exact arithmetic) fall where the phase model puts
    u₁ = π/2, up to the fourth-order term :func:`truncation_s` predicts (sign included).

    A wrong ḟ or f̈ would leave residuals of ~(τ/P)² or (τ/P)³ cycles: seconds, not microseconds.
    """
    eph = TimingEphemeris("primary_eclipse", P_S, PDOT, pddot)
    p = to_phase_params(eph)
    span = 3 * YEAR_S if pddot else 10 * YEAR_S
    for n in np.linspace(-span / P_S, span / P_S, 41).round():
        tau_poly = float(_poly_s(eph, Fraction(int(n))))
        k, dt, _, origin = solve_u(p, tau_poly - P_S / 4, tau_poly + P_S / 4, math.pi / 2)
        assert k.size == 1 and int(k[0]) == int(n)
        resid = origin + float(dt[0]) - tau_poly
        expect = float(truncation_s(eph, tau_poly))
        assert abs(resid - expect) < 2e-7 + 0.02 * abs(expect), (n, resid, expect)  # 0.2 µs
    assert abs(float(truncation_s(ZTF, 10 * YEAR_S))) == pytest.approx(1.16e-6, rel=0.02)


def test_cycle_time_is_the_polynomial() -> None:
    eph = TimingEphemeris("primary_eclipse", P_S, PDOT, 1e-21)
    for n in (-700000, -3, 0, 5, 760000):
        assert cycle_time_s(eph, n) == pytest.approx(float(_poly_s(eph, Fraction(n))), abs=1e-7)


@pytest.mark.parametrize(("mark", "u1"), list(MARKS.items()))
def test_marks_set_star_1s_argument_of_latitude_at_t0(mark: str, u1: float) -> None:
    """u₁(T0) is the mark; a secondary eclipse keeps φ_ref = 3π (reduced mod 2π it would give
    u₁ = π/2, the primary)."""
    p = to_phase_params(TimingEphemeris(mark, P_S, PDOT))
    assert _u1(p, 0.0) % (2 * math.pi) == pytest.approx(u1, abs=1e-12)
    if mark == "secondary_eclipse":
        assert p.phase == pytest.approx(3 * math.pi)
        wrapped = PhaseParams(p.phase % (2 * math.pi), p.f_gw, p.fdot, p.fddot)
        assert _u1(wrapped, 0.0) == pytest.approx(math.pi / 2)  # the primary: why 3π is kept


@pytest.mark.parametrize("mark", list(MARKS))
def test_eccentric_mark_is_solved_exactly(mark: str) -> None:
    """With (η, κ) the first-order u₁(T0) equals the mark to 1e-13 rad (not only to O(e))."""
    eph = TimingEphemeris(mark, P_S, PDOT, 0.0, 0.03, -0.05, 1e-7)
    p = to_phase_params(eph)
    u = float(arg_latitude(p, np.array([0.0]))[0])
    assert math.remainder(u - MARKS[mark], 2 * math.pi) == pytest.approx(0.0, abs=1e-13)
    assert p.eta == 0.03 and p.kappa == -0.05 and p.omega_dot == 1e-7


def test_mark_phase_against_a_bracketing_solver() -> None:
    for u_mark in (0.0, math.pi / 2, 3 * math.pi / 2):
        for eta, kappa in ((0.0, 0.0), (0.05, 0.02), (-0.07, 0.06)):
            phi = mark_phase_asc(u_mark, eta, kappa)

            def g(x: float, u: float = u_mark, e: float = eta, k: float = kappa) -> float:
                return x + 2 * k * math.sin(x) - 2 * e * math.cos(x) - u

            ref = brentq(g, u_mark - 1.0, u_mark + 1.0, xtol=1e-15)
            assert phi == pytest.approx(ref, abs=1e-13)


ECC = TimingEphemeris("secondary_eclipse", P_S, PDOT, 4e-21, 0.02, 0.03, 2e-7)
_STEPS = {
    "t0": 1e-3,
    "period": 1e-7,
    "pdot": 1e-14,
    "pddot": 1e-23,
    "eta": 1e-6,
    "kappa": 1e-6,
    "omega_dot": 1e-10,
}


def _phase_params_moved(eph: TimingEphemeris, d_t0: float) -> PhaseParams:
    """Phase model at the fixed t_ref when T0 moves by ``d_t0`` (φ_ref from u₁(d_t0) = mark)."""
    base = to_phase_params(eph)

    def resid(phi: float) -> float:
        trial = PhaseParams(**{**{n: getattr(base, n) for n in PARAM_NAMES}, "phase": phi})
        return float(arg_latitude(trial, np.array([d_t0]))[0]) - eph.mark_u

    phi = brentq(resid, base.phase - 0.5, base.phase + 0.5, xtol=1e-15)
    return PhaseParams(**{**{n: getattr(base, n) for n in PARAM_NAMES}, "phase": phi})


@pytest.mark.parametrize("name", TIMING_NAMES)
def test_jacobian_matches_finite_differences(name: str) -> None:
    """∂(φ_ref, f, ḟ, f̈, η, κ, ω̇)/∂(T0, P, Ṗ, P̈, η, κ, ω̇): analytic vs central differences."""
    j = phase_jacobian(ECC)[:, TIMING_NAMES.index(name)]
    h = _STEPS[name]
    if name == "t0":
        plus, minus = _phase_params_moved(ECC, h), _phase_params_moved(ECC, -h)
    else:
        fields = {
            "period": "period_s",
            "pdot": "pdot",
            "pddot": "pddot",
            "eta": "eta",
            "kappa": "kappa",
            "omega_dot": "omega_dot",
        }
        attrs = {
            f: getattr(ECC, f)
            for f in ("mark", "period_s", "pdot", "pddot", "eta", "kappa", "omega_dot")
        }
        up = dict(attrs, **{fields[name]: attrs[fields[name]] + h})
        down = dict(attrs, **{fields[name]: attrs[fields[name]] - h})
        plus, minus = (
            to_phase_params(TimingEphemeris(**up)),
            to_phase_params(TimingEphemeris(**down)),
        )
    fd = (plus.as_array() - minus.as_array()) / (2 * h)
    scale = np.maximum(np.abs(j), np.abs(fd))
    assert np.all(np.abs(j - fd) <= 1e-6 * scale + 1e-300), (name, j, fd)


def test_covariance_is_the_jacobian_product_and_keeps_precision() -> None:
    """J C Jᵀ on the correlation matrix equals the direct product (entries 1e-62 … 1)."""
    sig = np.array([0.73, 2.9e-6, 5e-14, 1e-22, 1e-3, 2e-3, 1e-9])
    rho = np.eye(7)
    rho[1, 2] = rho[2, 1] = -0.8
    rho[0, 1] = rho[1, 0] = 0.3
    rho[4, 5] = rho[5, 4] = 0.5
    cov = rho * np.outer(sig, sig)
    out = phase_covariance(ECC, cov)
    j = phase_jacobian(ECC)
    direct = j @ cov @ j.T
    s = np.sqrt(np.diag(direct))
    assert np.allclose(out / np.outer(s, s), direct / np.outer(s, s), atol=1e-12)
    assert np.all(np.linalg.eigvalsh(out / np.outer(s, s)) > -1e-12)


def test_pure_period_covariance() -> None:
    """σ(P) alone with Ṗ = 0: σ_f = 2σ_P/P², nothing else."""
    eph = TimingEphemeris("primary_eclipse", P_S, 0.0)
    cov = np.zeros((7, 7))
    cov[1, 1] = (2.9e-6) ** 2
    out = phase_covariance(eph, cov)
    assert math.sqrt(out[1, 1]) == pytest.approx(2 * 2.9e-6 / P_S**2, rel=1e-14)
    out[1, 1] = 0.0
    assert not np.any(out)


@pytest.mark.parametrize(
    ("eph", "field", "years"),
    [
        (TimingEphemeris("primary_eclipse", 400.0, -4e-6), "pdot", 3.17),  # P/|Ṗ| = 1e8 s
        (TimingEphemeris("primary_eclipse", 400.0, 4e-6), "pdot", -3.17),
        (TimingEphemeris("primary_eclipse", 400.0, 0.0, -1e-15), "pddot", 28.3),
    ],
)
def test_period_sign_change_within_100_yr(eph: TimingEphemeris, field: str, years: float) -> None:
    which, when = period_sign_change(eph)
    assert which == field
    assert when / YEAR_S == pytest.approx(years, rel=0.01)


def test_a_second_derivative_may_save_the_sign() -> None:
    """Ṗ alone would reach zero 3.2 yr after T0, but a large P̈ > 0 keeps P + Ṗτ + ½P̈τ² (and the
    model frequency) positive; a small one does not."""
    assert period_sign_change(TimingEphemeris("primary_eclipse", 400.0, -4e-6, 1e-13))[0] == ""
    which, when = period_sign_change(TimingEphemeris("primary_eclipse", 400.0, -4e-6, 1e-15))
    assert which == "pdot" and when / YEAR_S == pytest.approx(3.2, abs=0.1)


def test_no_sign_change_for_real_systems() -> None:
    assert period_sign_change(ZTF) == ("", pytest.approx(math.nan, nan_ok=True))
    which, _ = period_sign_change(TimingEphemeris("primary_eclipse", 400.0, -1e-10))
    assert which == ""  # P/|Ṗ| = 127 kyr
