"""Target builders shared by the tests (and the benchmarks)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ucbplan.core.constants import YEAR_S


def random_targets(n: int, seed: int) -> tuple[np.ndarray, ...]:
    """Circular and (ω̇ = 0) eccentric targets with correlated covariances; 30 % timing-like."""
    rng = np.random.default_rng(seed)
    f = 10 ** rng.uniform(-3.5, -2, n)
    fd = f ** (11 / 3) * 10 ** rng.uniform(-6, -4.5, n)
    pars = np.zeros((n, 7))
    pars[:, 0], pars[:, 1], pars[:, 2] = rng.uniform(0, 2 * math.pi, n), f, fd
    pars[:, 3] = rng.choice([0.0, 1.0], n) * 11 / 3 * fd**2 / f
    ecc = rng.random(n) < 0.5
    pars[ecc, 4:6] = rng.normal(0, 0.01, (ecc.sum(), 2))
    sig = np.column_stack(
        [
            10 ** rng.uniform(-3, -0.5, n),
            10 ** rng.uniform(-12, -9, n),
            10 ** rng.uniform(-20, -17, n),
            np.where(pars[:, 3] != 0, 10 ** rng.uniform(-28, -26, n), 0),
            np.where(ecc, 1e-3, 0),
            np.where(ecc, 1e-3, 0),
            np.where(ecc, 1e-9, 0),
        ]
    )
    a = rng.normal(size=(n, 7, 7))
    corr = a @ np.swapaxes(a, 1, 2) + 7 * np.eye(7)
    d = np.sqrt(np.einsum("nii->ni", corr))
    covs = corr / (d[:, :, None] * d[:, None, :]) * sig[:, :, None] * sig[:, None, :]
    t_obs = np.where(rng.random(n) < 0.3, 0.0, 4 * YEAR_S)
    thr = 10 ** rng.uniform(-2, 0, n)
    return pars, covs, t_obs, thr


BASE = {
    "name": "Test",
    "sky": {"ra": "08h06m23.2s", "dec": "+15d27m30s"},
    "lisa": {
        "t_ref": "2037-01-01T00:00:00",
        "t_obs": "126232599.05 s",
        "phase": 5.5,
        "f_gw": "6.2204944286e-3 Hz",
        "fdot": "7.073958e-16 Hz / s",
        "covariance": {"sigma": {"phase": 0.02, "f_gw": "7.7e-12 Hz"}},
    },
}


def ztf_j1539_doc(
    name: str = "ZTF J1539+5027 (test input)",
    *,
    pdot: float | str = -2.373e-11,
    spectroscopy: bool = True,
) -> dict[str, Any]:
    """ZTF J1539+5027's timing ephemeris as quoted in issue 10 (Burdge et al. 2019, Nature 571,
    528), as a target document: TEST INPUT, not a catalog entry. A fresh copy on every call.

    Parameters
    ----------
    name : str
        The document's ``name``.
    pdot : float or str
        Ṗ [s/s] as written in the file (a float, or the string form a test wants to read).
    spectroscopy : bool
        Add the issue's SB2 spectroscopy block (K1 = 300, K2 = 870, σ_v = 20 km/s).
    """
    doc: dict[str, Any] = {
        "name": name,
        "sky": {"ra": "15h39m32.16s", "dec": "+50d27m38.8s"},
        "timing": {
            "t0": "BJD_TDB 2458305.6827886",
            "t0_marks": "primary_eclipse",
            "period": "414.7915404 s",
            "pdot": pdot,
            "covariance": {"sigma": {"t0": "8.4e-6 d", "period": "2.9e-6 s", "pdot": 5.0e-14}},
            "source": "Burdge et al. 2019, Nature 571, 528",
        },
    }
    if spectroscopy:
        doc["spectroscopy"] = {
            "lines": "SB2",
            "K1": "300 km/s",
            "K2": "870 km/s",
            "sigma_v": "20 km/s",
        }
    return doc
