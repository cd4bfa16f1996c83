"""Appendix B smearing factors against the paper's and docs/method.md's checked numbers."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ucbplan.core.smearing import (
    comb_attenuation,
    lambda_k,
    lambda_kappa,
    parse_smear_budget,
    smear_velocity,
)
from ucbplan.errors import UcbplanError

P_B = 300.0  # any period: the factors depend on dt/P only
N_BAR = 2 * math.pi / P_B  # n̄_b = π f_GW = 2π / P_orb


def test_paper_values() -> None:
    # docs/method.md, "Smearing" (4-5 significant digits printed -> tolerances at the last digit).
    assert 1.0 / lambda_k(P_B / 3, N_BAR) == pytest.approx(1.2092, abs=5e-5)
    assert lambda_k(P_B / 8, N_BAR) == pytest.approx(0.97450, abs=5e-6)
    assert lambda_kappa(P_B / 3, N_BAR) == pytest.approx(0.4135, abs=5e-5)
    # Appendix B text: Lambda_K ~ 0.83 at P/3.
    assert lambda_k(P_B / 3, N_BAR) == pytest.approx(0.83, abs=5e-3)
    # Eq. Deltav_smear_est: 10 s at P_b = 5 min, K = 750 km/s -> 1.37 km/s (docs/method.md).
    assert smear_velocity(750.0, lambda_k(10.0, N_BAR)) == pytest.approx(1.37, abs=5e-3)


def test_not_numpy_sinc_convention_and_limits() -> None:
    # Independent analytic form: sin(x)/x with x = n̄ dt / 2.
    x = N_BAR * 37.0 / 2
    assert lambda_k(37.0, N_BAR) == pytest.approx(math.sin(x) / x, rel=1e-14)
    assert lambda_kappa(37.0, N_BAR) == pytest.approx(math.sin(2 * x) / (2 * x), rel=1e-14)
    assert lambda_k(0.0, N_BAR) == 1.0
    # Small-window limit, Eq. Deltav_smear second line: K (n̄T)^2 / 24 (relative error ~ (n̄T)^2/40).
    dt = 3.0
    assert smear_velocity(600.0, lambda_k(dt, N_BAR)) == pytest.approx(
        600.0 * (N_BAR * dt) ** 2 / 24, rel=1e-3
    )


def test_comb_equals_uniform_window_without_readout() -> None:
    # n contiguous exposures = one uniform window of width n T (exact identity).
    for n in (1, 2, 5):
        assert comb_attenuation(20.0, 0.0, n, N_BAR) == pytest.approx(
            float(lambda_k(20.0 * n, N_BAR)), rel=1e-12
        )
        assert comb_attenuation(20.0, 0.0, n, N_BAR, harmonic=2) == pytest.approx(
            float(lambda_kappa(20.0 * n, N_BAR)), rel=1e-12
        )


def test_comb_with_readout_matches_brute_force_average() -> None:
    # Brute force: average cos(n̄ t) over the exposed instants of a 3 x (25 s + 10 s gap) comb.
    t_exp, gap, n = 25.0, 10.0, 3
    span = n * t_exp + (n - 1) * gap
    t = np.linspace(-span / 2, span / 2, 2_000_001)
    inside = ((t + span / 2) % (t_exp + gap)) <= t_exp
    brute = float(np.mean(np.cos(N_BAR * t[inside])))
    # Tolerance 1e-5: grid discretisation of the exposure edges (dt = 5e-5 s).
    assert comb_attenuation(t_exp, gap, n, N_BAR) == pytest.approx(brute, abs=1e-5)


def test_parse_budget() -> None:
    assert parse_smear_budget("0.5*sigma_v", 15.0) == 7.5
    assert parse_smear_budget("sigma_v", 15.0) == 15.0
    assert parse_smear_budget("2 km/s", None) == 2.0
    assert parse_smear_budget("1.5", None) == 1.5
    with pytest.raises(UcbplanError, match="needs sigma_v"):
        parse_smear_budget("0.5*sigma_v", None)
    with pytest.raises(UcbplanError, match=r"expected e\.g\."):
        parse_smear_budget("lots", 15.0)
    with pytest.raises(UcbplanError, match="positive"):
        parse_smear_budget("-1", 15.0)
