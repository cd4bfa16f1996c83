"""Intra-session velocity regressions (paper Sec. 3.1): v_j = γ_j ± K_j F, finite-bin corrected.

All numbers here are plain float64 arrays in km/s (velocities) and radians (phases); the
ephemeris evaluation that produces the design variable lives in :mod:`ucbplan.reduce.design`.

Design variable
---------------
For a uniformly weighted exposure (or co-add window) of width Δt centred on the spectrum's
mid-time, the phase-averaged velocity is (Eq. vbar_master)

    v̄_j = γ_j ± K_j [Λ_K cos Φ_c + Λ_κ (κ cos 2Φ_c + η sin 2Φ_c)],

with Φ_c = Φ_asc at mid-exposure, Λ_K = sin x / x, Λ_κ = sin 2x / 2x, x = n̄_b Δt / 2
(Eqs. Lambda_K, Lambda_kappa). For Λ = 1 the bracket equals F = cos u + κ (Eq. F_definition) to
O(e²), so regressing on the bracket ``G`` gives slope K_j and intercept γ_j directly, up to its
O(e²) remainder (≈ −e²K_j in K_j). ``ucbplan reduce`` therefore regresses on the exposure average
of the exact Kepler curve instead (:mod:`ucbplan.reduce.design`, :mod:`ucbplan.core.kepler`);
:func:`binned_design` is the paper's first-order form, kept for cross-checks. For a common
window this is the paper's recipe (slope on F divided by Λ_K, intercept with the Λ_κ κ_s K_j
term, Eq. sb2_half_sum_ecc) plus the O(e(1−Λ)) term ∝ (Λ_K − Λ_κ) sin u that the F regression
leaves in the residuals; see :func:`paper_recipe` for the literal form used as a cross-check.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

#: Residuals beyond this many σ are flagged (reported, never dropped).
OUTLIER_NSIGMA = 4.0

F64 = NDArray[np.float64]


def lambda_k_to_x(lam: ArrayLike) -> F64:
    """Invert Λ_K = sin x / x for x ∈ [0, π) (used when only Λ_K is given, e.g. by a plan).

    Raises
    ------
    ValueError
        If any Λ_K is outside (0, 1].
    """
    lam_a = np.atleast_1d(np.asarray(lam, dtype=np.float64))
    if np.any(~np.isfinite(lam_a)) or np.any(lam_a <= 0.0) or np.any(lam_a > 1.0):
        raise ValueError("lambda_k must lie in (0, 1]")
    x = np.sqrt(6.0 * (1.0 - lam_a))  # small-x start: sin x/x ≈ 1 − x²/6
    x = np.minimum(x, 3.0)
    for _ in range(60):
        s, c = np.sin(x), np.cos(x)
        safe = np.where(x > 1e-8, x, 1.0)
        f = np.where(x > 1e-8, s / safe, 1.0 - x * x / 6.0) - lam_a
        df = np.where(x > 1e-8, (c * safe - s) / safe**2, -x / 3.0)
        df = np.where(np.abs(df) < 1e-12, -1e-12, df)
        step = f / df
        x = np.clip(x - step, 0.0, math.pi - 1e-9)
        if np.all(np.abs(step) < 1e-14):
            break
    return np.asarray(x, dtype=np.float64)


def binned_design(
    phase_asc_rad: ArrayLike,
    eta: ArrayLike,
    kappa: ArrayLike,
    lam_k: ArrayLike = 1.0,
    lam_kappa: ArrayLike = 1.0,
) -> F64:
    """Window-averaged orbital factor G = Λ_K cos Φ_c + Λ_κ(κ cos 2Φ_c + η sin 2Φ_c).

    Parameters
    ----------
    phase_asc_rad : array_like
        Φ_asc = Φ_GW/2 at mid-exposure [rad].
    eta, kappa : array_like
        Laplace–Lagrange pair η_LISA(t), κ_LISA(t) at mid-exposure [1].
    lam_k, lam_kappa : array_like
        Λ_K and Λ_κ of each spectrum's window [1].

    Returns
    -------
    ndarray
        G [1]; v̄_1 = γ_1 + K_1 G, v̄_2 = γ_2 − K_2 G.

    Notes
    -----
    Eq. vbar_master. With Λ = 1, G = cos u + κ = F (Eq. F_definition) to first order in e.
    """
    phi = np.asarray(phase_asc_rad, dtype=np.float64)
    return np.asarray(
        np.asarray(lam_k) * np.cos(phi)
        + np.asarray(lam_kappa)
        * (np.asarray(kappa) * np.cos(2.0 * phi) + np.asarray(eta) * np.sin(2.0 * phi)),
        dtype=np.float64,
    )


@dataclass(frozen=True, slots=True)
class LineFit:
    """Weighted least-squares straight line y = intercept + slope·x.

    Attributes
    ----------
    slope, intercept : float
        Best-fit coefficients (units of y per x, units of y).
    cov : ndarray
        2×2 covariance of (intercept, slope), scaled by max(1, χ²/dof) (Birge ratio) when
        ``scaled`` is true.
    chi2 : float
        χ² of the fit with the input σ.
    dof : int
        Degrees of freedom, n − 2.
    rms : float
        Unweighted rms of the residuals (units of y).
    residuals : ndarray
        y − model.
    normalized : ndarray
        residuals / σ.
    outliers : ndarray
        Boolean mask |normalized| > :data:`OUTLIER_NSIGMA` (flagged, not dropped).
    scaled : bool
        Whether ``cov`` was inflated by χ²/dof > 1.
    """

    slope: float
    intercept: float
    cov: F64
    chi2: float
    dof: int
    rms: float
    residuals: F64
    normalized: F64
    outliers: NDArray[np.bool_]
    scaled: bool

    @property
    def scale(self) -> float:
        """The factor ``cov``'s σ's were multiplied by: √(χ²/dof) when ``scaled``, else 1."""
        return math.sqrt(self.chi2 / self.dof) if self.scaled else 1.0

    @property
    def sigma_slope(self) -> float:
        """1σ uncertainty of the slope."""
        return float(math.sqrt(self.cov[1, 1]))

    @property
    def sigma_intercept(self) -> float:
        """1σ uncertainty of the intercept."""
        return float(math.sqrt(self.cov[0, 0]))


def weighted_line(
    x: ArrayLike, y: ArrayLike, sigma: ArrayLike, *, scale: bool = True, weights: F64 | None = None
) -> LineFit:
    """Weighted linear regression y = a + b x with Gaussian errors σ on y.

    Parameters
    ----------
    x, y, sigma : array_like
        Abscissa, ordinate and 1σ ordinate errors (σ > 0), same length ≥ 2.
    scale : bool
        Inflate the covariance by χ²/dof when that exceeds 1 (honest errors under extra scatter).
    weights : ndarray, optional
        :func:`line_weights` of ``sigma``, when the caller has them (the same doubles).

    Returns
    -------
    LineFit

    Raises
    ------
    ValueError
        Fewer than two points, non-positive σ, or all x equal.
    """
    xa = np.asarray(x, dtype=np.float64)
    ya = np.asarray(y, dtype=np.float64)
    sa = np.asarray(sigma, dtype=np.float64)
    if xa.size < 2:
        raise ValueError("need at least two points for a line fit")
    buf = np.empty(xa.shape)  # every product summed is written here (no 8 MB temporaries)
    w = line_weights(sa) if weights is None else weights
    sw, xm, sxx, b, a = _line(xa, ya, w, buf)
    var_b = 1.0 / sxx
    var_a = 1.0 / sw + xm * xm / sxx
    cov_ab = -xm / sxx
    cov = np.array([[var_a, cov_ab], [cov_ab, var_b]])
    res = np.subtract(ya, np.add(a, np.multiply(b, xa, out=buf), out=buf))  # ya − (a + b·xa)
    norm = res / sa
    chi2 = float(np.multiply(norm, norm, out=buf).sum())
    dof = xa.size - 2
    scaled = False
    if scale and dof > 0 and chi2 / dof > 1.0:
        cov = cov * (chi2 / dof)
        scaled = True
    return LineFit(
        slope=b,
        intercept=a,
        cov=cov,
        chi2=chi2,
        dof=dof,
        rms=float(np.sqrt(np.mean(np.multiply(res, res, out=buf)))),
        residuals=res,
        normalized=norm,
        outliers=np.abs(norm, out=buf) > OUTLIER_NSIGMA,
        scaled=scaled,
    )


def line_weights(sigma: F64) -> F64:
    """The weights 1/σ² of :func:`weighted_line` [1/σ's unit²].

    Raises
    ------
    ValueError
        A σ that is not positive and finite.
    """
    if np.any(sigma <= 0) or not np.all(np.isfinite(sigma)):
        raise ValueError("sigma must be positive and finite")
    return np.asarray(1.0 / sigma**2, dtype=np.float64)


def line_slope(x: F64, y: F64, w: F64) -> tuple[float, float]:
    """(slope, intercept) of :func:`weighted_line` from the weights (:func:`line_weights`):
    the same doubles, without the residuals, χ² and covariance."""
    if x.size < 2:
        raise ValueError("need at least two points for a line fit")
    _sw, _xm, _sxx, b, a = _line(x, y, w, np.empty(x.shape))
    return b, a


def _line(x: F64, y: F64, w: F64, buf: F64) -> tuple[float, float, float, float, float]:
    """Σw, x̄, S_xx, slope and intercept of the weighted line (``buf``: scratch of x's shape)."""
    sw = w.sum()
    xm = float(np.multiply(w, x, out=buf).sum() / sw)
    ym = float(np.multiply(w, y, out=buf).sum() / sw)
    dx = x - xm
    wdx = np.multiply(w, dx, out=buf)
    sxx = float(np.multiply(wdx, dx, out=dx).sum())
    if sxx <= 0.0 or not math.isfinite(sxx):
        raise ValueError("all abscissae are equal: the slope is undetermined")
    b = float(np.multiply(wdx, np.subtract(y, ym, out=dx), out=dx).sum() / sxx)
    return float(sw), xm, sxx, b, ym - b * xm


@dataclass(frozen=True, slots=True)
class ComponentFit:
    """One component's semi-amplitude and intercept from the v–G regression.

    Attributes
    ----------
    star : int
        1 or 2 (sign +1 / −1 in v = γ ± K G).
    K, gamma : float
        Semi-amplitude and systemic intercept [km/s], finite-window corrected.
    cov : ndarray
        2×2 statistical covariance of (γ, K) [km²/s²].
    line : LineFit
        The raw regression (slope = ±K).
    """

    star: int
    K: float
    gamma: float
    cov: F64
    line: LineFit

    @property
    def sigma_K(self) -> float:
        """Statistical 1σ of K [km/s], scaled by √(χ²/dof) when χ²/dof > 1 (``line.scale``)."""
        return float(math.sqrt(self.cov[1, 1]))

    @property
    def sigma_K_input(self) -> float:
        """Statistical 1σ of K from the given σ_v alone, before any scaling [km/s]."""
        return self.sigma_K / self.line.scale

    @property
    def sigma_gamma(self) -> float:
        """Statistical 1σ of γ [km/s]."""
        return float(math.sqrt(self.cov[0, 0]))


def fit_component(
    design: ArrayLike, v: ArrayLike, sigma: ArrayLike, star: int, weights: F64 | None = None
) -> ComponentFit:
    """Fit v = γ + s K G (s = +1 for star 1, −1 for star 2) by weighted least squares.

    Parameters
    ----------
    design : array_like
        G from :func:`binned_design` [1].
    v, sigma : array_like
        Velocities and 1σ errors [km/s].
    star : int
        1 or 2.
    weights : ndarray, optional
        :func:`line_weights` of ``sigma``, when the caller has them.

    Returns
    -------
    ComponentFit

    Notes
    -----
    Eqs. v1v2_ecc_rv (v1v2_circular_rv for e = 0) with the finite-window design of Eq. vbar_master;
    K_j is the slope divided by Λ_K (Appendix B), which the design already contains.
    """
    if star not in (1, 2):
        raise ValueError("star must be 1 or 2")
    sign = 1.0 if star == 1 else -1.0
    line = weighted_line(design, v, sigma, weights=weights)
    jac = np.diag([1.0, sign])
    return ComponentFit(
        star=star,
        K=sign * line.slope,
        gamma=line.intercept,
        cov=jac @ line.cov @ jac.T,
        line=line,
    )


def paper_recipe(
    F: ArrayLike,
    v: ArrayLike,
    sigma: ArrayLike,
    star: int,
    lam_k: float,
    lam_kappa: float,
    kappa_s: float,
) -> tuple[float, float]:
    """The paper's literal recipe for a common window: regress on F, K = |slope|/Λ_K, then γ.

    Returns
    -------
    (K, gamma) : tuple of float
        [km/s]. γ_j = intercept ± K_j κ_s (Λ_K − Λ_κ), i.e. Eq. sb2_half_sum_ecc with the
        κ_s K_j term replaced by Λ_κ κ_s K_j (Sec. 3.1.3) after the intercept absorbed Λ_K κ_s K_j.
    """
    sign = 1.0 if star == 1 else -1.0
    line = weighted_line(F, v, sigma, scale=False)
    K = sign * line.slope / lam_k
    gamma = line.intercept + sign * K * kappa_s * (lam_k - lam_kappa)
    return float(K), float(gamma)


def two_spectrum_solution(
    v_u0: float, v_upi: float, star: int, kappa_s: float = 0.0, lam_kappa: float = 1.0
) -> tuple[float, float]:
    """K_j and γ_j from one spectrum at each quadrature (u = 0, π).

    Returns
    -------
    (K, gamma) : tuple of float
        Eq. sb2_half_diff and Eq. sb2_half_sum_ecc (κ_s K_j → Λ_κ κ_s K_j for co-added spectra;
        the velocities must already be divided by nothing: K here is the *observed* half
        difference, i.e. Λ_K K for finite windows).
    """
    if star == 1:
        K = 0.5 * (v_u0 - v_upi)
        gamma = 0.5 * (v_u0 + v_upi - 2.0 * lam_kappa * kappa_s * K)
    else:
        K = 0.5 * (v_upi - v_u0)
        gamma = 0.5 * (v_upi + v_u0 + 2.0 * lam_kappa * kappa_s * K)
    return float(K), float(gamma)


@dataclass(frozen=True, slots=True)
class WilsonFit:
    """WIL41 velocity–velocity line v1 = (γ1 + qγ2) − q v2 (Eq. wilson_line_general).

    Attributes
    ----------
    q, sigma_q : float
        Mass ratio M2/M1 = −slope and its 1σ.
    intercept, sigma_intercept : float
        γ1 + qγ2 [km/s] and 1σ.
    chi2 : float
        χ² with effective variance σ1² + q²σ2² at the fitted q.
    dof : int
        n − 2.
    """

    q: float
    sigma_q: float
    intercept: float
    sigma_intercept: float
    chi2: float
    dof: int


def wilson_fit(
    v1: ArrayLike, s1: ArrayLike, v2: ArrayLike, s2: ArrayLike, q0: float = 1.0
) -> WilsonFit:
    """Fit the WIL41 line with errors on both velocities (maximum likelihood, York 2004).

    Parameters
    ----------
    v1, s1, v2, s2 : array_like
        Simultaneous velocities of the two stars and their 1σ [km/s].
    q0 : float
        Starting mass ratio.

    Returns
    -------
    WilsonFit

    Raises
    ------
    ValueError
        Fewer than two pairs, non-positive σ, or all v2 equal.

    Notes
    -----
    Eq. wilson_line_general. The line minimises χ² = Σ (v1 − a + q v2)²/(σ1² + q²σ2²), with q in
    the denominator too (the maximum-likelihood line for Gaussian errors in both coordinates:
    Deming/York). A regression of v1 on v2 with weights 1/(σ1² + q²σ2²) alone is not: its slope
    is diluted by Var(v2)/(Var(v2) + σ2²). Solved by York et al. (2004, Am. J. Phys. 72, 367)
    fixed-point iteration for uncorrelated errors; σ_q and σ_a are York's first-order errors.
    """
    x, y = np.asarray(v2, float), np.asarray(v1, float)
    wx, wy = 1.0 / np.asarray(s2, float) ** 2, 1.0 / np.asarray(s1, float) ** 2
    _check_wilson_inputs(x, wx, wy)
    work = np.empty((6, x.size))  # York's arrays, rewritten at every step (no fresh 8 MB each)
    b = _york_slope(x, y, wx, wy, -float(q0), work)
    W, xm, _U, _V, beta = _york_terms(x, y, wx, wy, b, work)
    tmp = work[5]
    ym = float(np.multiply(W, y, out=tmp).sum() / W.sum())
    a = ym - b * xm
    xa = np.add(xm, beta, out=beta)  # York's adjusted abscissae
    ua = np.subtract(xa, float(np.multiply(W, xa, out=tmp).sum() / W.sum()), out=work[4])
    var_b = 1.0 / float(np.multiply(np.multiply(W, ua, out=tmp), ua, out=tmp).sum())
    var_a = 1.0 / float(W.sum()) + float(np.multiply(W, xa, out=tmp).sum() / W.sum()) ** 2 * var_b
    res = np.subtract(np.subtract(y, a, out=work[4]), np.multiply(b, x, out=tmp), out=work[4])
    return WilsonFit(
        q=-b,
        sigma_q=math.sqrt(var_b),
        intercept=a,
        sigma_intercept=math.sqrt(var_a),
        chi2=float(np.multiply(np.multiply(W, res, out=tmp), res, out=tmp).sum()),
        dof=x.size - 2,
    )


def _check_wilson_inputs(x: F64, wx: F64, wy: F64) -> None:
    """Raise ValueError for fewer than two pairs, a weight that is not positive and finite, or
    a constant v2 (``x``)."""
    if x.size < 2:
        raise ValueError("need at least two velocity pairs for the WIL41 line")
    if not (
        np.all(np.isfinite(wx)) and np.all(np.isfinite(wy)) and np.all(wx > 0) and np.all(wy > 0)
    ):
        raise ValueError("sigma must be positive and finite")
    if not np.ptp(x) > 0.0:
        raise ValueError("all v2 are equal: the WIL41 slope is undetermined")


def _york_slope(x: F64, y: F64, wx: F64, wy: F64, b: float, work: F64) -> float:
    """York's fixed-point iteration for the slope, from ``b`` (at most 200 steps, relative
    tolerance 1e-13; ``work``: :func:`_york_terms`' arrays)."""
    for _ in range(200):
        W, _xm, U, V, beta = _york_terms(x, y, wx, wy, b, work)
        wb, tmp = np.multiply(W, beta, out=work[4]), work[5]
        b_new = float(np.multiply(wb, V, out=tmp).sum() / np.multiply(wb, U, out=tmp).sum())
        done = abs(b_new - b) <= 1e-13 * max(1.0, abs(b_new))
        b = b_new
        if done:
            break
    return b


def _york_terms(
    x: F64, y: F64, wx: F64, wy: F64, b: float, work: F64
) -> tuple[F64, float, F64, F64, F64]:
    """York's W_i, x̄, U_i, V_i and β_i at slope ``b`` (uncorrelated errors), written into the
    rows of ``work`` (6, n): W, U, V, β and two scratch rows."""
    W, U, V, beta, t1, t2 = work
    np.divide(np.multiply(wx, wy, out=t1), np.add(wx, np.multiply(b * b, wy, out=t2), out=t2), W)
    xm = float(np.multiply(W, x, out=t1).sum() / W.sum())
    ym = float(np.multiply(W, y, out=t1).sum() / W.sum())
    np.subtract(x, xm, out=U)
    np.subtract(y, ym, out=V)
    np.add(np.divide(U, wy, out=t1), np.divide(np.multiply(b, V, out=t2), wx, out=t2), out=t1)
    np.multiply(W, t1, out=beta)
    return W, xm, U, V, beta


def phase_sensitivity(
    design: ArrayLike,
    sigma: ArrayLike,
    d_design: ArrayLike,
    K: float,
    sign: float,
    weights: F64 | None = None,
) -> tuple[F64, F64]:
    """Linear response of (K, γ) of one component to the ephemeris parameters.

    Parameters
    ----------
    design : array_like, shape (n,)
        G of each spectrum [1].
    sigma : array_like, shape (n,)
        Velocity errors (weights) [km/s].
    d_design : array_like, shape (n, p)
        ∂G_i/∂θ_k for the p ephemeris parameters.
    K : float
        Fitted semi-amplitude [km/s].
    sign : float
        +1 (star 1) or −1 (star 2).
    weights : ndarray, optional
        1/σ² (:func:`line_weights`), when the caller has them (the same doubles).

    Returns
    -------
    (dK, dgamma) : tuple of ndarray, each shape (p,)
        ∂K/∂θ and ∂γ/∂θ [km/s per parameter unit] at fixed velocities.

    Notes
    -----
    If the true orbital factors are G + δG, the data are v = γ ± K(G + δG); regressing on G
    returns slope b + δb with δb = Σ w (x − x̄)(±K δG)/S_xx and intercept shift
    δa = ±K Σw δG/Σw − x̄ δb. Contracting with the LISA covariance gives the ephemeris
    (σ_u, σ_κ) contribution to σ_K and σ_γ (Appendix C1).
    """
    x = np.asarray(design, float)
    w = 1.0 / np.asarray(sigma, float) ** 2 if weights is None else weights
    dG = np.asarray(d_design, float)
    sw = w.sum()
    xm = (w * x).sum() / sw
    sxx = (w * (x - xm) ** 2).sum()
    d_slope = sign * K * _weighted_column_sums(w * (x - xm), dG) / sxx
    d_int = sign * K * _weighted_column_sums(w, dG) / sw - xm * d_slope
    return np.asarray(sign * d_slope, dtype=np.float64), np.asarray(d_int, dtype=np.float64)


#: Rows of the (n, p) products summed at a time by :func:`_weighted_column_sums`.
_SUM_ROWS = 1 << 13


def _weighted_column_sums(weights: F64, d: F64) -> F64:
    """Σ_i weights_i d_i over the rows of ``d`` (n, p): ``(weights[:, None] * d).sum(axis=0)``
    bit for bit, without the (n, p) product (56 MB per call at 10⁶ spectra, fresh pages each).

    numpy sums a C-ordered array over its first axis row after row (no pairwise splitting), so
    the sum is carried from block to block as the first row of the next: the same additions in
    the same order (``tests/reduce/test_reduce_regression.py`` compares with the whole product).
    """
    n, cols = d.shape
    buf = np.empty((min(n, _SUM_ROWS) + 1, cols))
    acc = np.zeros(cols)
    for lo in range(0, n, _SUM_ROWS):
        m = min(_SUM_ROWS, n - lo)
        start = 1 if lo == 0 else 0  # the first block starts from its own first row
        buf[0] = acc
        np.multiply(weights[lo : lo + m, None], d[lo : lo + m], out=buf[1 : m + 1])
        acc = buf[start : m + 1].sum(axis=0)
    return acc
