"""Exact horizons where σ_u² is a polynomial in time: the roots of σ_u²(τ) − thr².

When σ_u does not oscillate (ω̇ = 0, or a circular orbit whose eccentricity is not in the
covariance) the anchor puts Φ_asc at a fixed value, so every entry of ∂u/∂θ is a polynomial in τ
of degree ≤ 3 (Eq. arg_latitude_main differentiated, ``jacobian_kernel``) and
σ_u²(τ) = J C Jᵀ is a polynomial of degree ≤ 6. The first admissible window of
:func:`ucbplan.core.forecast.t_valid_batch` then follows from the real roots of
σ_u²(τ) − thr² for each u★ of the anchor: no sampling, so no window is missed between samples.

Time is scaled to x = (τ − τ_end)/cap ∈ [0, 1]; roots come from batched companion-matrix
eigenvalues (one ``eigvals`` call per polynomial degree) and are polished by Newton steps.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
_BINOM = np.array([[math.comb(k, j) for j in range(4)] for k in range(4)], dtype=np.float64)
#: Leading coefficients below this fraction of the largest term on [0, 1] are dropped.
_REL_ZERO = 1e-15


def anchor_phase(
    eta: FloatArray, kap: FloatArray, u_star: float, star: int
) -> tuple[FloatArray, FloatArray]:
    """sin, cos of Φ_asc at the anchor for (η, κ) of any shape, as in the grid search (two
    fixed-point steps)."""
    eps = 0.0 if star == 1 else math.pi
    phi = np.full(np.shape(eta), u_star - eps)
    if np.any(eta != 0.0) or np.any(kap != 0.0):
        for _ in range(2):
            phi = u_star - eps - (2 * kap * np.sin(phi) - 2 * eta * np.cos(phi))
    return np.sin(phi), np.cos(phi)


def sigma2_coefficients(
    pars: FloatArray,
    covs: FloatArray,
    tau_end: FloatArray,
    scale_s: float,
    u_star: float,
    star: int = 1,
    shift: FloatArray | None = None,
) -> FloatArray:
    """Coefficients (n, 7) in ascending powers of x = (τ − τ_end)/scale of σ_u²(τ) [rad²].

    Valid for rows whose σ_u does not oscillate (see the module docstring); there
    ``jacobian_kernel`` at the anchor is ∑_k b_k τ^k with the b_k below. ``shift``: the
    :func:`shift_matrix` of ``tau_end`` and ``scale_s`` if the caller has it already.
    """
    n = pars.shape[0]
    eta, kap = pars[:, 4], pars[:, 5]
    s, c = anchor_phase(eta, kap, u_star, star)
    d = 1.0 + 2.0 * kap * c + 2.0 * eta * s
    b = np.zeros((n, 4, 7))
    b[:, 0, 0] = 0.5 * d
    b[:, 0, 4] = -2.0 * c  # ω̇τ = 0 here, or these rows of C vanish
    b[:, 0, 5] = 2.0 * s
    b[:, 1, 1] = math.pi * d
    b[:, 1, 6] = -2.0 * (eta * s + kap * c)
    b[:, 2, 2] = math.pi * d / 2.0
    b[:, 3, 3] = math.pi * d / 6.0
    return power_gram(b, covs, tau_end, scale_s, shift)


def shift_matrix(tau_end: FloatArray, scale_s: float) -> FloatArray:
    """S (n, 4, 4) with τ^k = ∑_j S[k, j] x^j for x = (τ − τ_end)/scale."""
    # τ^k = ∑_j C(k, j) τ_end^(k−j) scale^j x^j
    powers = np.arange(4)
    diff = powers[:, None] - powers[None, :]
    te = tau_end[:, None, None] ** np.maximum(diff, 0)[None]
    out: FloatArray = (
        np.where(diff[None] >= 0, _BINOM[None] * te, 0.0) * scale_s ** powers[None, None, :]
    )
    return out


def power_gram(
    b: FloatArray,
    covs: FloatArray,
    tau_end: FloatArray,
    scale_s: float,
    shift: FloatArray | None = None,
) -> FloatArray:
    """Coefficients (n, 7) in x = (τ − τ_end)/scale of (∑_k b_k τ^k) C (∑_k b_k τ^k)ᵀ.

    ``b`` (n, 4, 7): the Jacobian's coefficients of τ^0..τ^3; ``covs`` (n, 7, 7); ``shift``:
    :func:`shift_matrix` of ``tau_end`` and ``scale_s`` (computed when not given).
    """
    n = b.shape[0]
    s = shift_matrix(tau_end, scale_s) if shift is None else shift
    bx = np.swapaxes(s, 1, 2) @ b  # stacked matmul: ~20x quicker than the batched einsum
    m = bx @ covs @ np.swapaxes(bx, 1, 2)
    coef = np.zeros((n, 7))
    for j in range(4):
        for k in range(4):
            coef[:, j + k] += m[:, j, k]
    return coef


def horner(coef: FloatArray, x: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Value and derivative of polynomials (n, D+1) ascending at points x (n, m)."""
    val = np.zeros_like(x) + coef[:, -1:]
    der = np.zeros_like(x)
    for k in range(coef.shape[1] - 2, -1, -1):
        der = der * x + val
        val = val * x + coef[:, k : k + 1]
    return val, der


def _bernstein_matrix(m: int) -> FloatArray:
    """M with (power coefficients of degree ≤ m) @ M = Bernstein coefficients on [0, 1]."""
    out = np.zeros((m + 1, m + 1))
    for k in range(m + 1):
        for j in range(k, m + 1):
            out[k, j] = math.comb(j, k) / math.comb(m, k)
    return out


def monotone_01(coef: FloatArray) -> NDArray[np.bool_]:
    """Rows whose polynomial is strictly monotone on [0, 1] (its derivative's Bernstein
    coefficients all share one strict sign: a sufficient condition)."""
    width = coef.shape[1]
    deriv = coef[:, 1:] * np.arange(1, width)[None, :]
    bern = deriv @ _bernstein_matrix(width - 2)
    out: NDArray[np.bool_] = np.all(bern > 0.0, axis=1) | np.all(bern < 0.0, axis=1)
    return out


def _monotone_root(coef: FloatArray) -> FloatArray:
    """The root in (0, 1) of polynomials monotone on [0, 1] with a sign change there.

    Safeguarded Newton: the bracket [lo, hi] always holds the root; a Newton step that leaves it
    is replaced by bisection. Converges to the last bit of x in ~10 iterations. Each row stops
    at its own convergence, so a row's root does not depend on the other rows of the batch
    (a population forecast's table is the same whatever the chunking).
    """
    n = coef.shape[0]
    x = np.full(n, 0.5)
    rows = np.arange(n)  # the live rows' indices, in step with the arrays below
    cols = np.ascontiguousarray(coef.T)  # (D+1, live): one contiguous row per power
    rising = coef.sum(axis=1) > coef[:, 0]  # P(1) > P(0)
    xl, ll, hl = x.copy(), np.zeros(n), np.ones(n)
    for _ in range(100):
        val, der = _horner_1d(cols, xl)
        above = (val > 0.0) == rising  # the root is below x
        hl, ll = np.where(above, xl, hl), np.where(above, ll, xl)
        with np.errstate(divide="ignore", invalid="ignore"):
            newton = xl - val / der
        new = np.where((newton > ll) & (newton < hl), newton, 0.5 * (ll + hl))
        new = np.where(val == 0.0, xl, new)
        done = (new == xl) | (hl - ll <= 4e-16)
        xl = new
        if done.any():  # the finished rows leave the arrays (each row stops on its own)
            x[rows[done]] = xl[done]
            keep = ~done
            if not keep.any():
                return x
            rows, xl, ll, hl, rising = rows[keep], xl[keep], ll[keep], hl[keep], rising[keep]
            cols = cols[:, keep]
    x[rows] = xl
    return x


def _horner_1d(cols: FloatArray, x: FloatArray) -> tuple[FloatArray, FloatArray]:
    """:func:`horner` for one point per polynomial, coefficients by power ``cols`` (D+1, n):
    the same operations in the same order, on contiguous 1-d arrays and in place."""
    val = np.zeros_like(x) + cols[-1]
    der = np.zeros_like(x)
    for k in range(cols.shape[0] - 2, -1, -1):
        der *= x
        der += val
        val *= x
        val += cols[k]
    return val, der


def roots_01(coef: FloatArray) -> FloatArray:
    """Real roots in (0, 1) of each row's polynomial (ascending), NaN-padded to (n, D).

    A polynomial monotone on [0, 1] (the usual σ_u², growing after the end of the information)
    has at most one root there, found by :func:`_monotone_root`; the others take the
    eigenvalues of their companion matrix (:func:`companion_roots_01`).
    """
    n, width = coef.shape
    out = np.full((n, width - 1), np.nan)
    mono = monotone_01(coef)
    p0, p1 = coef[:, 0], coef.sum(axis=1)
    one = np.nonzero(mono & (((p0 < 0.0) & (p1 > 0.0)) | ((p0 > 0.0) & (p1 < 0.0))))[0]
    if one.size:
        out[one, 0] = _monotone_root(coef[one])
    rest = np.nonzero(~mono)[0]
    out[rest] = companion_roots_01(coef[rest])
    return out


def companion_roots_01(coef: FloatArray) -> FloatArray:
    """Real roots in (0, 1) from companion-matrix eigenvalues, Newton-polished, NaN-padded."""
    n, width = coef.shape
    out = np.full((n, width - 1), np.nan)
    size = np.sum(np.abs(coef), axis=1)  # bound of |p| on [0, 1]
    live = np.abs(coef) > _REL_ZERO * size[:, None]
    deg = np.where(live.any(axis=1), width - 1 - np.argmax(live[:, ::-1], axis=1), 0)
    for d in range(1, width):
        rows = np.nonzero(deg == d)[0]
        if rows.size == 0:
            continue
        monic = coef[rows, :d] / coef[rows, d : d + 1]
        comp = np.zeros((rows.size, d, d))
        comp[:, 0, :] = -monic[:, ::-1]
        comp[:, np.arange(1, d), np.arange(d - 1)] = 1.0
        z = np.linalg.eigvals(comp)
        x = np.where(np.abs(z.imag) <= 1e-6 * (1.0 + np.abs(z.real)), z.real, np.nan)
        for _ in range(3):  # Newton polish on the unscaled polynomial
            val, der = horner(coef[rows, : d + 1], np.nan_to_num(x))
            with np.errstate(divide="ignore", invalid="ignore"):
                step = np.where(der != 0.0, val / der, 0.0)
            x = x - np.where(np.abs(step) < 1e-3, step, 0.0)
        out[rows, :d] = np.where((x > 0.0) & (x < 1.0), x, np.nan)
    return out


def t_valid_poly(
    pars: FloatArray,
    covs: FloatArray,
    t_obs: FloatArray,
    thr: FloatArray,
    us: Sequence[float],
    star: int,
    cap_s: float,
) -> FloatArray:
    """Closing τ − τ_end of the first window max_u★ σ_u ≤ thr after τ_end = T/2 [s] (0 if none).

    Same contract as the grid search (:func:`ucbplan.core.validity_grid.t_valid_grid`): a window
    still open at ``cap_s`` closes there. Rows must not oscillate.
    """
    return t_valid_from_sigma2(sigma2_polys(pars, covs, t_obs, us, star, cap_s), thr, cap_s)


def sigma2_polys(
    pars: FloatArray,
    covs: FloatArray,
    t_obs: FloatArray,
    us: Sequence[float],
    star: int,
    cap_s: float,
) -> list[FloatArray]:
    """σ_u²(x) per u★ (:func:`sigma2_coefficients` after τ_end = T/2, x in units of ``cap_s``),
    one :func:`shift_matrix` for all of them: what :func:`t_valid_from_sigma2` takes, so that
    several thresholds (α) reuse one set of polynomials."""
    tau_end = t_obs / 2.0
    shift = shift_matrix(tau_end, cap_s)
    return [sigma2_coefficients(pars, covs, tau_end, cap_s, u, star, shift) for u in us]


def t_valid_from_sigma2(sigma2: Sequence[FloatArray], thr: FloatArray, cap_s: float) -> FloatArray:
    """:func:`t_valid_poly` from the polynomials of :func:`sigma2_polys` (left unchanged) [s]."""
    polys = [p.copy() for p in sigma2]
    for p in polys:
        p[:, 0] -= thr**2
    n = polys[0].shape[0]
    roots = np.full((n, 6 * len(polys)), np.nan)
    for j, p in enumerate(polys):  # a u★ whose σ_u² repeats an earlier one adds no roots
        new = np.ones(n, dtype=bool)
        for q in polys[:j]:
            new &= ~np.all(p == q, axis=1)
        roots[new, 6 * j : 6 * j + 6] = roots_01(p[new])
    pts = np.sort(np.concatenate([np.zeros((n, 1)), roots, np.ones((n, 1))], axis=1), axis=1)
    # NaN (no root) sorts last, after the closing 1: its zero-length segments at x = 1 would only
    # repeat the state of the segment ending there, so the columns no row needs are dropped
    pts = pts[:, : 2 + int(np.max(np.sum(~np.isnan(roots), axis=1), initial=0))]
    pts = np.where(np.isnan(pts), 1.0, pts)
    mid = 0.5 * (pts[:, :-1] + pts[:, 1:])
    worst = np.max([horner(p, mid)[0] for p in polys], axis=0)
    cols = np.arange(mid.shape[1])
    # a zero-length segment (a repeated root) takes the state of the segment before it
    src = np.maximum.accumulate(np.where(pts[:, 1:] > pts[:, :-1], cols[None, :], 0), axis=1)
    ok = np.take_along_axis(worst <= 0.0, src, axis=1)
    has = ok.any(axis=1)
    first = np.argmax(ok, axis=1)
    rest = (~ok) & (cols[None, :] >= first[:, None])
    close = np.where(rest.any(axis=1), pts[np.arange(n), np.argmax(rest, axis=1)], 1.0)
    out: FloatArray = np.where(has, close * cap_s, 0.0)
    return out
