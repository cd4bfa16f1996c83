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
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

F64 = NDArray[np.float64]

#: Harmonics are kept until the dropped tail is below this fraction of h (K·1e-14 ≪ 1 mm/s).
_SERIES_TOL = 1e-14
#: Spectra per chunk of the window-average kernel (its temporaries stay in cache), and of the
#: callers' per-spectrum passes over the same arrays (:func:`row_chunks`): the same boundaries,
#: since numpy's complex product of a one-element array is not the vectorised loop's double (a
#: chunk of one row elsewhere would round differently).
CHUNK_ROWS = 8192
#: Half-window floor [s]: a zero window evaluates as this one (sin x/x = 1 to rounding).
_HALF_FLOOR_S = 1e-280
#: Series terms whose coefficient and e-derivative are both below this are skipped [1].
_TERM_FLOOR = 1e-15
#: Never more harmonics than this (e < 0.1, what a target may have, needs ≤ 19).
_MAX_HARMONICS = 400


def row_chunks(n: int) -> Iterator[slice]:
    """Consecutive slices of at most :data:`CHUNK_ROWS` rows covering ``n`` rows."""
    return (slice(lo, lo + CHUNK_ROWS) for lo in range(0, n, CHUNK_ROWS))


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


def window_rotation(omega_dot: float, window_s: ArrayLike) -> tuple[F64, F64]:
    """cos and sin of ω̇Δt/2 per window (the apsidal turn over half an exposure, a zero window
    floored as in :func:`window_average`), for its ``rotation`` [1].

    Parameters
    ----------
    omega_dot : float
        Apsidal rate ω̇ [rad/s].
    window_s : array_like
        Exposure (or co-add window) length Δt [s].
    """
    c = omega_dot * _half_window(window_s)
    return np.cos(c), np.sin(c)


def _half_window(window_s: ArrayLike) -> F64:
    """Δt/2 [s], a zero window the limit Δt → 0 (sin x/x = 1 to rounding with Δt/2 = 1e-280 s)."""
    return np.maximum(0.5 * np.asarray(window_s, dtype=np.float64), _HALF_FLOOR_S)


def window_average(
    phase_asc_rad: ArrayLike,
    omega_rad: ArrayLike,
    e: float,
    nb_rad_s: ArrayLike,
    omega_dot: float,
    window_s: ArrayLike,
    derivatives: bool = True,
    rotation: tuple[ArrayLike, ArrayLike] | None = None,
    terms: list[Term] | None = None,
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
        Also compute the partial derivatives (else they are zero arrays). ⟨h⟩ is the same
        either way, bit for bit: the terms kept for the derivatives only (coefficient below
        1e-15, its e-derivative not) do not enter it.
    rotation : tuple of array_like, optional
        :func:`window_rotation` of ``omega_dot`` and ``window_s``, when the caller averages the
        same windows more than once (the same doubles as computed here).
    terms : list, optional
        :func:`series_terms` of ``e`` and ``derivatives``, when the caller averages chunk by
        chunk (the same list as computed here).

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
    half = _half_window(window_s)
    nb = np.asarray(nb_rad_s, dtype=np.float64)
    shape = np.broadcast(phi, om, half, nb).shape
    fphi, fom, fhalf, fnb = (np.broadcast_to(x, shape).ravel() for x in (phi, om, half, nb))
    rot = None if rotation is None else [np.broadcast_to(x, shape).ravel() for x in rotation]
    terms = series_terms(e, derivatives) if terms is None else terms
    out = np.zeros((4, fphi.size))
    for sl in row_chunks(fphi.size):  # chunks that stay in cache
        chunk = (fphi[sl], fom[sl], fhalf[sl], fnb[sl])
        turn = None if rot is None else (rot[0][sl], rot[1][sl])
        _kernel(*chunk, omega_dot, terms, derivatives, out[:, sl], turn)
    return WindowedVelocity(*(np.asarray(o.reshape(shape)) for o in out))


#: One harmonic of the kernel: k, (P_k, Q_k) of ⟨h⟩ (None: the term is not in ⟨h⟩), and
#: (P_k, Q_k, dP_k/de, dQ_k/de) of the derivatives.
Term = tuple[int, tuple[float, float] | None, tuple[float, float, float, float]]


def series_terms(e: float, derivatives: bool) -> list[Term]:
    """The harmonics that matter for :func:`window_average`, in increasing k.

    A coefficient is zeroed when it is negligible (Q_k ~ e²P_k): for ⟨h⟩ when |P_k| is below
    _TERM_FLOOR; for the derivatives when |e·dP_k/de| is too (the same for Q_k). ⟨h⟩ takes the
    same terms with and without derivatives.
    """
    pk, qk, dpk, dqk = harmonics(e)
    scale = e if derivatives else 0.0
    h_p, h_q = np.abs(pk) > _TERM_FLOOR, np.abs(qk) > _TERM_FLOOR
    keep_p = h_p | (scale * np.abs(dpk) > _TERM_FLOOR)
    keep_q = h_q | (scale * np.abs(dqk) > _TERM_FLOOR)
    out: list[Term] = []
    for i in np.flatnonzero(keep_p | keep_q):
        p, q = float(pk[i]), float(qk[i])
        kp, kq = bool(keep_p[i]), bool(keep_q[i])
        h = (p if h_p[i] else 0.0, q if h_q[i] else 0.0) if h_p[i] or h_q[i] else None
        d = (p if kp else 0.0, q if kq else 0.0, float(dpk[i]) if kp else 0.0)
        out.append((int(i) + 1, h, (*d, float(dqk[i]) if kq else 0.0)))
    return out


def _kernel(
    phi: F64,
    om: F64,
    half: F64,
    nb: F64,
    omega_dot: float,
    terms: list[Term],
    derivatives: bool,
    out: F64,
    rotation: tuple[F64, F64] | None,
) -> None:
    """Accumulate ⟨h⟩ (and its partials) of one chunk into ``out`` (4, n) (``rotation``: cos
    and sin of ω̇Δt/2 if the caller has them).

    Term P_k: angle kM + ω = kΦ − (k−1)ω, window x = k n_bΔt/2 + ω̇Δt/2; term Q_k: kM − ω,
    x = k n_bΔt/2 − ω̇Δt/2. e^{ikM} and e^{ik n_bΔt/2} by recurrence.
    """
    a = nb * half  # n_b Δt/2
    c = omega_dot * half  # ω̇ Δt/2
    w1 = np.exp(1j * (phi - om))  # e^{iM}
    a1 = np.exp(1j * a)
    co, so = np.cos(om), np.sin(om)
    cc, sc = (np.cos(c), np.sin(c)) if rotation is None else rotation
    wk, ak = np.ones_like(w1), np.ones_like(a1)
    done = 0  # wk = e^{i·done·M}, ak = e^{i·done·a}
    for k, h, (p, q, dp, dq) in terms:
        for _ in range(k - done):
            wk *= w1
            ak *= a1
        done = k
        ka = k * a
        t1, t2 = ak.imag * cc, ak.real * sc  # sin(ka ± c) = t1 ± t2
        u1, u2 = wk.real * co, wk.imag * so  # cos(kM ± ω) = u1 ∓ u2
        sinc_p, sinc_q = (t1 + t2) / (ka + c), (t1 - t2) / (ka - c)
        if h is not None:
            out[0] += h[0] * sinc_p * (u1 - u2) + h[1] * sinc_q * (u1 + u2)
        if derivatives:
            v1, v2 = wk.imag * co, wk.real * so  # sin(kM ± ω) = v1 ± v2
            sp, sq = p * sinc_p * (v1 + v2), q * sinc_q * (v1 - v2)
            out[1] -= k * (sp + sq)
            out[2] += (k - 1) * sp + (k + 1) * sq
            out[3] += dp * sinc_p * (u1 - u2) + dq * sinc_q * (u1 + u2)
