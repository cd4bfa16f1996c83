"""``ucbplan.simulate``, ``ucbplan.fisher`` and ``ucbplan.waveform``: the reduced LISA
simulation (paper Sec. 4.1), the library behind ``ucbplan simulate | fisher | waveform``.

Their options are declared once, here: the defaults in the signatures (from
:mod:`ucbplan.lisa`, which the library and the population runs share) and the command line's
flags and help in :data:`SIMULATE_FLAGS`, :data:`FISHER_FLAGS` and :data:`WAVEFORM_FLAGS`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ucbplan.api._convert import as_float, scope
from ucbplan.api.ephemeris import TargetLike, load_target
from ucbplan.api.flagspec import Flag
from ucbplan.api.reduction import check_count, check_seed
from ucbplan.errors import InputError, ReduceWarning, SamplerConvergenceWarning, emit, shorten
from ucbplan.lisa import (
    DEFAULT_MAX_STEPS,
    DEFAULT_N_BINS,
    DEFAULT_STEPS,
    DEFAULT_WALKERS,
    MAX_N_BINS,
    MIN_T_OBS_S,
)

if TYPE_CHECKING:
    from ucbplan.lisa.lines import WaveformLines
    from ucbplan.lisa.outputs import SimulationFiles
    from ucbplan.lisa.pipeline import FisherForecast
    from ucbplan.lisa.simulation import (
        LisaModel,
        SimulateOptions,
        SimulationProblem,
        SimulationResult,
    )

#: Most walkers and chain steps accepted (memory: walkers × steps × parameters floats).
MAX_WALKERS = 100_000
MAX_CHAIN_STEPS = 10_000_000

#: The options ``simulate``, ``fisher`` and ``waveform`` share.
LISA_FLAGS: dict[str, Flag] = {
    "target": Flag((), "Target or injection YAML (needs amplitude, psi)."),
    "t_obs": Flag(("--t-obs",), "Observation length, e.g. '4yr'."),
    "n_bins": Flag(("--n-bins",), "Band width N in bins."),
}
#: How ``ucbplan simulate`` spells the parameters of :func:`simulate`.
SIMULATE_FLAGS: dict[str, Flag] = {
    **LISA_FLAGS,
    "seed": Flag(("--seed",), "Seed for the noise and the sampler.", min=0),
    "walkers": Flag(("--walkers",), "emcee walkers (>= 2 x parameters)."),
    "steps": Flag(("--steps",), "Steps (minimum with --until-converged).", min=1),
    "until_converged": Flag(("--until-converged",), "Extend the chain until it is >= 50 τ long."),
    "max_steps": Flag(("--max-steps",), "Cap for --until-converged.", min=1),
    "noise": Flag(("--noise/--no-noise",), "Add a Gaussian noise draw."),
    "n_bins": Flag(("--n-bins",), "Band width N in bins (injection = templates)."),
    "circular": Flag(("--circular",), "Fit the 6-parameter circular model."),
    "resume": Flag(("--resume",), "Continue a saved chain (.npz) of a run with the same options."),
}
#: How ``ucbplan fisher`` spells the parameters of :func:`fisher`.
FISHER_FLAGS: dict[str, Flag] = {
    **LISA_FLAGS,
    "circular": Flag(("--circular",), "6-parameter circular model."),
}
#: How ``ucbplan waveform`` spells the parameters of :func:`waveform`.
WAVEFORM_FLAGS: dict[str, Flag] = dict(LISA_FLAGS)


def check_n_bins(n_bins: Any, parameter: str = "n_bins") -> int:
    """The band width N: an even whole number of bins in [16, MAX_N_BINS].

    Raises
    ------
    InputError
        One line naming ``parameter``.
    """
    if not (_whole(n_bins) and 16 <= n_bins <= MAX_N_BINS and n_bins % 2 == 0):
        raise InputError(
            f"{parameter}: expected an even number of bins in [16, {MAX_N_BINS}], "
            f"got {shorten(n_bins, 40)}",
            parameter=parameter,
        )
    return int(n_bins)


def t_obs_seconds(t_obs: Any, default_s: float, parameter: str = "t_obs") -> float:
    """An observation length [s] from text (``4yr``, Julian years), seconds or a Quantity.

    Raises
    ------
    InputError
        Not a duration of at least a day (naming ``parameter``).
    """
    if t_obs is None:
        return default_s
    import astropy.units as u

    value = as_float(t_obs, "s", parameter)
    if isinstance(value, str):
        try:
            value = float(u.Quantity(value.replace(" ", "")).to_value(u.s))
        except (TypeError, ValueError, u.UnitsError):
            raise InputError(
                f"{parameter}: expected a duration like '4yr' (Julian) or '126232599.054s', "
                f"got {shorten(t_obs)}",
                parameter=parameter,
            ) from None
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise InputError(f"{parameter}: expected a duration, got {shorten(t_obs)}", parameter)
    if not MIN_T_OBS_S <= value < float("inf"):
        raise InputError(
            f"{parameter}: expected a finite duration of at least 1 day, got {shorten(t_obs)}",
            parameter=parameter,
        )
    return float(value)


def _whole(value: Any) -> bool:
    """A whole number (int, or a float or numpy number without a fraction), not a bool."""
    from ucbplan.inputs import is_number

    return is_number(value) and math.isfinite(float(value)) and float(value) == int(value)


def _walkers(value: Any, n_parameters: int | None = None) -> int:
    """emcee walkers: a whole number up to :data:`MAX_WALKERS`, and (once the model is known)
    at least 2 per sampled parameter."""
    if not (_whole(value) and value <= MAX_WALKERS):
        raise InputError(
            f"walkers: expected a whole number of at most {MAX_WALKERS} (at least 2 per "
            f"parameter), got {shorten(value, 40)}",
            parameter="walkers",
        )
    if n_parameters is not None and value < 2 * n_parameters:
        raise InputError(
            f"walkers: expected at least {2 * n_parameters} (2 per parameter, "
            f"{n_parameters} parameters), got {int(value)}",
            parameter="walkers",
        )
    return int(value)


def _flag(value: Any, parameter: str) -> bool:
    if not isinstance(value, bool):
        raise InputError(f"{parameter}: expected True or False, got {shorten(value)}", parameter)
    return value


def _model(target: TargetLike, t_obs: Any, n_bins: Any, circular: Any) -> LisaModel:
    """The injection model of ``target`` (options checked before the target is read)."""
    from ucbplan.lisa.pipeline import build_model

    n_bins, circular = check_n_bins(n_bins), _flag(circular, "circular")
    tgt = load_target(target)
    where = str(target) if isinstance(target, str | Path) else None
    t_obs_s = t_obs_seconds(t_obs, tgt.t_obs_s)
    return build_model(tgt, t_obs_s=t_obs_s, n_bins=n_bins, circular=circular, where=where)


def fisher(
    target: TargetLike,
    *,
    t_obs: Any = None,
    n_bins: int = DEFAULT_N_BINS,
    circular: bool = False,
    warn: bool = True,
) -> FisherForecast:
    """Fisher-matrix forecast of the targeted-search parameters (``ucbplan fisher``).

    Parameters
    ----------
    target : str, Path, dict or Target
        Target or injection (needs ``lisa.amplitude``, ``cos_inclination``, ``psi``).
    t_obs : str, float or Quantity, optional
        Observation length (``"4yr"``, seconds or a time Quantity; default: the target's).
    n_bins : int
        Band width N in bins (even, 16 to :data:`ucbplan.lisa.MAX_N_BINS`).
    circular : bool
        Forecast the 6-parameter circular model even if the target is eccentric.
    warn : bool
        Emit the forecast's warnings as :class:`ucbplan.ReduceWarning` (besides returning them).

    Returns
    -------
    FisherForecast
        ``.target`` (a Gaussian target at the midpoint), ``.snr``, ``.sigmas``, ``.warnings``.

    Raises
    ------
    UcbplanError
        A target without the LISA injection fields, or a bad ``t_obs`` or ``n_bins``: one line
        naming it.

    Examples
    --------
    >>> import ucbplan
    >>> ucbplan.fisher("catalogs/fiducial-injection.yaml", n_bins=64)
    <FisherForecast Fiducial eccentric dWD (injection) (Fisher forecast): SNR 831.8, 9 σ's>
    """
    from ucbplan.lisa.pipeline import fisher_forecast

    with scope():
        forecast = fisher_forecast(_model(target, t_obs, n_bins, circular))
    if warn:
        emit(list(forecast.warnings), ReduceWarning)
    return forecast


def waveform(
    target: TargetLike, *, t_obs: Any = None, n_bins: int = DEFAULT_N_BINS
) -> WaveformLines:
    """The injected TDI A, E per band with the noise PSD (``ucbplan waveform``).

    Parameters
    ----------
    target : str, Path, dict or Target
        Target or injection (needs ``lisa.amplitude``, ``cos_inclination``, ``psi``).
    t_obs, n_bins
        As :func:`fisher`.

    Returns
    -------
    WaveformLines
        ``.table`` (band, freq_hz [Hz], A_re, A_im, E_re, E_im [1/Hz], psd_a [1/Hz]), ``.snr``.

    Raises
    ------
    UcbplanError
        As :func:`fisher`.

    Examples
    --------
    >>> import ucbplan
    >>> ucbplan.waveform("catalogs/fiducial-injection.yaml", n_bins=64)
    <WaveformLines Fiducial eccentric dWD (injection): 3 bands x 64 bins, SNR 831.8>
    """
    from ucbplan.lisa.lines import waveform_lines

    with scope():
        return waveform_lines(_model(target, t_obs, n_bins, False))


def _sampler_options(
    seed: Any,
    walkers: Any,
    steps: Any,
    until_converged: Any,
    max_steps: Any,
    noise: Any,
    resume: Any,
) -> SimulateOptions:
    """The checked sampler options of :func:`simulate` (one line naming the parameter)."""
    from ucbplan.lisa.simulation import SimulateOptions

    return SimulateOptions(
        seed=int(check_seed(seed) or 0),  # not None: optional=False
        walkers=_walkers(walkers),
        steps=check_count("steps", steps, 1, MAX_CHAIN_STEPS),
        until_converged=_flag(until_converged, "until_converged"),
        max_steps=check_count("max_steps", max_steps, 1, MAX_CHAIN_STEPS),
        noise=_flag(noise, "noise"),
        resume=_resume(resume),
    )


def _resume(resume: Any) -> Path | None:
    if resume is None or isinstance(resume, str | Path):
        return None if resume is None else Path(resume)
    raise InputError(
        f"resume: expected a chain file (.npz) or None, got {shorten(resume)}", "resume"
    )


def simulate(
    target: TargetLike,
    seed: int = 0,
    *,
    t_obs: Any = None,
    n_bins: int = DEFAULT_N_BINS,
    circular: bool = False,
    walkers: int = DEFAULT_WALKERS,
    steps: int = DEFAULT_STEPS,
    until_converged: bool = False,
    max_steps: int = DEFAULT_MAX_STEPS,
    noise: bool = True,
    resume: str | Path | None = None,
    progress: Callable[[int, int, float], None] | None = None,
    on_ready: Callable[[SimulationProblem], None] | None = None,
    warn: bool = True,
) -> SimulationResult:
    """Simulate a LISA observation, sample the targeted-search posterior (``ucbplan simulate``).

    Parameters
    ----------
    target, t_obs, n_bins, circular
        As :func:`fisher` (the band width is that of the injection and the templates).
    seed : int
        Seed (>= 0) of the noise draw and the sampler.
    walkers, steps, max_steps : int
        emcee walkers (>= 2 per parameter); chain steps (the minimum with ``until_converged``,
        which extends the chain until it is >= 50 τ long, or ``max_steps``).
    until_converged, noise : bool
        See ``steps``; add a Gaussian noise draw (else zero-noise data).
    resume : str or Path, optional
        Chain (.npz) of an earlier run with the same options to continue.
    progress, on_ready : callable, optional
        ``progress(step, total, tau_max)`` every few steps; ``on_ready(problem)`` with the
        drawn data before sampling (to show the run; for :func:`save_interrupted`).
    warn : bool
        Emit the result's warnings as :class:`ucbplan.ReduceWarning` too.

    Returns
    -------
    SimulationResult
        Posterior samples, mean, σ and the Fisher σ (write it with :func:`write_simulation`).

    Raises
    ------
    InputError, SamplerInterrupted
        Bad options (one line naming the parameter), before the target is read; Ctrl-C (a
        ``KeyboardInterrupt``) carrying the chain so far as ``.partial``.

    Examples
    --------
    A short chain (20 steps; a real run takes the default 2000 or ``until_converged``):

    >>> import ucbplan
    >>> ucbplan.simulate("catalogs/fiducial-injection.yaml", seed=1, n_bins=64, steps=20)
    <SimulationResult Fiducial eccentric dWD (injection): 20 steps, 512 samples of 9 parameters,
    SNR 831.8, seed 1>
    """
    from ucbplan.lisa.pipeline import prepare_simulation

    options = _sampler_options(seed, walkers, steps, until_converged, max_steps, noise, resume)
    with scope():
        model = _model(target, t_obs, n_bins, circular)
        _walkers(walkers, model.theta0().size)
        problem = prepare_simulation(model, options)
    if on_ready is not None:
        on_ready(problem)
    return _sample(problem, progress, warn)


# --------------------------------------------------------------- the files the commands write


def _sample(
    problem: SimulationProblem,
    progress: Callable[[int, int, float], None] | None = None,
    warn: bool = True,
) -> SimulationResult:
    """Sample a prepared simulation: the second half of :func:`simulate`."""
    from ucbplan.lisa.pipeline import run_simulation

    with scope():
        result = run_simulation(problem, progress)
    if warn:
        emit(list(result.warnings), SamplerConvergenceWarning)
    return result


def simulation_outputs(output: str | Path, chain: str | Path | None = None) -> SimulationFiles:
    """The files :func:`write_simulation` writes: the posterior target ``output`` (YAML), its
    samples (ECSV) and the chain (.npz, default next to ``output``)."""
    from ucbplan.lisa.outputs import simulation_files

    return simulation_files(Path(output), None if chain is None else Path(chain))


def corner_plot_paths(folder: str | Path) -> list[Path]:
    """The corner plots :func:`write_simulation` draws into ``folder``."""
    from ucbplan.lisa.plots import CORNER_NAMES

    return [Path(folder) / name for name in CORNER_NAMES]


def write_simulation(
    result: SimulationResult,
    files: SimulationFiles,
    *,
    overwrite: bool = False,
    source_name: str | None = None,
) -> None:
    """Write the posterior target, samples and chain (all or none) of :func:`simulate`."""
    from ucbplan.lisa.outputs import write_simulation as _write

    _write(result, files, overwrite=overwrite, source_name=source_name)


def write_corner_plots(
    result: SimulationResult, folder: str | Path, *, overwrite: bool = False
) -> list[Path]:
    """The corner plots of :func:`simulate` (:func:`corner_plot_paths`) in ``folder``."""
    from ucbplan.lisa.plots import simulation_corner_plots

    return list(simulation_corner_plots(result, Path(folder), overwrite=overwrite))


def save_interrupted(
    problem: SimulationProblem, partial: Any, path: str | Path, *, overwrite: bool = False
) -> None:
    """Save the chain of an interrupted run (``SamplerInterrupted.partial``) for ``resume``."""
    from ucbplan.lisa.outputs import save_interrupted as _save

    _save(problem, partial, Path(path), overwrite=overwrite)


def write_forecast(
    forecast: FisherForecast, path: str | Path, *, n_bins: int, overwrite: bool = False
) -> None:
    """Write a :func:`fisher` forecast as a target YAML (``ucbplan fisher -o``)."""
    from ucbplan.targets import write_target

    header = f"ucbplan fisher: SNR {forecast.snr:.1f}, N={n_bins}"
    write_target(forecast.target, Path(path), overwrite=overwrite, header=header)


def plot_waveform(lines: WaveformLines, path: str | Path, *, overwrite: bool = False) -> None:
    """The amplitude spectral density of the three bands (``ucbplan waveform --plot``)."""
    from ucbplan.lisa.plots import waveform_plot

    waveform_plot(lines, Path(path), overwrite=overwrite)
