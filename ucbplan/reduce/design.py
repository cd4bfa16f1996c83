"""The regression's design variable per spectrum, from the LISA ephemeris (paper Sec. 3.1).

Window factors Λ_K, Λ_κ and lengths Δt of each exposure, the orbit (Φ, η, κ, u) at mid-exposure,
the window-averaged orbital factor G per component (optionally at the emission time, for the
light travel time across the orbit) and its Jacobian ∂G/∂θ for the phase-error propagation.

G is the exposure average of the *exact* Keplerian velocity curve, cos(ω + ν) + e cos ω, with e,
ω and the mean anomaly M = Φ_asc − ω from the phase model (:func:`ucbplan.core.kepler.
window_average`; beyond the paper). The paper's Eq. vbar_master
(:func:`~ucbplan.reduce.regression.binned_design`) is its first order in e; its O(e²) remainder
biased K_j by ≈ −e²K_j (docs/method.md, "Reduction").
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ucbplan.core.constants import C_KM_S
from ucbplan.core.kepler import (
    Term,
    WindowedVelocity,
    row_chunks,
    series_terms,
    window_average,
    window_rotation,
)
from ucbplan.core.smearing import lambda_k, lambda_kappa
from ucbplan.reduce.regression import lambda_k_to_x

if TYPE_CHECKING:
    from ucbplan.core.params import PhaseParams
    from ucbplan.reduce.velocities import VelocityTable

#: Below this eccentricity the Jacobian uses Eq. vbar_master's (exact at e = 0; the O(e²)
#: remainder is < 1e-16) instead of dividing ∂G/∂ω by e.
_E_FIRST_ORDER = 1e-8

F64 = NDArray[np.float64]


def window_factors(table: VelocityTable, f_hz: float) -> tuple[F64, F64]:
    """Λ_K and Λ_κ per spectrum from the window widths (or the given Λ_K).

    Raises
    ------
    VelocityFileError
        A window as long as the orbital period P_b = 2π/n̄_b or longer (Λ_K ≤ 0).

    Notes
    -----
    Eqs. Lambda_K, Lambda_kappa with n̄_b = π f. Where only Λ_K is known, x = n̄_b Δt/2 is
    recovered by inverting sin x/x and Λ_κ = sin 2x/2x.
    """
    nbar = math.pi * f_hz
    w = np.asarray(table.window_s, dtype=np.float64)
    _check_windows(table, 2.0 * math.pi / nbar)
    lk, lkap = np.empty(w.shape), np.empty(w.shape)
    for sl in row_chunks(w.size):  # elementwise: chunk by chunk, the same doubles
        width = np.nan_to_num(w[sl])
        lk[sl], lkap[sl] = lambda_k(width, nbar), lambda_kappa(width, nbar)
    given = ~np.isfinite(w)
    if np.any(given):  # Λ_K given: x = n̄_bΔt/2 from it, Λ_κ = sin 2x/2x
        lk[given] = table.lambda_k[given]
        lkap[given] = np.sinc(2.0 * lambda_k_to_x(table.lambda_k[given]) / np.pi)
    return lk, lkap


def _check_windows(table: VelocityTable, period_s: float) -> None:
    """Every window shorter than the orbital period: Λ_K = sin x/x > 0 (x = πΔt/P_b < π).

    A window of one period averages the velocity curve to zero (Λ_K = 0) and a longer one flips
    its sign: K = slope/Λ_K would blow up or change sign (K1 of order −1e7 km/s).
    """
    from ucbplan.errors import VelocityFileError

    w = table.window_s
    bad = np.flatnonzero(np.isfinite(w) & (w >= period_s))
    if bad.size:
        i = int(bad[0])
        raise VelocityFileError(
            f"{table.source}: row {i + 1}, column {table.window_column!r}: got {w[i]:.6g} s, "
            f"expected a window shorter than the orbital period P_b = {period_s:.6g} s (Λ_K = "
            f"sin x/x ≤ 0 there: the exposure averages the orbit away); split the exposure or "
            "give shorter co-add windows"
        )


def window_durations(table: VelocityTable, f_hz: float) -> F64:
    """Window length Δt per spectrum [s]: the given width, or 2x/n̄_b with sin x/x = Λ_K.

    Raises
    ------
    VelocityFileError
        A window as long as the orbital period or longer (:func:`window_factors`).
    """
    nbar = math.pi * f_hz
    w = table.window_s
    _check_windows(table, 2.0 * math.pi / nbar)
    given = ~np.isfinite(w)
    out = np.nan_to_num(w)  # a copy; the given rows are replaced below
    if np.any(given):
        out[given] = 2.0 * lambda_k_to_x(table.lambda_k[given]) / nbar
    return np.asarray(out, dtype=np.float64)


def orbit(p: PhaseParams, tau: F64) -> tuple[F64, F64, F64, F64]:
    """(Φ_asc, η, κ, u of star 1) at ``tau`` [s since t_ref]."""
    from ucbplan.core.phase import orbit_state

    phi, eta, kap, u = orbit_state(p, tau)
    return phi, eta, kap, u


@dataclass(frozen=True)
class OrbitTrack:
    """The orbit at the mid-exposure times, evaluated once and shared by every design there.

    Attributes
    ----------
    phase, phase_mod : ndarray
        Φ_asc [rad], unwrapped and modulo 2π (:func:`ucbplan.core.phase.phase_asc_mod`).
    eta, kap : ndarray
        (η, κ) rotated to the times [1].
    u : ndarray
        Star 1's argument of latitude [rad] (unwrapped).
    cos_u, sin_u : ndarray
        Its cosine and sine (the light-time designs, F and the fixed-u groups use them).
    cos_w, sin_w : ndarray
        Cosine and sine of the apsidal turn ω̇τ since t_ref (the Jacobians use them).
    """

    phase: F64
    phase_mod: F64
    eta: F64
    kap: F64
    u: F64
    cos_u: F64
    sin_u: F64
    cos_w: F64
    sin_w: F64


def track(p: PhaseParams, tau: F64) -> OrbitTrack:
    """The orbit at ``tau``, bit-identical to :func:`orbit` and ``phase_asc_mod`` there."""
    from ucbplan.core.phase import orbit_state, phase_asc_mod

    tau = np.asarray(tau, dtype=np.float64)
    at = OrbitTrack(*(np.empty(tau.shape) for _ in range(9)))
    cols = (tau, at.phase, at.phase_mod, at.eta, at.kap, at.u, at.cos_u, at.sin_u, at.cos_w)
    flat = [x.reshape(-1) for x in (*cols, at.sin_w)]
    for sl in row_chunks(tau.size):  # elementwise: chunk by chunk, the same doubles
        t = flat[0][sl]
        phi, eta, kap, u = orbit_state(p, t)
        w = p.omega_dot * t
        trig = (np.cos(u), np.sin(u), np.cos(w), np.sin(w))
        orbit_rows = (phi, phase_asc_mod(p, t), eta, kap, u, *trig)
        for out, x in zip(flat[1:], orbit_rows, strict=True):
            out[sl] = x
    return at


#: cos and sin of ω̇Δt/2 per window (:func:`ucbplan.core.kepler.window_rotation`).
Rotation = tuple[F64, F64]


def _windowed_rows(
    p: PhaseParams,
    tau: F64,
    window_s: F64,
    derivatives: bool,
    at: tuple[F64, ...] | None,
    rotation: Rotation | None,
    terms: list[Term],
) -> tuple[WindowedVelocity, F64]:
    """The exact window average at ``tau`` and ω there (``at``: Φ_asc mod 2π, η and κ at
    ``tau`` when the caller has them; ``rotation``: the windows' :data:`Rotation`; ``terms``:
    the series of the eccentricity, :func:`~ucbplan.core.kepler.series_terms`), for one chunk
    of rows."""
    from ucbplan.core.phase import ll_pair, phase_asc_mod

    if at is None:
        phi = phase_asc_mod(p, tau)
        eta, kap = ll_pair(p, tau)
    else:  # orbit_state's (η, κ) are ll_pair's bit for bit
        phi, eta, kap = at
    om = np.arctan2(eta, kap)
    nb = math.pi * (p.f_gw + p.fdot * tau + p.fddot * tau**2 / 2.0) - p.omega_dot
    e, wdot = p.eccentricity, p.omega_dot
    return window_average(phi, om, e, nb, wdot, window_s, derivatives, rotation, terms), om


def _windowed(
    p: PhaseParams,
    tau: F64,
    window_s: F64,
    derivatives: bool = True,
    at: OrbitTrack | None = None,
    rotation: Rotation | None = None,
) -> tuple[WindowedVelocity, F64]:
    """The exact window average at ``tau`` and ω there (the orbit from ``at``, the windows'
    rotation from ``rotation`` when given), chunk by chunk
    (:func:`~ucbplan.core.kepler.row_chunks`: temporaries in cache)."""
    tau = np.asarray(tau, dtype=np.float64)
    shape = np.broadcast_shapes(tau.shape, np.shape(window_s))
    t, w = (np.broadcast_to(x, shape).reshape(-1) for x in (tau, window_s))
    orbit_rows = None if at is None else [x.reshape(-1) for x in (at.phase_mod, at.eta, at.kap)]
    turn = None if rotation is None else [np.broadcast_to(x, shape).reshape(-1) for x in rotation]
    out = np.zeros((5, t.size))  # ⟨h⟩, its three partials (zero without derivatives), ω
    terms = series_terms(p.eccentricity, derivatives)  # once for every chunk
    for sl in row_chunks(t.size):
        rows = None if orbit_rows is None else tuple(x[sl] for x in orbit_rows)
        rot = None if turn is None else (turn[0][sl], turn[1][sl])
        wv, om = _windowed_rows(p, t[sl], w[sl], derivatives, rows, rot, terms)
        out[0, sl], out[4, sl] = wv.h, om
        if derivatives:
            out[1, sl], out[2, sl], out[3, sl] = wv.d_phase, wv.d_omega, wv.d_e
    wv = WindowedVelocity(*(np.asarray(x.reshape(shape)) for x in out[:4]))
    return wv, out[4].reshape(shape)


def mid_exposure(
    p: PhaseParams, tau: F64, window_s: F64, at: OrbitTrack, rotation: Rotation | None = None
) -> tuple[WindowedVelocity, F64]:
    """The window average at mid-exposure and ω there, with the partial derivatives when
    :func:`design_jacobian` uses them: one pass for the plain design (its ``h``, the same with
    or without derivatives) and the Jacobian (``rotation``: the windows' :data:`Rotation`)."""
    return _windowed(p, tau, window_s, p.eccentricity >= _E_FIRST_ORDER, at, rotation)


def design_jacobian(
    p: PhaseParams,
    tau: F64,
    window_s: F64,
    at: OrbitTrack | None = None,
    mid: tuple[WindowedVelocity, F64] | None = None,
) -> F64:
    """∂G_i/∂θ for θ in PARAM_NAMES order, shape (n, 7), at fixed windows.

    ``at``, ``mid``: the orbit at ``tau`` (:func:`track`) and :func:`mid_exposure` if the caller
    has them already.

    Notes
    -----
    Φ = φ_ref/2 + π(fτ + ḟτ²/2 + f̈τ³/6); (η, κ)(τ) rotated at ω̇ (Eq. kappa_lisa_prediction);
    ∂G/∂(Φ, ω, e) of :func:`ucbplan.core.kepler.window_average`, with ∂e/∂η = sin ω,
    ∂ω/∂η = cos ω/e, ∂e/∂κ = cos ω, ∂ω/∂κ = −sin ω/e. The window rates' own dependence on f
    and ω̇ (a relative 1e-5 of Λ) is not differentiated.
    """
    at = track(p, tau) if at is None else at
    rows: Callable[..., None] = _first_order_rows
    args: tuple[F64, ...] = (np.asarray(window_s, float), at.phase, at.eta, at.kap)
    if p.eccentricity >= _E_FIRST_ORDER:
        wv, om = _windowed(p, tau, window_s, at=at) if mid is None else mid
        rows, args = _exact_rows, (wv.d_phase, wv.d_omega, wv.d_e, om, at.eta, at.kap)
    args = (*args, at.cos_w, at.sin_w)
    t = np.reshape(tau, -1)
    flat = [np.broadcast_to(x, np.shape(tau)).reshape(-1) for x in args]
    jac = np.empty((t.size, 7))
    for sl in row_chunks(t.size):  # elementwise: chunk by chunk, the same doubles
        rows(p, t[sl], *(x[sl] for x in flat), jac[sl])
    return jac


def _exact_rows(
    p: PhaseParams,
    tau: F64,
    d_phase: F64,
    d_omega: F64,
    d_e: F64,
    om: F64,
    eta: F64,
    kap: F64,
    cos_w: F64,
    sin_w: F64,
    out: F64,
) -> None:
    """∂G/∂θ of the exact design into ``out`` from its partials ∂⟨h⟩/∂(Φ, ω, e) at ω (``cos_w``,
    ``sin_w``: of ω̇τ)."""
    e = p.eccentricity
    so, co = np.sin(om), np.cos(om)
    dG_deta = so * d_e + co / e * d_omega
    dG_dkap = co * d_e - so / e * d_omega
    _chain(p, tau, d_phase, (dG_deta, dG_dkap), (eta, kap, cos_w, sin_w), out)


def _first_order_rows(
    p: PhaseParams,
    tau: F64,
    window_s: F64,
    phi: F64,
    eta: F64,
    kap: F64,
    cos_w: F64,
    sin_w: F64,
    out: F64,
) -> None:
    """∂G/∂θ of Eq. vbar_master (exact at e = 0) into ``out``, with the window rates of the
    exact design: n̄(τ) for the cos Φ term and 2n̄(τ) − ω̇ for the (η, κ) term."""
    nbar = math.pi * (p.f_gw + p.fdot * tau + p.fddot * tau**2 / 2.0)
    half = 0.5 * window_s
    lam_k = np.sinc(nbar * half / math.pi)
    lam_kap = np.sinc((2.0 * nbar - p.omega_dot) * half / math.pi)
    dG_dphi = -lam_k * np.sin(phi) + 2.0 * lam_kap * (
        -kap * np.sin(2 * phi) + eta * np.cos(2 * phi)
    )
    dG_deta, dG_dkap = lam_kap * np.sin(2 * phi), lam_kap * np.cos(2 * phi)
    _chain(p, tau, dG_dphi, (dG_deta, dG_dkap), (eta, kap, cos_w, sin_w), out)


def _chain(
    p: PhaseParams,
    tau: F64,
    dG_dphi: F64,
    dG_dll: tuple[F64, F64],
    orbit: tuple[F64, F64, F64, F64],
    jac: F64,
) -> None:
    """∂G/∂θ (into ``jac``, rows × 7) from ∂G/∂(Φ, η(τ), κ(τ)) (``dG_dll``: the last two) through
    the phase model and the apsidal rotation (``orbit``: η, κ, cos ω̇τ, sin ω̇τ)."""
    dG_deta, dG_dkap = dG_dll
    eta, kap, c, s = orbit
    jac[:, 0] = 0.5 * dG_dphi
    jac[:, 1] = math.pi * tau * dG_dphi
    jac[:, 2] = math.pi * tau**2 / 2.0 * dG_dphi
    jac[:, 3] = math.pi * tau**3 / 6.0 * dG_dphi
    jac[:, 4] = dG_deta * c - dG_dkap * s  # ∂/∂η_ref
    jac[:, 5] = dG_deta * s + dG_dkap * c  # ∂/∂κ_ref
    jac[:, 6] = dG_deta * tau * kap - dG_dkap * tau * eta  # ∂/∂ω̇


def designs(
    p: PhaseParams,
    tau: F64,
    window_s: F64,
    ncomp: int,
    K: tuple[float, ...] | None,
    at: OrbitTrack | None = None,
    rotation: Rotation | None = None,
) -> tuple[F64, ...]:
    """Design G per component; with K given, evaluated at the emission time τ − ΔR_j.

    G is the exact Keplerian velocity factor averaged over each window (module docstring).
    ``at``, ``rotation``: the orbit at ``tau`` (:func:`track`) and the windows'
    :data:`Rotation` if the caller has them already.
    """
    if K is None:  # both stars see the same G at mid-exposure
        return (_windowed(p, tau, window_s, False, at, rotation)[0].h,) * ncomp
    sin_u = np.sin(orbit(p, tau)[3]) if at is None else at.sin_u
    nb = math.pi * p.f_gw - p.omega_dot
    rot = rotation or window_rotation(p.omega_dot, window_s)
    shape = np.shape(tau)
    t, w, cc, sc = (np.broadcast_to(x, shape).reshape(-1) for x in (tau, window_s, *rot))
    out = np.empty((ncomp, t.size))
    terms = series_terms(p.eccentricity, False)  # once for every chunk
    flat_sin_u = np.broadcast_to(sin_u, shape).reshape(-1)
    for sl in row_chunks(t.size):  # both stars' emission times from one sin u
        for j in range(ncomp):
            sign = 1.0 if j == 0 else -1.0
            emit = t[sl] - sign * K[j] / (C_KM_S * nb) * flat_sin_u[sl]
            turn = (cc[sl], sc[sl])
            out[j, sl] = _windowed_rows(p, emit, w[sl], False, None, turn, terms)[0].h
    return tuple(np.asarray(h.reshape(shape)) for h in out)
