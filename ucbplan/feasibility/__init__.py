"""Expected signal sizes before observing (paper Sec. 3): K_j, ω̇, Δv_aps, Δv_CM, timing errors.

- :mod:`.signals`: the Sec. 3 physics, one pure function per equation;
- :mod:`.report`: :class:`FeasibilityReport` for one binary or one loaded target;
- :mod:`.plots`: the apsidal-signal figure.
"""

from ucbplan.feasibility.plots import plot_apsidal_signal, plot_report
from ucbplan.feasibility.report import FeasibilityReport, feasibility_report, report_for_target
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
    optical_ephemeris,
    optical_timing_s,
    semi_amplitudes,
    tau_chirp_gr_s,
    tertiary_acceleration,
    tidal_deformability,
)

__all__ = [
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
    "optical_ephemeris",
    "optical_timing_s",
    "plot_apsidal_signal",
    "plot_report",
    "report_for_target",
    "semi_amplitudes",
    "tau_chirp_gr_s",
    "tertiary_acceleration",
    "tidal_deformability",
]
