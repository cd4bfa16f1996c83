"""Fisher-matrix forecast of the targeted-search parameters with the same waveform.

F_ij = (dh/dtheta_i | dh/dtheta_j), derivatives by central differences (the waveform is exactly
linear in eta and kappa, so their columns are exact). Step sizes are a small fraction of the
expected posterior width so that the O(step^2) truncation error is < 1e-4 relative.

Inverting F and whitening with its inverse go through :mod:`ucbplan.core.mvnormal`
(correlation-scaled), like every covariance in ucbplan. A parameter the data do not constrain
(face-on: phase and psi are degenerate; a faint source: all of them) raises a
:class:`~ucbplan.errors.NumericalError` naming it instead of returning NaN or a σ wider than
the prior.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ucbplan.core.mvnormal import correlation_split, inverse_scaled, sqrt_factor
from ucbplan.errors import NumericalError
from ucbplan.lisa.likelihood import Likelihood

#: Largest condition number of the Fisher correlation matrix that is still inverted: beyond it a
#: combination of parameters is unconstrained (round-off alone gives ~1e-16 relative errors).
MAX_CONDITION = 1e10
#: User-facing names of the sampled coordinates (error messages).
_LABELS = {"log10_amplitude": "amplitude", "log10_fdot": "fdot", "z_omega": "omega_dot"}

#: Central-difference steps in sampled coordinates (same order as ECCENTRIC_NAMES); f_gw is in
#: units of 1/T and a linear fdot in units of 1/T^2 (a phase step pi * 1e-5 rad), scaled at run
#: time.
STEPS: dict[str, float] = {
    "log10_amplitude": 1e-5,
    "f_gw": 1e-4,
    "log10_fdot": 1e-6,
    "fdot": 1e-5,
    "cos_inclination": 1e-5,
    "psi": 1e-6,
    "phase": 1e-6,
    "eta": 1e-5,
    "kappa": 1e-5,
    "z_omega": 1e-4,
}


def fisher_points(
    names: tuple[str, ...], t_obs_s: float, theta0: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The central-difference points (2D, D) around ``theta0`` and their steps (D,).

    Rows 2i and 2i + 1 are ``theta0`` ± step i (sampled coordinates, :data:`STEPS`; f_gw in
    units of 1/T and a linear fdot in units of 1/T², scaled by ``t_obs_s`` here).
    """
    steps = np.array([STEPS[n] for n in names])
    steps[names.index("f_gw")] /= t_obs_s
    if "fdot" in names:
        steps[names.index("fdot")] /= t_obs_s * t_obs_s
    d = len(names)
    pts = np.repeat(theta0[None, :], 2 * d, axis=0)
    for i in range(d):
        pts[2 * i, i] += steps[i]
        pts[2 * i + 1, i] -= steps[i]
    return pts, steps


def fisher_from_templates(
    like: Likelihood, h: NDArray[np.complex128], steps: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Fisher information (D, D) from the templates ``h`` (2D, bands, 2, N) at the points of
    :func:`fisher_points` and their ``steps``, with the likelihood's inner product."""
    d = steps.size
    deriv = (h[0::2] - h[1::2]) / (2.0 * steps[:, None, None, None])
    fis = np.empty((d, d))
    for i in range(d):
        fis[i] = like.inner(deriv[i][None], deriv)
    return np.asarray(0.5 * (fis + fis.T), dtype=np.float64)


def fisher_matrix(like: Likelihood, theta0: NDArray[np.float64]) -> NDArray[np.float64]:
    """Fisher information (D, D) at ``theta0`` in sampled coordinates.

    Parameters
    ----------
    like : Likelihood
        Supplies the templates and the noise-weighted inner product.
    theta0 : numpy.ndarray
        Sampled parameters (D,) (start epoch).
    """
    pts, steps = fisher_points(like.prior.names, like.model.grid.t_obs_s, theta0)
    return fisher_from_templates(like, like.templates(pts), steps)


def fisher_covariance(
    like: Likelihood,
    theta0: NDArray[np.float64],
    where: str = "source",
    *,
    within_prior: bool = True,
    fisher: NDArray[np.float64] | None = None,
) -> NDArray[np.float64]:
    """Inverse Fisher matrix at ``theta0`` (sampled coordinates), checked.

    Parameters
    ----------
    like : Likelihood
        Templates, inner product and the prior (its widths bound a meaningful σ).
    theta0 : numpy.ndarray
        Sampled parameters (D,) (start epoch).
    where : str
        Prefix of the error message (the target file).
    within_prior : bool
        Also require every 1σ to be narrower than the parameter's prior (the sampler's whitening
        needs it; a forecast reports it with :func:`prior_excess` instead).
    fisher : numpy.ndarray, optional
        The Fisher matrix at ``theta0`` if already computed (default: :func:`fisher_matrix`).

    Raises
    ------
    NumericalError
        "unconstrained": the Fisher matrix is not finite, singular (a degenerate combination,
        e.g. phase and psi of a face-on source), or (``within_prior``) gives a parameter a 1σ
        wider than its prior.
    """
    names = like.prior.names
    fis = fisher_matrix(like, theta0) if fisher is None else fisher
    _check_conditioned(fis, like, theta0, where)
    try:
        cov = inverse_scaled(fis)
    except np.linalg.LinAlgError:
        raise _unconstrained(where, names, np.arange(len(names)), like, theta0) from None
    if within_prior:
        excess = prior_excess(like, theta0, cov, where)
        if excess is not None:
            raise excess
    return cov


def _check_conditioned(
    fis: NDArray[np.float64], like: Likelihood, theta0: NDArray[np.float64], where: str
) -> None:
    """The Fisher matrix is finite, positive on its diagonal and not near-singular.

    Raises
    ------
    NumericalError
        "unconstrained", naming the parameters concerned.
    """
    names = like.prior.names
    if not np.all(np.isfinite(fis)):
        raise _unconstrained(where, names, np.flatnonzero(~np.isfinite(np.diag(fis))), like, theta0)
    zero = np.flatnonzero(~(np.diag(fis) > 0))
    if zero.size:
        raise _unconstrained(where, names, zero, like, theta0)
    _, corr = correlation_split(fis)
    vals, vecs = np.linalg.eigh(corr)
    if not vals[0] > vals[-1] / MAX_CONDITION:
        # the weakest eigen-direction: the parameters that make it up are the degenerate ones
        weak = np.argsort(-np.abs(vecs[:, 0]))
        weak = weak[np.abs(vecs[weak, 0]) > 0.3]
        raise _unconstrained(where, names, weak, like, theta0)


def prior_excess(
    like: Likelihood,
    theta0: NDArray[np.float64],
    cov: NDArray[np.float64],
    where: str = "source",
) -> NumericalError | None:
    """The "unconstrained" error for parameters whose 1σ exceeds their prior width, or None."""
    names = like.prior.names
    width = np.asarray(like.prior.high) - np.asarray(like.prior.low)
    sigma = np.sqrt(np.diag(cov))
    wide = np.flatnonzero(~(sigma < width))
    if not wide.size:
        return None
    return _unconstrained(
        where, names, wide[np.argsort(-(sigma / width)[wide])], like, theta0, sigma
    )


def _unconstrained(
    where: str,
    names: tuple[str, ...],
    idx: NDArray[np.intp],
    like: Likelihood,
    theta0: NDArray[np.float64],
    sigma: NDArray[np.float64] | None = None,
) -> NumericalError:
    """One-line "unconstrained" error naming the parameters ``names[idx]`` and a likely cause."""
    which = list(dict.fromkeys(_LABELS.get(names[i], names[i]) for i in idx)) or list(names)
    if sigma is not None:
        i = int(idx[0])
        span = like.prior.high[i] - like.prior.low[i]
        what = f"{which[0]} unconstrained: the Fisher 1σ of {names[i]} ({sigma[i]:.3g}) exceeds "
        what += f"its prior width ({span:.3g})"
        what += f" (also {', '.join(which[1:])})" if len(which) > 1 else ""
    elif len(which) > 1:
        what = f"{', '.join(which)} unconstrained: degenerate (singular Fisher matrix)"
    else:
        what = f"{which[0]} unconstrained: the Fisher matrix has no usable information on it"
    cos_i = float(theta0[names.index("cos_inclination")])
    snr = float(like.snr(theta0[None])[0])
    if abs(cos_i) > 0.99 or (abs(cos_i) > 0.9 and {"phase", "psi"} <= set(which)):
        why = f"the source is nearly face-on (cos_inclination = {cos_i:.4g}): phase and psi mix"
    elif snr < 10.0:
        why = f"optimal SNR {snr:.3g}: too faint"
    else:
        why = f"the data (optimal SNR {snr:.3g}) do not measure it"
    return NumericalError(f"{where}: Fisher matrix: {what}; {why}")


def whitening(cov: NDArray[np.float64]) -> NDArray[np.float64]:
    """A with A Aᵀ = ``cov``: θ = θ0 + A x whitens the posterior (x ~ N(0, I) for θ ~ N(θ0, C)).

    :func:`ucbplan.core.mvnormal.sqrt_factor` (correlation-scaled) so that parameters with tiny
    absolute widths (f_gw: 1e-11 Hz) do not spoil the factorisation.
    """
    return sqrt_factor(cov)


def unwhiten(
    cov: NDArray[np.float64], root: NDArray[np.float64], delta: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Whitened x of offsets ``delta`` = θ − θ0 (rows), the inverse of θ = θ0 + A x.

    A⁻¹ = Aᵀ C⁻¹ for A Aᵀ = C, with C⁻¹ from :func:`ucbplan.core.mvnormal.inverse_scaled`: no
    raw solve on a matrix whose entries span many orders of magnitude.
    """
    inv_root = root.T @ inverse_scaled(cov)
    return np.asarray(delta @ inv_root.T, dtype=np.float64)
