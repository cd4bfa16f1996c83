"""The summary ``ucbplan validate`` prints of a target: its phase model and its uncertainties."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ucbplan.targets import Target


def summary(t: Target) -> dict[str, Any]:
    """The validate row of one target: times as TDB ISO strings, the rest SI floats."""
    from astropy.time import TimeDelta

    if t.kind == "timing":
        return _timing_summary(t)
    from ucbplan.core.forecast import sigma_u_end
    from ucbplan.core.phase import ascending_node_s, sigma_ascending_node_s

    p = t.params
    t_asc = t.t_ref + TimeDelta(ascending_node_s(p), format="sec")
    sigmas = {n: float(math.sqrt(t.cov_matrix[i, i])) for i, n in enumerate(t.cov_names)}
    if t.samples_covariance is not None and t.covariance_source.startswith("samples"):
        sigmas |= _samples_sigmas(t.covariance)
    return {
        "name": t.name,
        "file": str(t.source.name) if t.source else "",
        "t_ref_tdb": t.t_ref.tdb.isot,
        "t_end_tdb": t.t_end.tdb.isot,
        "period_s": p.period_s,
        "period_asc_s": 2 / p.f_gw,
        "eccentricity": p.eccentricity,
        "omega_deg": math.degrees(p.omega_rad),
        "omega_dot_rad_s": p.omega_dot,
        "t_asc_tdb": t_asc.tdb.isot,
        "sigma_t_asc_s": sigma_ascending_node_s(p, t.covariance),
        "sigma_u_end_mrad": 1e3 * sigma_u_end(t, "quadrature"),
        "sigmas": sigmas,
        "covariance_from": t.covariance_source,
    }


def _samples_sigmas(cov: Any) -> dict[str, float]:
    """σ of each sampled phase-model parameter from the samples' covariance (SI)."""
    from ucbplan.core.params import PARAM_NAMES

    return {n: float(math.sqrt(cov[k, k])) for k, n in enumerate(PARAM_NAMES) if cov[k, k] > 0}


def _timing_summary(t: Target) -> dict[str, Any]:
    """The validate row of a timing ephemeris: T0, P, Ṗ (P̈) with σ, σ_u at ±1 yr."""
    import numpy as np

    from ucbplan.core.constants import YEAR_S
    from ucbplan.core.forecast import anchor_sigma_u
    from ucbplan.core.timing_epochs import format_bjd_tdb

    assert t.timing is not None  # kind == "timing" guarantees the section
    sec, e, p = t.timing, t.timing.ephemeris, t.params
    tau = np.array([-YEAR_S, YEAR_S])
    sig = np.maximum(
        anchor_sigma_u(p, t.covariance, tau, 0.0), anchor_sigma_u(p, t.covariance, tau, math.pi)
    )
    rate = math.pi * (p.f_gw + p.fdot * tau + p.fddot * tau**2 / 2)
    sig_t = sig / np.abs(rate)
    return {
        "name": t.name,
        "file": str(t.source.name) if t.source else "",
        "kind": "timing",
        "t0_tdb": t.t_ref.tdb.isot,
        "t0_bjd_tdb": format_bjd_tdb(t.t_ref).split()[1],
        "sigma_t0_s": sec.sigma("t0"),
        "t0_marks": e.mark,
        "period_s": e.period_s,
        "sigma_period_s": sec.sigma("period"),
        "pdot": e.pdot,
        "sigma_pdot": sec.sigma("pdot"),
        "pddot_per_s": e.pddot,
        "sigma_pddot_per_s": sec.sigma("pddot"),
        "eccentricity": p.eccentricity,
        "omega_deg": math.degrees(p.omega_rad),
        "omega_dot_rad_s": p.omega_dot,
        "sigma_u_before_1yr_mrad": 1e3 * float(sig[0]),
        "sigma_u_after_1yr_mrad": 1e3 * float(sig[1]),
        "sigma_t_before_1yr_s": float(sig_t[0]),
        "sigma_t_after_1yr_s": float(sig_t[1]),
        "source": sec.source,
    }
