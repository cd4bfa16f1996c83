"""Horizons of apsidally precessing targets: an envelope bracket, then a certified scan.

With ω̇ ≠ 0 the anchor's Jacobian (``jacobian_kernel`` with Φ_asc placed on u★) is a cubic in τ
whose coefficients are four functions of the apsidal angle w = ω̇τ alone (∂u/∂Φ_asc, the η and κ
columns, η sin Φ + κ cos Φ), so in x = (τ − τ_end)/cap

    σ_u²(x) = ∑_{m=0}^{6} x^m F_m(w),   w = ω̇ (τ_end + cap·x),

each F_m a smooth 2π-periodic function of w built from one Gram matrix per target (the same for
every anchor). The F_m at 32 angles give their extremes (padded by max|F_m''| h²/8) and Fourier
sums ∑_k k^p |c_k| (padded) that bound |F_m'| and |F_m''|. For x ≥ 0 that yields

* an envelope L(x) ≤ σ_u²(x) ≤ U(x) of two polynomials: no window can close before U reaches
  thr², and one has closed once L exceeds it; the crossing is searched between the two;
* a curvature bound K(x) ≥ |d²σ_u²/dx²|, a polynomial with non-negative coefficients.

Inside the bracket σ_u² is sampled every P_aps/12 (or finer); a sample gap is cleared when its
ends lie further below thr² than K h²/8 (it cannot hide a crossing), and the others are
subdivided 32-fold (twice at most). The first gap that crosses is narrowed by two 32-fold
subdivisions (first crossing sample each round) and its secant. σ_u is evaluated exactly as by
the grid search (:func:`ucbplan.core.validity_grid.anchor_sigma_batch`), so the definition of the
window is the same; a window is found however brief (the grid may step over one: its result then
differs and a dense evaluation agrees with this one). A row whose scan would need more than
``_MAX_SAMPLES`` samples is left to the grid search (reported by :func:`t_valid_apsidal`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ucbplan.core.validity_grid import anchor_sigma_batch
from ucbplan.core.validity_poly import (
    anchor_phase,
    companion_roots_01,
    horner,
    monotone_01,
    shift_matrix,
)

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]
#: Samples of the apsidal angle per period for the Fourier bounds of the F_m.
_N_ANGLE = 32
#: Safety factor on the Fourier sums (harmonics above 16 alias into them).
_PAD = 1.25
#: Scan samples in the first chunk (doubling per chunk up to the last); samples per row before
#: it is left to the grid search.
_CHUNKS, _MAX_SAMPLES = (64, 128, 256, 512, 1024), 16_384
#: Subdivisions of a doubtful or crossing gap; levels of doubt subdivision; narrowing rounds
#: of a closing (32²: a P_aps/12 gap to ~6 min, then its secant) and of an opening (only its
#: window matters).
_SUB, _LEVELS, _ROUNDS, _ROUNDS_OPEN = 32, 2, 2, 1
_SUBSTEPS = np.linspace(0.0, 1.0, _SUB + 1)
#: First samples of an envelope's sign change, as fractions of [x0, 1].
_GEOM = np.concatenate([[0.0], np.geomspace(1e-12, 1.0, 48)])
_BISECT = np.linspace(0.0, 1.0, 65)


def _basis_gram(
    pars: FloatArray, covs: FloatArray, tau_end: FloatArray, scale: float
) -> FloatArray:
    """G (n, 4, 4, 7): σ_u² = ∑_m x^m ∑_ab g_a(w) g_b(w) G[a, b, m] for the factors of
    :func:`_angle_factors`; the same for every anchor."""
    n = pars.shape[0]
    basis = np.zeros((4, 4, 7))  # factor a, power of τ, parameter: ∂u/∂θ = ∑_a g_a(w) B_a(τ)
    basis[0, [0, 1, 2, 3], [0, 1, 2, 3]] = 0.5, math.pi, math.pi / 2.0, math.pi / 6.0
    basis[1, 0, 4] = basis[2, 0, 5] = 1.0
    basis[3, 1, 6] = -2.0
    shift = np.swapaxes(shift_matrix(tau_end, scale), 1, 2)  # powers of τ → powers of x
    bx = (shift[:, None] @ basis[None]).reshape(n, 16, 7)
    gram = (bx @ covs @ np.swapaxes(bx, 1, 2)).reshape(n, 4, 4, 4, 4)  # a, j, b, k
    out = np.zeros((n, 4, 4, 7))
    for j in range(4):
        for k in range(4):
            out[..., j + k] += gram[:, :, j, :, k]
    return out


def _angle_factors(pars: FloatArray, u_star: float, star: int) -> FloatArray:
    """g (n, N, 4) at w_i = 2πi/N: ∂u/∂Φ_asc, the η and κ columns, and (η sin + κ cos) Φ_asc,
    with Φ_asc placed on u★ as in the grid search (``jacobian_kernel`` at w)."""
    w = 2.0 * math.pi * np.arange(_N_ANGLE) / _N_ANGLE
    cw, sw = np.cos(w), np.sin(w)
    eta0, kap0 = pars[:, 4:5], pars[:, 5:6]
    eta, kap = eta0 * cw + kap0 * sw, kap0 * cw - eta0 * sw
    s, c = anchor_phase(eta, kap, u_star, star)
    d = 1.0 + 2.0 * kap * c + 2.0 * eta * s
    cols = (d, -2.0 * sw * s - 2.0 * cw * c, 2.0 * cw * s - 2.0 * sw * c, eta * s + kap * c)
    return np.stack(cols, axis=-1)


def _angle_coefficients(gram: FloatArray, g: FloatArray) -> FloatArray:
    """F_m at the angles: coefficients (n, N, 7) of σ_u² in powers of x."""
    n = g.shape[0]
    outer = (g[..., :, None] * g[..., None, :]).reshape(n, _N_ANGLE, 16)
    out: FloatArray = outer @ gram.reshape(n, 16, 7)
    return out


def envelope(
    pars: FloatArray,
    covs: FloatArray,
    tau_end: FloatArray,
    scale: float,
    u_star: float,
    star: int = 1,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """(lower, upper, curvature) coefficients (n, 7) in powers of x = (τ − τ_end)/scale.

    For x ≥ 0: lower(x) ≤ σ_u²(x) ≤ upper(x) and |d²σ_u²/dx²| ≤ curvature(x) [rad²].
    """
    coef = _angle_coefficients(
        _basis_gram(pars, covs, tau_end, scale), _angle_factors(pars, u_star, star)
    )
    return _bounds(coef, np.abs(pars[:, 6:7]) * scale)


def _bounds(coef: FloatArray, rate: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """:func:`envelope` from the F_m at the angles and dw/dx.

    Notes
    -----
    The extremes of F_m lie within ``max|F_m''| h²/8`` of its extreme samples (h = 2π/N, F_m' = 0
    there); the padded Fourier sums ∑ k^p |c_k| bound |F_m'| and |F_m''|.
    """
    amp = 2.0 * np.abs(np.fft.rfft(coef, axis=1)[:, 1:] / _N_ANGLE)
    amp[:, -1] *= 0.5  # the Nyquist term appears once
    k = np.arange(1, amp.shape[1] + 1, dtype=np.float64)[None, :, None]
    r1, r2 = (_PAD * np.sum(amp * k**p, axis=1) for p in (1, 2))
    top, bottom = coef.max(axis=1), coef.min(axis=1)
    pad = r2 * (2.0 * math.pi / _N_ANGLE) ** 2 / 8.0 + 1e-9 * (np.abs(top) + np.abs(bottom))
    upper, lower = top + pad, bottom - pad
    size = np.maximum(np.abs(upper), np.abs(lower))
    m = np.arange(7, dtype=np.float64)[None, :]
    curv = rate**2 * r2
    curv[:, :6] += 2.0 * m[:, 1:] * rate * r1[:, 1:]
    curv[:, :5] += m[:, 2:] * (m[:, 2:] - 1.0) * size[:, 2:]
    return lower, upper, curv


@dataclass(frozen=True)
class _Rows:
    """The precessing rows being searched, their envelopes and exact σ_u² − thr²."""

    pars: FloatArray
    covs: FloatArray
    tau_end: FloatArray
    thr2: FloatArray
    us: tuple[float, ...]
    star: int
    scale: float
    lower: FloatArray  # (n_u, n, 7) minus thr² in the constant term
    upper: FloatArray  # (n_u, n, 7) minus thr² in the constant term
    curv: FloatArray  # (n, 7), the largest over u★ coefficient-wise
    period: FloatArray  # apsidal period in x

    def values(self, rows: IntArray, x: FloatArray) -> FloatArray:
        """σ_u² − thr² (n_u, len(rows), m) at x (len(rows), m)."""
        tau = self.tau_end[rows, None] + self.scale * x
        p, c = self.pars[rows], self.covs[rows]
        sig = [anchor_sigma_batch(p, c, tau, u, self.star) for u in self.us]
        out: FloatArray = np.square(sig) - self.thr2[rows, None]
        return out

    def doubt(self, rows: IntArray, grid: FloatArray) -> FloatArray:
        """Bound K h²/8 on how far σ_u² can stray from the chord over each gap of ``grid``."""
        k = horner(self.curv[rows], grid[:, 1:])[0]  # K grows with x: its value at the right end
        out: FloatArray = k * np.square(np.diff(grid, axis=1)) / 8.0
        return out


def _setup(
    pars: FloatArray,
    covs: FloatArray,
    tau_end: FloatArray,
    thr: FloatArray,
    us: Sequence[float],
    star: int,
    cap_s: float,
) -> _Rows:
    """Envelopes (thr² subtracted) per u★ and the curvature bound (the largest over u★)."""
    gram = _basis_gram(pars, covs, tau_end, cap_s)
    rate = np.abs(pars[:, 6:7]) * cap_s
    lows, ups, curvs = [], [], []
    for u in us:
        lo, up, cu = _bounds(_angle_coefficients(gram, _angle_factors(pars, u, star)), rate)
        lo[:, 0] -= thr**2
        up[:, 0] -= thr**2
        lows.append(lo)
        ups.append(up)
        curvs.append(cu)
    period = 2.0 * math.pi / (np.abs(pars[:, 6]) * cap_s)
    low, up = np.array(lows), np.array(ups)
    return _Rows(
        pars, covs, tau_end, thr**2, tuple(us), star, cap_s,
        low, up, np.max(curvs, axis=0), period,
    )  # fmt: skip


def _first_nonneg(
    coef: FloatArray, x0: FloatArray, first: NDArray[np.bool_]
) -> tuple[FloatArray, FloatArray]:
    """Per row, a bracket (a, b) of a point in [x0, 1] where the polynomial turns ≥ 0: it is
    ≥ 0 at b, and (rows with ``first``) < 0 on all of [x0, a); (x0, x0) if it is ≥ 0 at x0,
    (inf, inf) if it stays < 0.

    Bisection from a geometric sampling finds a sign change; it is the first one where the
    polynomial is monotone on [0, 1] (the usual envelope); other ``first`` rows take their
    companion-matrix roots.
    """
    n = coef.shape[0]
    a, b = np.full(n, np.inf), np.full(n, np.inf)
    now = horner(coef, x0[:, None])[0][:, 0] >= 0.0
    a[now], b[now] = x0[now], x0[now]
    x = x0[:, None] + (1.0 - x0)[:, None] * _GEOM[None, :]
    up = horner(coef, x)[0] >= 0.0
    hard = first & ~monotone_01(coef) & ~now
    rows = np.nonzero(up[:, -1] & ~now & ~hard)[0]
    if rows.size:
        a[rows], b[rows] = _bisect(coef[rows], x[rows], np.argmax(up[rows], axis=1))
    rows = np.nonzero(hard)[0]
    if rows.size:
        r = companion_roots_01(coef[rows])
        with np.errstate(invalid="ignore"):
            r = np.where(r >= x0[rows, None], r, np.inf).min(axis=1, initial=np.inf)
        a[rows], b[rows] = r * (1.0 - 1e-9), r * (1.0 + 1e-9)
    return a, b


def _bisect(coef: FloatArray, x: FloatArray, j: IntArray) -> tuple[FloatArray, FloatArray]:
    """Bracket (a, b), b/a − 1 ≲ 2e-4, of a sign change (< 0 at a, ≥ 0 at b) of polynomials
    sampled at x (m, G) with the first non-negative sample j > 0: two 64-fold subdivisions (a
    scan start need not be sharper than its step)."""
    idx = np.arange(coef.shape[0])
    a, b = x[idx, j - 1], x[idx, j]
    for _ in range(2):
        sub = a[:, None] + (b - a)[:, None] * _BISECT[None, :]
        k = np.argmax(horner(coef, sub)[0] >= 0.0, axis=1)  # the last point is ≥ 0
        a, b = sub[idx, np.maximum(k - 1, 0)], sub[idx, k]
    return a, b


def _hits(v: FloatArray, closing: bool) -> NDArray[np.bool_]:
    """Samples past the crossing: some σ_u above thr (closing) or all below (opening)."""
    worst = v.max(axis=0)
    out: NDArray[np.bool_] = worst > 0.0 if closing else worst <= 0.0
    return out


def _clean(v: FloatArray, doubt: FloatArray, closing: bool) -> NDArray[np.bool_]:
    """Sample gaps that provably hold no crossing, given |σ_u²''| h²/8 ≤ doubt."""
    if closing:
        top = np.maximum(v[..., :-1], v[..., 1:]).max(axis=0)
        return top + doubt < 0.0
    low = np.minimum(v[..., :-1], v[..., 1:]).max(axis=0)  # one σ_u stays above thr
    return low - doubt > 0.0


def _first_gap(
    t: _Rows, rows: IntArray, grid: FloatArray, closing: bool, level: int = 0
) -> tuple[NDArray[np.bool_], FloatArray, FloatArray, FloatArray]:
    """Per row of sample points ``grid`` (m, G+1): whether a crossing lies on it, the gap
    [a, b] that holds the first one (b past it) and max_u σ_u² − thr² at a and b (2, m).

    Gaps before the first sample past the crossing that the curvature bound does not clear are
    subdivided ``_SUB``-fold, up to ``_LEVELS`` times (then cleared: the doubt left is < 1e-5
    of the first one).
    """
    v = t.values(rows, grid)
    hit = _hits(v, closing)
    size = grid.shape[1] - 1
    first = np.where(hit.any(axis=1), np.argmax(hit, axis=1), size + 1)
    idx = np.arange(rows.size)
    ends = np.clip(first - 1, 0, size), np.minimum(first, size)
    a, b = grid[idx, ends[0]], grid[idx, ends[1]]
    worst = v.max(axis=0)
    g = np.array([worst[idx, ends[0]], worst[idx, ends[1]]])
    found = first <= size
    if level == _LEVELS:
        return found, a, b, g
    cols = np.arange(size)[None, :]
    bad = ~_clean(v, t.doubt(rows, grid), closing) & (cols + 1 < first[:, None])
    pr, pj = np.nonzero(bad)  # ordered by row, then gap
    if pr.size:
        sub = grid[pr, pj, None] + (grid[pr, pj + 1] - grid[pr, pj])[:, None] * _SUBSTEPS[None, :]
        got, sa, sb, sg = _first_gap(t, rows[pr], sub, closing, level + 1)
        hits = np.nonzero(got)[0]
        owner, at = np.unique(pr[hits], return_index=True)  # the earliest such gap per row
        a[owner], b[owner], g[:, owner] = sa[hits[at]], sb[hits[at]], sg[:, hits[at]]
        found[owner] = True
    return found, a, b, g


def _scan(
    t: _Rows, rows: IntArray, lo: FloatArray, hi: FloatArray, closing: bool
) -> tuple[FloatArray, FloatArray, NDArray[np.int8]]:
    """First crossing gap [a, b] in [lo, hi] per row; state 1 found, 0 none, −1 unresolved."""
    n = rows.size
    a, b = np.full(n, np.nan), np.full(n, np.nan)
    state = np.full(n, -1, dtype=np.int8)
    step = np.minimum(t.period[rows] / 12.0, (hi - lo) / 16.0)
    x = lo.copy()
    act = np.arange(n)
    used, i = 0, 0
    while act.size and used < _MAX_SAMPLES:
        size = _CHUNKS[min(i, len(_CHUNKS) - 1)]
        i, used = i + 1, used + size
        grid = x[act, None] + step[act, None] * np.arange(size + 1.0)[None, :]
        grid = np.minimum(grid, hi[act, None])
        got, a[act], b[act], _ = _first_gap(t, rows[act], grid, closing)
        over = ~got & (grid[:, -1] >= hi[act])
        state[act[got]] = 1
        state[act[over]] = 0
        x[act] = grid[:, -1]
        act = act[~got & ~over]
    return a, b, state


def _narrow(t: _Rows, rows: IntArray, a: FloatArray, b: FloatArray, closing: bool) -> FloatArray:
    """The crossing in gaps [a, b] (b past it): ``_SUB``-fold subdivision rounds keeping the first
    crossing (doubtful sub-gaps checked in the first round: later ones are 32× finer), then the
    secant of the last gap for a closing, its end past the crossing for an opening."""
    g = np.full((2, rows.size), np.nan)
    for i in range(_ROUNDS if closing else _ROUNDS_OPEN):
        sub = a[:, None] + (b - a)[:, None] * _SUBSTEPS[None, :]
        got, sa, sb, sg = _first_gap(t, rows, sub, closing, 0 if i == 0 else _LEVELS)
        a, b, g = np.where(got, sa, a), np.where(got, sb, b), np.where(got, sg, g)
    if not closing:
        return b
    frac = np.clip(-g[0] / (g[1] - g[0]), 0.0, 1.0)
    out: FloatArray = np.where(np.isfinite(frac) & (g[0] <= 0.0), a + (b - a) * frac, 0.5 * (a + b))
    return out


def _segments_below(lower: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Per row, the intervals of [0, 1] where every lower envelope is ≤ thr² (the only places a
    window can open), in order: (starts, ends) (n, S), NaN-padded."""
    n = lower.shape[1]
    roots = companion_roots_01(lower.reshape(-1, 7)).reshape(lower.shape[0], n, 6)
    roots = np.concatenate(list(roots), axis=1)
    pts = np.sort(np.concatenate([np.zeros((n, 1)), roots, np.ones((n, 1))], axis=1), axis=1)
    pts = np.where(np.isnan(pts), 1.0, pts)
    mid = 0.5 * (pts[:, :-1] + pts[:, 1:])
    below = np.max([horner(low, mid)[0] for low in lower], axis=0) <= 0.0
    below &= pts[:, 1:] > pts[:, :-1]
    order = np.argsort(~below, axis=1, kind="stable")  # admissible segments first, in order
    keep = np.take_along_axis(below, order, axis=1)
    starts = np.where(keep, np.take_along_axis(pts[:, :-1], order, axis=1), np.nan)
    ends = np.where(keep, np.take_along_axis(pts[:, 1:], order, axis=1), np.nan)
    return starts, ends


def _open(t: _Rows) -> tuple[FloatArray, NDArray[np.int8]]:
    """Opening x of the first window σ_u ≤ thr per row; state 1 open, 0 never, −1 unresolved."""
    n = t.tau_end.size
    rows = np.arange(n)
    x_open = np.zeros(n)
    state = np.ones(n, dtype=np.int8)
    late = np.nonzero(_hits(t.values(rows, np.zeros((n, 1))), closing=True)[:, 0])[0]
    state[late] = 0
    # the usual late row never opens: one lower envelope rises from above thr² at x = 0
    low = t.lower[:, late]
    rising = (monotone_01(low.reshape(-1, 7)).reshape(low.shape[:2])) & (low[..., 0] > 0.0)
    late = late[~(rising & (low.sum(axis=-1) > low[..., 0])).any(axis=0)]
    starts, ends = _segments_below(t.lower[:, late])
    for k in range(starts.shape[1]):
        sel = np.nonzero((state[late] == 0) & np.isfinite(starts[:, k]))[0]
        if sel.size == 0:
            break
        lo = starts[sel, k] * (1.0 - 1e-9)
        hi = np.minimum(ends[sel, k] * (1.0 + 1e-9) + 1e-15, 1.0)
        a, b, got = _scan(t, late[sel], lo, hi, closing=False)
        found = got == 1
        x_open[late[sel[found]]] = _narrow(t, late[sel[found]], a[found], b[found], False)
        state[late[sel]] = got
    return x_open, state


def _close(t: _Rows, rows: IntArray, x_open: FloatArray) -> tuple[FloatArray, NDArray[np.int8]]:
    """Closing x of the window opened at ``x_open``; state 1 closes, 0 open at the cap, −1
    unresolved."""
    # L ≤ U: the lower envelope cannot reach thr² before the upper one, so both from x_open
    nu, m = len(t.us), rows.size
    env = np.concatenate([t.upper[:, rows], t.lower[:, rows]]).reshape(-1, 7)
    first = np.repeat([True, False], nu * m)  # the start must be the first: the end need not
    a, b = _first_nonneg(env, np.tile(x_open, 2 * nu), first)
    start = np.maximum(np.minimum(a[: nu * m].reshape(nu, m).min(axis=0), 1.0), x_open)
    hi = np.minimum(b[nu * m :].reshape(nu, m).min(axis=0), 1.0)
    sure = np.max([horner(low, hi[:, None])[0][:, 0] for low in t.lower[:, rows]], axis=0) > 0
    hi = np.where(sure, hi, 1.0)  # a spurious root: no bracket end
    a, b, state = _scan(t, rows, start, hi, closing=True)
    state[(state == 0) & (hi < 1.0)] = -1  # past the bracket without a crossing: rounding
    x = np.ones(rows.size)
    found = state == 1
    x[found] = _narrow(t, rows[found], a[found], b[found], closing=True)
    return x, state


def t_valid_apsidal(
    pars: FloatArray,
    covs: FloatArray,
    t_obs: FloatArray,
    thr: FloatArray,
    us: Sequence[float],
    star: int,
    cap_s: float,
) -> tuple[FloatArray, NDArray[np.bool_]]:
    """Closing τ − τ_end of the first window max_u★ σ_u ≤ thr after τ_end = T/2 [s] (0 if none),
    and the rows left unresolved (to be searched on the grid; their value is NaN).

    Same contract as :func:`ucbplan.core.validity_grid.t_valid_grid`; rows must have ω̇ ≠ 0.
    """
    t = _setup(pars, covs, t_obs / 2.0, thr, us, star, cap_s)
    x_open, opened = _open(t)
    out = np.where(opened == 0, 0.0, np.nan)
    rows = np.nonzero(opened == 1)[0]
    x_close, closed = _close(t, rows, x_open[rows])
    out[rows] = np.where(closed >= 0, x_close * cap_s, np.nan)
    res: FloatArray = out
    return res, np.isnan(out)
