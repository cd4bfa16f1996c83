"""The phase model: GW phase, argument of latitude u(t), its rate, velocities and ∂u/∂θ.

All kernels are pure numpy over float64 seconds ``tau_s`` measured from the target's reference
epoch (TDB at the barycentre). The GW phase is accumulated with a compensated (double-double)
product so that u(t) keeps ~1e-15 cycle precision at any baseline; ``origin_s`` lets callers keep
a far-away window origin separate from a small offset, so epochs are represented exactly enough
for 1e-10 rad round trips. The inversion u(t★) = u★ is :mod:`ucbplan.core.ephemeris`.

Conventions (``docs/method.md``, "Phase model"; paper Appendix A): Φ_asc = Φ_GW/2;
u_j = Φ_asc + ε_j + 2κ sin Φ_asc − 2η cos Φ_asc with ε_1 = 0, ε_2 = π; (η, κ) rotate at ω̇
(Laplace–Lagrange, Eq. kappa_lisa_prediction).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ucbplan.core.constants import TWO_PI
from ucbplan.core.mvnormal import rows_times
from ucbplan.core.params import PARAM_NAMES, PhaseParams
from ucbplan.errors import UcbplanError

FloatArray = NDArray[np.float64]

_SPLIT = 134217729.0  # 2**27 + 1, Dekker splitting constant


def _two_prod(a: ArrayLike, b: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Exact product a·b = p + e in float64 (Dekker), vectorised."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    p = a * b
    ca = _SPLIT * a
    a_hi = ca - (ca - a)
    a_lo = a - a_hi
    cb = _SPLIT * b
    b_hi = cb - (cb - b)
    b_lo = b - b_hi
    e = ((a_hi * b_hi - p) + a_hi * b_lo + a_lo * b_hi) + a_lo * b_lo
    return p, e


def _star_offset(star: int) -> float:
    if star not in (1, 2):
        raise UcbplanError(f"star must be 1 or 2, got {star}")
    return 0.0 if star == 1 else math.pi


def _gw_cycles(
    p: PhaseParams, dt_s: ArrayLike, origin_s: float = 0.0
) -> tuple[FloatArray, FloatArray]:
    """GW cycles since the reference split as (integer N, fraction F); Φ_GW = 2π(N + F).

    τ = origin_s + dt_s. The f·τ term uses exact products so F is accurate to ~1e-15.
    """
    dt = np.asarray(dt_s, dtype=np.float64)
    tau = origin_s + dt
    p1, e1 = _two_prod(p.f_gw, origin_s)
    p2, e2 = _two_prod(p.f_gw, dt)
    n1 = np.rint(p1)
    n2 = np.rint(p2)
    frac = (p1 - n1) + (p2 - n2) + (e1 + e2)
    frac = frac + (p.fdot * tau * tau / 2.0 + p.fddot * tau * tau * tau / 6.0)
    frac = frac + p.phase / TWO_PI
    n3 = np.floor(frac)
    return n1 + n2 + n3, frac - n3


def gw_phase(p: PhaseParams, tau_s: ArrayLike) -> FloatArray:
    """GW phase Φ_GW(τ) of the dominant mode [rad] (unwrapped).

    Notes
    -----
    Eq. app:phase_model_app: Φ = φ_ref + 2π[fτ + ḟτ²/2 + f̈τ³/6].
    """
    n, f = _gw_cycles(p, tau_s)
    return TWO_PI * (n + f)


def phase_asc(p: PhaseParams, tau_s: ArrayLike) -> FloatArray:
    """Mean orbital phase from the ascending node Φ_asc = Φ_GW/2 [rad] (Eq. app:PhiGW)."""
    return 0.5 * gw_phase(p, tau_s)


def phase_asc_mod(p: PhaseParams, tau_s: ArrayLike) -> FloatArray:
    """Φ_asc modulo 2π [rad], in [0, 2π), without the rounding of the unwrapped phase.

    At τ ~ 1e8 s the unwrapped Φ_asc ~ 1e7 rad carries 2e-9 rad of float64 rounding; the cycle
    split of the GW phase keeps ~1e-15 cycle here.
    """
    n, f = _gw_cycles(p, tau_s)
    half = np.floor(n / 2.0)
    out: FloatArray = TWO_PI * ((n - 2.0 * half + f) / 2.0)
    return out


def ascending_node_s(p: PhaseParams) -> float:
    """Ascending node nearest the reference epoch, T_asc − t_ref [s].

    Notes
    -----
    Appendix A1: Φ_asc = 0 at T_asc = t_ref − φ_ref/(2πf).
    """
    return -p.phase / (2 * math.pi * p.f_gw)


def sigma_ascending_node_s(p: PhaseParams, cov: FloatArray) -> float:
    """1σ of T_asc from the reference-phase variance, σ_φ/(2πf) [s].

    ``cov`` is the (7, 7) covariance in :data:`~ucbplan.core.params.PARAM_NAMES` order.
    """
    jac_scale = 1.0 / (math.pi * p.f_gw)
    return 0.5 * math.sqrt(cov[0, 0]) * jac_scale


def ll_pair(p: PhaseParams, tau_s: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Laplace–Lagrange pair (η(τ), κ(τ)) rotated rigidly at ω̇ (Eq. kappa_lisa_prediction)."""
    w = p.omega_dot * np.asarray(tau_s, dtype=np.float64)
    c, s = np.cos(w), np.sin(w)
    return p.eta * c + p.kappa * s, p.kappa * c - p.eta * s


def u_state(
    p: PhaseParams, dt_s: ArrayLike, origin_s: float = 0.0, star: int = 1
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """u/2π split as (integer m, remainder g = O(1)) and du/dt, from one phase evaluation.

    Parameters
    ----------
    p : PhaseParams
        Phase model at the reference epoch.
    dt_s : array_like
        Seconds after ``origin_s`` [s].
    origin_s : float
        Time origin, seconds since the reference epoch [s].
    star : {1, 2}
        Component (ε_1 = 0, ε_2 = π).

    Returns
    -------
    m, g, rate : ndarray
        u = 2π(m + g) [rad] with m integer-valued, and du/dt [rad/s].
    """
    n, f = _gw_cycles(p, dt_s, origin_s)
    half = np.floor(n / 2.0)  # exact: n is an integer-valued float < 2**53
    frac_orbit = (n - 2.0 * half + f) / 2.0  # Φ_asc/2π − half ∈ [0, 1)
    tau = origin_s + np.asarray(dt_s, dtype=np.float64)
    rate_a = math.pi * (p.f_gw + p.fdot * tau + p.fddot * tau * tau / 2.0)
    if p.eta == 0.0 and p.kappa == 0.0 and p.omega_dot == 0.0:
        # circular, no apsidal motion: η(τ) = κ(τ) = ±0, so δ and the rate's second term are
        # ±0 and add nothing (the same bits as below; tests compare)
        return half, frac_orbit + _star_offset(star) / TWO_PI, rate_a
    phi_a = TWO_PI * frac_orbit  # Φ_asc mod 2π
    w = p.omega_dot * tau
    cw, sw = np.cos(w), np.sin(w)
    eta = p.eta * cw + p.kappa * sw
    kap = p.kappa * cw - p.eta * sw
    s, c = np.sin(phi_a), np.cos(phi_a)
    delta = 2.0 * kap * s - 2.0 * eta * c
    rate = rate_a + 2.0 * (rate_a - p.omega_dot) * (kap * c + eta * s)
    return half, frac_orbit + (_star_offset(star) + delta) / TWO_PI, rate


def orbit_state(p: PhaseParams, tau_s: ArrayLike) -> tuple[FloatArray, ...]:
    """(Φ_asc, η, κ, u of star 1) at ``tau_s`` from one phase evaluation [rad, 1, 1, rad].

    Bit-identical to :func:`phase_asc`, :func:`ll_pair` and :func:`arg_latitude` (star 1) called
    separately, at the cost of one of them.
    """
    tau = np.asarray(tau_s, dtype=np.float64)
    n, f = _gw_cycles(p, tau)
    phi = 0.5 * (TWO_PI * (n + f))
    half = np.floor(n / 2.0)
    frac_orbit = (n - 2.0 * half + f) / 2.0
    phi_a = TWO_PI * frac_orbit
    w = p.omega_dot * tau
    cw, sw = np.cos(w), np.sin(w)
    eta = p.eta * cw + p.kappa * sw
    kap = p.kappa * cw - p.eta * sw
    delta = 2.0 * kap * np.sin(phi_a) - 2.0 * eta * np.cos(phi_a)
    u = TWO_PI * (half + (frac_orbit + delta / TWO_PI))
    return phi, eta, kap, u


def u_cycles(
    p: PhaseParams, dt_s: ArrayLike, origin_s: float = 0.0, star: int = 1
) -> tuple[FloatArray, FloatArray]:
    """u/2π split as (integer m, remainder g) with g of order unity, for exact bookkeeping.

    Same arguments as :func:`u_state`; u = 2π(m + g) [rad].
    """
    m, g, _ = u_state(p, dt_s, origin_s, star)
    return m, g


def arg_latitude(
    p: PhaseParams, tau_s: ArrayLike, star: int = 1, origin_s: float = 0.0
) -> FloatArray:
    """Argument of latitude u_j(τ) of star ``star`` [rad], unwrapped, first order in e.

    Parameters
    ----------
    p : PhaseParams
        Phase model at the reference epoch.
    tau_s : array_like
        Seconds since the reference epoch (TDB), or since ``t_ref + origin_s`` if given.
    star : {1, 2}
        Component; ε_1 = 0, ε_2 = π.
    origin_s : float
        Optional offset of the time origin [s] (keeps precision for far epochs).

    Notes
    -----
    Eq. u_precessing_app / Eq. arg_latitude_main with Eq. deltae_main.
    """
    m, g = u_cycles(p, tau_s, origin_s, star)
    return TWO_PI * (m + g)


def arg_latitude_rate(
    p: PhaseParams, tau_s: ArrayLike, star: int = 1, origin_s: float = 0.0
) -> FloatArray:
    """Analytic du/dt [rad/s] of :func:`arg_latitude` (all terms kept).

    Notes
    -----
    du/dt = Φ̇_asc + 2(Φ̇_asc − ω̇)(κ cos Φ_asc + η sin Φ_asc), Φ̇_asc = π(f + ḟτ + f̈τ²/2);
    Eq. sigma_tstar keeps only the leading term.
    """
    _, _, rate = u_state(p, tau_s, origin_s, star)
    return rate


def radial_velocity(
    p: PhaseParams,
    tau_s: ArrayLike,
    k: float,
    gamma: float = 0.0,
    star: int = 1,
) -> FloatArray:
    """Predicted line-of-sight velocity of star ``star`` (units of ``k``; positive = receding).

    Notes
    -----
    Eq. v1v2_ecc_rv / F_definition: v1 = γ1 + K1(cos u + κ), v2 = γ2 − K2(cos u + κ), with u
    star 1's argument of latitude and κ(t) from Eq. kappa_lisa_prediction.
    """
    u1 = arg_latitude(p, tau_s, star=1)
    _, kap = ll_pair(p, tau_s)
    sign = 1.0 if _star_offset(star) == 0.0 else -1.0
    out: FloatArray = gamma + sign * k * (np.cos(u1) + kap)
    return out


def u_jacobian(p: PhaseParams, tau_s: ArrayLike, star: int = 1) -> FloatArray:
    """Analytic ∂u/∂(φ_ref, f, ḟ, f̈, η_ref, κ_ref, ω̇) at ``tau_s`` → shape (..., 7).

    Notes
    -----
    Differentiates Eq. arg_latitude_main with Eq. deltae_main and Eq. kappa_lisa_prediction;
    used for σ_u² = J C Jᵀ (Sec. 4.1, Eq. sigma_u_from_PhiGW without dropping cross terms).
    """
    _star_offset(star)
    tau = np.asarray(tau_s, dtype=np.float64)
    n, f = _gw_cycles(p, tau)
    phi_a = math.pi * ((n - 2.0 * np.floor(n / 2.0)) + f)
    return jacobian_kernel(p.eta, p.kappa, p.omega_dot, tau, np.sin(phi_a), np.cos(phi_a))


def _times(jac: FloatArray, cov: FloatArray) -> FloatArray:
    """``jac @ cov`` for Jacobians (..., 7) through :func:`~ucbplan.core.mvnormal.rows_times`:
    in row blocks each small enough for OpenBLAS's calling thread (a product of more than 2¹⁹
    multiply-adds goes to a second thread, which then spins on, ~10 ms of CPU per product on a
    busy machine; a semester: ~0.1 s), each row the same double as in one product."""
    rows = np.reshape(jac, (-1, np.shape(jac)[-1]))
    out = rows_times(rows, np.asarray(cov, dtype=np.float64))
    return out.reshape((*np.shape(jac)[:-1], out.shape[-1]))


def sigma_u_from_jacobian(jac: FloatArray, cov: FloatArray) -> FloatArray:
    """σ_u = √(J C Jᵀ) for a stack of Jacobians ``jac`` (..., 7) [rad]."""
    var = np.sum(_times(jac, cov) * jac, axis=-1)
    out: FloatArray = np.sqrt(np.maximum(var, 0.0))
    return out


def jacobian_kernel(
    eta0: FloatArray | float,
    kap0: FloatArray | float,
    wdot: FloatArray | float,
    tau: FloatArray,
    s: FloatArray,
    c: FloatArray,
    cos_sin_w: tuple[FloatArray, FloatArray] | None = None,
) -> FloatArray:
    """∂u/∂(φ, f, ḟ, f̈, η_ref, κ_ref, ω̇) from (η_ref, κ_ref, ω̇), τ and sin/cos Φ_asc.

    Broadcasts: parameters may be arrays shaped like ``tau`` (batches of targets).
    ``cos_sin_w``: cos and sin of ω̇τ if the caller has them already.
    """
    if cos_sin_w is None:
        w = wdot * tau
        cw, sw = np.cos(w), np.sin(w)
    else:
        cw, sw = cos_sin_w
    eta = eta0 * cw + kap0 * sw
    kap = kap0 * cw - eta0 * sw
    d = 1.0 + 2.0 * kap * c + 2.0 * eta * s  # ∂u/∂Φ_asc
    jac = np.empty((*np.shape(tau), len(PARAM_NAMES)), dtype=np.float64)
    jac[..., 0] = 0.5 * d
    jac[..., 1] = math.pi * tau * d
    jac[..., 2] = math.pi * tau**2 / 2.0 * d
    jac[..., 3] = math.pi * tau**3 / 6.0 * d
    jac[..., 4] = -2.0 * sw * s - 2.0 * cw * c
    jac[..., 5] = 2.0 * cw * s - 2.0 * sw * c
    jac[..., 6] = -2.0 * tau * (eta * s + kap * c)
    return jac
