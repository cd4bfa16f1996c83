"""Expected signal magnitudes (paper Sec. 3): is a targeted-u programme feasible for this binary?

Pure functions over SI floats (velocities in m/s, times in s, angles in rad); masses are taken in
solar masses (``*_msun``) because that is how every user states them. :func:`feasibility_report`
collects everything the ``ucbplan feasibility`` command prints.

Notes
-----
Equation labels are the paper's: ``Eq. semiamp_est`` (exact Kepler form), ``Eq. omega_dot_GR``,
``Eq. del_om_tide`` (physical form of the tidal apsidal rate, which reproduces the paper's 3.7 rad
per month coefficient), ``Eq. tau_chirp``, ``Eq. DeltaK_bound``, ``Eq. apsidal_drift_est0``,
``Eq. DeltaVcm_est`` and ``Eq. optical_timing_prec``. SCIENCE.md errata apply: the tidal estimate
gives ≈100 rad per month at P_b = 5 min (≈256 at 3.97 min) and optical timing uses the orbital
frequency.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ucbplan.core.constants import AU_M, MONTH_S, YEAR_S
from ucbplan.core.constants import C_M_S as _C
from ucbplan.core.constants import G_SI as _G
from ucbplan.core.constants import MSUN_KG as _MSUN
from ucbplan.core.constants import RSUN_M as _RSUN

if TYPE_CHECKING:
    from ucbplan.target import Target

__all__ = [
    "AU_M",
    "MONTH_S",
    "YEAR_S",
    "FeasibilityReport",
    "OpticalEphemeris",
    "apsidal_period_s",
    "delta_k_bound",
    "delta_v_aps",
    "delta_v_cm",
    "eccentricity_floor",
    "feasibility_report",
    "gw_timing_s",
    "omega_dot_gr",
    "omega_dot_tide",
    "optical_timing_s",
    "plot_apsidal_signal",
    "report_for_target",
    "semi_amplitudes",
    "tau_chirp_gr_s",
    "tertiary_acceleration",
    "tidal_deformability",
]


def _check_positive(**values: float) -> None:
    for name, value in values.items():
        if not (np.all(np.isfinite(value)) and np.all(np.asarray(value) > 0)):
            raise ValueError(f"{name} must be finite and > 0, got {value!r}")


def _check_ecc(e: float) -> None:
    if not 0.0 <= e < 1.0:
        raise ValueError(f"eccentricity must be in [0, 1), got {e!r}")


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
    ValueError
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
    from ucbplan.core.binary import omega_dot_gr as _omega_dot_gr

    _check_positive(m_tot_msun=m_tot_msun, period_s=period_s)
    _check_ecc(e)
    return float(_omega_dot_gr(m_tot_msun * _MSUN, period_s, e))


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
    3.7 rad per month and carries the same (M_tot^{−5/3}, P_b^{−13/3}) scaling. SCIENCE.md erratum:
    the ≈100 rad/month quoted for 0.347 + 0.285 M_sun holds at P_b = 5 min; at 3.97 min it is ≈256.
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
        Orbital frequency f = 1/P_orb [Hz] (SCIENCE.md: the orbital, not the GW, frequency).
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


def optical_timing_s(eph: OpticalEphemeris, baseline_s: ArrayLike) -> NDArray[np.float64]:
    """Timing error of an optical ephemeris propagated over ΔT (independent errors).

    Returns
    -------
    ndarray
        δt = [(σ_φ0/f)² + (σ_f/f ΔT)² + (σ_ḟ/(2f) ΔT²)²]^{1/2} [s].

    Notes
    -----
    Eq. optical_timing_prec with f the orbital frequency (SCIENCE.md erratum): HM Cnc 1.24 s from
    the frequency terms and 1.79 s with the phase term after 4 yr.
    """
    dt = np.asarray(baseline_s, dtype=float)
    phase = eph.sigma_phase_cycles / eph.f_orb_hz
    freq = eph.sigma_f_rel * dt
    fdot = 0.5 * eph.sigma_fdot_rel_s * dt**2
    return np.sqrt(phase**2 + freq**2 + fdot**2)


def gw_timing_s(target: Target, baseline_s: ArrayLike) -> NDArray[np.float64]:
    """Timing error of the LISA ephemeris ΔT after its reference epoch (the LISA midpoint).

    Returns
    -------
    ndarray
        δt_u(ΔT) = σ_u(ΔT) / |u̇(ΔT)| with the target's full covariance [s].

    Notes
    -----
    Sec. 4 (Eq. sigma_tstar with σ_u from the full covariance, SCIENCE.md "Forecast"); the paper
    quotes δt_u ≈ 0.9 s for the HM Cnc-like system four years after the midpoint.
    """
    from ucbplan.core.ephemeris import arg_latitude_rate
    from ucbplan.core.forecast import sigma_u

    tau = np.asarray(baseline_s, dtype=float)
    sig = sigma_u(target.params, target.covariance, tau)
    rate = arg_latitude_rate(target.params, tau)
    return np.asarray(sig / np.abs(rate), dtype=float)


@dataclass(frozen=True, slots=True)
class FeasibilityReport:
    """Every Sec. 3 magnitude for one binary (SI units; see :func:`feasibility_report`)."""

    name: str
    period_s: float
    f_gw_hz: float
    sin_i: float | None
    e: float
    omega0_rad: float
    m1_msun: float | None
    m2_msun: float | None
    k1_m_s: float | None
    k2_m_s: float | None
    omega_dot_gr: float | None
    omega_dot_tide: float | None
    omega_dot_used: float
    omega_dot_source: str
    apsidal_period_s: float
    tau_chirp_s: float | None
    tau_chirp_source: str
    baseline_s: float
    delta_k_m_s: float | None
    delta_v_aps_max_m_s: float | None
    delta_v_aps_m_s: float | None
    sigma_v_m_s: float
    n_spectra: int
    e_floor: float | None
    a_cm_galactic: float
    delta_v_cm_galactic_m_s: float
    m3_msun: float
    a_out_au: float
    delta_v_cm_tertiary_m_s: float
    timing_years: list[float] = field(default_factory=list)
    gw_timing_s: list[float] | None = None
    optical_timing_s: list[float] | None = None
    notes: list[str] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        """Plain dict with unit-suffixed keys for ``--format json`` (inf/NaN → None)."""

        def clean(v: Any) -> Any:
            if isinstance(v, float) and not math.isfinite(v):
                return None
            if isinstance(v, list):
                return [clean(x) for x in v]
            return v

        return {k: clean(v) for k, v in asdict(self).items()}


def feasibility_report(
    *,
    name: str,
    period_s: float,
    f_gw_hz: float,
    sin_i: float | None = None,
    e: float = 0.0,
    omega0_rad: float = 0.0,
    omega_dot_target: float = 0.0,
    fdot_hz_s: float | None = None,
    m1_msun: float | None = None,
    m2_msun: float | None = None,
    k1_m_s: float | None = None,
    sigma_v_m_s: float = 15e3,
    n_spectra: int = 1,
    baseline_s: float = YEAR_S,
    m3_msun: float = 1.0,
    a_out_au: float = 5.0,
    a_cm_galactic: float = 1e-10,
) -> FeasibilityReport:
    """Evaluate the Sec. 3 magnitudes for one binary.

    Masses give K_j (Eq. semiamp_est), ω̇_GR, ω̇_tide and the GR chirp time; a measured ``fdot``
    overrides the GR chirp time and a nonzero ``omega_dot_target`` (LISA's total ω̇) overrides
    ω̇_GR + ω̇_tide for the apsidal signal. ``k1_m_s`` is used when masses are missing.
    """
    notes: list[str] = []
    k1 = k2 = w_gr = w_tide = None
    if m1_msun is not None and m2_msun is not None:
        w_gr = omega_dot_gr(m1_msun + m2_msun, period_s, e)
        w_tide = omega_dot_tide(m1_msun, m2_msun, period_s, e)
        if sin_i is not None:
            k1, k2 = semi_amplitudes(m1_msun, m2_msun, period_s, sin_i, e)
        else:
            notes.append("no inclination: K_j not computed; give cos_inclination in the target")
    else:
        notes.append("no masses: pass --m1/--m2 for K_j, omega_dot_GR/tide and tau_chirp")
    if k1 is None and k1_m_s is not None:
        k1 = k1_m_s
    if omega_dot_target != 0.0:
        w_used, w_src = omega_dot_target, "target (LISA)"
    elif w_gr is not None and w_tide is not None:
        w_used, w_src = w_gr + w_tide, "GR + tide from masses"
    else:
        w_used, w_src = 0.0, "none"
    if fdot_hz_s is not None and fdot_hz_s != 0.0:
        tau: float | None = f_gw_hz / abs(fdot_hz_s)
        tau_src = "f/fdot of the target"
    elif m1_msun is not None and m2_msun is not None:
        tau, tau_src = tau_chirp_gr_s(m1_msun, m2_msun, f_gw_hz), "GR from masses"
    else:
        tau, tau_src = None, "none"
    dk = delta_k_bound(k1, baseline_s, tau) if (k1 is not None and tau is not None) else None
    dv_max = 2.0 * k1 * e if k1 is not None else None
    dv = None
    if k1 is not None:
        dv = float(delta_v_aps(k1, e, omega0_rad, w_used, baseline_s))
    floor = eccentricity_floor(sigma_v_m_s, k1, n_spectra) if k1 is not None else None
    a_t = tertiary_acceleration(m3_msun, a_out_au)
    return FeasibilityReport(
        name=name,
        period_s=period_s,
        f_gw_hz=f_gw_hz,
        sin_i=sin_i,
        e=e,
        omega0_rad=omega0_rad,
        m1_msun=m1_msun,
        m2_msun=m2_msun,
        k1_m_s=k1,
        k2_m_s=k2,
        omega_dot_gr=w_gr,
        omega_dot_tide=w_tide,
        omega_dot_used=w_used,
        omega_dot_source=w_src,
        apsidal_period_s=apsidal_period_s(w_used),
        tau_chirp_s=tau,
        tau_chirp_source=tau_src,
        baseline_s=baseline_s,
        delta_k_m_s=dk,
        delta_v_aps_max_m_s=dv_max,
        delta_v_aps_m_s=dv,
        sigma_v_m_s=sigma_v_m_s,
        n_spectra=n_spectra,
        e_floor=floor,
        a_cm_galactic=a_cm_galactic,
        delta_v_cm_galactic_m_s=float(delta_v_cm(a_cm_galactic, baseline_s)),
        m3_msun=m3_msun,
        a_out_au=a_out_au,
        delta_v_cm_tertiary_m_s=float(delta_v_cm(a_t, baseline_s)),
        notes=notes,
    )


def report_for_target(
    target: Target,
    *,
    m1_msun: float | None = None,
    m2_msun: float | None = None,
    sigma_v_m_s: float | None = None,
    n_spectra: int = 1,
    baseline_s: float = YEAR_S,
    m3_msun: float = 1.0,
    a_out_au: float = 5.0,
    optical: OpticalEphemeris | None = None,
    optical_offset_s: float = 0.0,
    timing_years: tuple[float, ...] = (0.0, 1.0, 2.0, 4.0, 6.0, 8.0, 10.0),
) -> FeasibilityReport:
    """:func:`feasibility_report` for a loaded target; CLI values override the target file.

    ``optical_offset_s`` is the LISA midpoint minus the optical ephemeris reference epoch, so the
    optical ΔT at a given date is ΔT_LISA + offset (0: both referenced to the LISA midpoint).
    Timing rows are ΔT after the LISA midpoint in Julian years.
    """
    spec = target.spectroscopy
    m1 = m1_msun if m1_msun is not None else target.m1_msun
    m2 = m2_msun if m2_msun is not None else target.m2_msun
    if sigma_v_m_s is None:
        sv = spec.sigma_v_kms if spec is not None else None
        sigma_v_m_s = sv * 1e3 if sv is not None else 15e3
    k1_file = spec.K1_kms * 1e3 if (spec is not None and spec.K1_kms is not None) else None
    cos_i = target.cos_inclination
    p = target.params
    report = feasibility_report(
        name=target.name,
        period_s=target.period_s,
        f_gw_hz=p.f_gw,
        sin_i=math.sqrt(1.0 - cos_i**2) if cos_i is not None else None,
        e=p.eccentricity,
        omega0_rad=p.omega_rad,
        omega_dot_target=p.omega_dot,
        fdot_hz_s=p.fdot,
        m1_msun=m1,
        m2_msun=m2,
        k1_m_s=k1_file,
        sigma_v_m_s=sigma_v_m_s,
        n_spectra=n_spectra,
        baseline_s=baseline_s,
        m3_msun=m3_msun,
        a_out_au=a_out_au,
    )
    years = np.asarray(timing_years, dtype=float)
    dt = years * YEAR_S
    gw = gw_timing_s(target, dt) if np.any(target.covariance) else None
    opt = optical_timing_s(optical, dt + optical_offset_s) if optical is not None else None
    notes = list(report.notes)
    if gw is None:
        notes.append("target has no covariance: GW timing delta t_u not computed")
    return replace(
        report,
        timing_years=[float(y) for y in years],
        gw_timing_s=[float(x) for x in gw] if gw is not None else None,
        optical_timing_s=[float(x) for x in opt] if opt is not None else None,
        notes=notes,
    )


def plot_apsidal_signal(
    path: Any,
    *,
    k1_m_s: float,
    omega_dot_rad_s: float,
    e_values: tuple[float, ...] = (0.005, 0.01, 0.03),
    omega1_values: tuple[float, ...] = (0.0, math.pi / 4, math.pi / 2, 3 * math.pi / 4),
    target_e: float | None = None,
    target_omega1: float | None = None,
    title: str = "",
) -> None:
    """Plot Δv_aps against the baseline, like Fig. apsidal_signal_omega1_dependence.

    Colours are ω_1, line styles the eccentricities; the dashed vertical line marks the apsidal
    period 2π/ω̇; the target's own (e, ω_1) is drawn in black when given. Writes a PNG to ``path``.

    Raises
    ------
    ValueError
        If ω̇ = 0 (no apsidal signal to plot).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    if omega_dot_rad_s == 0:
        raise ValueError(
            "omega_dot is 0: no apsidal signal; give masses or a target with omega_dot"
        )
    t_aps = apsidal_period_s(omega_dot_rad_s)
    baseline = np.linspace(0.0, 2.5 * t_aps, 600)
    days = baseline / 86400.0
    fig, ax = plt.subplots(figsize=(8, 4.5))
    styles = ("-", "--", ":", "-.")
    colours = plt.get_cmap("viridis")(np.linspace(0, 0.9, len(omega1_values)))
    for j, w1 in enumerate(omega1_values):
        for i, e in enumerate(e_values):
            dv = delta_v_aps(k1_m_s, e, w1, omega_dot_rad_s, baseline) / 1e3
            label = f"ω₁={w1:.2f} rad" if i == 0 else None
            ax.plot(days, dv, color=colours[j], ls=styles[i % len(styles)], lw=1.2, label=label)
    for i, e in enumerate(e_values):
        ax.plot([], [], color="grey", ls=styles[i % len(styles)], label=f"e={e:g}")
    if target_e is not None and target_omega1 is not None:
        dv = delta_v_aps(k1_m_s, target_e, target_omega1, omega_dot_rad_s, baseline) / 1e3
        label = f"target e={target_e:.3g}, ω₁={target_omega1:.2f} rad"
        ax.plot(days, dv, color="k", lw=2.2, label=label)
    ax.axvline(t_aps / 86400.0, color="k", ls="--", lw=0.8, label="apsidal period 2π/ω̇")
    ax.set_xlabel("baseline ΔT = t_β − t_α [days]")
    ax.set_ylabel("Δv_aps [km/s]")
    ax.set_title(title or f"apsidal signal, K₁ = {k1_m_s / 1e3:.0f} km/s")
    ax.legend(fontsize=7, ncol=2, loc="upper right")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
