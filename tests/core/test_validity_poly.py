"""The analytic horizon (roots of the polynomial σ_u²) against the sampled-grid search."""

from __future__ import annotations

import math

import numpy as np
import pytest
from support.targets import random_targets

from ucbplan.core.constants import YEAR_S
from ucbplan.core.forecast import AFTER, BEFORE, HORIZON_CAP_S, anchor_sigma_u, t_valid_batch
from ucbplan.core.params import PhaseParams
from ucbplan.core.validity_grid import oscillating
from ucbplan.core.validity_poly import sigma2_coefficients
from ucbplan.errors import UcbplanError


@pytest.mark.parametrize("direction", [AFTER, BEFORE])
@pytest.mark.parametrize("anchor", [(0.0, math.pi), (math.pi / 2,), (1.0,)])
def test_analytic_matches_grid(direction: int, anchor: tuple[float, ...]) -> None:
    """T_valid from the roots equals the refined grid search within 1e-6 (goal: 0.1 %)."""
    pars, covs, t_obs, thr = random_targets(400, seed=11)
    assert not oscillating(pars, covs).any()
    got = t_valid_batch(pars, covs, t_obs, thr, anchor, 1, direction)
    ref = t_valid_batch(pars, covs, t_obs, thr, anchor, 1, direction, method="grid")
    assert np.count_nonzero(ref > 0) > 200  # most rows have a horizon: the check has teeth
    assert np.all(np.abs(got - ref) <= 1e-6 * np.maximum(ref, 86400.0))


def test_polynomial_equals_sigma_u() -> None:
    """The coefficients reproduce σ_u² of the Jacobian at the anchor (rel. 1e-10)."""
    pars, covs, t_obs, _ = random_targets(20, seed=3)
    x = np.linspace(0.0, 1.0, 9)
    cap = 10 * YEAR_S
    coef = sigma2_coefficients(pars, covs, t_obs / 2, cap, 0.3)
    for i in range(20):
        tau = t_obs[i] / 2 + cap * x
        ref = anchor_sigma_u(PhaseParams(*pars[i]), covs[i], tau, 0.3) ** 2
        got = np.polynomial.polynomial.polyval(x, coef[i])
        np.testing.assert_allclose(got, ref, rtol=1e-10)


def test_zero_covariance_is_capped_and_unreachable_is_zero() -> None:
    """σ_u ≡ 0 (no uncertainty) keeps the window open to the cap; thr below σ_u(τ_end) and a
    growing σ_u gives no window (0)."""
    pars = np.array([[0.0, 1e-3, 1e-17, 0, 0, 0, 0]] * 2)
    covs = np.zeros((2, 7, 7))
    covs[1, 0, 0] = 1.0  # σ_u = 0.5 rad forever
    out = t_valid_batch(pars, covs, np.zeros(2), 0.1, (0.0,))
    assert out[0] == HORIZON_CAP_S
    assert out[1] == 0.0


def test_window_opening_after_the_end() -> None:
    """A σ_u that dips below the threshold after τ_end (anti-correlated φ and f) opens late."""
    p = np.array([[0.0, 1e-3, 0, 0, 0, 0, 0]])
    cov = np.zeros((1, 7, 7))
    # σ_u² = ¼σ_φ² + π²τ²σ_f² + πτ cov(φ,f): minimum at τ_min = −cov/(2πσ_f²) > 0
    cov[0, 0, 0], cov[0, 1, 1], cov[0, 0, 1] = 1.0, 1e-16, -0.99e-8
    cov[0, 1, 0] = cov[0, 0, 1]
    thr = 0.2
    got = t_valid_batch(p, cov, np.zeros(1), thr, (0.0,))[0]
    # closed form: roots of π²σ_f²τ² + π c τ + ¼σ_φ² − thr² = 0, the larger one
    a, b, c = math.pi**2 * 1e-16, math.pi * -0.99e-8, 0.25 - thr**2
    assert got == pytest.approx((-b + math.sqrt(b * b - 4 * a * c)) / (2 * a), rel=1e-9)


def test_unknown_method() -> None:
    with pytest.raises(UcbplanError, match="method"):
        t_valid_batch(np.zeros((1, 7)), np.zeros((1, 7, 7)), 0.0, 1.0, (0.0,), method="dense")
