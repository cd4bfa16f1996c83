"""Joint Monte Carlo over the LISA posterior and the (γ_j, K_j) regressions → masses (Sec. 5).

Each sample draws the LISA parameters (from the samples file if the target has one, else the
Gaussian posterior of the covariance) and (γ_j, K_j) from the regression covariance, moves K_j and
γ_j by the phase sensitivity −∂K/∂θ·δθ (re-regressing on the design of that θ), and evaluates
:func:`ucbplan.reduce.masses.derive` (SB2) or the mass function (SB1). The pieces are in
:mod:`ucbplan.reduce.mc_samples`; above :data:`CHUNK` samples :mod:`ucbplan.reduce.mc_chunked`
runs the same stream in chunks.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ucbplan.reduce import masses as _masses
from ucbplan.reduce.mc_chunked import chunked_monte_carlo
from ucbplan.reduce.mc_samples import (
    EXTRA_NAMES as EXTRA_NAMES,
)
from ucbplan.reduce.mc_samples import (
    MonteCarlo,
    _draw_k_gamma,
    block_sums,
    derive_samples,
    final_warnings,
    posterior_samples,
)

if TYPE_CHECKING:
    from ucbplan.reduce.regression import ComponentFit
    from ucbplan.targets import Target

F64 = NDArray[np.float64]
#: Samples per chunk above which the Monte Carlo runs chunked (~0.6 kB per sample in flight).
CHUNK = 250_000


def monte_carlo(
    target: Target,
    fits: tuple[ComponentFit, ...],
    dK: F64,
    dg: F64,
    *,
    n_samples: int,
    cos_i_sigma: float,
    mass_radius: str | None,
    rng: np.random.Generator,
    columns: dict[str, F64] | None = None,
    chunk: int | None = None,
) -> MonteCarlo:
    """Joint Monte Carlo over the LISA posterior and the (γ_j, K_j) regression covariance.

    Parameters
    ----------
    fits : tuple of ComponentFit
        One (SB1) or two (SB2) regressions.
    dK, dg : numpy.ndarray
        ∂K_j/∂θ and ∂γ_j/∂θ per component (n_components, 7).
    columns : dict of numpy.ndarray, optional
        The target's posterior samples (see :func:`posterior_samples`).
    chunk : int, optional
        Default :data:`CHUNK`. More samples than this run in chunks of this size
        (:mod:`ucbplan.reduce.mc_chunked`): the same random stream and summaries (to 1e-12
        relative), memory bounded by the chunk, and ``samples`` left empty.
    """
    chunk = CHUNK if chunk is None else chunk
    if n_samples > chunk:
        return chunked_monte_carlo(
            target, fits, dK, dg, n_samples, cos_i_sigma, mass_radius, rng, columns, chunk
        )
    warn: list[str] = []
    theta = posterior_samples(target, n_samples, rng, cos_i_sigma, columns, warn)
    dtheta = theta[:, :7] - block_sums(theta[:, :7]).sum(axis=0) / n_samples
    Ks, gs = _draw_k_gamma(fits, dK, dg, dtheta, [rng, rng])
    out, more = derive_samples(target, fits, theta, Ks, gs, mass_radius)
    finite_m1 = float(np.isfinite(out["M1"]).mean()) if "M1" in out else None
    warn = final_warnings(warn, more, len(fits), finite_m1)
    summaries = {k: _masses.summarize(v) for k, v in out.items()}
    return MonteCarlo(out, summaries, tuple(warn))
