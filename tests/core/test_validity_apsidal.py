"""Horizons of apsidally precessing targets: the envelope search against the grid and brute force.

Goal (issue 14): T_valid within 0.1 % (relative; 1 d absolute floor, as in the benchmark) of the
sampled-grid search; checked here also against a brute-force dense evaluation of σ_u, which is
the independent reference where the grid itself misses a brief crossing.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from support.targets import random_targets

import ucbplan.core.validity_apsidal as ha
from ucbplan.core.constants import DAY_S, YEAR_S
from ucbplan.core.forecast import AFTER, BEFORE, HORIZON_CAP_S, t_valid_batch, time_reversed
from ucbplan.core.validity_grid import anchor_sigma_batch, oscillating
from ucbplan.core.validity_poly import horner

#: Goal of issue 14: |ΔT_valid| ≤ 1e-3 max(T_valid, 1 d).
REL = 1e-3
ANCHORS = [(0.0, math.pi), (math.pi / 2,), (1.0,)]


def _precessing(n: int, seed: int, e_max: float) -> tuple[np.ndarray, ...]:
    """Eccentric targets with ω̇ ≠ 0 (P_aps from ~2 d to ~20 yr, both signs), e up to e_max,
    σ_e from 1e-4 to 1e-2 and σ_ω̇ from 1e-12 to 1e-9 rad/s on the test_validity_poly targets."""
    pars, covs, t_obs, thr = random_targets(n, seed)
    rng = np.random.default_rng(seed + 1000)
    e = e_max * rng.random(n) ** 2
    om = rng.uniform(0, 2 * math.pi, n)
    pars[:, 4], pars[:, 5] = e * np.cos(om), e * np.sin(om)
    pars[:, 6] = rng.choice([-1.0, 1.0], n) * 10 ** rng.uniform(-8, -5.5, n)
    sig = np.sqrt(np.einsum("nii->ni", covs))
    scale = np.ones((n, 7))
    with np.errstate(divide="ignore"):
        sig_e, sig_w = 10 ** rng.uniform(-4, -2, n), 10 ** rng.uniform(-12, -9, n)
        scale[:, 4] = scale[:, 5] = np.where(sig[:, 4] > 0, sig_e / sig[:, 4], 1)
        scale[:, 6] = np.where(sig[:, 6] > 0, sig_w / sig[:, 6], 1)
    return pars, covs * scale[:, :, None] * scale[:, None, :], t_obs, thr


def sigma2(pars: np.ndarray, covs: np.ndarray, tau_end: np.ndarray, dt: np.ndarray, u: float):
    """σ_u² at τ_end + dt per row (dt: (n, m) [s])."""
    return anchor_sigma_batch(pars, covs, tau_end[:, None] + dt, u) ** 2


def _dense(p: np.ndarray, c: np.ndarray, t_obs: float, thr: float, us, span: float, step: float):
    """Brute force: closing of the first window max σ_u ≤ thr on a uniform grid [s after T/2]."""
    x = np.arange(0.0, span + step, step)
    tau = t_obs / 2 + x
    v = np.max([anchor_sigma_batch(p[None], c[None], tau[None], u)[0] for u in us], axis=0)
    ok = v <= thr
    if not ok.any():
        return 0.0
    rest = ~ok & (np.arange(x.size) >= np.argmax(ok))
    return 0.5 * (x[np.argmax(rest) - 1] + x[np.argmax(rest)]) if rest.any() else math.inf


@pytest.mark.parametrize("direction", [AFTER, BEFORE])
@pytest.mark.parametrize("anchor", ANCHORS)
def test_matches_grid(direction: int, anchor: tuple[float, ...]) -> None:
    """Envelope search = refined grid search within 0.1 % on 300 random precessing targets."""
    pars, covs, t_obs, thr = _precessing(300, seed=21, e_max=0.1)
    assert oscillating(pars, covs).all()
    got = t_valid_batch(pars, covs, t_obs, thr, anchor, 1, direction)
    ref = t_valid_batch(pars, covs, t_obs, thr, anchor, 1, direction, method="grid")
    assert np.count_nonzero(ref > 0) > 150  # most rows have a horizon: the check has teeth
    assert np.all(np.abs(got - ref) <= REL * np.maximum(ref, DAY_S))


@pytest.mark.slow
def test_benchmark_targets_match_grid() -> None:
    """The benchmark's precessing rows (P_aps ≈ 48 d): within 0.1 % of the grid (in fact 1e-6)."""
    pars, covs, t_obs, thr = random_targets(400, seed=3)
    ecc = pars[:, 4] != 0
    pars, covs, t_obs, thr = pars[ecc], covs[ecc], t_obs[ecc], thr[ecc]
    pars[:, 6] = 1.5e-6
    got = t_valid_batch(pars, covs, t_obs, thr, (0.0, math.pi))
    ref = t_valid_batch(pars, covs, t_obs, thr, (0.0, math.pi), method="grid")
    assert np.all(np.abs(got - ref) <= 1e-6 * np.maximum(ref, DAY_S))


def test_matches_brute_force() -> None:
    """Eccentric (e ≤ 0.4) and slowly or fast precessing targets against a dense evaluation
    (P_aps/200 steps over the whole span): within 0.1 % plus two dense steps. Among them a row
    where the grid search misses a brief early crossing (seed 2, row 70, before T0)."""
    pars, covs, t_obs, thr = _precessing(300, seed=2, e_max=0.4)
    rows = [70, *range(0, 300, 10)]
    p, c = time_reversed(pars[rows], covs[rows])
    us = (math.pi / 2,)
    got = t_valid_batch(p, c, t_obs[rows], thr[rows], us)  # BEFORE of the originals
    checked = 0
    for i, row in enumerate(rows):
        period = 2 * math.pi / abs(p[i, 6])
        span = min(1.2 * got[i] + 2 * period, 2e5 * period / 200)
        if got[i] >= span or got[i] == HORIZON_CAP_S:
            continue  # beyond a dense evaluation's reach
        step = period / 200
        ref = _dense(p[i], c[i], t_obs[row], thr[row], us, span, step)
        assert abs(got[i] - ref) <= REL * max(ref, DAY_S) + 2 * step, row
        checked += got[i] > 0
    assert checked >= 15


def test_envelope_and_curvature_bound_sigma() -> None:
    """lower ≤ σ_u² ≤ upper and |σ_u²''| ≤ curvature on a dense grid (e up to 0.4)."""
    pars, covs, t_obs, _ = _precessing(40, seed=5, e_max=0.4)
    scale = 30 * YEAR_S
    for u in (0.0, 1.0):
        lower, upper, curv = ha.envelope(pars, covs, t_obs / 2, scale, u)
        x = np.linspace(0.0, 1.0, 10_001)[None, :].repeat(40, axis=0)
        sig2 = sigma2(pars, covs, t_obs / 2, scale * x, u)
        lo, hi = horner(lower, x)[0], horner(upper, x)[0]
        tol = 1e-9 * np.abs(sig2).max(axis=1, keepdims=True)
        assert np.all(lo <= sig2 + tol) and np.all(sig2 <= hi + tol)
        # second differences on a grid fine against P_aps
        h = 1e-6
        xs = np.linspace(0.0, 0.05, 501)[None, :].repeat(40, axis=0)
        f = [sigma2(pars, covs, t_obs / 2, scale * (xs + k * h), u) for k in (-1, 0, 1)]
        second = (f[0] - 2 * f[1] + f[2]) / h**2
        bound = horner(curv, xs + h)[0]
        noise = 4e-16 * np.abs(f[1]) / h**2
        assert np.all(np.abs(second) <= bound * 1.01 + noise)


def test_window_closed_by_an_early_peak() -> None:
    """A large oscillation crosses thr well before its mean does: the first peak counts."""
    p = np.array([[0.0, 1e-3, 0.0, 0.0, 0.3, 0.0, 2 * math.pi / (100 * DAY_S)]])
    cov = np.zeros((1, 7, 7))
    cov[0, 1, 1] = (1e-10) ** 2  # σ_u ≈ π τ σ_f |∂u/∂Φ|, ∂u/∂Φ from 0.4 to 1.6 over P_aps
    cov[0, 4, 4] = cov[0, 5, 5] = (1e-3) ** 2
    thr = np.array([0.05])
    got = t_valid_batch(p, cov, np.zeros(1), thr, (0.0,))[0]
    step = 100 * DAY_S / 2000
    ref = _dense(p[0], cov[0], 0.0, 0.05, (0.0,), 20 * YEAR_S, step)
    grid = t_valid_batch(p, cov, np.zeros(1), thr, (0.0,), method="grid")[0]
    lower, _, _ = ha.envelope(p, cov, np.zeros(1), 20 * YEAR_S, 0.0)
    x = np.linspace(0, 1, 100_001)[None, :]
    past = x[0, np.argmax(horner(lower, x)[0] > thr[0] ** 2)] * 20 * YEAR_S
    assert 0 < got < 0.8 * past  # well before σ_u must have crossed at every phase
    assert abs(got - ref) <= REL * ref + 2 * step
    assert abs(got - grid) <= REL * grid


def test_unresolved_rows_go_to_the_grid(monkeypatch: pytest.MonkeyPatch) -> None:
    """With no scan budget every row is left to the grid search: the result is the grid's (up to
    its refinement, which depends on the other rows of its chunk: 1e-6)."""
    monkeypatch.setattr(ha, "_MAX_SAMPLES", 0)
    pars, covs, t_obs, thr = _precessing(40, seed=8, e_max=0.1)
    _, left = ha.t_valid_apsidal(pars, covs, t_obs, thr, (0.0,), 1, HORIZON_CAP_S)
    got = t_valid_batch(pars, covs, t_obs, thr, (0.0,))
    ref = t_valid_batch(pars, covs, t_obs, thr, (0.0,), method="grid")
    assert left.sum() > 20
    np.testing.assert_allclose(got, ref, rtol=1e-6)
