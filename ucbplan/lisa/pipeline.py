"""The LISA simulation as library calls: injection model, Fisher forecast, posterior sampling.

Each ``ucbplan simulate | fisher | waveform`` command is one of these functions plus printing;
they return records and never print, so a notebook or a Dask worker can call them directly::

    model = build_model(load_target("catalogs/fiducial-injection.yaml"))
    forecast = fisher_forecast(model)                   # Gaussian target at the midpoint
    result = simulate(model, SimulateOptions(seed=1, steps=60))  # from ucbplan.lisa.simulation
    write_simulation(result, simulation_files(Path("posterior.yaml")))  # YAML + samples + chain

Data flow: :func:`build_model` (start-epoch truth, four-line model, midpoint target) →
:func:`prepare_simulation` (noise draw, likelihood, SNR, Fisher covariance; both, options
checked, in :func:`ucbplan.simulate`) →
:func:`run_simulation` (emcee, midpoint transform, π-mode fold) →
:func:`ucbplan.lisa.outputs.write_simulation`. The records it passes along (:class:`LisaModel`,
:class:`SimulateOptions`, :class:`SimulationProblem`, :class:`SimulationResult`) are declared in
:mod:`ucbplan.lisa.simulation`; import them from there.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from astropy.time import TimeDelta
from numpy.typing import NDArray

from ucbplan.errors import InputError
from ucbplan.lisa import DEFAULT_N_BINS
from ucbplan.lisa import posterior as post
from ucbplan.lisa.fisher import (
    fisher_covariance,
    fisher_from_templates,
    fisher_points,
    prior_excess,
)
from ucbplan.lisa.likelihood import (
    Likelihood,
    Prior,
    model_for_target,
    physical_from_theta,
    simulate_data,
    source_from_target,
)
from ucbplan.lisa.noise import SANGRIA
from ucbplan.lisa.outputs import load_resume
from ucbplan.lisa.sampler import CONVERGENCE_FACTOR, SamplerResult, run_sampler
from ucbplan.lisa.simulation import (
    LisaModel,
    SimulateOptions,
    SimulationProblem,
    SimulationResult,
    parameter_sigmas,
)

if TYPE_CHECKING:
    from ucbplan.lisa.source import SourceParams
    from ucbplan.lisa.waveform import FourLineModel
    from ucbplan.targets import Target

F64 = NDArray[np.float64]
#: ``progress(step, total, tau_max)``, called every few sampler steps.
Progress = Callable[[int, int, float], None]


def build_model(
    target: Target,
    *,
    t_obs_s: float | None = None,
    n_bins: int = DEFAULT_N_BINS,
    circular: bool = False,
    where: str | None = None,
    ecliptic_rad: tuple[float, float] | None = None,
) -> LisaModel:
    """Injection model of ``target`` (needs lisa.amplitude, cos_inclination, psi).

    Parameters
    ----------
    target : Target
        Target or injection (midpoint-referenced parameters).
    t_obs_s : float, optional
        Observation length [s] (default: the target's).
    n_bins : int
        Band width N (even, ≥ 16); injection and templates share it.
    circular : bool
        Fit the 6-parameter circular model even if the target is eccentric.
    where : str, optional
        Prefix of error messages (default: the target's file).
    ecliptic_rad : (float, float), optional
        The target's barycentric mean ecliptic (λ, β) [rad] if already converted (default:
        converted from its ICRS position here).

    Raises
    ------
    InputError
        ``n_bins`` odd or below 16, or ω̇ puts z_ω = ω̇T/2π outside the prior [0, 50] bins.
    TargetFileError
        The target lacks the GW-only fields (amplitude, cos_inclination, psi).
    """
    if n_bins < 16 or n_bins % 2:
        raise InputError(f"n_bins: expected an even number >= 16, got {n_bins}")
    t_obs = target.t_obs_s if t_obs_s is None else t_obs_s
    truth, eccentric = _injection(target, t_obs, circular, where)
    mid = target.t_start + TimeDelta(0.5 * t_obs, format="sec")
    base = dataclasses.replace(target, t_ref=mid, t_obs_s=t_obs)
    model = _templates(target, truth, t_obs, n_bins, eccentric, ecliptic_rad)
    return LisaModel(base=base, truth=truth, model=model, eccentric=eccentric, n_bins=n_bins)


def _injection(
    target: Target, t_obs: float, circular: bool, where: str | None
) -> tuple[SourceParams, bool]:
    """Injected parameters of ``target`` and whether the eccentric model fits them.

    Raises
    ------
    InputError
        ω̇ puts z_ω = ω̇T/2π outside the prior [0, 50] bins.
    """
    truth = source_from_target(target)
    eccentric = (not circular) and (truth.eta != 0.0 or truth.kappa != 0.0)
    if not eccentric:
        truth = dataclasses.replace(truth, eta=0.0, kappa=0.0, omega_dot=0.0)
    if eccentric and not 0.0 <= truth.omega_dot * t_obs / (2 * np.pi) <= 50.0:
        raise InputError(
            f"{where or target.source or target.name}: omega_dot gives z_omega outside the prior "
            f"[0, 50] bins for T = {t_obs:.6g} s; use a shorter `t_obs` or `circular`"
        )
    return truth, eccentric


def _templates(
    target: Target,
    truth: SourceParams,
    t_obs: float,
    n_bins: int,
    eccentric: bool,
    ecliptic_rad: tuple[float, float] | None,
) -> FourLineModel:
    """Four-line templates of ``target`` on the band grid around the injection ``truth``."""
    return model_for_target(
        target,
        t_obs,
        n_bins,
        eccentric,
        truth.f_gw,
        fdot_ref=truth.fdot,
        omega_dot_ref=truth.omega_dot,
        ecliptic_rad=ecliptic_rad,
    )


def _where(model: LisaModel) -> str:
    """Prefix of error messages: the target file (or the target's name)."""
    src = model.base.source
    return str(src) if src is not None else model.base.name


@dataclass(frozen=True, slots=True, eq=False)
class FisherForecast:
    """Fisher-matrix forecast (zero-noise data) as a Gaussian target at the midpoint.

    Attributes
    ----------
    target : Target
        Named "<name> (Fisher forecast)"; covariance over the physical parameters.
    snr : float
        Optimal SNR of the injection.
    theta0, cov_theta : numpy.ndarray
        Injection and inverse Fisher matrix in sampled coordinates (start epoch).
    warnings : tuple of str
        Parameters whose forecast 1σ exceeds their prior width (not measured by these data).
    """

    target: Target
    snr: float
    theta0: F64
    cov_theta: F64
    warnings: tuple[str, ...] = ()

    def __repr__(self) -> str:
        return f"<FisherForecast {self.target.name}: SNR {self.snr:.1f}, {len(self.sigmas)} σ's>"

    @property
    def sigmas(self) -> dict[str, float]:
        """Forecast 1σ per parameter (covariance order)."""
        return parameter_sigmas(self.target)

    @property
    def values(self) -> dict[str, float]:
        """Injected value per parameter (midpoint; covariance order)."""
        t = self.target
        return {n: float(getattr(t.params, n, getattr(t, n, np.nan))) for n in t.cov_names}


def fisher_forecast(model: LisaModel) -> FisherForecast:
    """Fisher forecast of the targeted-search parameters (the library behind ``ucbplan fisher``).

    Raises
    ------
    NumericalError
        A singular Fisher matrix: parameters the data cannot separate, e.g. phase and psi of a
        face-on source (:func:`ucbplan.lisa.fisher.fisher_covariance`). A 1σ wider than the
        prior is a warning of the forecast instead.

    Notes
    -----
    The zero-noise data (the injection at ``theta0``), the SNR and the central-difference
    points of the Fisher matrix are one batch of templates (one waveform call per source).
    """
    theta0 = model.theta0()
    prior = Prior.paper(model.truth, model.t_obs_s, model.eccentric)
    pts, steps = fisher_points(prior.names, model.t_obs_s, theta0)
    # one batch of templates: the injection at theta0 (zero-noise data) and the Fisher points
    h = model.model.bands(
        **physical_from_theta(np.vstack([theta0, pts]), model.t_obs_s, prior.names)
    )
    like = Likelihood(model.model, h[0], prior, SANGRIA)
    snr = float(np.sqrt(like.inner(h[:1], h[:1])[0]))
    info = fisher_from_templates(like, h[1:], steps)
    cov = fisher_covariance(like, theta0, _where(model), within_prior=False, fisher=info)
    excess = prior_excess(like, theta0, cov, _where(model))
    warnings = () if excess is None else (f"{excess}; its forecast σ is not meaningful",)
    fis = post.gaussian_target(model.base, theta0, cov, model.t_obs_s, like.prior.names)
    fis = dataclasses.replace(fis, name=f"{model.base.name} (Fisher forecast)")
    return FisherForecast(target=fis, snr=snr, theta0=theta0, cov_theta=cov, warnings=warnings)


def prepare_simulation(model: LisaModel, options: SimulateOptions) -> SimulationProblem:
    """Draw the data (seeded), build the likelihood, its SNR and the Fisher covariance.

    Raises
    ------
    InputError
        Fewer than 2 walkers per parameter, or no steps.
    NumericalError
        The Fisher matrix leaves a parameter unconstrained
        (:func:`ucbplan.lisa.fisher.fisher_covariance`).
    InputFileError
        ``options.resume`` does not fit this run
        (:func:`ucbplan.lisa.outputs.load_resume`).
    """
    theta0 = model.theta0()
    if options.walkers < 2 * theta0.size:
        raise InputError(
            f"walkers: expected at least {2 * theta0.size} (2 per parameter, "
            f"{theta0.size} parameters), got {options.walkers}"
        )
    if options.steps < 1 or options.max_steps < 1:
        raise InputError(f"steps/max_steps: expected >= 1, got {options.steps}")
    rng = np.random.default_rng(options.seed)
    data = simulate_data(model.model, model.truth, SANGRIA, rng if options.noise else None)
    like = model.likelihood(data)
    snr = float(like.snr(theta0[None])[0])
    cov = fisher_covariance(like, theta0, _where(model))
    previous = None
    if options.resume is not None:
        previous, cov = load_resume(
            options.resume,
            theta0,
            seed=options.seed,
            noise=options.noise,
            n_bins=model.n_bins,
            t_obs_s=model.t_obs_s,
            walkers=options.walkers,
        )
    return SimulationProblem(model, options, theta0, like, snr, cov, previous)


def _convergence_warnings(chain: SamplerResult) -> tuple[str, ...]:
    if chain.converged:
        return ()
    n_done, tau_max = chain.theta.shape[0], float(np.max(chain.tau))
    if not np.isfinite(tau_max):
        return (
            f"chain of {n_done} steps is too short to estimate τ (a walker has not moved yet): "
            "the posterior σ's are not reliable; rerun with more --steps or --until-converged",
        )
    return (
        f"chain of {n_done} steps is shorter than {CONVERGENCE_FACTOR:g} τ "
        f"(τ_max = {tau_max:.0f} steps): the posterior σ's are not reliable; rerun with "
        f"--steps {int(CONVERGENCE_FACTOR * tau_max) + 1} or --until-converged",
    )


def run_simulation(
    problem: SimulationProblem, progress: Progress | None = None
) -> SimulationResult:
    """Sample the posterior of ``problem`` and move it to the midpoint.

    Parameters
    ----------
    problem : SimulationProblem
        From :func:`prepare_simulation`.
    progress : callable, optional
        ``progress(step, total, tau_max)`` for a progress bar.
    """
    opts, theta0 = problem.options, problem.theta0
    t_obs_s = problem.model.t_obs_s
    chain = run_sampler(
        problem.likelihood,
        theta0,
        problem.fisher_cov,
        n_walkers=opts.walkers,
        n_steps=opts.steps,
        until_converged=opts.until_converged,
        max_steps=opts.max_steps,
        seed=opts.seed,
        progress=progress,
        previous=problem.previous,
    )
    flat = chain.flat_samples()
    names = problem.likelihood.prior.names
    cols = post.midpoint_samples(flat, t_obs_s, names)
    inj = {k: float(v[0]) for k, v in post.midpoint_samples(theta0[None], t_obs_s, names).items()}
    cols, n_fold = post.fold_phase_mode(cols, inj["phase"])
    fis = post.gaussian_target(problem.model.base, theta0, problem.fisher_cov, t_obs_s, names)
    return SimulationResult(
        problem, chain, flat, cols, inj, n_fold, fis, _convergence_warnings(chain)
    )


def simulate(
    model: LisaModel, options: SimulateOptions, progress: Progress | None = None
) -> SimulationResult:
    """Simulate a LISA observation and sample the targeted-search posterior (``ucbplan simulate``).

    :func:`prepare_simulation` followed by :func:`run_simulation`.

    Raises
    ------
    SamplerInterrupted
        Ctrl-C during sampling; its ``partial`` holds the chain so far
        (:func:`ucbplan.lisa.outputs.save_interrupted` keeps it for ``resume``).
    """
    return run_simulation(prepare_simulation(model, options), progress)
