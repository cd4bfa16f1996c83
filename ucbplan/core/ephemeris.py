"""GW ephemeris → argument of latitude u(t), its rate, predicted velocities and the t★ inversion.

All kernels are pure numpy over float64 seconds ``tau_s`` measured from the target's reference
epoch (TDB at the barycentre). The GW phase is accumulated with a compensated (double-double)
product so that u(t) keeps ~1e-15 cycle precision at any baseline; ``origin_s`` lets callers keep
a far-away window origin separate from a small offset, so epochs are represented exactly enough
for 1e-10 rad round trips.

Conventions (SCIENCE.md "Phase model"): Φ_asc = Φ_GW/2; u_j = Φ_asc + ε_j + 2κ sin Φ_asc −
2η cos Φ_asc with ε_1 = 0, ε_2 = π; (η, κ) rotate at ω̇ (Laplace–Lagrange).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ucbplan.core.constants import TWO_PI
from ucbplan.core.params import PARAM_NAMES, PhaseParams
from ucbplan.errors import ConvergenceError, UcbplanError

if TYPE_CHECKING:
    from ucbplan.target import Target

__all__ = [
    "ANCHORS",
    "EpochSet",
    "arg_latitude",
    "arg_latitude_rate",
    "find_epochs",
    "gw_phase",
    "ll_pair",
    "phase_asc",
    "radial_velocity",
    "resolve_anchor",
    "sigma_u_from_jacobian",
    "solve_u",
    "u_jacobian",
]

FloatArray = NDArray[np.float64]

#: Named anchors → the u★ values they stand for [rad]; "zero-crossing" is solved from cos u = −κ(t).
ANCHORS: dict[str, tuple[float, ...]] = {
    "quadrature": (0.0, math.pi),
    "conjunction": (math.pi / 2, 3 * math.pi / 2),
    "zero-crossing": (math.pi / 2, 3 * math.pi / 2),
}

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


def ll_pair(p: PhaseParams, tau_s: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Laplace–Lagrange pair (η(τ), κ(τ)) rotated rigidly at ω̇ (Eq. kappa_lisa_prediction)."""
    w = p.omega_dot * np.asarray(tau_s, dtype=np.float64)
    c, s = np.cos(w), np.sin(w)
    return p.eta * c + p.kappa * s, p.kappa * c - p.eta * s


def _u_state(
    p: PhaseParams, dt_s: ArrayLike, origin_s: float = 0.0, star: int = 1
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """u/2π split as (integer m, remainder g = O(1)) and du/dt, from one phase evaluation."""
    n, f = _gw_cycles(p, dt_s, origin_s)
    half = np.floor(n / 2.0)  # exact: n is an integer-valued float < 2**53
    frac_orbit = (n - 2.0 * half + f) / 2.0  # Φ_asc/2π − half ∈ [0, 1)
    phi_a = TWO_PI * frac_orbit  # Φ_asc mod 2π
    tau = origin_s + np.asarray(dt_s, dtype=np.float64)
    w = p.omega_dot * tau
    cw, sw = np.cos(w), np.sin(w)
    eta = p.eta * cw + p.kappa * sw
    kap = p.kappa * cw - p.eta * sw
    s, c = np.sin(phi_a), np.cos(phi_a)
    delta = 2.0 * kap * s - 2.0 * eta * c
    rate_a = math.pi * (p.f_gw + p.fdot * tau + p.fddot * tau * tau / 2.0)
    rate = rate_a + 2.0 * (rate_a - p.omega_dot) * (kap * c + eta * s)
    return half, frac_orbit + (_star_offset(star) + delta) / TWO_PI, rate


def _u_cycles(
    p: PhaseParams, dt_s: ArrayLike, origin_s: float = 0.0, star: int = 1
) -> tuple[FloatArray, FloatArray]:
    """u/2π split as (integer m, remainder g) with g of order unity, for exact bookkeeping."""
    m, g, _ = _u_state(p, dt_s, origin_s, star)
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
    m, g = _u_cycles(p, tau_s, origin_s, star)
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
    _, _, rate = _u_state(p, tau_s, origin_s, star)
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
    return _jacobian_at(p, tau, np.sin(phi_a), np.cos(phi_a))


def _jacobian_at(p: PhaseParams, tau: FloatArray, s: FloatArray, c: FloatArray) -> FloatArray:
    """Jacobian given sin/cos of Φ_asc (lets the forecast place Φ_asc at an anchor)."""
    return jacobian_kernel(p.eta, p.kappa, p.omega_dot, tau, s, c)


def sigma_u_from_jacobian(jac: FloatArray, cov: FloatArray) -> FloatArray:
    """σ_u = √(J C Jᵀ) for a stack of Jacobians ``jac`` (..., 7) [rad]."""
    var = np.sum((jac @ cov) * jac, axis=-1)
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


# ---------------------------------------------------------------------------------------------
# Inversion u(t★) = u★
# ---------------------------------------------------------------------------------------------


def _zero_crossing_target(
    p: PhaseParams, tau: FloatArray, branch: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """u★(τ) and du★/dτ for the RV zero crossing cos u = −κ(τ) (branch 0: u≈π/2+κ, 1: 3π/2−κ)."""
    eta, kap = ll_pair(p, tau)
    base = np.arccos(np.clip(-kap, -1.0, 1.0))
    dkap = -p.omega_dot * eta
    dbase = dkap / np.sqrt(1.0 - kap * kap)
    ustar = np.where(branch == 0, base, TWO_PI - base)
    dustar = np.where(branch == 0, dbase, -dbase)
    return ustar, dustar


def _newton(
    p: PhaseParams,
    origin_s: float,
    dt0: FloatArray,
    target_m: FloatArray,
    ustar: FloatArray,
    star: int,
    zero_branch: FloatArray | None = None,
    tol_rad: float = 1e-12,
    max_iter: int = 30,
) -> tuple[FloatArray, FloatArray]:
    """Vectorised Newton on u(origin+dt) = 2π·target_m + u★; returns (dt, final u★)."""
    dt = dt0.astype(np.float64, copy=True)
    resid = np.full_like(dt, np.inf)
    floor = np.full_like(dt, tol_rad)
    for _ in range(max_iter):
        if zero_branch is not None:
            ustar, dustar = _zero_crossing_target(p, origin_s + dt, zero_branch)
        else:
            dustar = np.zeros_like(dt)
        m, g, rate = _u_state(p, dt, origin_s, star)
        resid = TWO_PI * ((m - target_m) + (g - ustar / TWO_PI))
        # the float64 time grid limits |u − u★| to ~u̇·spacing(dt): accept that floor
        floor = tol_rad + 2.0 * np.abs(rate) * np.spacing(np.abs(dt))
        if np.all(np.abs(resid) <= floor):
            break
        dt = dt - resid / (rate - dustar)
    if resid.size and not np.all(np.abs(resid) <= 1e-9 + floor):
        worst = float(np.max(np.abs(resid)))
        raise ConvergenceError(
            f"t★ inversion did not converge (worst |u − u★| = {worst:.3g} rad); "
            "check that e < 0.1 and the frequency model is physical"
        )
    if zero_branch is not None:
        ustar, _ = _zero_crossing_target(p, origin_s + dt, zero_branch)
    return dt, np.broadcast_to(ustar, dt.shape).astype(np.float64)


def _mean_seeds(p: PhaseParams, origin_s: float, target_cycles: FloatArray) -> FloatArray:
    """Seed offsets from the mean phase: Newton on the polynomial Φ_asc(origin+dt)/2π = target.

    ``target_cycles`` are orbit cycles counted from the origin's own mean phase.
    """
    # orbit frequency and derivatives at the origin
    nu0 = 0.5 * (p.f_gw + p.fdot * origin_s + p.fddot * origin_s**2 / 2)
    nu1 = 0.5 * (p.fdot + p.fddot * origin_s)
    nu2 = 0.5 * p.fddot
    dt = target_cycles / nu0
    for _ in range(8):
        val = nu0 * dt + nu1 * dt**2 / 2 + nu2 * dt**3 / 6 - target_cycles
        der = nu0 + nu1 * dt + nu2 * dt**2 / 2
        dt = dt - val / der
    return dt


def solve_u(
    p: PhaseParams,
    tau_start_s: float,
    tau_end_s: float,
    u_star: float | str,
    star: int = 1,
) -> tuple[NDArray[np.int64], FloatArray, FloatArray, float]:
    """All epochs in [start, end] (seconds from t_ref) where u(τ) = u★ (mod 2π).

    Parameters
    ----------
    p : PhaseParams
        Phase model.
    tau_start_s, tau_end_s : float
        Window (TDB seconds since the reference epoch).
    u_star : float or "zero-crossing+" / "zero-crossing-"
        Target argument of latitude [rad] or one branch of the RV zero crossing cos u = −κ(t).
    star : {1, 2}
        Whose argument of latitude.

    Returns
    -------
    k : ndarray of int64
        Orbit count: u(τ★) = 2πk + u★.
    dt_s : ndarray
        Epoch offsets from ``origin_s`` [s].
    u_star_rad : ndarray
        u★ per epoch (constant except for the zero crossing).
    origin_s : float
        The window start; τ★ = origin_s + dt_s.

    Notes
    -----
    Appendix A2, Eq. u_precessing_app: vectorised Newton seeded from the mean phase; converged to
    |u − u★| < 1e-12 rad in exact arithmetic on the model (float64 time grid permitting).
    """
    if not tau_end_s > tau_start_s:
        raise UcbplanError(f"empty time window: end ({tau_end_s} s) must be after start")
    origin = float(tau_start_s)
    span = float(tau_end_s - tau_start_s)
    zero_branch: int | None = None
    if isinstance(u_star, str):
        zero_branch = {"zero-crossing+": 0, "zero-crossing-": 1}[u_star]
        ustar_nominal = math.pi / 2 if zero_branch == 0 else 3 * math.pi / 2
    else:
        ustar_nominal = float(u_star) % TWO_PI
    # u/2π at both ends (first order in e is enough to count passages; refine at the edges)
    m0, g0 = _u_cycles(p, np.array([0.0, span]), origin, star)
    c0 = (m0[0] + g0[0]) - ustar_nominal / TWO_PI
    c1 = (m0[1] + g0[1]) - ustar_nominal / TWO_PI
    k_lo = math.ceil(c0) - 1
    k_hi = math.floor(c1) + 1
    ks = np.arange(k_lo, k_hi + 1, dtype=np.float64)
    # mean-phase seeds: orbit cycles from the origin's u
    seeds = _mean_seeds(p, origin, ks - c0)
    branch = None if zero_branch is None else np.full(ks.shape, zero_branch, dtype=np.float64)
    dt, ustar_arr = _newton(p, origin, seeds, ks, np.full(ks.shape, ustar_nominal), star, branch)
    keep = (dt >= 0.0) & (dt <= span)
    return ks[keep].astype(np.int64), dt[keep], ustar_arr[keep], origin


def resolve_anchor(anchor: str | float) -> tuple[str, list[float | str]]:
    """Anchor name or numeric u★ → (label, list of targets for :func:`solve_u`).

    Raises
    ------
    UcbplanError
        For an unknown anchor name (lists the valid ones).
    """
    if isinstance(anchor, int | float):
        return f"u={float(anchor):.6g}", [float(anchor)]
    text = str(anchor).strip().lower()
    if text in ("quadrature", "conjunction"):
        return text, list(ANCHORS[text])
    if text in ("zero-crossing", "zero_crossing", "zerocrossing"):
        return "zero-crossing", ["zero-crossing+", "zero-crossing-"]
    if text.startswith("u="):
        text = text[2:]
    try:
        value = float(text)
    except ValueError:
        raise UcbplanError(
            f"unknown anchor {anchor!r}: expected quadrature, conjunction, zero-crossing or a "
            "number u★ in radians (e.g. 0.7854)"
        ) from None
    if not math.isfinite(value):
        raise UcbplanError(f"anchor u★ must be finite, got {anchor!r}")
    return f"u={value:.6g}", [value]


@dataclass(frozen=True, slots=True)
class EpochSet:
    """Epochs t★ (barycentric TDB) where u = u★, sorted by time.

    ``tau_s`` is seconds since the target's reference epoch; ``origin_s + dt_s`` is the same epoch
    split for full precision.
    """

    anchor: str
    star: int
    u_star_rad: FloatArray
    k: NDArray[np.int64]
    origin_s: float
    dt_s: FloatArray
    sigma_t_s: FloatArray
    sigma_u_rad: FloatArray
    tau_alt_s: FloatArray
    u_rate: FloatArray

    @property
    def tau_s(self) -> FloatArray:
        """Seconds since the reference epoch (TDB)."""
        return self.origin_s + self.dt_s

    def __len__(self) -> int:
        return int(self.dt_s.size)


def find_epochs(
    target: Target,
    tau_start_s: float,
    tau_end_s: float,
    anchor: str | float,
    star: int = 1,
) -> EpochSet:
    """All anchor epochs of ``target`` in a window, with σ_t and the φ_ref π-mode alternative.

    Parameters
    ----------
    target : Target
        Loaded target (parameters at its reference epoch).
    tau_start_s, tau_end_s : float
        Window in TDB seconds since ``target.t_ref``.
    anchor : str or float
        ``quadrature`` (u★ = 0, π), ``conjunction`` (π/2, 3π/2), ``zero-crossing`` (cos u = −κ),
        or a numeric u★ [rad].
    star : {1, 2}
        Component whose argument of latitude is targeted.

    Returns
    -------
    EpochSet

    Notes
    -----
    σ_t = σ_u(t★)/|u̇(t★)| (Eq. sigma_tstar, all terms of u̇ kept). The alternative epoch solves the
    same u★ with φ_ref + π (Appendix A1: the GW phase posterior's second mode), ≈ P_b/4 earlier.
    """

    label, targets = resolve_anchor(anchor)
    p = target.params
    parts: list[tuple[NDArray[np.int64], FloatArray, FloatArray]] = []
    origin = float(tau_start_s)
    for tgt in targets:
        k, dt, us, origin = solve_u(p, tau_start_s, tau_end_s, tgt, star)
        parts.append((k, dt, us))
    k = np.concatenate([x[0] for x in parts]) if parts else np.zeros(0, np.int64)
    dt = np.concatenate([x[1] for x in parts]) if parts else np.zeros(0)
    us = np.concatenate([x[2] for x in parts]) if parts else np.zeros(0)
    order = np.argsort(dt, kind="stable")
    k, dt, us = k[order], dt[order], us[order]
    tau = origin + dt
    rate = arg_latitude_rate(p, dt, star, origin)
    sig_u = sigma_u_from_jacobian(u_jacobian(p, tau, star), target.covariance)
    sigma_t = sig_u / np.abs(rate)
    # φ_ref π-mode: same u★ with phase + π, seeded a quarter orbit earlier
    p_alt = PhaseParams(**{n: getattr(p, n) for n in PARAM_NAMES} | {"phase": p.phase + math.pi})
    if dt.size:
        quarter = 0.25 * TWO_PI / rate
        m_alt, g_alt = _u_cycles(p_alt, dt - quarter, origin, star)
        target_m = np.rint((m_alt + g_alt) - us / TWO_PI)
        branch = None
        if label == "zero-crossing":
            branch = np.where(np.abs(us - math.pi / 2) < 1.0, 0.0, 1.0)
        dt_alt, _ = _newton(p_alt, origin, dt - quarter, target_m, us.copy(), star, branch)
    else:
        dt_alt = np.zeros(0)
    return EpochSet(
        anchor=label,
        star=star,
        u_star_rad=us,
        k=k,
        origin_s=origin,
        dt_s=dt,
        sigma_t_s=sigma_t,
        sigma_u_rad=sig_u,
        tau_alt_s=origin + dt_alt,
        u_rate=rate,
    )
