"""The exact Keplerian velocity curve as a Fourier series, and its average over an exposure.

Beyond the paper's first order in e (``docs/method.md``, "Reduction: the exact Kepler design").
Star 1's line-of-sight velocity is v₁ = γ₁ + K₁ h and star 2's v₂ = γ₂ − K₂ h with

    h = cos(ω + ν) + e cos ω,     M = Φ_asc − ω  (mean anomaly; ν the true anomaly),

(η, κ) = e (sin ω, cos ω) and Φ_asc = Φ_GW/2 of the phase model. With the classical Bessel
expansions cos ν = −e + 2(1−e²)/e Σ J_k(ke) cos kM and sin ν = 2√(1−e²) Σ J_k′(ke) sin kM,

    h = Σ_{k≥1} P_k cos(kΦ − (k−1)ω) + Q_k cos(kΦ − (k+1)ω),
    P_k = (A_k + B_k)/2,  Q_k = (A_k − B_k)/2,  A_k = 2(1−e²) J_k(ke)/e,  B_k = 2√(1−e²) J_k′(ke).

Each term's angle advances at a constant rate over one exposure (k n̄ − (k∓1) ω̇; the frequency
derivative inside one exposure shifts the phase by π ḟ Δt²/4 ≲ 1e-11 rad), so the average over a
uniformly weighted window Δt is the term at mid-window times sinc(rate·Δt/2). At first order in e
this is Eq. vbar_master: P₁ = 1 − O(e²) carries Λ_K cos Φ and P₂ = e + O(e³) carries
Λ_κ (κ cos 2Φ + η sin 2Φ); the rest is O(e²).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["WindowedVelocity", "harmonics", "n_harmonics", "window_average"]

F64 = NDArray[np.float64]

#: Harmonics are kept until the dropped tail is below this fraction of h (K·1e-14 ≪ 1 mm/s).
_SERIES_TOL = 1e-14
#: Half-window floor [s]: a zero window evaluates as this one (sin x/x = 1 to rounding).
_HALF_FLOOR_S = 1e-280
#: Series terms whose coefficient and e-derivative are both below this are skipped [1].
_TERM_FLOOR = 1e-15
#: Never more harmonics than this (e < 0.1, what a target may have, needs ≤ 19).
_MAX_HARMONICS = 400


def n_harmonics(e: float) -> int:
    """Harmonics k = 1 … n for which the dropped tail of the series is below 1e-14 of h.

    Notes
    -----
    J_k(ke) ≤ (e exp√(1−e²)/(1 + √(1−e²)))^k (Watson §8.7): a geometric bound on the terms.
    """
    if e == 0.0:
        return 1
    s = math.sqrt(1.0 - e * e)
    ratio = e * math.exp(s) / (1.0 + s)
    n = math.ceil(math.log(_SERIES_TOL) / math.log(ratio)) + 2
    return int(min(max(n, 2), _MAX_HARMONICS))


def harmonics(e: float, n: int | None = None) -> tuple[F64, F64, F64, F64]:
    """(P_k, Q_k, dP_k/de, dQ_k/de) for k = 1 … n of the velocity factor h (module docstring).

    Parameters
    ----------
    e : float
        Eccentricity, 0 ≤ e < 1.
    n : int, optional
        Number of harmonics (default :func:`n_harmonics`).

    Raises
    ------
    ValueError
        e outside [0, 1).
    """
    from scipy.special import jv, jvp

    if not 0.0 <= e < 1.0:
        raise ValueError(f"eccentricity must lie in [0, 1), got {e}")
    n = n_harmonics(e) if n is None else n
    if e == 0.0:  # the limits: P₁ = 1, dP₂/de = 1 (P₂ = e + O(e³)), dQ₁/de = 0
        p, dp = np.zeros(n), np.zeros(n)
        p[0] = 1.0
        if n > 1:
            dp[1] = 1.0
        return p, np.zeros(n), dp, np.zeros(n)
    k = np.arange(1, n + 1, dtype=np.float64)
    z = k * e
    j, j1, j2 = jv(k, z), jvp(k, z, 1), jvp(k, z, 2)
    s = math.sqrt(1.0 - e * e)
    a = 2.0 * (1.0 - e * e) * j / e
    b = 2.0 * s * j1
    da = 2.0 * (-2.0 * j + (1.0 - e * e) * (k * j1 / e - j / (e * e)))
    db = 2.0 * (-e / s * j1 + s * k * j2)
    return (
        np.asarray(0.5 * (a + b), np.float64),
        np.asarray(0.5 * (a - b), np.float64),
        np.asarray(0.5 * (da + db), np.float64),
        np.asarray(0.5 * (da - db), np.float64),
    )


@dataclass(frozen=True, slots=True)
class WindowedVelocity:
    """⟨h⟩ over each exposure and its partial derivatives at fixed window [1 per unit].

    Attributes
    ----------
    h : ndarray
        Window average of h = cos(ω + ν) + e cos ω.
    d_phase : ndarray
        ∂⟨h⟩/∂Φ_asc at fixed (e, ω) [1/rad].
    d_omega : ndarray
        ∂⟨h⟩/∂ω at fixed (Φ_asc, e) [1/rad].
    d_e : ndarray
        ∂⟨h⟩/∂e at fixed (Φ_asc, ω).
    """

    h: F64
    d_phase: F64
    d_omega: F64
    d_e: F64


def window_average(
    phase_asc_rad: ArrayLike,
    omega_rad: ArrayLike,
    e: float,
    nb_rad_s: ArrayLike,
    omega_dot: float,
    window_s: ArrayLike,
    derivatives: bool = True,
) -> WindowedVelocity:
    """Average of h = cos(ω + ν) + e cos ω over exposures centred on the given phases.

    Parameters
    ----------
    phase_asc_rad : array_like
        Φ_asc at mid-exposure [rad] (reduce it modulo 2π first for full precision).
    omega_rad : array_like
        Argument of periastron ω of star 1 at mid-exposure [rad].
    e : float
        Eccentricity (constant under the rigid apsidal rotation), 0 ≤ e < 1.
    nb_rad_s : array_like
        Anomalistic mean motion n_b = dM/dt at mid-exposure [rad/s].
    omega_dot : float
        Apsidal rate ω̇ [rad/s].
    window_s : array_like
        Exposure (or co-add window) length Δt [s]; 0 gives h at mid-exposure.
    derivatives : bool
        Also compute the partial derivatives (else they are zero arrays).

    Returns
    -------
    WindowedVelocity
        v̄₁ = γ₁ + K₁⟨h⟩, v̄₂ = γ₂ − K₂⟨h⟩.

    Notes
    -----
    Exact Keplerian motion (module docstring); Eq. vbar_master is its first order in e. Powers
    of e^{iM} and of the window phase e^{i n_b Δt/2} are built by recurrence (k ≤ 19 for
    e < 0.1: rounding grows by k ulp).
    """
    phi = np.asarray(phase_asc_rad, dtype=np.float64)
    om = np.asarray(omega_rad, dtype=np.float64)
    # a zero window is the limit Δt → 0: sin x/x = 1 to rounding with Δt/2 = 1e-280 s
    half = np.maximum(0.5 * np.asarray(window_s, dtype=np.float64), _HALF_FLOOR_S)
    shape = np.broadcast(phi, om, half, np.asarray(nb_rad_s)).shape
    a = np.broadcast_to(np.asarray(nb_rad_s, np.float64) * half, shape)  # n_b Δt/2
    c = np.broadcast_to(omega_dot * half, shape)  # ω̇ Δt/2
    wk1 = np.broadcast_to(np.exp(1j * (phi - om)), shape)  # e^{iM}
    ak1 = np.exp(1j * a)  # e^{i n_b Δt/2}
    co, so = np.cos(om), np.sin(om)
    cc, sc = np.cos(c), np.sin(c)
    pk, qk, dpk, dqk = harmonics(e)
    # negligible terms are skipped (Q_k ~ e²P_k): |coefficient| and, for the derivatives,
    # |e·∂coefficient/∂e| below _TERM_FLOOR
    scale = e if derivatives else 0.0
    keep_p = (np.abs(pk) > _TERM_FLOOR) | (scale * np.abs(dpk) > _TERM_FLOOR)
    keep_q = (np.abs(qk) > _TERM_FLOOR) | (scale * np.abs(dqk) > _TERM_FLOOR)
    out = [np.zeros(shape) for _ in range(4)]
    wk, ak = np.ones(shape, complex), np.ones(shape, complex)
    for k in range(1, pk.size + 1):
        wk, ak = wk * wk1, ak * ak1
        wr, wi, ar, ai = wk.real, wk.imag, ak.real, ak.imag
        for coef, dcoef, m, sign, keep in (
            (pk[k - 1], dpk[k - 1], k - 1, 1.0, keep_p[k - 1]),
            (qk[k - 1], dqk[k - 1], k + 1, -1.0, keep_q[k - 1]),
        ):
            if not keep:
                continue
            # sin x/x, x = k n_b Δt/2 ± ω̇Δt/2: Im(e^{ikа} e^{±ic}) / x
            sinc = (ai * cc + sign * ar * sc) / (k * a + sign * c)
            # e^{i(kM ± ω)} = e^{i(kΦ − mω)}
            cos_t = wr * co - sign * wi * so
            out[0] += coef * sinc * cos_t
            if derivatives:
                sin_t = wi * co + sign * wr * so
                out[1] -= k * coef * sinc * sin_t
                out[2] += m * coef * sinc * sin_t
                out[3] += dcoef * sinc * cos_t
    return WindowedVelocity(*out)
