"""The t★ inversion: epochs where the argument of latitude reaches u★, with σ_t and the π-mode.

Vectorised Newton on the phase model of :mod:`ucbplan.core.phase` (paper Appendix A2,
Eq. u_precessing_app), seeded from the mean phase; times are float64 seconds since the target's
reference epoch (TDB at the barycentre), split as ``origin_s + dt_s`` for full precision. The
phase-model functions are re-exported here for callers that know them from this module.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from ucbplan.core.constants import TWO_PI
from ucbplan.core.params import PARAM_NAMES, EphemerisSource, PhaseParams
from ucbplan.core.phase import (
    arg_latitude as arg_latitude,
)
from ucbplan.core.phase import (
    arg_latitude_rate,
    ll_pair,
    sigma_u_from_jacobian,
    u_cycles,
    u_jacobian,
    u_state,
)
from ucbplan.core.phase import (
    gw_phase as gw_phase,
)
from ucbplan.core.phase import (
    jacobian_kernel as jacobian_kernel,
)
from ucbplan.core.phase import (
    phase_asc as phase_asc,
)
from ucbplan.core.phase import (
    radial_velocity as radial_velocity,
)
from ucbplan.errors import ConvergenceError, UcbplanError, shorten

FloatArray = NDArray[np.float64]

#: Named anchors → the u★ values they stand for [rad]; "zero-crossing" is solved from cos u₁ = −κ(t)
#: (for star 2, in its own u₂ = u₁ + π: cos u₂ = +κ, the same instants).
#: "eclipse" is the conjunctions labelled by which star is behind: star 1 (the star eclipsed at
#: primary eclipse) at u₁ = π/2 is the primary eclipse, u₁ = 3π/2 the secondary.
ANCHORS: dict[str, tuple[float, ...]] = {
    "quadrature": (0.0, math.pi),
    "conjunction": (math.pi / 2, 3 * math.pi / 2),
    "zero-crossing": (math.pi / 2, 3 * math.pi / 2),
    "eclipse": (math.pi / 2, 3 * math.pi / 2),
}


def eclipse_kind(u_star_rad: FloatArray, star: int = 1) -> list[str]:
    """``"primary"`` or ``"secondary"`` for conjunction epochs of ``star`` with u★ = π/2, 3π/2.

    Primary: star 1 behind (u₁ = π/2, i.e. u₂ = 3π/2); secondary: star 2 behind.
    """
    u1 = np.mod(np.asarray(u_star_rad, dtype=np.float64) - (0.0 if star == 1 else math.pi), TWO_PI)
    return ["primary" if abs(x - math.pi / 2) < 1.0 else "secondary" for x in np.atleast_1d(u1)]


def _zero_crossing_target(
    p: PhaseParams, tau: FloatArray, branch: FloatArray, star: int = 1
) -> tuple[FloatArray, FloatArray]:
    """u★(τ) and du★/dτ of the RV zero crossing of ``star``, in that star's own u.

    Both velocities vanish (relative to γ_j) where cos u₁ = −κ(τ) (Eq. v1v2_ecc_rv: v₂ = γ₂ −
    K₂(cos u₁ + κ)), so star 2's zero crossings are star 1's instants: in u₂ = u₁ + π that is
    cos u₂ = +κ. Branch 0: u_j ≈ π/2 ± κ (star 1: +, star 2: −); branch 1: 3π/2 ∓ κ.
    """
    sign = 1.0 if star == 1 else -1.0
    eta, kap = ll_pair(p, tau)
    base = np.arccos(np.clip(-sign * kap, -1.0, 1.0))
    dkap = -p.omega_dot * eta
    dbase = sign * dkap / np.sqrt(1.0 - kap * kap)
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
            ustar, dustar = _zero_crossing_target(p, origin_s + dt, zero_branch, star)
        else:
            dustar = np.zeros_like(dt)
        m, g, rate = u_state(p, dt, origin_s, star)
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
        ustar, _ = _zero_crossing_target(p, origin_s + dt, zero_branch, star)
    return dt, np.broadcast_to(ustar, dt.shape).astype(np.float64)


def _mean_seeds(p: PhaseParams, origin_s: float, target_cycles: FloatArray) -> FloatArray:
    """Seed offsets from the mean phase: Newton on the polynomial Φ_asc(origin+dt)/2π = target.

    ``target_cycles`` are orbit cycles counted from the origin's own mean phase.
    """
    # orbit frequency and derivatives at the origin
    nu0 = 0.5 * (p.f_gw + p.fdot * origin_s + p.fddot * origin_s**2 / 2)
    nu1 = 0.5 * (p.fdot + p.fddot * origin_s)
    nu2 = 0.5 * p.fddot
    cycles = np.asarray(target_cycles, dtype=np.float64).ravel()
    dt = cycles / nu0
    live = None  # every offset; then those a step still moved
    for _ in range(8):  # elementwise: an offset that a step leaves unchanged, bit for bit, ...
        d, c = (dt, cycles) if live is None else (dt[live], cycles[live])
        val = nu0 * d + nu1 * d**2 / 2 + nu2 * d**3 / 6 - c
        der = nu0 + nu1 * d + nu2 * d**2 / 2
        step = d - val / der
        moved = step.view(np.int64) != d.view(np.int64)  # ... every later step leaves so
        if live is None:
            dt, live = step, np.flatnonzero(moved)
        else:
            dt[live] = step
            live = live[moved]
    return dt.reshape(np.shape(target_cycles))


def solve_u(
    p: PhaseParams,
    tau_start_s: float,
    tau_end_s: float,
    u_star: float | str,
    star: int = 1,
    windows: FloatArray | None = None,
) -> tuple[NDArray[np.int64], FloatArray, FloatArray, float]:
    """All epochs in [start, end] (seconds from t_ref) where u(τ) = u★ (mod 2π).

    Parameters
    ----------
    p : PhaseParams
        Phase model.
    tau_start_s, tau_end_s : float
        Window (TDB seconds since the reference epoch).
    u_star : float or "zero-crossing+" / "zero-crossing-"
        Target argument of latitude [rad] or one branch of the RV zero crossing cos u₁ = −κ(t)
        (star 2: cos u₂ = +κ(t), the same instants; u★ is returned in ``star``'s u).
    star : {1, 2}
        Whose argument of latitude.
    windows : ndarray, shape (m, 2), optional
        Only epochs inside these sub-windows of [start, end] (TDB s since the reference,
        sorted, disjoint): the orbits between them are never solved (a plan's nights). The
        origin stays ``tau_start_s`` and each epoch gets the value the whole window would
        give it, up to the rounding of Newton's last step (≤ 2 ulp of dt; tests compare).

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
    zero_branch, ustar_nominal = _nominal_target(u_star)
    rel = None if windows is None else _relative_windows(windows, origin, span)
    ks, c0 = _passages(p, origin, span, ustar_nominal, star, rel)
    # mean-phase seeds: orbit cycles from the origin's u
    seeds = _mean_seeds(p, origin, ks - c0)
    branch = None if zero_branch is None else np.full(ks.shape, zero_branch, dtype=np.float64)
    dt, ustar_arr = _newton(p, origin, seeds, ks, np.full(ks.shape, ustar_nominal), star, branch)
    keep = (dt >= 0.0) & (dt <= span)
    if rel is not None:
        j = np.searchsorted(rel[:, 0], dt, side="right") - 1
        keep &= (j >= 0) & (dt <= rel[np.maximum(j, 0), 1])
    return ks[keep].astype(np.int64), dt[keep], ustar_arr[keep], origin


def _relative_windows(windows: FloatArray, origin: float, span: float) -> FloatArray:
    """Sub-windows as offsets from ``origin``, clipped to [0, span], sorted, empty ones
    dropped (m, 2)."""
    w = np.asarray(windows, dtype=np.float64).reshape(-1, 2) - origin
    w = np.clip(w, 0.0, span)
    w = w[w[:, 1] > w[:, 0]]
    return np.asarray(w[np.argsort(w[:, 0], kind="stable")], dtype=np.float64)


def _nominal_target(u_star: float | str) -> tuple[int | None, float]:
    """(zero-crossing branch or None, u★ in [0, 2π) [rad]) for a :func:`solve_u` target."""
    if isinstance(u_star, str):
        zero_branch = {"zero-crossing+": 0, "zero-crossing-": 1}[u_star]
        return zero_branch, math.pi / 2 if zero_branch == 0 else 3 * math.pi / 2
    return None, float(u_star) % TWO_PI


def _passages(
    p: PhaseParams,
    origin: float,
    span: float,
    ustar: float,
    star: int,
    rel: FloatArray | None = None,
) -> tuple[FloatArray, float]:
    """Candidate orbit counts k (one spare at each end) and (u/2π − u★/2π) at the window start;
    with ``rel`` (sub-windows, offsets from the origin), only the counts of those.

    First order in e is enough to count passages; Newton refines the edges.
    """
    edges = np.array([span]) if rel is None else rel.ravel()
    m0, g0 = u_cycles(p, np.concatenate([[0.0], edges]), origin, star)
    c = (m0 + g0) - ustar / TWO_PI
    c0 = float(c[0])
    if rel is None:
        return np.arange(math.ceil(c0) - 1, math.floor(c[1]) + 2, dtype=np.float64), c0
    lo = np.ceil(c[1::2]).astype(np.int64) - 1
    hi = np.floor(c[2::2]).astype(np.int64) + 1
    if lo.size == 0:
        return np.zeros(0), c0
    return integer_union(lo, hi).astype(np.float64), c0


def integer_union(lo: NDArray[np.int64], hi: NDArray[np.int64]) -> NDArray[np.int64]:
    """Every integer of the ranges [lo_i, hi_i] (inclusive) once, ascending: ``np.unique`` of
    their concatenation without its sort (the ranges sorted by ``lo`` give new values above
    all earlier ones: each range keeps those beyond the largest end before it)."""
    order = np.argsort(lo, kind="stable")
    lo, hi = lo[order], hi[order]
    top = np.maximum.accumulate(hi)
    first = np.maximum(lo, np.concatenate([lo[:1], top[:-1] + 1]))
    count = np.maximum(hi - first + 1, 0)
    start = np.repeat(first - np.concatenate([[0], np.cumsum(count)[:-1]]), count)
    return np.asarray(start + np.arange(int(count.sum()), dtype=np.int64), dtype=np.int64)


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
    if text in ("quadrature", "conjunction", "eclipse"):
        return text, list(ANCHORS[text])
    if text == "eclipses":
        return "eclipse", list(ANCHORS["eclipse"])
    if text in ("zero-crossing", "zero_crossing", "zerocrossing"):
        return "zero-crossing", ["zero-crossing+", "zero-crossing-"]
    if text.startswith("u="):
        text = text[2:]
    try:
        value = float(text)
    except ValueError:
        raise UcbplanError(
            f"unknown anchor {shorten(anchor, 60)}: expected quadrature, conjunction, eclipse, "
            "zero-crossing or a number u★ in radians (e.g. 0.7854)"
        ) from None
    if not math.isfinite(value):
        raise UcbplanError(f"anchor u★ must be finite, got {shorten(anchor, 60)}")
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
    source: EphemerisSource,
    tau_start_s: float,
    tau_end_s: float,
    anchor: str | float,
    star: int = 1,
    pi_mode: bool | None = None,
    details: bool = True,
    windows: FloatArray | None = None,
) -> EpochSet:
    """All anchor epochs of a target in a window, with σ_t and the φ_ref π-mode alternative.

    Parameters
    ----------
    source : EphemerisSource
        A loaded target (parameters at its reference epoch, and their covariance).
    tau_start_s, tau_end_s : float
        Window in TDB seconds since the target's reference epoch ``t_ref``.
    anchor : str or float
        ``quadrature`` (u★ = 0, π), ``conjunction`` or ``eclipse`` (π/2, 3π/2),
        ``zero-crossing`` (v_j = γ_j: cos u₁ = −κ), or a numeric u★ [rad].
    star : {1, 2}
        Component whose argument of latitude is targeted.
    pi_mode : bool, optional
        Solve the φ_ref + π alternative. Default: the source's ``has_pi_mode`` (True when it
        has none: a LISA posterior's GW phase has the second mode, a timing ephemeris not);
        without it ``tau_alt_s`` is NaN.
    details : bool
        Compute σ_t, σ_u, u̇ and the π-mode alternative of every epoch. False leaves them NaN,
        for a caller that needs them for a few epochs only (:func:`with_details`).
    windows : ndarray, shape (m, 2), optional
        Only the epochs inside these sorted, disjoint sub-windows (:func:`solve_u`).

    Returns
    -------
    EpochSet

    Notes
    -----
    σ_t = σ_u(t★)/|u̇(t★)| (Eq. sigma_tstar, all terms of u̇ kept). The alternative epoch solves the
    same u★ with φ_ref + π (Appendix A1: the GW phase posterior's second mode), ≈ P_b/4 earlier.
    """
    label, targets = resolve_anchor(anchor)
    k, dt, us, origin = _solve_sorted(source.params, tau_start_s, tau_end_s, targets, star, windows)
    es = EpochSet(
        anchor=label,
        star=star,
        u_star_rad=us,
        k=k,
        origin_s=origin,
        dt_s=dt,
        sigma_t_s=np.full(dt.shape, np.nan),
        sigma_u_rad=np.full(dt.shape, np.nan),
        tau_alt_s=np.full(dt.shape, np.nan),
        u_rate=np.full(dt.shape, np.nan),
    )
    return with_details(source, es, pi_mode=pi_mode) if details else es


def with_details(
    source: EphemerisSource,
    es: EpochSet,
    idx: NDArray[np.int64] | None = None,
    pi_mode: bool | None = None,
) -> EpochSet:
    """``es`` with σ_t, σ_u, u̇ and the π-mode alternative computed at the epochs ``idx`` (all
    by default); the other epochs keep the values they had.

    Every quantity is computed epoch by epoch, so a subset gets the values the whole set would
    (tests compare them bit for bit). Arguments as :func:`find_epochs`.
    """
    p = source.params
    sel = np.arange(len(es)) if idx is None else np.asarray(idx, dtype=np.int64)
    dt, us, origin = es.dt_s[sel], es.u_star_rad[sel], es.origin_s
    rate = arg_latitude_rate(p, dt, es.star, origin)
    sig_u = sigma_u_from_jacobian(u_jacobian(p, origin + dt, es.star), source.covariance)
    if pi_mode is None:
        pi_mode = bool(getattr(source, "has_pi_mode", True))
    if pi_mode:
        zero = es.anchor == "zero-crossing"
        tau_alt = origin + _pi_mode_offsets(p, origin, dt, us, rate, es.star, zero_crossing=zero)
    else:
        tau_alt = np.full(dt.shape, np.nan)
    values = {"sigma_t_s": sig_u / np.abs(rate), "sigma_u_rad": sig_u, "tau_alt_s": tau_alt}
    out = {name: getattr(es, name).copy() for name in (*values, "u_rate")}
    for name, v in (*values.items(), ("u_rate", rate)):
        out[name][sel] = v
    return replace(es, **out)


def _solve_sorted(
    p: PhaseParams,
    tau_start_s: float,
    tau_end_s: float,
    targets: list[float | str],
    star: int,
    windows: FloatArray | None = None,
) -> tuple[NDArray[np.int64], FloatArray, FloatArray, float]:
    """:func:`solve_u` for every u★ of an anchor, merged in time order: (k, dt, u★, origin)."""
    parts: list[tuple[NDArray[np.int64], FloatArray, FloatArray]] = []
    origin = float(tau_start_s)
    for tgt in targets:
        k, dt, us, origin = solve_u(p, tau_start_s, tau_end_s, tgt, star, windows)
        parts.append((k, dt, us))
    k = np.concatenate([x[0] for x in parts]) if parts else np.zeros(0, np.int64)
    dt = np.concatenate([x[1] for x in parts]) if parts else np.zeros(0)
    us = np.concatenate([x[2] for x in parts]) if parts else np.zeros(0)
    order = np.argsort(dt, kind="stable")
    return k[order], dt[order], us[order], origin


def _pi_mode_offsets(
    p: PhaseParams,
    origin: float,
    dt: FloatArray,
    us: FloatArray,
    rate: FloatArray,
    star: int,
    zero_crossing: bool,
) -> FloatArray:
    """Offsets of the same u★ under φ_ref + π, seeded a quarter orbit earlier (Appendix A1)."""
    if not dt.size:
        return np.zeros(0)
    p_alt = PhaseParams(**{n: getattr(p, n) for n in PARAM_NAMES} | {"phase": p.phase + math.pi})
    quarter = 0.25 * TWO_PI / rate
    m_alt, g_alt = u_cycles(p_alt, dt - quarter, origin, star)
    target_m = np.rint((m_alt + g_alt) - us / TWO_PI)
    branch = np.where(np.abs(us - math.pi / 2) < 1.0, 0.0, 1.0) if zero_crossing else None
    dt_alt, _ = _newton(p_alt, origin, dt - quarter, target_m, us.copy(), star, branch)
    return dt_alt
