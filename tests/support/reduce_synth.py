"""Exact-Keplerian synthetic velocities for the reduce tests and benchmarks."""

from __future__ import annotations

import math

import numpy as np

from ucbplan.core import ephemeris
from ucbplan.core.params import PhaseParams

FIDUCIAL = {
    "name": "synthetic fiducial",
    "sky": {"ra": "108.3181849 deg", "dec": "-55.6516852 deg"},
    "lisa": {
        "t_ref": "2037-01-01T00:00:00",
        "t_obs": "126232599.05 s",
        "phase": 2.410235,
        "f_gw": "8.4062899940e-3 Hz",
        "fdot": "1.640367e-15 Hz / s",
        "eta": 8.249643e-3,
        "kappa": 4.524585e-3,
        "omega_dot": "1.496836e-6 rad / s",
        "cos_inclination": 0.09316104,
        "amplitude": 10**-21.309,
        "covariance": {
            "sigma": {
                "phase": 0.001978,
                "f_gw": "5.5e-12 Hz",
                "fdot": "3.41e-19 Hz / s",
                "eta": 5.38244e-4,
                "kappa": 5.41031e-4,
                "omega_dot": "1.505e-9 rad / s",
            },
            "correlation": {"phase,fdot": -0.7},
        },
    },
    "spectroscopy": {"lines": "SB2", "K1": "585.3 km/s", "K2": "712.6 km/s", "sigma_v": "15 km/s"},
}


def solve_kepler(M: np.ndarray, e: float | np.ndarray) -> np.ndarray:
    """Eccentric anomaly E with E − e sin E = M (Newton, |residual| < 1e-14)."""
    E = np.array(M, dtype=float, copy=True)
    for _ in range(50):
        d = (E - e * np.sin(E) - M) / (1.0 - e * np.cos(E))
        E -= d
        if np.max(np.abs(d)) < 1e-15:
            break
    return E


def make_target(circular: bool = False, **lisa: object):  # type: ignore[no-untyped-def]
    """Fiducial target (optionally circular: η = κ = ω̇ = 0) via the lead's target parser."""
    from ucbplan.targets import target_from_dict

    doc = {**FIDUCIAL, "lisa": {**FIDUCIAL["lisa"], **lisa}}  # type: ignore[dict-item]
    if circular:
        doc["lisa"] |= {"eta": 0.0, "kappa": 0.0, "omega_dot": "0 rad/s"}  # type: ignore[operator]
        sig = dict(doc["lisa"]["covariance"]["sigma"])  # type: ignore[index]
        for k in ("eta", "kappa", "omega_dot"):
            sig.pop(k)
        doc["lisa"]["covariance"] = {"sigma": sig, "correlation": {"phase,fdot": -0.7}}  # type: ignore[index]
    return target_from_dict(doc)


def exact_factor(p: PhaseParams, tau: np.ndarray, *, ecc: bool = True) -> np.ndarray:
    """Exact cos u + e cos ω of star 1 at τ (truth of F)."""
    phi = ephemeris.phase_asc(p, tau)
    eta, kap = ephemeris.ll_pair(p, tau)
    e = np.hypot(eta, kap)
    om = np.arctan2(eta, kap)
    if not ecc:
        return np.cos(phi)
    E = solve_kepler(phi - om, e)
    nu = 2.0 * np.arctan2(np.sqrt(1 + e) * np.sin(E / 2), np.sqrt(1 - e) * np.cos(E / 2))
    return np.asarray(np.cos(om + nu) + kap, dtype=float)


def exposure_factor(p: PhaseParams, tau_mid: np.ndarray, dt_s: np.ndarray | float) -> np.ndarray:
    """Window average of :func:`exact_factor` (24-node Gauss–Legendre)."""
    x, w = np.polynomial.legendre.leggauss(24)
    dt = np.broadcast_to(np.asarray(dt_s, float), np.shape(tau_mid))
    t = tau_mid[:, None] + 0.5 * dt[:, None] * x[None, :]
    vals = exact_factor(p, t.ravel()).reshape(t.shape)
    return np.asarray((vals * w).sum(axis=1) / 2.0, dtype=float)


def session_times(p: PhaseParams, tau0: float, n_orbits: int = 60, per_orbit: int = 8):
    """Contiguous exposures of P_b/per_orbit over n_orbits orbits starting at τ0 (paper Sec. 5)."""
    pb = 2.0 * math.pi / (math.pi * p.f_gw - p.omega_dot)
    dt = pb / per_orbit
    tau = tau0 + (np.arange(n_orbits * per_orbit) + 0.5) * dt
    return tau, dt
