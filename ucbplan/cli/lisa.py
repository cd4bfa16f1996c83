"""``ucbplan simulate | fisher | waveform``: the reduced LISA simulation (paper Sec. 4.1).

A thin shell: parse options, build the model from the target file, call
:mod:`ucbplan.lisa.pipeline` (or :mod:`ucbplan.lisa.lines`), print. Human-readable summaries go to
stderr. The option types are module-level aliases so each command reads as its parameter list.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer
from rich.markup import escape

from ucbplan.cli._console import check_output_path, err_console, write_output
from ucbplan.cli._options import OverwriteAllOpt
from ucbplan.errors import InputError, UcbplanError
from ucbplan.io import output_format
from ucbplan.lisa import MAX_N_BINS as MAX_BINS

if TYPE_CHECKING:
    from ucbplan.lisa.outputs import SimulationFiles
    from ucbplan.lisa.sampler import SamplerInterrupted
    from ucbplan.lisa.simulation import LisaModel, SimulationProblem, SimulationResult
    from ucbplan.target import Target

__all__ = ["register"]

InjectionArg = Annotated[
    Path, typer.Argument(help="Target or injection YAML (needs amplitude, psi).")
]
TObsOpt = Annotated[str | None, typer.Option("--t-obs", help="Observation length, e.g. '4yr'.")]
BinsOpt = Annotated[int, typer.Option("--n-bins", help="Band width N in bins.")]
# simulate
PosteriorOutputOpt = Annotated[
    Path, typer.Option("-o", "--output", help="Posterior target YAML to write.")
]
SeedOpt = Annotated[int, typer.Option("--seed", min=0, help="Seed for the noise and the sampler.")]
WalkersOpt = Annotated[int, typer.Option("--walkers", help="emcee walkers (>= 2 x parameters).")]
StepsOpt = Annotated[
    int, typer.Option("--steps", min=1, help="Steps (minimum with --until-converged).")
]
UntilConvergedOpt = Annotated[
    bool, typer.Option("--until-converged", help="Extend the chain until it is >= 50 τ long.")
]
MaxStepsOpt = Annotated[int, typer.Option("--max-steps", min=1, help="Cap for --until-converged.")]
NoiseOpt = Annotated[bool, typer.Option("--noise/--no-noise", help="Add a Gaussian noise draw.")]
SimulateBinsOpt = Annotated[
    int, typer.Option("--n-bins", help="Band width N in bins (injection = templates).")
]
CircularFitOpt = Annotated[
    bool, typer.Option("--circular", help="Fit the 6-parameter circular model.")
]
ChainOpt = Annotated[Path | None, typer.Option("--chain", help="Chain .npz (default: next to -o).")]
PlotsOpt = Annotated[Path | None, typer.Option("--plots", help="Folder for corner plots.")]
ResumeOpt = Annotated[
    Path | None,
    typer.Option("--resume", help="Continue a saved chain (.npz) of a run with the same options."),
]
# fisher
ForecastOutputOpt = Annotated[
    Path | None, typer.Option("-o", "--output", help="Forecast target YAML.")
]
CircularOpt = Annotated[bool, typer.Option("--circular", help="6-parameter circular model.")]
OverwriteForecastOpt = Annotated[
    bool, typer.Option("--overwrite", help="Replace an existing output.")
]
# waveform
LinesOutputOpt = Annotated[Path, typer.Option("-o", "--output", help="Lines table (ECSV).")]
AsdPlotOpt = Annotated[Path | None, typer.Option("--plot", help="ASD figure of the three bands.")]
OverwritesOpt = Annotated[bool, typer.Option("--overwrite", help="Replace existing outputs.")]


def _t_obs(text: str | None, default_s: float) -> float:
    from ucbplan.api.reduction import t_obs_seconds

    return t_obs_seconds(text, default_s, "--t-obs")


def _check_n_bins(n_bins: int) -> None:
    if not (16 <= n_bins <= MAX_BINS and n_bins % 2 == 0):
        raise InputError(
            f"--n-bins: expected an even number of bins in [16, {MAX_BINS}], got {n_bins}"
        )


def _require_suffix(path: Path, fmt: str, option: str, what: str) -> None:
    """The -o rule for single-format outputs: a suffix naming another format is an error."""
    known = ("yaml", "json", "ecsv", "csv")
    if output_format(path, None, known, fmt) != fmt:
        raise InputError(f"{option} {path}: {what} is {fmt.upper()}; give the file a .{fmt} name")


def _target(target_path: Path, t_obs: str | None, n_bins: int) -> tuple[Target, float]:
    """Parse the shared options: the target file and the observation length [s]."""
    from ucbplan.target import load_target

    _check_n_bins(n_bins)
    target = load_target(target_path)
    return target, _t_obs(t_obs, target.t_obs_s)


def _model(target_path: Path, t_obs: str | None, n_bins: int, circular: bool) -> LisaModel:
    """Parse the shared options and build the injection model from the target file."""
    from ucbplan.lisa.pipeline import build_model

    target, t_obs_s = _target(target_path, t_obs, n_bins)
    return build_model(
        target, t_obs_s=t_obs_s, n_bins=n_bins, circular=circular, where=str(target_path)
    )


_UNITS = {"phase": "rad", "f_gw": "Hz", "fdot": "Hz/s", "omega_dot": "rad/s", "psi": "rad"}


def _summary(
    title: str,
    names: tuple[str, ...],
    inj: dict,
    sig: dict,
    mean: dict | None = None,
    fis: dict | None = None,
) -> None:
    """Rich table on stderr: value (and posterior mean, Fisher σ when given) per parameter."""
    from rich.table import Table

    cols = ["parameter (midpoint)", "unit", "injected" if mean is not None else "value"]
    cols += ["estimate"] if mean is not None else []
    cols += ["σ"] + (["Fisher σ", "σ/Fisher"] if fis is not None else [])
    tab = Table(title=title, title_justify="left")
    for col in cols:
        tab.add_column(col, justify="left" if col == cols[0] else "right")
    for n in names:
        row = [n, _UNITS.get(n, "1"), f"{inj[n]:.10g}"]
        row += [f"{mean[n]:.10g}"] if mean is not None else []
        row += [f"{sig[n]:.4g}"]
        if fis is not None:
            row += [f"{fis[n]:.4g}", f"{sig[n] / fis[n]:.3f}"]
        tab.add_row(*row)
    err_console.print(tab)


def simulate(
    target: InjectionArg,
    output: PosteriorOutputOpt,
    t_obs: TObsOpt = None,
    seed: SeedOpt = 0,
    walkers: WalkersOpt = 32,
    steps: StepsOpt = 2000,
    until_converged: UntilConvergedOpt = False,
    max_steps: MaxStepsOpt = 50000,
    noise: NoiseOpt = True,
    n_bins: SimulateBinsOpt = 512,
    circular: CircularFitOpt = False,
    chain: ChainOpt = None,
    plots: PlotsOpt = None,
    resume: ResumeOpt = None,
    overwrite: OverwriteAllOpt = False,
) -> None:
    """Simulate a LISA observation and sample the targeted-search posterior → target YAML."""
    from ucbplan.lisa.pipeline import setup_simulation
    from ucbplan.lisa.sampler import SamplerInterrupted

    files = _simulation_files(output, chain, plots, overwrite)
    tgt, t_obs_s = _target(target, t_obs, n_bins)
    problem = setup_simulation(
        tgt,
        t_obs_s=t_obs_s,
        n_bins=n_bins,
        circular=circular,
        seed=seed,
        walkers=walkers,
        steps=steps,
        until_converged=until_converged,
        max_steps=max_steps,
        noise=noise,
        resume=resume,
        where=str(target),
    )
    model = problem.model
    err_console.print(
        f"{model.base.name}: optimal SNR {problem.snr:.1f}, T_obs = {model.t_obs_s:.6f} s, "
        f"N = {n_bins} bins, {problem.theta0.size} parameters, noise {'on' if noise else 'off'}, "
        f"seed {seed}"
    )
    try:
        result = _run_with_progress(problem, steps)
    except SamplerInterrupted as stop:
        _save_interrupted(problem, stop, files, target, overwrite)
        raise
    _write_simulation(result, files, target, plots, overwrite)


def _simulation_files(
    output: Path, chain: Path | None, plots: Path | None, overwrite: bool
) -> SimulationFiles:
    """The files ``simulate`` writes, each checked before any work is done."""
    from ucbplan.lisa.outputs import simulation_files

    _require_suffix(output, "yaml", "-o", "the posterior target file")
    files = simulation_files(output, chain)
    for p in (files.target, files.samples, files.chain):
        check_output_path(p, overwrite)
    if plots is not None:
        from ucbplan.lisa.plots import CORNER_NAMES

        if not plots.is_dir():
            raise UcbplanError(f"--plots: folder {plots} does not exist; create it first")
        for name in CORNER_NAMES:  # before sampling, not after it
            check_output_path(plots / name, overwrite)
    return files


def _write_simulation(
    result: SimulationResult,
    files: SimulationFiles,
    target: Path,
    plots: Path | None,
    overwrite: bool,
) -> None:
    """Warnings, the posterior file set, the summary table and the corner plots."""
    from ucbplan.lisa.outputs import write_simulation
    from ucbplan.lisa.plots import simulation_corner_plots

    for warning in result.warnings:
        err_console.print(f"[yellow]warning: {escape(warning)}[/yellow]")
    write_simulation(result, files, overwrite=overwrite, source_name=target.name)
    title = f"{result.model.base.name} (posterior): posterior vs injection"
    sigma, mean = result.posterior_sigma, result.posterior_mean
    _summary(title, result.names, result.injected, sigma, mean, result.fisher_sigma)
    if plots is not None:
        simulation_corner_plots(result, plots, overwrite=overwrite)
    written = f"{files.target}, {files.samples.name}, {files.chain.name}"
    err_console.print(f"wrote {escape(written)}")


def _save_interrupted(
    problem: SimulationProblem,
    stop: SamplerInterrupted,
    files: SimulationFiles,
    target: Path,
    overwrite: bool,
) -> None:
    """Ctrl-C: keep the chain so far for --resume (the interrupt then ends the program)."""
    from ucbplan.cli._flags import cli_message
    from ucbplan.errors import OutputError
    from ucbplan.lisa.outputs import save_interrupted

    if stop.partial is None:
        err_console.print("interrupted before the first step: nothing to save", markup=False)
        return
    n = stop.partial.theta.shape[0]
    try:
        save_interrupted(problem, stop.partial, files.chain, overwrite=overwrite)
    except OutputError as exc:
        err_console.print(
            f"interrupted after {n} steps; the chain was not saved: {cli_message(str(exc))}",
            markup=False,
        )
        return
    err_console.print(
        f"interrupted after {n} steps: chain saved to {files.chain}; continue with "
        f"ucbplan simulate {target} -o {files.target} --resume {files.chain} --overwrite "
        "and the same options",
        markup=False,
        soft_wrap=True,
    )


def _run_with_progress(problem: SimulationProblem, steps: int) -> SimulationResult:
    """:func:`ucbplan.lisa.pipeline.run_simulation` under a transient progress bar on stderr."""
    from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

    from ucbplan.lisa.pipeline import run_simulation

    with Progress(
        TextColumn("emcee"),
        BarColumn(),
        TextColumn("{task.completed}/{task.total} steps τ_max≈{task.fields[tau]}"),
        TimeRemainingColumn(),
        console=err_console,
        transient=True,
    ) as prog:
        task = prog.add_task("emcee", total=steps, tau="?")

        def _progress(done: int, total: int, tau: float) -> None:
            prog.update(task, completed=done, total=total, tau=f"{tau:.0f}")

        return run_simulation(problem, _progress)


def fisher(
    target: InjectionArg,
    output: ForecastOutputOpt = None,
    t_obs: TObsOpt = None,
    n_bins: BinsOpt = 512,
    circular: CircularOpt = False,
    overwrite: OverwriteForecastOpt = False,
) -> None:
    """Fisher-matrix forecast of the targeted-search parameters → target YAML (midpoint)."""
    from ucbplan.lisa.pipeline import fisher_forecast
    from ucbplan.target import write_target

    if output is not None:
        _require_suffix(output, "yaml", "-o", "the forecast target file")
        check_output_path(output, overwrite)
    model = _model(target, t_obs, n_bins, circular)
    forecast = fisher_forecast(model)
    for warning in forecast.warnings:
        err_console.print(f"[yellow]warning: {escape(warning)}[/yellow]")
    fis = forecast.target
    _summary(f"{fis.name}: SNR {forecast.snr:.1f}", fis.cov_names, forecast.values, forecast.sigmas)
    if output is not None:
        header = f"ucbplan fisher: SNR {forecast.snr:.1f}, N={n_bins}"
        write_target(fis, output, overwrite=overwrite, header=header)
        err_console.print(f"wrote {escape(str(output))}")


def waveform(
    target: InjectionArg,
    output: LinesOutputOpt,
    plot: AsdPlotOpt = None,
    t_obs: TObsOpt = None,
    n_bins: BinsOpt = 512,
    overwrite: OverwritesOpt = False,
) -> None:
    """Injected TDI A, E per band (ECSV: band, freq_hz, A_re, A_im, E_re, E_im, psd_a)."""
    from ucbplan.lisa.lines import waveform_lines
    from ucbplan.lisa.plots import waveform_plot

    _require_suffix(output, "ecsv", "-o", "the lines table")
    if plot is not None and plot.resolve() == output.resolve():
        raise InputError(f"{plot}: --plot and -o name the same file; give each its own name")
    check_output_path(output, overwrite)
    if plot is not None:
        from ucbplan.plotting import check_figure_path

        check_figure_path(plot, overwrite)
    model = _model(target, t_obs, n_bins, False)
    lines = waveform_lines(model)
    write_output(output, lambda h: lines.table.write(h, format="ascii.ecsv"), overwrite=overwrite)
    if plot is not None:
        waveform_plot(lines, plot, overwrite=overwrite)
    nb, n = model.model.freqs_hz.shape
    err_console.print(
        escape(
            f"{model.base.name}: {nb} bands x {n} bins, optimal SNR {lines.snr:.1f}; "
            f"wrote {output}" + (f" and {plot}" if plot is not None else "")
        )
    )


def register(app: typer.Typer) -> None:
    """Add ``simulate``, ``fisher`` and ``waveform`` to the ucbplan app."""
    app.command("simulate")(simulate)
    app.command("fisher")(fisher)
    app.command("waveform")(waveform)
