"""The mass Monte Carlo in chunks: the same random stream, memory bounded by the chunk size.

The one-shot Monte Carlo (:func:`ucbplan.reduce.montecarlo.monte_carlo`) draws from one generator
in this order: the (n, 9) posterior normals, the resampling indices of a samples file, then
(n, 2) normals per component. A chunked run must draw exactly the same numbers, so it first walks
the generator through the posterior normals (summing them for the posterior mean) and through
component 1's normals, keeping a copy of the generator at the start of each section; the chunks
then draw from those copies in step. ``Generator.standard_normal`` fills arrays in order, so
(c₁, d) then (c₂, d) draws equal one (c₁ + c₂, d) draw. Summaries are exact percentiles
(:class:`~ucbplan.reduce.quantiles.ChunkedPercentiles`); the per-sample arrays are not kept.

The posterior mean is a sum of fixed blocks of rows (:func:`~ucbplan.reduce.mc_samples.
block_sums`) in both runs, and a chunk is a whole number of blocks, so the summaries agree to
rounding of the row-wise matrix products (tested at 1e-12 relative).
"""

from __future__ import annotations

import copy
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from ucbplan.core.mvnormal import rows_times, sqrt_factor
from ucbplan.core.params import PARAM_NAMES
from ucbplan.reduce import masses as _masses
from ucbplan.reduce.mc_samples import (
    _COS_I,
    _COS_I_FIXED,
    EXTRA_NAMES,
    MEAN_BLOCK,
    MonteCarlo,
    _draw_k_gamma,
    _ext_cov,
    block_sums,
    derive_samples,
    final_warnings,
)
from ucbplan.reduce.quantiles import BracketMissed, ChunkedPercentiles

if TYPE_CHECKING:
    from ucbplan.reduce.regression import ComponentFit
    from ucbplan.targets import Target

F64 = NDArray[np.float64]
_QS = (15.865525393145708, 50.0, 84.13447460685429)  # as masses.summarize


def _spans(n: int, chunk: int) -> list[tuple[int, int]]:
    return [(s, min(s + chunk, n)) for s in range(0, n, chunk)]


def _theta(
    rng: np.random.Generator,
    mean: F64,
    root: F64,
    columns: dict[str, F64] | None,
    idx: NDArray[np.int64] | None,
    s: int,
    e: int,
) -> F64:
    """Posterior rows s:e, as :func:`~ucbplan.reduce.mc_samples.posterior_samples` makes them."""
    theta: F64 = mean + rows_times(rng.standard_normal((e - s, mean.size)), root.T)
    if columns is not None and idx is not None:
        for k, name in enumerate((*PARAM_NAMES, *EXTRA_NAMES)):
            if name in columns:
                theta[:, k] = columns[name][idx[s:e]]
    theta[:, _COS_I] = np.clip(theta[:, _COS_I], -1.0, 1.0)
    return theta


def chunked_monte_carlo(
    target: Target,
    fits: tuple[ComponentFit, ...],
    dK: F64,
    dg: F64,
    n: int,
    cos_i_sigma: float,
    mass_radius: str | None,
    rng: np.random.Generator,
    columns: dict[str, F64] | None,
    chunk: int,
) -> MonteCarlo:
    """:func:`~ucbplan.reduce.montecarlo.monte_carlo` for ``n`` samples in chunks of ``chunk``."""
    warn: list[str] = []
    mean, cov = _ext_cov(target)
    if "cos_inclination" not in target.cov_names and target.cos_inclination is not None:
        cov[_COS_I, _COS_I] = cos_i_sigma**2
        if cos_i_sigma == 0.0:
            warn.append(_COS_I_FIXED)
    root = sqrt_factor(cov)
    chunk = max(chunk // MEAN_BLOCK, 1) * MEAN_BLOCK
    spans = _spans(n, chunk)
    theta_rng = copy.deepcopy(rng)
    for s, e in spans:  # walk the posterior normals to the resampling indices
        rng.standard_normal((e - s, mean.size))
    idx = None
    if columns is not None:
        size = len(next(iter(columns.values())))
        idx = rng.choice(size, size=n, replace=size < n)
    walk = copy.deepcopy(theta_rng)
    sums = np.concatenate(
        [block_sums(_theta(walk, mean, root, columns, idx, s, e)[:, :7]) for s, e in spans]
    )
    k_rngs = [copy.deepcopy(rng)]
    if len(fits) == 2:
        for s, e in spans:
            rng.standard_normal((e - s, 2))
        k_rngs.append(copy.deepcopy(rng))
    state = (theta_rng, k_rngs, mean, root, columns, idx, sums.sum(axis=0) / n)
    widen = 1.0
    while True:
        try:
            acc, derived = _pass(target, fits, dK, dg, mass_radius, spans, state, n, widen)
            summaries = {}
            for key, a in acc.items():
                lo, med, hi = a.result()
                summaries[key] = _masses.Summary(med, 0.5 * (hi - lo), lo, hi, a.n_finite)
            break
        except BracketMissed:
            widen *= 10.0
    finite_m1 = acc["M1"].n_finite / n if "M1" in acc else None
    warn = final_warnings(warn, derived, len(fits), finite_m1)
    return MonteCarlo({}, summaries, tuple(warn))


def _pass(
    target: Target,
    fits: tuple[ComponentFit, ...],
    dK: F64,
    dg: F64,
    mass_radius: str | None,
    spans: list[tuple[int, int]],
    state: tuple[Any, ...],
    n: int,
    widen: float,
) -> tuple[dict[str, ChunkedPercentiles], list[str]]:
    """One pass over the chunks from copies of the section generators."""
    theta_rng0, k_rngs0, mean, root, columns, idx, mean7 = state
    theta_rng = copy.deepcopy(theta_rng0)
    k_rngs = [copy.deepcopy(r) for r in k_rngs0]
    acc: dict[str, ChunkedPercentiles] = {}
    derived: list[str] = []
    for s, e in spans:
        theta = _theta(theta_rng, mean, root, columns, idx, s, e)
        Ks, gs = _draw_k_gamma(fits, dK, dg, theta[:, :7] - mean7, k_rngs)
        out, derived = derive_samples(target, fits, theta, Ks, gs, mass_radius)
        for key, values in out.items():
            acc.setdefault(key, ChunkedPercentiles(_QS, n, widen)).add(values)
    return acc, derived
