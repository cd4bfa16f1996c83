"""``ucbplan simulate | fisher | waveform``: the reduced LISA simulation (paper Sec. 4.1).

A thin shell over :mod:`ucbplan.api.lisa_analysis`: parse options (their defaults, flags and
help derived from the API's declarations), call the API, print. Human-readable summaries go to
stderr.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer
from rich.markup import escape

from ucbplan.api import lisa_analysis as api
from ucbplan.api.shell_files import check_figure_path, file_format
from ucbplan.cli._console import check_output_path, err_console, write_output
from ucbplan.cli._derive import argument, option
from ucbplan.cli._flags import cli_message
from ucbplan.cli._options import OverwriteAllOpt
from ucbplan.errors import InputError, OutputError, UcbplanError

if TYPE_CHECKING:
    from rich.progress import Progress, TaskID

    from ucbplan.api.lisa_analysis import SimulationFiles, SimulationProblem, SimulationResult

SIM, FIS, WAV = api.SIMULATE_FLAGS, api.FISHER_FLAGS, api.WAVEFORM_FLAGS
# simulate
PosteriorOutputOpt = Annotated[
    Path, typer.Option("-o", "--output", help="Posterior target YAML to write.")
]
ChainOpt = Annotated[Path | None, typer.Option("--chain", help="Chain .npz (default: next to -o).")]
PlotsOpt = Annotated[Path | None, typer.Option("--plots", help="Folder for corner plots.")]
# fisher
ForecastOutputOpt = Annotated[
    Path | None, typer.Option("-o", "--output", help="Forecast target YAML.")
]
OverwriteForecastOpt = Annotated[
    bool, typer.Option("--overwrite", help="Replace an existing output.")
]
# waveform
LinesOutputOpt = Annotated[Path, typer.Option("-o", "--output", help="Lines table (ECSV).")]
AsdPlotOpt = Annotated[Path | None, typer.Option("--plot", help="ASD figure of the three bands.")]
OverwritesOpt = Annotated[bool, typer.Option("--overwrite", help="Replace existing outputs.")]


def _require_suffix(path: Path, fmt: str, option: str, what: str) -> None:
    """The -o rule for single-format outputs: a suffix naming another format is an error."""
    if file_format(path, fmt) != fmt:
        raise InputError(f"{option} {path}: {what} is {fmt.upper()}; give the file a .{fmt} name")


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
    target: Path = argument(SIM, "target"),
    output: PosteriorOutputOpt = ...,  # type: ignore[assignment]
    t_obs: str | None = option(api.simulate, SIM, "t_obs"),
    seed: int = option(api.simulate, SIM, "seed"),
    walkers: int = option(api.simulate, SIM, "walkers"),
    steps: int = option(api.simulate, SIM, "steps"),
    until_converged: bool = option(api.simulate, SIM, "until_converged"),
    max_steps: int = option(api.simulate, SIM, "max_steps"),
    noise: bool = option(api.simulate, SIM, "noise"),
    n_bins: int = option(api.simulate, SIM, "n_bins"),
    circular: bool = option(api.simulate, SIM, "circular"),
    chain: ChainOpt = None,
    plots: PlotsOpt = None,
    resume: Path | None = option(api.simulate, SIM, "resume"),
    overwrite: OverwriteAllOpt = False,
) -> None:
    """Simulate a LISA observation and sample the targeted-search posterior → target YAML."""
    files = _simulation_files(output, chain, plots, overwrite)
    shown = _Shown(steps)
    try:
        result = api.simulate(
            target,
            seed,
            t_obs=t_obs,
            n_bins=n_bins,
            circular=circular,
            walkers=walkers,
            steps=steps,
            until_converged=until_converged,
            max_steps=max_steps,
            noise=noise,
            resume=resume,
            progress=shown.progress,
            on_ready=shown.ready,
            warn=False,
        )
    except KeyboardInterrupt as stop:
        shown.close()
        if shown.problem is not None and hasattr(stop, "partial"):  # SamplerInterrupted
            _save_interrupted(shown.problem, stop.partial, files, target, overwrite)
        raise
    finally:
        shown.close()
    _write_simulation(result, files, target, plots, overwrite)


def _simulation_files(
    output: Path, chain: Path | None, plots: Path | None, overwrite: bool
) -> SimulationFiles:
    """The files ``simulate`` writes, each checked before any work is done."""
    _require_suffix(output, "yaml", "-o", "the posterior target file")
    files = api.simulation_outputs(output, chain)
    for p in (files.target, files.samples, files.chain):
        check_output_path(p, overwrite)
    if plots is not None:
        if not plots.is_dir():
            raise UcbplanError(f"--plots: folder {plots} does not exist; create it first")
        for path in api.corner_plot_paths(plots):  # before sampling, not after it
            check_output_path(path, overwrite)
    return files


def _write_simulation(
    result: SimulationResult,
    files: SimulationFiles,
    target: Path,
    plots: Path | None,
    overwrite: bool,
) -> None:
    """Warnings, the posterior file set, the summary table and the corner plots."""
    for warning in result.warnings:
        err_console.print(f"[yellow]warning: {escape(warning)}[/yellow]")
    api.write_simulation(result, files, overwrite=overwrite, source_name=target.name)
    title = f"{result.model.base.name} (posterior): posterior vs injection"
    sigma, mean = result.posterior_sigma, result.posterior_mean
    _summary(title, result.names, result.injected, sigma, mean, result.fisher_sigma)
    if plots is not None:
        api.write_corner_plots(result, plots, overwrite=overwrite)
    written = f"{files.target}, {files.samples.name}, {files.chain.name}"
    err_console.print(f"wrote {escape(written)}")


def _save_interrupted(
    problem: SimulationProblem,
    partial: object,
    files: SimulationFiles,
    target: Path,
    overwrite: bool,
) -> None:
    """Ctrl-C: keep the chain so far for --resume (the interrupt then ends the program)."""
    if partial is None:
        err_console.print("interrupted before the first step: nothing to save", markup=False)
        return
    n = partial.theta.shape[0]  # type: ignore[attr-defined]
    try:
        api.save_interrupted(problem, partial, files.chain, overwrite=overwrite)
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


class _Shown:
    """The run on stderr: its summary line once the data are drawn, then a transient progress
    bar while the sampler runs."""

    def __init__(self, steps: int) -> None:
        self.steps = steps
        self.problem: SimulationProblem | None = None
        self.bar: Progress | None = None
        self.task: TaskID | None = None

    def ready(self, problem: SimulationProblem) -> None:
        from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

        self.problem, model, opts = problem, problem.model, problem.options
        err_console.print(
            f"{model.base.name}: optimal SNR {problem.snr:.1f}, T_obs = {model.t_obs_s:.6f} s, "
            f"N = {model.n_bins} bins, {problem.theta0.size} parameters, "
            f"noise {'on' if opts.noise else 'off'}, seed {opts.seed}"
        )
        bar = self.bar = Progress(
            TextColumn("emcee"),
            BarColumn(),
            TextColumn("{task.completed}/{task.total} steps τ_max≈{task.fields[tau]}"),
            TimeRemainingColumn(),
            console=err_console,
            transient=True,
        )
        bar.start()
        self.task = bar.add_task("emcee", total=self.steps, tau="?")

    def progress(self, done: int, total: int, tau: float) -> None:
        if self.bar is not None and self.task is not None:
            self.bar.update(self.task, completed=done, total=total, tau=f"{tau:.0f}")

    def close(self) -> None:
        if self.bar is not None:
            self.bar.stop()
            self.bar = None


def fisher(
    target: Path = argument(FIS, "target"),
    output: ForecastOutputOpt = None,
    t_obs: str | None = option(api.fisher, FIS, "t_obs"),
    n_bins: int = option(api.fisher, FIS, "n_bins"),
    circular: bool = option(api.fisher, FIS, "circular"),
    overwrite: OverwriteForecastOpt = False,
) -> None:
    """Fisher-matrix forecast of the targeted-search parameters → target YAML (midpoint)."""
    if output is not None:
        _require_suffix(output, "yaml", "-o", "the forecast target file")
        check_output_path(output, overwrite)
    forecast = api.fisher(target, t_obs=t_obs, n_bins=n_bins, circular=circular, warn=False)
    for warning in forecast.warnings:
        err_console.print(f"[yellow]warning: {escape(warning)}[/yellow]")
    fis = forecast.target
    _summary(f"{fis.name}: SNR {forecast.snr:.1f}", fis.cov_names, forecast.values, forecast.sigmas)
    if output is not None:
        api.write_forecast(forecast, output, n_bins=n_bins, overwrite=overwrite)
        err_console.print(f"wrote {escape(str(output))}")


def waveform(
    target: Path = argument(WAV, "target"),
    output: LinesOutputOpt = ...,  # type: ignore[assignment]
    plot: AsdPlotOpt = None,
    t_obs: str | None = option(api.waveform, WAV, "t_obs"),
    n_bins: int = option(api.waveform, WAV, "n_bins"),
    overwrite: OverwritesOpt = False,
) -> None:
    """Injected TDI A, E per band (ECSV: band, freq_hz, A_re, A_im, E_re, E_im, psd_a)."""
    _require_suffix(output, "ecsv", "-o", "the lines table")
    if plot is not None and plot.resolve() == output.resolve():
        raise InputError(f"{plot}: --plot and -o name the same file; give each its own name")
    check_output_path(output, overwrite)
    if plot is not None:
        check_figure_path(plot, overwrite)
    lines = api.waveform(target, t_obs=t_obs, n_bins=n_bins)
    write_output(output, lambda h: lines.table.write(h, format="ascii.ecsv"), overwrite=overwrite)
    if plot is not None:
        api.plot_waveform(lines, plot, overwrite=overwrite)
    nb, n = lines.model.model.freqs_hz.shape
    err_console.print(
        escape(
            f"{lines.model.base.name}: {nb} bands x {n} bins, optimal SNR {lines.snr:.1f}; "
            f"wrote {output}" + (f" and {plot}" if plot is not None else "")
        )
    )


def register(app: typer.Typer) -> None:
    """Add ``simulate``, ``fisher`` and ``waveform`` to the ucbplan app."""
    app.command("simulate")(simulate)
    app.command("fisher")(fisher)
    app.command("waveform")(waveform)
