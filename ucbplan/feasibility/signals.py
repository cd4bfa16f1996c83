"""Expected signal magnitudes (paper Sec. 3): the physics behind ``ucbplan feasibility``.

Pure functions over SI floats (velocities in m/s, times in s, angles in rad); masses are taken in
solar masses (``*_msun``) because that is how every user states them. :mod:`.report` collects them
for one binary, :mod:`.plots` draws the apsidal signal.

Notes
-----
Equation labels are the paper's: ``Eq. semiamp_est`` (exact Kepler form), ``Eq. omega_dot_GR``,
``Eq. del_om_tide`` (physical form of the tidal apsidal rate, which reproduces the paper's 3.7 rad
per month coefficient), ``Eq. tau_chirp``, ``Eq. DeltaK_bound``, ``Eq. apsidal_drift_est0``,
``Eq. DeltaVcm_est`` and ``Eq. optical_timing_prec``. The errata of ``docs/method.md`` ("Errata of
the paper") apply: the tidal estimate gives ≈100 rad per month at P_b = 5 min (≈256 at 3.97 min)
and optical timing uses the orbital frequency.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ucbplan.core import binary
from ucbplan.core.constants import AU_M
from ucbplan.core.constants import C_M_S as _C
from ucbplan.core.constants import G_SI as _G
from ucbplan.core.constants import MSUN_KG as _MSUN
from ucbplan.core.constants import RSUN_M as _RSUN
from ucbplan.core.forecast import sigma_u
from ucbplan.core.params import EphemerisSource
from ucbplan.core.phase import arg_latitude_rate
from ucbplan.errors import InputError, UcbplanError
from ucbplan.inputs import check_range


def _check_positive(**values: float) -> None:
    for name, value in values.items():
        if not (np.all(np.isfinite(value)) and np.all(np.asarray(value) > 0)):
            raise InputError(f"{name} must be finite and > 0, got {value!r}", parameter=name)


def _check_ecc(e: float) -> None:
    if not 0.0 <= e < 1.0:
        raise InputError(f"eccentricity must be in [0, 1), got {e!r}", parameter="eccentricity")


def semi_amplitudes(
    m1_msun: float, m2_msun: float, period_s: float, sin_i: float, e: float = 0.0
) -> tuple[float, float]:
    """Radial-velocity semi-amplitudes of both stars from Kepler's third law.

    Parameters
    ----------
    m1_msun, m2_msun : float
        Component masses [M_sun].
    period_s : float
        Anomalistic orbital period P_b [s].
    sin_i : float
        Sine of the orbital inclination [1].
    e : float
        Eccentricity [1].

    Returns
    -------
    k1_m_s, k2_m_s : float
        K_1 = (2πG/P_b)^{1/3} M_2 sin ι / [M_tot^{2/3} (1−e²)^{1/2}], K_2 likewise with M_1
        [m/s].

    Raises
    ------
    InputError
        For non-positive masses or period, or e outside [0, 1).

    Notes
    -----
    Eq. semiamp_est in its exact form (the paper's 747 km/s is its value at 0.6 + 0.6 M_sun,
    P_b = 5 min, sin ι = 1).
    """
    _check_positive(m1_msun=m1_msun, m2_msun=m2_msun, period_s=period_s)
    _check_ecc(e)
    m_tot = (m1_msun + m2_msun) * _MSUN
    scale = (2.0 * math.pi * _G / period_s) ** (1.0 / 3.0) * sin_i / math.sqrt(1.0 - e * e)
    scale /= m_tot ** (2.0 / 3.0)
    return scale * m2_msun * _MSUN, scale * m1_msun * _MSUN


def omega_dot_gr(m_tot_msun: float, period_s: float, e: float = 0.0) -> float:
    """Relativistic apsidal advance rate at leading post-Newtonian order.

    Parameters
    ----------
    m_tot_msun : float
        Total mass [M_sun].
    period_s : float
        Orbital period P_b [s].
    e : float
        Eccentricity [1].

    Returns
    -------
    float
        ω̇_GR = 3/(1−e²) (2π/P_b)^{5/3} (G M_tot/c³)^{2/3} [rad/s].

    Notes
    -----
    Eq. omega_dot_GR.
    """
    _check_positive(m_tot_msun=m_tot_msun, period_s=period_s)
    _check_ecc(e)
    return float(binary.omega_dot_gr(m_tot_msun * _MSUN, period_s, e))


def tidal_deformability(m_msun: float) -> float:
    """White-dwarf tidal deformability factor 𝒦(M) = k R^5 [1e-10 R_sun^5].

    Notes
    -----
    The fit 𝒦(M) = −0.632 + 0.370 M^{−1.709} quoted with Eq. del_om_tide (Valsecchi et al. 2012).
    """
    _check_positive(m_msun=m_msun)
    return -0.632 + 0.370 * m_msun ** (-1.709)


def omega_dot_tide(m1_msun: float, m2_msun: float, period_s: float, e: float = 0.0) -> float:
    """Tidal (quadrupole) apsidal advance rate.

    Parameters
    ----------
    m1_msun, m2_msun : float
        Component masses [M_sun].
    period_s : float
        Orbital period P_b [s].
    e : float
        Eccentricity [1].

    Returns
    -------
    float
        ω̇_tide = 15 n_b f_tide(e) [q 𝒦(M_1) + q^{−1} 𝒦(M_2)] / a⁵ [rad/s], with q = M_2/M_1,
        n_b = 2π/P_b, a from Kepler's third law and f_tide = (1 + 3e²/2 + e⁴/8)/(1−e²)⁵.

    Notes
    -----
    Physical form of Eq. del_om_tide: at 0.6 + 0.6 M_sun and P_b = 5 min it gives the paper's
    3.7 rad per month and carries the same (M_tot^{−5/3}, P_b^{−13/3}) scaling. Erratum
    (``docs/method.md``, "Errata of the paper"): the ≈100 rad/month quoted for
    0.347 + 0.285 M_sun holds at P_b = 5 min; at 3.97 min it is ≈256.
    """
    _check_positive(m1_msun=m1_msun, m2_msun=m2_msun, period_s=period_s)
    _check_ecc(e)
    n_b = 2.0 * math.pi / period_s
    a_m = (_G * (m1_msun + m2_msun) * _MSUN / n_b**2) ** (1.0 / 3.0)
    q = m2_msun / m1_msun
    f_tide = (1.0 + 1.5 * e**2 + e**4 / 8.0) / (1.0 - e * e) ** 5
    k_sum = q * tidal_deformability(m1_msun) + tidal_deformability(m2_msun) / q
    return 15.0 * n_b * f_tide * k_sum * 1e-10 * _RSUN**5 / a_m**5


def tau_chirp_gr_s(m1_msun: float, m2_msun: float, f_gw_hz: float) -> float:
    """Chirp time-scale f/ḟ for inspiral driven by gravitational radiation alone.

    Returns
    -------
    float
        τ_chirp = f/ḟ with ḟ = (96/5) π^{8/3} (G M_c/c³)^{5/3} f^{11/3} [s].

    Notes
    -----
    Eq. tau_chirp (≈1e5 yr at M_c = 0.52 M_sun, P_b = 5 min). With a measured ḟ (mass transfer,
    tides) use f/ḟ directly instead.
    """
    _check_positive(m1_msun=m1_msun, m2_msun=m2_msun, f_gw_hz=f_gw_hz)
    m_chirp = (m1_msun * m2_msun) ** 0.6 / (m1_msun + m2_msun) ** 0.2 * _MSUN
    fdot = 96.0 / 5.0 * math.pi ** (8.0 / 3.0) * (_G * m_chirp / _C**3) ** (5.0 / 3.0)
    fdot *= f_gw_hz ** (11.0 / 3.0)
    return f_gw_hz / fdot


def delta_k_bound(k_m_s: float, baseline_s: float, tau_chirp_s: float) -> float:
    """Secular change of K over a baseline, |ΔK cos u★| ≤ K T/(3 τ_chirp) [m/s].

    Notes
    -----
    Eq. DeltaK_bound (K ∝ n_b^{1/3}, so K̇/K = ḟ/(3f)).
    """
    return k_m_s * baseline_s / (3.0 * tau_chirp_s)


def apsidal_period_s(omega_dot_rad_s: float) -> float:
    """Apsidal period 2π/ω̇ [s] (``inf`` when ω̇ = 0)."""
    return math.inf if omega_dot_rad_s == 0 else 2.0 * math.pi / abs(omega_dot_rad_s)


def delta_v_aps(
    k1_m_s: float,
    e: float,
    omega1_rad: ArrayLike,
    omega_dot_rad_s: float,
    baseline_s: ArrayLike,
) -> NDArray[np.float64]:
    """Apsidal velocity difference of a fixed-u spectrum pair.

    Parameters
    ----------
    k1_m_s : float
        Semi-amplitude of the star observed [m/s].
    e : float
        Eccentricity [1].
    omega1_rad : array_like
        Argument of periastron at the first epoch t_α [rad].
    omega_dot_rad_s : float
        Apsidal advance rate [rad/s].
    baseline_s : array_like
        ΔT = t_β − t_α [s]; broadcast against ``omega1_rad``.

    Returns
    -------
    ndarray
        Δv_aps = −2 K_1 e sin(ω_1 + Δω/2) sin(Δω/2), Δω = ω̇ ΔT [m/s]; |Δv_aps| ≤ 2 K_1 e.

    Notes
    -----
    Eq. apsidal_drift_est0.
    """
    d_omega = omega_dot_rad_s * np.asarray(baseline_s, dtype=float)
    omega1 = np.asarray(omega1_rad, dtype=float)
    return -2.0 * k1_m_s * e * np.sin(omega1 + d_omega / 2.0) * np.sin(d_omega / 2.0)


def eccentricity_floor(sigma_v_m_s: float, k_m_s: float, n_spectra: int = 1) -> float:
    """Smallest eccentricity whose apsidal signal 2Ke reaches the velocity precision.

    Parameters
    ----------
    sigma_v_m_s : float
        Precision of one velocity measurement [m/s].
    k_m_s : float
        Semi-amplitude of the star observed [m/s].
    n_spectra : int
        Spectra co-added at each epoch; the precision improves as N^{-1/2}.

    Returns
    -------
    float
        e_min = σ_v / (2 K √N) [1].

    Notes
    -----
    Sec. 3 after Eq. apsidal_drift_est0: |Δv_aps| ≤ 2K_1 e against σ_v ≳ 15 km/s gives e ≳ 0.01 for
    one spectrum pair; co-adding N spectra lowers the bound by N^{-1/2}.
    """
    _check_positive(sigma_v_m_s=sigma_v_m_s, k_m_s=k_m_s, n_spectra=n_spectra)
    return sigma_v_m_s / (2.0 * k_m_s * math.sqrt(n_spectra))


def tertiary_acceleration(m3_msun: float, a_out_au: float) -> float:
    """Centre-of-mass acceleration G M_3 / a_out² from a tertiary [m/s²]."""
    _check_positive(m3_msun=m3_msun, a_out_au=a_out_au)
    return _G * m3_msun * _MSUN / (a_out_au * AU_M) ** 2


def delta_v_cm(a_cm_m_s2: float, baseline_s: ArrayLike) -> NDArray[np.float64]:
    """Centre-of-mass velocity drift Δv_CM ≈ a_CM ΔT for ΔT ≪ P_out [m/s].

    Notes
    -----
    Eq. DeltaVcm_est (3 mm/s per year at a_CM = 1e-10 m/s²; 0.6 km/s per month for 1 M_sun at
    5 AU).
    """
    return a_cm_m_s2 * np.asarray(baseline_s, dtype=float)


@dataclass(frozen=True, slots=True)
class OpticalEphemeris:
    """Independent 1σ uncertainties of an optical (or X-ray) timing ephemeris.

    Attributes
    ----------
    sigma_phase_cycles : float
        σ_φ0, reference-phase uncertainty [cycles].
    sigma_f_rel : float
        σ_f/f, relative orbital-frequency uncertainty [1].
    sigma_fdot_rel_s : float
        σ_ḟ/f [1/s].
    f_orb_hz : float
        Orbital frequency f = 1/P_orb [Hz] (the orbital, not the GW, frequency;
        ``docs/method.md``, "Errata of the paper").
    """

    sigma_phase_cycles: float
    sigma_f_rel: float
    sigma_fdot_rel_s: float
    f_orb_hz: float

    @classmethod
    def from_period(
        cls, period_s: float, sigma_p_s: float, sigma_pdot: float, sigma_t0_s: float
    ) -> OpticalEphemeris:
        """From period-style uncertainties σ_P [s], σ_Ṗ [s/s] and σ_T0 [s].

        σ_f/f = σ_P/P, σ_ḟ/f = σ_Ṗ/P (from ḟ = −Ṗ/P², covariances neglected), σ_φ0 = σ_T0/P.
        """
        _check_positive(period_s=period_s)
        return cls(sigma_t0_s / period_s, sigma_p_s / period_s, sigma_pdot / period_s, 1 / period_s)


def optical_ephemeris(
    period_s: float,
    *,
    sigma_phase_cycles: float | None = None,
    sigma_f_rel: float | None = None,
    sigma_fdot_rel_s: float | None = None,
    sigma_p_s: float | None = None,
    sigma_pdot: float | None = None,
    sigma_t0_s: float | None = None,
) -> OpticalEphemeris | None:
    """An optical ephemeris from either frequency-style or period-style uncertainties.

    Parameters
    ----------
    period_s : float
        The ephemeris's own period P_orb [s] (sets f = 1/P_orb): node to node, as eclipses and
        light curves repeat (``PhaseParams.nodal_period_s`` = 2/f_gw), not the anomalistic P_b.
    sigma_phase_cycles, sigma_f_rel, sigma_fdot_rel_s : float, optional
        Frequency style: σ_φ0 [cycles], σ_f/f [1], σ_ḟ/f [1/s]; missing ones are 0.
    sigma_p_s, sigma_pdot, sigma_t0_s : float, optional
        Period style: σ_P [s], σ_Ṗ [s/s], σ_T0 [s] (:meth:`OpticalEphemeris.from_period`).

    Returns
    -------
    OpticalEphemeris or None
        None when no uncertainty is given at all.

    Raises
    ------
    UcbplanError
        If both styles are given, or an uncertainty is negative or not finite.
    """
    freq = (sigma_phase_cycles, sigma_f_rel, sigma_fdot_rel_s)
    period = (sigma_p_s, sigma_pdot, sigma_t0_s)
    _check_optical_sigmas(period_s, (*freq, *period))
    freq_style = any(v is not None for v in freq)
    period_style = any(v is not None for v in period)
    if freq_style and period_style:
        raise UcbplanError(
            "optical ephemeris: give either optical_sigma_phase/optical_sigma_f_rel/"
            "optical_sigma_fdot_rel or optical_sigma_p/optical_sigma_pdot/optical_sigma_t0, "
            "not both"
        )
    if period_style:
        return OpticalEphemeris.from_period(
            period_s, sigma_p_s or 0.0, sigma_pdot or 0.0, sigma_t0_s or 0.0
        )
    if freq_style:
        phase, f_rel, fdot_rel = (v or 0.0 for v in freq)
        return OpticalEphemeris(phase, f_rel, fdot_rel, 1.0 / period_s)
    return None


def _check_optical_sigmas(period_s: float, values: tuple[float | None, ...]) -> None:
    """Each given σ of :func:`optical_ephemeris` (frequency style, then period style) is finite,
    ≥ 0 and below the 1σ bound beyond which an ephemeris says nothing (and squares overflow)."""
    limits = (  # (name, max, unit)
        ("phase", 1.0, "cycles"),
        ("f-rel", 1.0, ""),
        ("fdot-rel", 1e-6, "1/s"),
        ("p", period_s, "s"),
        ("pdot", 1e-3, "s/s"),
        ("t0", 1e9, "s"),
    )
    for (name, high, unit), value in zip(limits, values, strict=True):
        if value is not None:
            why = "a 1σ uncertainty; a larger one carries no phase information"
            check_range(f"optical_sigma_{name.replace('-', '_')}", value, 0.0, high, unit, why)


def optical_timing_s(eph: OpticalEphemeris, baseline_s: ArrayLike) -> NDArray[np.float64]:
    """Timing error of an optical ephemeris propagated over ΔT (independent errors).

    Returns
    -------
    ndarray
        δt = [(σ_φ0/f)² + (σ_f/f ΔT)² + (σ_ḟ/(2f) ΔT²)²]^{1/2} [s].

    Notes
    -----
    Eq. optical_timing_prec with f the orbital frequency (``docs/method.md``, "Errata of the
    paper"): HM Cnc 1.24 s from the frequency terms and 1.79 s with the phase term after 4 yr.
    """
    dt = np.asarray(baseline_s, dtype=float)
    phase = eph.sigma_phase_cycles / eph.f_orb_hz
    freq = eph.sigma_f_rel * dt
    fdot = 0.5 * eph.sigma_fdot_rel_s * dt**2
    return np.sqrt(phase**2 + freq**2 + fdot**2)


def gw_timing_s(target: EphemerisSource, baseline_s: ArrayLike) -> NDArray[np.float64]:
    """Timing error of the target's ephemeris ΔT after its reference epoch.

    The reference epoch is the LISA midpoint for a LISA posterior and T0 for a timing ephemeris
    (the same phase model: for a timing target this is the error of T0 + P n + ½PṖn²).

    Returns
    -------
    ndarray
        δt_u(ΔT) = σ_u(ΔT) / |u̇(ΔT)| with the target's full covariance [s].

    Notes
    -----
    Sec. 4 (Eq. sigma_tstar with σ_u from the full covariance; ``docs/method.md``, "Forecast"):
    the paper quotes δt_u ≈ 0.9 s for the HM Cnc-like system four years after the midpoint.
    """
    tau = np.asarray(baseline_s, dtype=float)
    sig = sigma_u(target.params, target.covariance, tau)
    rate = arg_latitude_rate(target.params, tau)
    return np.asarray(sig / np.abs(rate), dtype=float)
