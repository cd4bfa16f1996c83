"""The sampled-grid horizon search: σ_u on a geometric time grid, refined by subdivision.

The reference method behind :func:`ucbplan.core.forecast.t_valid_batch` for rows whose σ_u
oscillates on the apsidal period (ω̇ ≠ 0 with an eccentricity or its uncertainty), and the
independent check of the analytic search (:mod:`ucbplan.core.validity_poly`) elsewhere.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np
from numpy.typing import NDArray

from ucbplan.core.constants import YEAR_S
from ucbplan.core.phase import jacobian_kernel

FloatArray = NDArray[np.float64]
#: Horizons are searched up to this long after the end of the information [s].
HORIZON_CAP_S = 300.0 * YEAR_S


def anchor_sigma_batch(
    pars: FloatArray, covs: FloatArray, tau: FloatArray, u_star: float, star: int = 1
) -> FloatArray:
    """Batched :func:`anchor_sigma_u`: pars (n, 7), covs (n, 7, 7), tau (n, G) → (n, G)."""
    eta0, kap0, wdot = pars[:, 4:5], pars[:, 5:6], pars[:, 6:7]
    eps = 0.0 if star == 1 else math.pi
    w = wdot * tau
    cw, sw = np.cos(w), np.sin(w)
    phi_a = np.full_like(tau, u_star - eps)
    if np.any(eta0 != 0.0) or np.any(kap0 != 0.0):
        eta = eta0 * cw + kap0 * sw
        kap = kap0 * cw - eta0 * sw
        for _ in range(2):  # Φ_asc = u★ − ε − δ(Φ_asc): contraction 2e, two steps leave O(e³)
            phi_a = u_star - eps - (2 * kap * np.sin(phi_a) - 2 * eta * np.cos(phi_a))
    jac = jacobian_kernel(eta0, kap0, wdot, tau, np.sin(phi_a), np.cos(phi_a), (cw, sw))
    var = np.sum(np.matmul(jac, covs) * jac, axis=-1)
    out: FloatArray = np.sqrt(np.maximum(var, 0.0))
    return out


_OFFSETS = np.concatenate([[0.0], np.geomspace(60.0, HORIZON_CAP_S, 320)])
_REFINE = np.linspace(0.0, 1.0, 65)


def oscillating(pars: FloatArray, covs: FloatArray) -> NDArray[np.bool_]:
    """Rows whose anchor σ_u oscillates (apsidal period): ω̇ ≠ 0 and e or its σ non-zero."""
    ecc = (pars[:, 4] != 0) | (pars[:, 5] != 0) | np.any(covs[:, 4:7, :] != 0, axis=(1, 2))
    out: NDArray[np.bool_] = (pars[:, 6] != 0) & ecc
    return out


def t_valid_grid(
    pars: FloatArray,
    covs: FloatArray,
    t_obs: FloatArray,
    thr: FloatArray,
    us: Sequence[float],
    star: int,
    oscillating: bool,
) -> FloatArray:
    def fn(tau: FloatArray) -> FloatArray:
        vals = [anchor_sigma_batch(pars, covs, tau, u, star) for u in us]
        return np.max(vals, axis=0)

    tau_end = t_obs / 2.0
    grid = tau_end[:, None] + _OFFSETS[None, :]
    vals = fn(grid)
    if oscillating:
        grid, vals = _resolve_oscillation(fn, grid, vals, thr, pars[:, 6])
        vals = _with_peaks(grid, vals)
    ok = vals <= thr[:, None]
    has = ok.any(axis=1)
    first = np.argmax(ok, axis=1)
    cols = np.arange(grid.shape[1])[None, :]
    rest = (~ok) & (cols >= first[:, None])
    closes = rest.any(axis=1)
    close = np.argmax(rest, axis=1)
    rows = np.arange(grid.shape[0])
    a = grid[rows, np.maximum(close - 1, 0)]
    # an interpolated peak at ``close`` may lie up to one step beyond it
    b = grid[rows, np.minimum(close + 1, grid.shape[1] - 1) if oscillating else close]
    for _ in range(3):  # three 64-fold subdivisions: 6 % grid step → 2e-7 relative
        g = a[:, None] + (b - a)[:, None] * _REFINE[None, :]
        above = fn(g) > thr[:, None]
        j = np.argmax(above, axis=1)
        j = np.where(above.any(axis=1), j, _REFINE.size - 1)
        j = np.maximum(j, 1)
        a, b = g[rows, j - 1], g[rows, j]
    tau_close = np.where(closes, 0.5 * (a + b), grid[:, -1])
    res: FloatArray = np.where(has, np.maximum(tau_close - tau_end, 0.0), 0.0)
    return res


def _with_peaks(grid: FloatArray, vals: FloatArray) -> FloatArray:
    """Replace sampled local maxima by their parabolic peak value (sampling-independent peaks).

    At P_aps/24 sampling a sinusoid's maximum can be under-sampled by up to 1 %; a peak that
    touches the threshold between samples still closes the window.
    """
    x0, x1, x2 = grid[:, :-2], grid[:, 1:-1], grid[:, 2:]
    v0, v1, v2 = vals[:, :-2], vals[:, 1:-1], vals[:, 2:]
    with np.errstate(divide="ignore", invalid="ignore"):
        d1 = (v1 - v0) / (x1 - x0)
        d2 = (v2 - v1) / (x2 - x1)
        a = (d2 - d1) / (x2 - x0)
        b = (d1 * (x2 - x1) + d2 * (x1 - x0)) / (x2 - x0)
        peak = np.where((v1 >= v0) & (v1 >= v2) & (a < 0), v1 - b * b / (4 * a), v1)
    out = vals.copy()
    out[:, 1:-1] = np.maximum(v1, np.nan_to_num(peak, nan=0.0, posinf=0.0, neginf=0.0))
    return out


def _resolve_oscillation(
    fn: Callable[[FloatArray], FloatArray],
    grid: FloatArray,
    vals: FloatArray,
    thr: FloatArray,
    wdot: FloatArray,
) -> tuple[FloatArray, FloatArray]:
    """Add a P_aps/24 grid wherever the coarse σ_u is within 30 % of the threshold."""
    ok = vals <= thr[:, None]
    near = np.abs(vals - thr[:, None]) < 0.3 * thr[:, None]
    first = np.where(near.any(axis=1), np.argmax(near, axis=1), 0)
    cols = np.arange(grid.shape[1])[None, :]
    beyond = (~ok) & (cols >= first[:, None])
    last = np.where(beyond.any(axis=1), np.argmax(beyond, axis=1), grid.shape[1] - 1)
    rows = np.arange(grid.shape[0])
    lo = grid[rows, np.maximum(first - 1, 0)]
    hi = grid[rows, np.minimum(last + 1, grid.shape[1] - 1)]
    period = 2 * math.pi / np.abs(wdot)
    n_fine = int(np.clip(np.max(np.ceil((hi - lo) / (period / 24.0))), 2, 20_000))
    fine = lo[:, None] + (hi - lo)[:, None] * np.linspace(0.0, 1.0, n_fine + 1)[None, :]
    merged = np.sort(np.concatenate([grid, fine], axis=1), axis=1)
    return merged, fn(merged)
