"""Finite phase averaging (Appendix B): attenuation of K and of the eccentricity terms.

A spectrum (or a co-add) records the velocity averaged over the orbital arc it spans. For a
uniformly weighted window of width Δt centred on the anchor, ``cos u`` is attenuated by
Λ_K = sin x / x and the eccentricity terms (twice the orbital rate) by Λ_κ = sin 2x / 2x, with
x = n̄_b Δt / 2 and n̄_b = π f_GW the mean orbital rate. ``numpy.sinc`` is sin(πx)/(πx): every
function here converts explicitly.
"""

from __future__ import annotations

import math
import re

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ucbplan.errors import UcbplanError

FloatArray = NDArray[np.float64]


def _sinc(x: ArrayLike) -> FloatArray:
    """sin(x)/x with the removable singularity at 0 (numpy.sinc is normalised by π)."""
    return np.asarray(np.sinc(np.asarray(x, dtype=np.float64) / math.pi), dtype=np.float64)


def lambda_k(dt_s: ArrayLike, n_bar: ArrayLike) -> FloatArray:
    """Λ_K = sin(x)/x, x = n̄_b Δt/2: attenuation of K by a uniform window of width Δt.

    Parameters
    ----------
    dt_s : array_like
        Window width Δt_bin (or exposure time) [s].
    n_bar : array_like
        Mean orbital angular rate n̄_b = π f_GW [rad/s].

    Notes
    -----
    Eq. Lambda_K (Appendix B); Eq. Deltav_smear for a single exposure.
    """
    return _sinc(np.asarray(n_bar) * np.asarray(dt_s) / 2.0)


def lambda_kappa(dt_s: ArrayLike, n_bar: ArrayLike) -> FloatArray:
    """Λ_κ = sin(2x)/(2x), x = n̄_b Δt/2: attenuation of the κ, η terms (twice the orbital rate).

    Notes
    -----
    Eq. Lambda_kappa (Appendix B).
    """
    return _sinc(np.asarray(n_bar) * np.asarray(dt_s))


def comb_attenuation(
    exptime_s: float, readout_s: float, n_exp: int, n_bar: float, harmonic: int = 1
) -> float:
    """Attenuation of the ``harmonic``-th orbital harmonic by a comb of equal exposures.

    ``n_exp`` exposures of ``exptime_s`` separated by ``readout_s`` gaps, equally weighted and
    centred on the anchor: Λ = sinc(h n̄ T/2) · (1/n) Σ_i cos(h n̄ δ_i), δ_i the exposure centres
    relative to the block centre. For ``readout_s = 0`` this equals the paper's uniform window
    sinc(h n̄ Δt/2) with Δt = n T (Eq. Lambda_K for h = 1, Eq. Lambda_kappa for h = 2).

    Parameters
    ----------
    exptime_s, readout_s : float
        Single-exposure time and dead time between exposures [s].
    n_exp : int
        Number of exposures (≥ 1).
    n_bar : float
        Mean orbital rate π f_GW [rad/s].
    harmonic : {1, 2}
        1 for Λ_K, 2 for Λ_κ.
    """
    if n_exp < 1:
        raise UcbplanError(f"n_exp must be >= 1, got {n_exp}")
    w = harmonic * n_bar
    centres = (np.arange(n_exp) - (n_exp - 1) / 2.0) * (exptime_s + readout_s)
    return float(_sinc(w * exptime_s / 2.0) * np.mean(np.cos(w * centres)))


def smear_velocity(k_kms: ArrayLike, lam_k: ArrayLike) -> FloatArray:
    """Velocity smear Δv_smear = K (1 − Λ_K) [same unit as K].

    Notes
    -----
    Eq. Deltav_smear; ≈ K (n̄Δt)²/24 for n̄Δt ≪ 1 (Eq. Deltav_smear_est).
    """
    return np.asarray(k_kms, dtype=np.float64) * (1.0 - np.asarray(lam_k, dtype=np.float64))


_BUDGET_RE = re.compile(r"^\s*(?:([0-9.eE+-]+)\s*\*\s*)?sigma_v\s*$")


def parse_smear_budget(text: str, sigma_v_kms: float | None) -> float:
    """Parse ``--max-smear``: ``"0.5*sigma_v"``, ``"sigma_v"``, ``"2 km/s"`` or ``"2"`` (km/s).

    Returns
    -------
    float
        Budget [km/s].

    Raises
    ------
    UcbplanError
        For unparsable text, non-positive budgets or ``sigma_v`` without a known σ_v.
    """
    match = _BUDGET_RE.match(text)
    if match:
        if sigma_v_kms is None:
            raise UcbplanError(
                f"max_smear {text!r} needs sigma_v: give `sigma_v` or spectroscopy.sigma_v "
                "in the target file"
            )
        factor = float(match.group(1)) if match.group(1) else 1.0
        value = factor * sigma_v_kms
    else:
        cleaned = text.strip().lower().replace("km/s", "").replace("kms", "").strip()
        try:
            value = float(cleaned)
        except ValueError:
            raise UcbplanError(
                f"max_smear: expected e.g. '0.5*sigma_v' or '2 km/s', got {text!r}"
            ) from None
    if not (value > 0 and math.isfinite(value)):
        raise UcbplanError(f"max_smear must be positive, got {text!r}")
    return value
