"""Binary-star physics: Kepler's third law, chirp mass, GR periastron advance, WD radii (SI).

Vectorised: every function takes float64 arrays (masses in kg, velocities in m/s, times in s) and
broadcasts. Used by the reduction's Monte Carlo and by the feasibility estimates.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ucbplan.core.constants import C_M_S, G_SI

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
