"""Masses and derived quantities from K_1, K_2 and the LISA parameters (Secs. 3.1.2–3.1.3, 3.3, 5).

:func:`derive` evaluates the whole chain of :mod:`ucbplan.core.binary` relations for arrays of
Monte-Carlo samples (SI inside); :func:`summarize` turns sample arrays into median and 16/84 %
percentiles. The single relations and constants live in :mod:`ucbplan.core.binary` and
:mod:`ucbplan.core.constants`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ucbplan.core.binary import (
    MASS_RADIUS_MODELS,
    a_total_m,
    chirp_mass,
    chirp_mass_from_fdot,
    distance_from_amplitude_m,
    fdot_gw_only,
    kepler_total_mass,
    mass_from_omega_dot,
    omega_dot_gr,
    redshift_difference_orbital,
)
from ucbplan.core.constants import C_M_S, G_SI, KPC_M, MSUN_KG, RSUN_M

F64 = NDArray[np.float64]


def _f(x: ArrayLike) -> F64:
    return np.asarray(x, dtype=np.float64)


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
    K1_km_s, K2_km_s, gamma1_km_s, gamma2_km_s : ndarray
        Finite-window-corrected semi-amplitudes and intercepts [km/s] (γ None: no redshifts).
    f_hz, fdot_hz_s, eta, kappa, omega_dot, cos_i : ndarray
        LISA parameters at the reference epoch [Hz, Hz/s, 1, 1, rad/s] and cos ι [1].
    amplitude, mass_radius : ndarray or None, str or None
        GW strain amplitude 𝒜 for the distance; key of ``MASS_RADIUS_MODELS`` for the
        predicted redshift difference.

    Returns
    -------
    dict of ndarray
        Keys (units): n_b (rad/s), P_b (s), e (1), sin_i (1), a (m), M_tot, M1, M2, M_c (Msun),
        q (1), omega_dot_GR, omega_dot_remainder (rad/s), M_tot_omega_dot, M_c_fdot (Msun),
        fdot_GW_only, fdot_minus_GW_only (Hz/s), distance (kpc, if amplitude), gamma_diff,
        redshift_orbital, redshift_grav (km/s, if γ), R1, R2 (R_sun), redshift_grav_model and
        redshift_grav_minus_model (km/s, if model). Eqs. semimajor_axis_j, Kepler_mtot,
        M1M2_cir_and_ecc, omega_dot_GR, omega_dot_full, GW_amplitude, M_c_q; n_b = πf − ω̇.
    """
    out, m = _orbit(K1_km_s, K2_km_s, f_hz, omega_dot, eta, kappa, cos_i)
    out |= _gr_checks(m.mtot, m.mc, m.pb, out["e"], _f(omega_dot), fdot_hz_s, f_hz)
    if amplitude is not None:
        out["distance"] = distance_from_amplitude_m(m.mc, f_hz, amplitude) / KPC_M
    if gamma1_km_s is not None and gamma2_km_s is not None:
        out |= _redshifts(_f(gamma1_km_s) - _f(gamma2_km_s), m.m1, m.m2, m.a)
    if mass_radius is not None:
        out |= _model_redshift(mass_radius, m.m1, m.m2, out.get("redshift_grav"))
    return out


@dataclass(frozen=True, slots=True)
class _Masses:
    """The SI values the later steps of :func:`derive` use: P_b [s], a [m], M_tot, M1, M2 and
    M_c [kg]."""

    pb: F64
    a: F64
    mtot: F64
    m1: F64
    m2: F64
    mc: F64


def _orbit(
    K1_km_s: F64, K2_km_s: F64, f_hz: F64, omega_dot: F64, eta: F64, kappa: F64, cos_i: F64
) -> tuple[dict[str, F64], _Masses]:
    """n_b, P_b, e, sin ι, a and the dynamical masses (Msun in the dict, SI in ``_Masses``)."""
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
    out: dict[str, F64] = {"n_b": nb, "P_b": pb, "e": e, "sin_i": sin_i, "a": a}
    out |= {"M_tot": mtot / MSUN_KG, "q": q, "M1": m1 / MSUN_KG, "M2": m2 / MSUN_KG}
    out["M_c"] = mc / MSUN_KG
    return out, _Masses(pb, a, mtot, m1, m2, mc)


def _gr_checks(
    mtot: F64, mc: F64, pb: F64, e: F64, omega_dot: F64, fdot_hz_s: F64, f_hz: F64
) -> dict[str, F64]:
    """ω̇_GR and the remainder, the masses implied by ω̇ and ḟ alone, the GW-only ḟ (Sec. 3.3)."""
    od_gr = omega_dot_gr(mtot, pb, e)
    out: dict[str, F64] = {
        "omega_dot_GR": od_gr,
        "omega_dot_remainder": omega_dot - od_gr,
        "M_tot_omega_dot": mass_from_omega_dot(omega_dot, pb, e) / MSUN_KG,
        "M_c_fdot": chirp_mass_from_fdot(fdot_hz_s, f_hz, e) / MSUN_KG,
        "fdot_GW_only": fdot_gw_only(mc, f_hz, e),
    }
    out["fdot_minus_GW_only"] = _f(fdot_hz_s) - out["fdot_GW_only"]
    return out


def _redshifts(gamma_diff: F64, m1: F64, m2: F64, a: F64) -> dict[str, F64]:
    """γ1 − γ2 split into the orbital term and the gravitational redshift difference [km/s]."""
    orbital = redshift_difference_orbital(m1, m2, a) / 1e3
    return {
        "gamma_diff": gamma_diff,
        "redshift_orbital": orbital,
        "redshift_grav": gamma_diff - orbital,
    }


def _model_redshift(model: str, m1: F64, m2: F64, measured: F64 | None) -> dict[str, F64]:
    """Radii of a WD mass–radius relation and the predicted G(M1/R1 − M2/R2)/c [km/s]."""
    rfun = MASS_RADIUS_MODELS[model]
    r1 = rfun(m1 / MSUN_KG) * RSUN_M
    r2 = rfun(m2 / MSUN_KG) * RSUN_M
    out = {"R1": r1 / RSUN_M, "R2": r2 / RSUN_M}
    out["redshift_grav_model"] = G_SI * (m1 / r1 - m2 / r2) / C_M_S / 1e3
    if measured is not None:
        out["redshift_grav_minus_model"] = measured - out["redshift_grav_model"]
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
