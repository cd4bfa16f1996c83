"""The records of a LISA simulation: injection model, options, problem and result.

:mod:`ucbplan.lisa.pipeline` builds and runs them; :mod:`ucbplan.lisa.outputs` writes a
:class:`SimulationResult` as files and reads a chain back for a resumed :class:`SimulationProblem`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from ucbplan.lisa import DEFAULT_MAX_STEPS, DEFAULT_STEPS, DEFAULT_WALKERS
from ucbplan.lisa import posterior as post
from ucbplan.lisa.likelihood import Likelihood, Prior, theta_from_source
from ucbplan.lisa.noise import SANGRIA
from ucbplan.lisa.sampler import SamplerResult

if TYPE_CHECKING:
    from ucbplan.lisa.source import SourceParams
    from ucbplan.lisa.waveform import FourLineModel
    from ucbplan.targets import Target

F64 = NDArray[np.float64]


@dataclass(frozen=True, slots=True, eq=False)
class LisaModel:
    """Injection and search set-up built from a target file.

    Attributes
    ----------
    base : Target
        The target referenced to the midpoint of an observation of ``t_obs_s`` (t_ref moved).
    truth : SourceParams
        Injected waveform parameters at the start of the observation (e = 0 if circular).
    model : FourLineModel
        Templates on the band grid (N = ``n_bins`` per band).
    eccentric : bool
        Whether the 9-parameter eccentric model is used (else the 6-parameter circular one).
    n_bins : int
        Band width N in Fourier bins.
    """

    base: Target
    truth: SourceParams
    model: FourLineModel
    eccentric: bool
    n_bins: int

    @property
    def t_obs_s(self) -> float:
        """Observation length T [s]."""
        return float(self.model.grid.t_obs_s)

    def theta0(self) -> F64:
        """Injected parameters in sampled coordinates (start epoch)."""
        return np.asarray(theta_from_source(self.truth, self.t_obs_s, self.eccentric), dtype=float)

    def likelihood(self, data: NDArray[np.complex128]) -> Likelihood:
        """Whittle likelihood of ``data`` with the paper's priors around the injection."""
        prior = Prior.paper(self.truth, self.t_obs_s, self.eccentric)
        return Likelihood(self.model, data, prior, SANGRIA)


def parameter_sigmas(t: Target) -> dict[str, float]:
    """1σ of each covariance entry of ``t``."""
    return {n: float(np.sqrt(t.cov_matrix[i, i])) for i, n in enumerate(t.cov_names)}


@dataclass(frozen=True, slots=True)
class SimulateOptions:
    """Options of :func:`simulate` (noise draw and emcee run).

    Attributes
    ----------
    seed : int
        Seed of the noise draw and the sampler.
    walkers, steps : int
        emcee ensemble size (≥ 2 × parameters) and steps (the minimum with ``until_converged``).
    until_converged : bool
        Extend the chain until it is ≥ 50 τ long or ``max_steps``.
    max_steps : int
        Cap for ``until_converged``.
    noise : bool
        Add a Gaussian noise draw (else zero-noise data).
    resume : Path, optional
        Chain (.npz) of an earlier run with the same options to continue.
    """

    seed: int = 0
    walkers: int = DEFAULT_WALKERS
    steps: int = DEFAULT_STEPS
    until_converged: bool = False
    max_steps: int = DEFAULT_MAX_STEPS
    noise: bool = True
    resume: Path | None = None


@dataclass(frozen=True, slots=True, eq=False)
class SimulationProblem:
    """Data, likelihood and start point of one simulation, before sampling.

    ``fisher_cov`` whitens the sampler (the saved one when resuming); ``previous`` is the resumed
    (theta chain, log_prob) or None.
    """

    model: LisaModel
    options: SimulateOptions
    theta0: F64
    likelihood: Likelihood
    snr: float
    fisher_cov: F64
    previous: tuple[F64, F64] | None = None


@dataclass(frozen=True, slots=True, eq=False)
class SimulationResult:
    """Posterior of one simulation, at the midpoint, with the Fisher forecast beside it.

    Attributes
    ----------
    problem : SimulationProblem
        Data, likelihood and start point.
    chain : SamplerResult
        emcee chain (sampled coordinates, start epoch) and convergence diagnostics.
    samples : numpy.ndarray
        Burnt-in, thinned chain (S, D) in sampled coordinates (start epoch).
    columns : dict of numpy.ndarray
        Physical samples at the midpoint after folding the π mode.
    injected : dict of float
        Injection at the midpoint (same keys as ``columns``).
    n_folded : int
        Samples moved from the π mode onto the injected branch.
    fisher : Target
        Gaussian forecast from the whitening covariance (same names as the posterior).
    warnings : tuple of str
        E.g. a chain shorter than 50 τ.
    """

    problem: SimulationProblem
    chain: SamplerResult
    samples: F64
    columns: dict[str, F64]
    injected: dict[str, float]
    n_folded: int
    fisher: Target
    warnings: tuple[str, ...] = field(default_factory=tuple)

    def __repr__(self) -> str:
        return (
            f"<SimulationResult {self.model.base.name}: {self.n_steps} steps, "
            f"{self.samples.shape[0]} samples of {len(self.names)} parameters, "
            f"SNR {self.problem.snr:.1f}, seed {self.problem.options.seed}>"
        )

    @property
    def model(self) -> LisaModel:
        """The injection model."""
        return self.problem.model

    @property
    def n_steps(self) -> int:
        """Chain length in steps (including a resumed part)."""
        return int(self.chain.theta.shape[0])

    @property
    def tau_max(self) -> float:
        """Largest integrated autocorrelation time [steps]."""
        return float(np.max(self.chain.tau))

    def posterior(self, samples_path: Path | None = None) -> Target:
        """Posterior target (means, sample covariance); ``samples_path`` is recorded in it."""
        base = self.model.base
        name = f"{base.name} (posterior)"
        return post.posterior_target(base, self.columns, samples_path, name=name)

    @property
    def names(self) -> tuple[str, ...]:
        """Physical parameter names of the posterior (covariance order)."""
        return self.fisher.cov_names

    @property
    def posterior_mean(self) -> dict[str, float]:
        """Posterior mean per parameter (midpoint)."""
        return {n: float(np.mean(self.columns[n])) for n in self.names}

    @property
    def posterior_sigma(self) -> dict[str, float]:
        """Posterior standard deviation per parameter (midpoint)."""
        return {n: float(np.std(self.columns[n])) for n in self.names}

    @property
    def fisher_sigma(self) -> dict[str, float]:
        """Fisher 1σ per parameter (midpoint)."""
        return parameter_sigmas(self.fisher)

    def samples_meta(self) -> dict[str, Any]:
        """Metadata of the samples ECSV (reference epoch, seed, convergence, SNR)."""
        return {
            "reference": "midpoint of the LISA observation (t_ref of the target YAML, TDB)",
            "t_ref_tdb": self.model.base.t_ref.tdb.isot,
            "seed": self.problem.options.seed,
            "n_steps": self.n_steps,
            "tau_max_steps": self.tau_max,
            "converged": self.chain.converged,
            "folded_pi_mode_samples": self.n_folded,
            "snr": self.problem.snr,
        }
