"""Fisher-matrix forecast of the targeted-search parameters with the same waveform.

F_ij = (dh/dtheta_i | dh/dtheta_j), derivatives by central differences (the waveform is exactly
linear in eta and kappa, so their columns are exact). Step sizes are a small fraction of the
expected posterior width so that the O(step^2) truncation error is < 1e-4 relative.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ucbplan.lisa.likelihood import Likelihood

__all__ = ["STEPS", "fisher_matrix", "whitening"]

#: Central-difference steps in sampled coordinates (same order as ECCENTRIC_NAMES); f_gw is in
#: units of 1/T and scaled at run time.
STEPS: dict[str, float] = {
    "log10_amplitude": 1e-5,
    "f_gw": 1e-4,
    "log10_fdot": 1e-6,
    "cos_inclination": 1e-5,
    "psi": 1e-6,
    "phase": 1e-6,
    "eta": 1e-5,
    "kappa": 1e-5,
    "z_omega": 1e-4,
}


def fisher_matrix(like: Likelihood, theta0: NDArray[np.float64]) -> NDArray[np.float64]:
    """Fisher information (D, D) at ``theta0`` in sampled coordinates.

    Parameters
    ----------
    like : Likelihood
        Supplies the templates and the noise-weighted inner product.
    theta0 : numpy.ndarray
        Sampled parameters (D,) (start epoch).
    """
    names = like.prior.names
    steps = np.array([STEPS[n] for n in names])
    steps[names.index("f_gw")] /= like.model.grid.t_obs_s
    d = len(names)
    pts = np.repeat(theta0[None, :], 2 * d, axis=0)
    for i in range(d):
        pts[2 * i, i] += steps[i]
        pts[2 * i + 1, i] -= steps[i]
    h = like.templates(pts)
    deriv = (h[0::2] - h[1::2]) / (2.0 * steps[:, None, None, None])
    fis = np.empty((d, d))
    for i in range(d):
        fis[i] = like.inner(deriv[i][None], deriv)
    return 0.5 * (fis + fis.T)


def whitening(cov: NDArray[np.float64]) -> NDArray[np.float64]:
    """Lower Cholesky factor L of ``cov`` (C = L L^T): theta = theta0 + L x whitens the posterior.

    Uses correlation scaling first (C = s R s) so that parameters with tiny absolute widths
    (f_gw: 1e-11 Hz) do not spoil the factorisation.
    """
    s = np.sqrt(np.diag(cov))
    corr = cov / np.outer(s, s)
    return np.asarray(s[:, None] * np.linalg.cholesky(0.5 * (corr + corr.T)))
