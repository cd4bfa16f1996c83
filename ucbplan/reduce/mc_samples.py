"""Building blocks of the mass Monte Carlo (one-shot and chunked): draws, derived quantities.

Joint Monte Carlo over the LISA posterior and the (γ_j, K_j) regressions → masses (Sec. 5).

Each sample draws the LISA parameters (from the samples file if the target has one, else the
Gaussian posterior of the covariance) and (γ_j, K_j) from the regression covariance, moves K_j and
γ_j by the phase sensitivity −∂K/∂θ·δθ (re-regressing on the design of that θ), and evaluates
:func:`ucbplan.reduce.masses.derive` (SB2) or the mass function (SB1).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ucbplan.core.constants import G_SI, MSUN_KG
from ucbplan.core.mvnormal import sample_normal, sqrt_factor
from ucbplan.core.params import PARAM_NAMES
from ucbplan.reduce import masses as _masses

if TYPE_CHECKING:
    from ucbplan.reduce.regression import ComponentFit
    from ucbplan.targets import Target

F64 = NDArray[np.float64]
#: Columns drawn beyond PARAM_NAMES (cos ι, GW amplitude 𝒜): 9 columns in all.
EXTRA_NAMES = ("cos_inclination", "amplitude")
_COS_I = 7  # column of cos ι in the (n, 9) draws
#: Rows per block of the posterior-mean sum (a chunk is a whole number of blocks).
MEAN_BLOCK = 1000
_COS_I_FIXED = (
    "cos ι has no uncertainty in the target (covariance or samples): it is "
    "held fixed, so mass σ exclude the inclination; pass --cos-i-sigma or "
    "add cos_inclination to the covariance"
)


@dataclass(frozen=True)
class MonteCarlo:
    """Monte-Carlo samples of K_j, γ_j and every derived quantity, with their summaries."""

    samples: dict[str, F64]
    summaries: dict[str, _masses.Summary]
    warnings: tuple[str, ...] = field(default_factory=tuple)


def _ext_cov(target: Target) -> tuple[F64, F64]:
    """Mean and covariance of (PARAM_NAMES…, cos ι, amplitude) from the target (9 entries)."""
    names = (*PARAM_NAMES, *EXTRA_NAMES)
    mean = np.array(
        [
            *target.params.as_array(),
            target.cos_inclination if target.cos_inclination is not None else 0.0,
            target.amplitude if target.amplitude is not None else 0.0,
        ]
    )
    cov = np.zeros((9, 9))
    idx = [names.index(n) for n in target.cov_names if n in names]
    sub = [i for i, n in enumerate(target.cov_names) if n in names]
    cov[np.ix_(idx, idx)] = np.asarray(target.cov_matrix)[np.ix_(sub, sub)]
    return mean, cov


def posterior_samples(
    target: Target,
    n: int,
    rng: np.random.Generator,
    cos_i_sigma: float,
    columns: dict[str, F64] | None,
    warn: list[str],
) -> F64:
    """(n, 9) samples of (PARAM_NAMES…, cos ι, amplitude): ``columns`` if any, else Gaussian.

    Parameters
    ----------
    columns : dict of numpy.ndarray, optional
        The target's posterior samples file (read by the caller); rows are resampled from it for
        every column it has, the Gaussian draw fills the others.
    warn : list of str
        Receives the warning that cos ι is held fixed.
    """
    mean, cov = _ext_cov(target)
    if "cos_inclination" not in target.cov_names and target.cos_inclination is not None:
        cov[_COS_I, _COS_I] = cos_i_sigma**2
        if cos_i_sigma == 0.0:
            warn.append(_COS_I_FIXED)
    # Correlation-scaled draw (core.mvnormal): the σ's span ~40 orders of magnitude.
    out = sample_normal(mean, cov, n, rng)
    if columns is not None:
        size = len(next(iter(columns.values())))
        idx = rng.choice(size, size=n, replace=size < n)
        for k, name in enumerate((*PARAM_NAMES, *EXTRA_NAMES)):
            if name in columns:
                out[:, k] = columns[name][idx]
    out[:, _COS_I] = np.clip(out[:, _COS_I], -1.0, 1.0)
    return out


def block_sums(x: F64) -> F64:
    """Column sums of consecutive blocks of :data:`MEAN_BLOCK` rows (the last may be shorter).

    The posterior mean is the sum of these over blocks: the same numbers whether the samples are
    held at once or in chunks of a multiple of the block (:mod:`ucbplan.reduce.mc_chunked`).
    """
    full = x.shape[0] // MEAN_BLOCK * MEAN_BLOCK
    parts = [np.ascontiguousarray(x[:full]).reshape(-1, MEAN_BLOCK, x.shape[1]).sum(axis=1)]
    if full < x.shape[0]:
        parts.append(np.ascontiguousarray(x[full:]).sum(axis=0)[None, :])
    return np.concatenate(parts)


def _draw_k_gamma(
    fits: tuple[ComponentFit, ...],
    dK: F64,
    dg: F64,
    dtheta: F64,
    rngs: Sequence[np.random.Generator],
) -> tuple[list[F64], list[F64]]:
    """K_j, γ_j per sample: regression covariance draw minus the phase sensitivity ∂/∂θ·δθ.

    ``rngs[j]`` draws component j (the same generator twice: component 2 follows component 1).
    """
    n = dtheta.shape[0]
    Ks, gs = [], []
    for j, f in enumerate(fits):
        z = rngs[j].standard_normal((n, 2)) @ sqrt_factor(f.cov).T
        # Re-regressing on the design of sample θ shifts K by −∂K/∂θ·δθ (phase_sensitivity).
        Ks.append(f.K + z[:, 1] - dtheta @ dK[j])
        gs.append(f.gamma + z[:, 0] - dtheta @ dg[j])
    return Ks, gs


def _sb2_masses(
    Ks: list[F64], gs: list[F64], theta: F64, with_amplitude: bool, mass_radius: str | None
) -> dict[str, F64]:
    """Every derived quantity of :func:`ucbplan.reduce.masses.derive` per sample."""
    return _masses.derive(
        K1_km_s=Ks[0],
        K2_km_s=Ks[1],
        gamma1_km_s=gs[0],
        gamma2_km_s=gs[1],
        f_hz=theta[:, 1],
        fdot_hz_s=theta[:, 2],
        eta=theta[:, 4],
        kappa=theta[:, 5],
        omega_dot=theta[:, 6],
        cos_i=theta[:, _COS_I],
        amplitude=theta[:, 8] if with_amplitude else None,
        mass_radius=mass_radius,
    )


def _mass_function(K1: F64, theta: F64) -> F64:
    """SB1 mass function f(M) = P K³(1−e²)^{3/2}/(2πG) per sample [M☉]."""
    nb = math.pi * theta[:, 1] - theta[:, 6]
    e = np.hypot(theta[:, 4], theta[:, 5])
    k = K1 * 1e3
    return np.asarray((k**3 * (1 - e**2) ** 1.5 / (nb * G_SI)) / MSUN_KG, dtype=np.float64)


def derive_samples(
    target: Target,
    fits: tuple[ComponentFit, ...],
    theta: F64,
    Ks: list[F64],
    gs: list[F64],
    mass_radius: str | None,
) -> tuple[dict[str, F64], list[str]]:
    """Every Monte-Carlo quantity per sample, and the warnings that do not depend on the draws."""
    warn: list[str] = []
    out: dict[str, F64] = {"K1": Ks[0], "gamma1": gs[0]}
    if len(fits) == 2:
        out |= {"K2": Ks[1], "gamma2": gs[1]}
        if target.cos_inclination is None:
            warn.append(
                "target has no lisa.cos_inclination: component masses not computed; add "
                "it (and its σ) to the target file"
            )
        elif min(f.K for f in fits) <= 0.0:
            j = min(range(2), key=lambda i: fits[i].K)
            warn.append(
                f"star {j + 1}: K = {fits[j].K:.4g} km/s ≤ 0: its velocities do not follow the "
                f"LISA phase of star {j + 1} (v1/v2 swapped, a wrong time column or another "
                "target?); component masses not computed"
            )
        else:
            # draws with K ≤ 0 (K within a few σ of 0) give no masses: NaN, dropped by
            # summarize() and reported by final_warnings
            with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
                out |= _sb2_masses(Ks, gs, theta, target.amplitude is not None, mass_radius)
    else:
        with np.errstate(invalid="ignore", over="ignore"):
            out["mass_function"] = _mass_function(Ks[0], theta)
    return out, warn


def final_warnings(
    drawn: list[str], derived: list[str], n_fits: int, finite_m1: float | None
) -> list[str]:
    """The run's warnings: the draw's, the derivation's, lost draws, the SB1 note.

    ``finite_m1`` is the fraction of draws with a finite M1 (None: masses not computed).
    """
    warn = [*drawn, *derived]
    if n_fits == 2:
        if finite_m1 is not None and 1.0 - finite_m1 > 0.001:
            lost = 1.0 - finite_m1
            warn.append(
                f"{100 * lost:.1f} % of the Monte-Carlo draws give no masses (K drawn ≤ 0): "
                "the mass summaries are conditional on K > 0"
            )
    else:
        warn = [w for w in warn if w != _COS_I_FIXED]  # f(M) does not use ι
        warn.append(
            "SB1: only the mass function f(M) = P K³(1−e²)^{3/2}/(2πG) is reported; "
            "component masses need both stars' velocities"
        )
    return warn
