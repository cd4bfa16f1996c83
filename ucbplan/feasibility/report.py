"""Every Sec. 3 magnitude for one binary, as the ``ucbplan feasibility`` command reports them.

:func:`feasibility_report` works from plain numbers; :func:`report_for_target` takes a loaded
target, lets explicit values override the file and adds the GW and optical timing errors.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, replace
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from ucbplan.core.constants import YEAR_S
from ucbplan.feasibility.signals import (
    OpticalEphemeris,
    apsidal_period_s,
    delta_k_bound,
    delta_v_aps,
    delta_v_cm,
    eccentricity_floor,
    gw_timing_s,
    omega_dot_gr,
    omega_dot_tide,
    optical_timing_s,
    semi_amplitudes,
    tau_chirp_gr_s,
    tertiary_acceleration,
)

if TYPE_CHECKING:
    from ucbplan.targets import Target

#: Default velocity precision per spectrum when neither the caller nor the target gives one [m/s].
DEFAULT_SIGMA_V_M_S = 15e3
#: Default rows of the timing table: ΔT after the reference epoch (LISA midpoint or T0) [Julian yr].
TIMING_YEARS = (0.0, 1.0, 2.0, 4.0, 6.0, 8.0, 10.0)


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


class _MassTerms(NamedTuple):
    """What the component masses give: K_1, K_2 [m/s] and ω̇_GR, ω̇_tide [rad/s]."""

    k1: float | None
    k2: float | None
    w_gr: float | None
    w_tide: float | None


class _K1Signals(NamedTuple):
    """Velocity signals that scale with K_1 [m/s] and the eccentricity floor [1]."""

    delta_k: float | None
    dv_aps_max: float | None
    dv_aps: float | None
    e_floor: float | None


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
    sigma_v_m_s: float = DEFAULT_SIGMA_V_M_S,
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
    # Long only by its keywords and the report's fields, one per line; the steps are helpers.
    notes: list[str] = []
    mass = _mass_terms(m1_msun, m2_msun, period_s, sin_i, e, notes)
    k1 = mass.k1 if mass.k1 is not None else k1_m_s
    w_used, w_src = _apsidal_rate(omega_dot_target, mass.w_gr, mass.w_tide)
    tau, tau_src = _chirp_time(f_gw_hz, fdot_hz_s, m1_msun, m2_msun)
    sig = _k1_signals(k1, e, omega0_rad, w_used, tau, baseline_s, sigma_v_m_s, n_spectra)
    a_tertiary = tertiary_acceleration(m3_msun, a_out_au)
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
        k2_m_s=mass.k2,
        omega_dot_gr=mass.w_gr,
        omega_dot_tide=mass.w_tide,
        omega_dot_used=w_used,
        omega_dot_source=w_src,
        apsidal_period_s=apsidal_period_s(w_used),
        tau_chirp_s=tau,
        tau_chirp_source=tau_src,
        baseline_s=baseline_s,
        delta_k_m_s=sig.delta_k,
        delta_v_aps_max_m_s=sig.dv_aps_max,
        delta_v_aps_m_s=sig.dv_aps,
        sigma_v_m_s=sigma_v_m_s,
        n_spectra=n_spectra,
        e_floor=sig.e_floor,
        a_cm_galactic=a_cm_galactic,
        delta_v_cm_galactic_m_s=float(delta_v_cm(a_cm_galactic, baseline_s)),
        m3_msun=m3_msun,
        a_out_au=a_out_au,
        delta_v_cm_tertiary_m_s=float(delta_v_cm(a_tertiary, baseline_s)),
        notes=notes,
    )


def _mass_terms(
    m1_msun: float | None,
    m2_msun: float | None,
    period_s: float,
    sin_i: float | None,
    e: float,
    notes: list[str],
) -> _MassTerms:
    """K_j and the apsidal rates from the masses; says in ``notes`` what could not be computed."""
    if m1_msun is None or m2_msun is None:
        notes.append("no masses: pass --m1/--m2 for K_j, omega_dot_GR/tide and tau_chirp")
        return _MassTerms(None, None, None, None)
    w_gr = omega_dot_gr(m1_msun + m2_msun, period_s, e)
    w_tide = omega_dot_tide(m1_msun, m2_msun, period_s, e)
    if sin_i is None:
        notes.append(
            "no inclination: K_j not computed; give lisa.cos_inclination or timing.inclination "
            "in the target file"
        )
        return _MassTerms(None, None, w_gr, w_tide)
    k1, k2 = semi_amplitudes(m1_msun, m2_msun, period_s, sin_i, e)
    return _MassTerms(k1, k2, w_gr, w_tide)


def _apsidal_rate(
    omega_dot_target: float, w_gr: float | None, w_tide: float | None
) -> tuple[float, str]:
    """ω̇ for the apsidal signal [rad/s] and where it came from (LISA's, else GR + tide, else 0)."""
    if omega_dot_target != 0.0:
        return omega_dot_target, "target file"
    if w_gr is not None and w_tide is not None:
        return w_gr + w_tide, "GR + tide from masses"
    return 0.0, "none"


def _chirp_time(
    f_gw_hz: float, fdot_hz_s: float | None, m1_msun: float | None, m2_msun: float | None
) -> tuple[float | None, str]:
    """τ_chirp [s] and its source: the measured f/ḟ, else GR from the masses, else unknown."""
    if fdot_hz_s is not None and fdot_hz_s != 0.0:
        return f_gw_hz / abs(fdot_hz_s), "f/fdot of the target"
    if m1_msun is not None and m2_msun is not None:
        return tau_chirp_gr_s(m1_msun, m2_msun, f_gw_hz), "GR from masses"
    return None, "none"


def _k1_signals(
    k1: float | None,
    e: float,
    omega0_rad: float,
    omega_dot: float,
    tau_chirp_s: float | None,
    baseline_s: float,
    sigma_v_m_s: float,
    n_spectra: int,
) -> _K1Signals:
    """ΔK bound, max and actual Δv_aps over the baseline and the e floor (None without K_1)."""
    if k1 is None:
        return _K1Signals(None, None, None, None)
    dk = delta_k_bound(k1, baseline_s, tau_chirp_s) if tau_chirp_s is not None else None
    return _K1Signals(
        delta_k=dk,
        dv_aps_max=2.0 * k1 * e,
        dv_aps=float(delta_v_aps(k1, e, omega0_rad, omega_dot, baseline_s)),
        e_floor=eccentricity_floor(sigma_v_m_s, k1, n_spectra),
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
    timing_years: tuple[float, ...] = TIMING_YEARS,
) -> FeasibilityReport:
    """:func:`feasibility_report` for a loaded target; explicit values override the target file.

    ``optical_offset_s`` is the target's reference epoch (the LISA midpoint, or T0 of a timing
    ephemeris) minus the optical ephemeris reference epoch, so the optical ΔT at a given date is
    ΔT_target + offset (0: both referenced to the same epoch). Timing rows are ΔT after the
    target's reference epoch in Julian years; for a timing target the "GW" column is the timing
    ephemeris's own error (its T0, P, Ṗ covariance), the same phase model.
    """
    p = target.params
    cos_i = target.cos_inclination
    report = feasibility_report(
        name=target.name,
        period_s=target.period_s,
        f_gw_hz=p.f_gw,
        sin_i=math.sqrt(1.0 - cos_i**2) if cos_i is not None else None,
        e=p.eccentricity,
        omega0_rad=p.omega_rad,
        omega_dot_target=p.omega_dot,
        fdot_hz_s=p.fdot,
        m1_msun=m1_msun if m1_msun is not None else target.m1_msun,
        m2_msun=m2_msun if m2_msun is not None else target.m2_msun,
        k1_m_s=_file_k1_m_s(target),
        sigma_v_m_s=sigma_v_m_s if sigma_v_m_s is not None else _file_sigma_v_m_s(target),
        n_spectra=n_spectra,
        baseline_s=baseline_s,
        m3_msun=m3_msun,
        a_out_au=a_out_au,
    )
    return _with_timing(report, target, optical, optical_offset_s, timing_years)


def _file_sigma_v_m_s(target: Target) -> float:
    """The target file's velocity precision [m/s], else :data:`DEFAULT_SIGMA_V_M_S`."""
    spec = target.spectroscopy
    sv = spec.sigma_v_kms if spec is not None else None
    return sv * 1e3 if sv is not None else DEFAULT_SIGMA_V_M_S


def _file_k1_m_s(target: Target) -> float | None:
    """K_1 from the target file's spectroscopy block [m/s], if given."""
    spec = target.spectroscopy
    return spec.K1_kms * 1e3 if (spec is not None and spec.K1_kms is not None) else None


def _with_timing(
    report: FeasibilityReport,
    target: Target,
    optical: OpticalEphemeris | None,
    optical_offset_s: float,
    timing_years: tuple[float, ...],
) -> FeasibilityReport:
    """``report`` with the GW (full covariance) and optical timing errors at ``timing_years``."""
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
