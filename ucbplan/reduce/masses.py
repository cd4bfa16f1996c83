"""Masses and derived quantities from K_1, K_2 and the LISA parameters (Secs. 3.1.2–3.1.3, 3.3, 5).

Vectorised over Monte-Carlo samples: every function takes float64 arrays in SI units (velocities
in m/s inside this module, masses in kg) and broadcasts. :func:`derive` evaluates the whole chain
for arrays of samples; :func:`summarize` turns sample arrays into median and 16/84 % percentiles.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ucbplan.core.constants import C_M_S, G_SI, MSUN_KG, RSUN_M

__all__ = [
    "C_M_S",
    "G_SI",
    "MASS_RADIUS_MODELS",
    "MSUN_KG",
    "RSUN_M",
    "Summary",
    "a_total_m",
    "chirp_mass",
    "chirp_mass_from_amplitude",
    "chirp_mass_from_fdot",
    "derive",
    "distance_from_amplitude_m",
    "fdot_gw_only",
    "kepler_total_mass",
    "mass_from_omega_dot",
    "omega_dot_gr",
    "peters_mathews_enhancement",
    "radius_eggleton",
    "radius_nauenberg",
    "redshift_difference_orbital",
    "summarize",
]

# CODATA 2018 / IAU 2015 nominal values (identical to astropy.constants; hard-coded so the core
# imports nothing heavy).

F64 = NDArray[np.float64]


def _f(x: ArrayLike) -> F64:
    return np.asarray(x, dtype=np.float64)


def a_total_m(
    k1_m_s: ArrayLike, k2_m_s: ArrayLike, e: ArrayLike, pb_s: ArrayLike, sin_i: ArrayLike
) -> F64:
    """Semi-major axis of the relative orbit, a = (K1+K2)√(1−e²) P_b / (2π sin ι) [m].

    Notes
    -----
    Eq. semimajor_axis_j; P_b anomalistic (n_b = πf − ω̇).
    """
    return _f(
        (_f(k1_m_s) + _f(k2_m_s))
        * np.sqrt(1.0 - _f(e) ** 2)
        * _f(pb_s)
        / (2.0 * math.pi * _f(sin_i))
    )


def kepler_total_mass(a_m: ArrayLike, pb_s: ArrayLike) -> F64:
    """M_tot = 4π² a³ / (G P_b²) [kg] (Eq. Kepler_mtot)."""
    return _f(4.0 * math.pi**2 * _f(a_m) ** 3 / (G_SI * _f(pb_s) ** 2))


def chirp_mass(m1_kg: ArrayLike, m2_kg: ArrayLike) -> F64:
    """M_c = (M1 M2)^{3/5} / (M1 + M2)^{1/5} [kg] (Sec. 5, locus 3)."""
    m1, m2 = _f(m1_kg), _f(m2_kg)
    return _f((m1 * m2) ** 0.6 / (m1 + m2) ** 0.2)


def peters_mathews_enhancement(e: ArrayLike) -> F64:
    """F(e) = (1 + 73e²/24 + 37e⁴/96)/(1 − e²)^{7/2} (Peters & Mathews 1963) ≈ 1 + 6.5e²."""
    e2 = _f(e) ** 2
    return _f((1.0 + 73.0 / 24.0 * e2 + 37.0 / 96.0 * e2 * e2) / (1.0 - e2) ** 3.5)


def fdot_gw_only(mc_kg: ArrayLike, f_hz: ArrayLike, e: ArrayLike = 0.0) -> F64:
    """ḟ_GW only = (96/5) π^{8/3} (G M_c/c³)^{5/3} f^{11/3} F(e) [Hz/s] (GW radiation only).

    Notes
    -----
    Eq. fdot_decomposition's ḟ_GW only (quadrupole formula; F(e) − 1 ≈ 6e-4 at e = 0.0096).
    """
    tc = G_SI * _f(mc_kg) / C_M_S**3
    return _f(
        96.0
        / 5.0
        * math.pi ** (8.0 / 3.0)
        * tc ** (5.0 / 3.0)
        * _f(f_hz) ** (11.0 / 3.0)
        * peters_mathews_enhancement(e)
    )


def chirp_mass_from_fdot(fdot_hz_s: ArrayLike, f_hz: ArrayLike, e: ArrayLike = 0.0) -> F64:
    """Invert :func:`fdot_gw_only`: M_c [kg] if ḟ were GW-driven only; NaN where ḟ ≤ 0."""
    fd = _f(fdot_hz_s)
    base = np.where(fd > 0, fd, np.nan) / (
        96.0
        / 5.0
        * math.pi ** (8.0 / 3.0)
        * _f(f_hz) ** (11.0 / 3.0)
        * peters_mathews_enhancement(e)
    )
    return _f(base**0.6 * C_M_S**3 / G_SI)


def distance_from_amplitude_m(mc_kg: ArrayLike, f_hz: ArrayLike, amplitude: ArrayLike) -> F64:
    """d = 2 (G M_c)^{5/3} (π f)^{2/3} / (c⁴ 𝒜) [m] (Eq. GW_amplitude solved for d)."""
    return _f(
        2.0
        * (G_SI * _f(mc_kg)) ** (5.0 / 3.0)
        * (math.pi * _f(f_hz)) ** (2.0 / 3.0)
        / (C_M_S**4 * _f(amplitude))
    )


def chirp_mass_from_amplitude(amplitude: ArrayLike, f_hz: ArrayLike, d_m: ArrayLike) -> F64:
    """M_c [kg] from Eq. GW_amplitude with a known distance."""
    x = _f(amplitude) * C_M_S**4 * _f(d_m) / (2.0 * (math.pi * _f(f_hz)) ** (2.0 / 3.0))
    return _f(x**0.6 / G_SI)


def omega_dot_gr(mtot_kg: ArrayLike, pb_s: ArrayLike, e: ArrayLike) -> F64:
    """ω̇_GR = 3/(1−e²) (2π/P_b)^{5/3} (G M_tot/c³)^{2/3} [rad/s] (Eq. omega_dot_GR)."""
    return _f(
        3.0
        / (1.0 - _f(e) ** 2)
        * (2.0 * math.pi / _f(pb_s)) ** (5.0 / 3.0)
        * (G_SI * _f(mtot_kg) / C_M_S**3) ** (2.0 / 3.0)
    )


def mass_from_omega_dot(omega_dot: ArrayLike, pb_s: ArrayLike, e: ArrayLike) -> F64:
    """M_tot^ω̇ [kg]: invert :func:`omega_dot_gr` (all of ω̇ attributed to GR; NaN where ω̇ ≤ 0)."""
    od = _f(omega_dot)
    x = (
        np.where(od > 0, od, np.nan)
        * (1.0 - _f(e) ** 2)
        / 3.0
        / (2.0 * math.pi / _f(pb_s)) ** (5.0 / 3.0)
    )
    return _f(x**1.5 * C_M_S**3 / G_SI)


def redshift_difference_orbital(m1_kg: ArrayLike, m2_kg: ArrayLike, a_m: ArrayLike) -> F64:
    """3G(M2 − M1)/(2ac) [m/s]: companion potential + 2nd-order Doppler in γ1 − γ2 (Sec. 3.1.2)."""
    return _f(1.5 * G_SI * (_f(m2_kg) - _f(m1_kg)) / (_f(a_m) * C_M_S))


def radius_eggleton(m_msun: ArrayLike) -> F64:
    """Zero-temperature WD radius [R_sun], Eggleton's fit quoted by Verbunt & Rappaport (1988).

    R/R_sun = 0.0114 [(M/M_ch)^{−2/3} − (M/M_ch)^{2/3}]^{1/2}
    × [1 + 3.5 (M/M_p)^{−2/3} + (M_p/M)]^{−2/3},
    M_ch = 1.44, M_p = 0.00057 M_sun (Verbunt F., Rappaport S., 1988, ApJ 332, 193). NaN outside
    0 < M < 1.44.
    """
    m = _f(m_msun)
    ok = (m > 0) & (m < 1.44)
    mm = np.where(ok, m, 0.5)
    r1 = 0.0114 * np.sqrt((mm / 1.44) ** (-2.0 / 3.0) - (mm / 1.44) ** (2.0 / 3.0))
    r2 = (1.0 + 3.5 * (mm / 0.00057) ** (-2.0 / 3.0) + 0.00057 / mm) ** (-2.0 / 3.0)
    return _f(np.where(ok, r1 * r2, np.nan))


def radius_nauenberg(m_msun: ArrayLike) -> F64:
    """Zero-temperature WD radius [R_sun], Nauenberg (1972, ApJ 175, 417).

    R/R_sun = 0.0112 [(M/M_ch)^{−2/3} − (M/M_ch)^{2/3}]^{1/2}, M_ch = 1.433 (μ_e = 2); NaN outside.
    """
    m = _f(m_msun)
    ok = (m > 0) & (m < 1.433)
    mm = np.where(ok, m, 0.5)
    fac = (mm / 1.433) ** (2.0 / 3.0)
    return _f(np.where(ok, 0.0112 * np.sqrt(1.0 / fac - fac), np.nan))


#: Registered analytic WD mass–radius relations (name → R[R_sun](M[M_sun])).
MASS_RADIUS_MODELS: dict[str, Callable[[ArrayLike], F64]] = {
    "eggleton": radius_eggleton,
    "nauenberg": radius_nauenberg,
}


def derive(
    *,
    K1_km_s: F64,
    K2_km_s: F64,
    gamma1_km_s: F64 | None,
    gamma2_km_s: F64 | None,
    f_hz: F64,
    fdot_hz_s: F64,
    eta: F64,
    kappa: F64,
    omega_dot: F64,
    cos_i: F64,
    amplitude: F64 | None = None,
    mass_radius: str | None = None,
) -> dict[str, F64]:
    """Evaluate every derived quantity for arrays of samples (all arrays broadcast).

    Parameters
    ----------
    K1_km_s, K2_km_s : ndarray
        Finite-window-corrected semi-amplitudes [km/s].
    gamma1_km_s, gamma2_km_s : ndarray or None
        Intercepts [km/s] (None: no redshift quantities).
    f_hz, fdot_hz_s, eta, kappa, omega_dot : ndarray
        LISA parameters at the reference epoch [Hz, Hz/s, 1, 1, rad/s].
    cos_i : ndarray
        cos ι [1].
    amplitude : ndarray or None
        GW strain amplitude 𝒜 (Eq. GW_amplitude) for the distance.
    mass_radius : str or None
        Key of :data:`MASS_RADIUS_MODELS` for the predicted redshift difference.

    Returns
    -------
    dict of ndarray
        Keys (units): n_b (rad/s), P_b (s), e (1), sin_i (1), a (m), M_tot, M1, M2, M_c (Msun),
        q (1), omega_dot_GR, omega_dot_remainder (rad/s), M_tot_omega_dot, M_c_fdot (Msun),
        fdot_GW_only, fdot_minus_GW_only (Hz/s), distance (kpc, if amplitude), gamma_diff,
        redshift_orbital, redshift_grav (km/s, if γ), R1, R2 (R_sun), redshift_grav_model and
        redshift_grav_minus_model (km/s, if model).

    Notes
    -----
    Eqs. semimajor_axis_j, Kepler_mtot, M1M2_cir_and_ecc, omega_dot_GR, omega_dot_full,
    GW_amplitude, M_c_q; n_b = πf − ω̇ (anomalistic).
    """
    k1 = _f(K1_km_s) * 1e3
    k2 = _f(K2_km_s) * 1e3
    nb = math.pi * _f(f_hz) - _f(omega_dot)
    pb = 2.0 * math.pi / nb
    e = np.hypot(_f(eta), _f(kappa))
    sin_i = np.sqrt(np.clip(1.0 - _f(cos_i) ** 2, 0.0, 1.0))
    a = a_total_m(k1, k2, e, pb, sin_i)
    mtot = kepler_total_mass(a, pb)
    q = k1 / k2
    m1 = mtot / (1.0 + q)
    m2 = q * m1
    mc = chirp_mass(m1, m2)
    od_gr = omega_dot_gr(mtot, pb, e)
    out: dict[str, F64] = {
        "n_b": nb,
        "P_b": pb,
        "e": e,
        "sin_i": sin_i,
        "a": a,
        "M_tot": mtot / MSUN_KG,
        "q": q,
        "M1": m1 / MSUN_KG,
        "M2": m2 / MSUN_KG,
        "M_c": mc / MSUN_KG,
        "omega_dot_GR": od_gr,
        "omega_dot_remainder": _f(omega_dot) - od_gr,
        "M_tot_omega_dot": mass_from_omega_dot(omega_dot, pb, e) / MSUN_KG,
        "M_c_fdot": chirp_mass_from_fdot(fdot_hz_s, f_hz, e) / MSUN_KG,
        "fdot_GW_only": fdot_gw_only(mc, f_hz, e),
    }
    out["fdot_minus_GW_only"] = _f(fdot_hz_s) - out["fdot_GW_only"]
    if amplitude is not None:
        out["distance"] = distance_from_amplitude_m(mc, f_hz, amplitude) / 3.0856775814913673e19
    if gamma1_km_s is not None and gamma2_km_s is not None:
        out["gamma_diff"] = _f(gamma1_km_s) - _f(gamma2_km_s)
        out["redshift_orbital"] = redshift_difference_orbital(m1, m2, a) / 1e3
        out["redshift_grav"] = out["gamma_diff"] - out["redshift_orbital"]
    if mass_radius is not None:
        rfun = MASS_RADIUS_MODELS[mass_radius]
        r1 = rfun(m1 / MSUN_KG) * RSUN_M
        r2 = rfun(m2 / MSUN_KG) * RSUN_M
        out["R1"] = r1 / RSUN_M
        out["R2"] = r2 / RSUN_M
        out["redshift_grav_model"] = G_SI * (m1 / r1 - m2 / r2) / C_M_S / 1e3
        if "redshift_grav" in out:
            out["redshift_grav_minus_model"] = out["redshift_grav"] - out["redshift_grav_model"]
    return out


@dataclass(frozen=True, slots=True)
class Summary:
    """Median and 16/84 % percentiles of a Monte-Carlo sample (NaNs excluded).

    ``sigma`` is half the 16–84 % width; ``n_valid`` counts finite samples.
    """

    value: float
    sigma: float
    lo: float
    hi: float
    n_valid: int


def summarize(samples: ArrayLike) -> Summary:
    """Median, σ = (p84 − p16)/2, lo = p16, hi = p84 of the finite samples."""
    x = _f(samples).ravel()
    x = x[np.isfinite(x)]
    if x.size == 0:
        nan = float("nan")
        return Summary(nan, nan, nan, nan, 0)
    lo, med, hi = np.percentile(x, [15.865525393145708, 50.0, 84.13447460685429])
    return Summary(float(med), float(0.5 * (hi - lo)), float(lo), float(hi), int(x.size))
