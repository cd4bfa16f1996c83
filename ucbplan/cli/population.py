"""``ucbplan population …``: whole LISA catalogs.

Thin shells: read the catalog, run one library function of :mod:`ucbplan.population` through
the executor seam (serial, ``--workers N`` processes, ``--scheduler tcp://HOST:PORT`` Dask, or a
``--cluster slurm|pbs`` started with dask-jobqueue), show a progress line on stderr, write the
ECSV table (and figures or target files). The options the commands share are declared once in
:mod:`ucbplan.cli._population_options` and reach the library as one
:class:`~ucbplan.population.execute.RunControl`.
"""

from __future__ import annotations

import contextlib
import dataclasses
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

import typer
from rich.markup import escape

from ucbplan.api import population_runs as runs
from ucbplan.api import populations as api
from ucbplan.api.flagspec import Flag
from ucbplan.cli._console import check_output_path, err_console
from ucbplan.cli._derive import option
from ucbplan.cli._population_options import (
    CatalogArg,
    Overwrite,
    PopulationArgs,
    TableOut,
    population_options,
)
from ucbplan.errors import UcbplanError

if TYPE_CHECKING:
    from rich.progress import Progress, TaskID

    from ucbplan.api.population_runs import ForecastRun
    from ucbplan.api.populations import Catalog, ExecutorSpec, ForecastOptions, RunControl

VIS, RANK, SIM = runs.VISIBILITY_FLAGS, runs.RANK_FLAGS, runs.POPULATION_SIMULATE_FLAGS


def _required(flags: dict[str, Flag], parameter: str) -> Any:
    """A required ``typer.Option`` with the flag and help declared for ``parameter``."""
    spec = flags[parameter]
    return typer.Option(..., *spec.decls, help=spec.help)


population_app = typer.Typer(
    help="Whole LISA catalogs: forecasts, visibility, ranking and simulations per source.",
    no_args_is_help=True,
)


def _catalog(path: Path, shared: PopulationArgs) -> Catalog:
    """The catalog, with its skipped rows printed (one yellow line each)."""
    cat = api.read_population(
        path, columns=shared.columns, hdf5_path=shared.hdf5_path, skip_bad=shared.skip_bad
    )
    _skipped(cat)
    return cat


def _skipped(cat: Catalog) -> None:
    for row, msg in cat.bad:
        err_console.print(f"[yellow]skipped row {row}: {escape(msg)}[/yellow]")


def _inputs(path: Path, shared: PopulationArgs) -> tuple[Catalog, ForecastOptions]:
    """The catalog and the checked forecast options (``--k-eff`` needed without masses)."""
    cat = _catalog(path, shared)
    opts = api.forecast_settings(
        sigma_v=shared.sigma_v,
        k_eff=shared.k_eff,
        t_obs=shared.t_obs,
        t_start=shared.t_start,
        n_bins=shared.n_bins,
    )
    api.check_k_source(cat, shared.k_eff)
    return cat, opts


def _control(output: Path, overwrite: bool, shared: PopulationArgs) -> RunControl:
    """Refuse an existing ``output`` (without ``--overwrite``), then the run control (checked)
    with the part files next to ``output``."""
    check_output_path(output, overwrite)
    return shared.control(api.parts_of(output), overwrite)


def _announce(cat: Catalog, path: Path, control: RunControl, where: str = "") -> None:
    err_console.print(
        f"{len(cat.sources)} sources from {escape(str(path))}; {where}{control.executor.describe()}"
    )


class _Bar:
    """A transient progress line on stderr (sources done, rate, ETA) while a run works."""

    def __init__(self, label: str) -> None:
        self.label, self.rate = label, api.progress_rate()
        self.prog: Progress | None = None
        self.task: TaskID | None = None

    def start(self, total: int) -> None:
        from rich.progress import BarColumn, Progress, TextColumn

        self.prog = Progress(
            TextColumn(self.label),
            BarColumn(),
            TextColumn(
                "{task.completed}/{task.total} sources {task.fields[rate]} ETA {task.fields[eta]}"
            ),
            console=err_console,
            transient=True,
        )
        self.prog.start()
        self.task = self.prog.add_task(self.label, total=total, rate="", eta="?")

    def update(self, done: int, n: int) -> None:
        r, eta = self.rate.eta(done, n)
        eta_text = "?" if eta != eta else f"{eta:.0f} s"
        if self.prog is not None and self.task is not None:
            self.prog.update(self.task, completed=done, rate=f"{r:.1f}/s", eta=eta_text)

    def __enter__(self) -> _Bar:
        return self

    def __exit__(self, *exc: object) -> None:
        if self.prog is not None:
            self.prog.stop()
            self.prog = None


def _run(
    label: str, cat: Catalog, control: RunControl, call: Callable[[RunControl], ForecastRun]
) -> ForecastRun:
    """``call(control)`` under a progress line on stderr (sources done, rate, ETA)."""
    with _Bar(label) as bar:
        bar.start(len(cat.sources))
        return call(dataclasses.replace(control, progress=bar.update))


def _finish(run: ForecastRun, output: Path, control: RunControl, keep_parts: bool) -> None:
    """Write the merged table, remove the parts (unless kept), print the summary line."""
    api.write_run(run.table, output, control.parts, overwrite=control.overwrite, keep=keep_parts)
    _summary(run.table.meta, output, run.chunk, run.reused, run.n_chunks)


def _summary(meta: Any, output: Path, chunk: int, reused: int, n_chunks: int) -> None:
    err_console.print(
        f"wrote {escape(str(output))}: {meta['n_ok']} ok, "
        f"{meta['n_below_threshold']} below threshold, {meta['n_unconstrained']} unconstrained, "
        f"{meta['n_failed']} failed; chunk {chunk}, {reused}/{n_chunks} parts reused"
    )


@population_app.command("forecast")
@population_options()
def forecast(
    catalog: CatalogArg,
    output: TableOut,
    *,
    shared: PopulationArgs,
    plots: Path | None = typer.Option(None, "--plots", help="Folder for the summary plots."),
    overwrite: Overwrite = False,
) -> None:
    """Per-source Fisher forecast of a catalog → ECSV (σ_u at the end, T_valid, SNR, status)."""
    _control(output, overwrite, shared)
    if plots is not None and not plots.is_dir():
        raise UcbplanError(f"--plots: folder {plots} does not exist; create it first")
    bar = _Bar("forecast")

    def ready(cat: Catalog, executor: ExecutorSpec) -> None:
        _skipped(cat)
        err_console.print(
            f"{len(cat.sources)} sources from {escape(str(catalog))}; {executor.describe()}"
        )
        bar.start(len(cat.sources))

    with bar:
        result = api.population_forecast(
            catalog,
            **{f.name: getattr(shared, f.name) for f in dataclasses.fields(shared)},
            output=output,
            overwrite=overwrite,
            progress=bar.update,
            on_ready=ready,
        )
    _summary(result.table.meta, output, result.chunk, result.reused, result.n_chunks)
    if plots is not None:
        for path in result.plot(plots, overwrite=overwrite):
            err_console.print(f"wrote {escape(str(path))}")


@population_app.command("visibility")
@population_options()
def visibility(
    catalog: CatalogArg,
    output: TableOut,
    semester: str = _required(VIS, "semester"),
    site: str | None = option(runs.visibility_settings, VIS, "site"),
    site_lonlat: str | None = option(runs.visibility_settings, VIS, "site_lonlat"),
    sites_file: Path | None = option(runs.visibility_settings, VIS, "sites_file"),
    airmass_max: float = option(runs.visibility_settings, VIS, "airmass_max"),
    twilight: str = option(runs.visibility_settings, VIS, "twilight"),
    moon_sep: float = option(runs.visibility_settings, VIS, "moon_sep"),
    min_hours: float = option(runs.visibility_settings, VIS, "min_hours"),
    exptime: float = option(runs.visibility_settings, VIS, "exptime"),
    alpha: float = option(runs.visibility_settings, VIS, "alpha"),
    *,
    shared: PopulationArgs,
    overwrite: Overwrite = False,
) -> None:
    """Per source: usable nights, hours at airmass < X, anchor epochs inside T_valid → ECSV."""
    control = _control(output, overwrite, shared)
    settings = runs.visibility_settings(
        semester,
        site=site,
        site_lonlat=site_lonlat,
        sites_file=sites_file,
        airmass_max=airmass_max,
        twilight=twilight,
        moon_sep=moon_sep,
        min_hours=min_hours,
        exptime=exptime,
        alpha=alpha,
    )
    cat, fopts = _inputs(catalog, shared)
    opts = dataclasses.replace(settings, forecast=fopts)
    where = f"{escape(opts.site.name)}, {opts.semester.upper()}; "
    _announce(cat, catalog, control, where)
    run = _run("visibility", cat, control, lambda c: runs.run_visibility(cat, opts, c))
    _finish(run, output, control, shared.keep_parts)


def _check_out_dir(out_dir: Path, first: Path | None, overwrite: bool) -> None:
    """Refuse an ``--out-dir`` that is not a folder, or whose ``first`` file exists, before any
    work; the folder itself is made only when there is something to write (:func:`_made_folder`).
    """
    if out_dir.exists() and not out_dir.is_dir():
        raise UcbplanError(f"--out-dir {out_dir}: exists and is not a folder; name a folder")
    if first is not None and out_dir.is_dir():
        check_output_path(first, overwrite)


@contextlib.contextmanager
def _made_folder(out_dir: Path) -> Iterator[None]:
    """Make ``out_dir`` (and its parents) for the block; remove it again if the block fails and
    left it empty, so that a failed run leaves no folder behind."""
    made = [p for p in (out_dir, *out_dir.parents) if not p.exists()]
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise UcbplanError(f"--out-dir {out_dir}: cannot create it ({exc.strerror})") from None
    try:
        yield
    except BaseException:
        for folder in made:  # deepest first
            with contextlib.suppress(OSError):
                folder.rmdir()  # only if empty
        raise


def _ranked_source(
    source: Path,
    catalog: Path | None,
    out_dir: Path,
    shared: PopulationArgs,
    executor: ExecutorSpec,
) -> tuple[Any, Catalog, ForecastOptions]:
    """(forecast table, catalog, forecast options) of ``rank``'s SOURCE: a forecast table
    (checked against its catalog), or a catalog forecast here (its parts removed after)."""
    forecast = runs.read_forecast(source)
    if forecast is not None:
        tab, fopts, cat_path = forecast
        cat = _catalog(catalog or cat_path, shared)
        runs.check_forecast_catalog(tab, cat, source)
        return tab, cat, fopts
    cat, fopts = _inputs(source, shared)
    with _made_folder(out_dir):
        parts = api.parts_of(out_dir / "forecast.ecsv")
        control = api.run_control(parts, executor, overwrite=True)
        try:
            tab = _run("forecast", cat, control, lambda c: runs.run_forecast(cat, fopts, c)).table
        finally:
            runs.remove_parts(control.parts)
    return tab, cat, fopts


@population_app.command("rank")
@population_options(parts=False)
def rank(
    source: Path = typer.Argument(..., help="Forecast table (ECSV) or an LDC-style catalog."),
    out_dir: Path = typer.Option(..., "--out-dir", help="Folder for ranked.ecsv and targets."),
    top: int = option(runs.rank_settings, RANK, "top"),
    goal: str = option(runs.rank_settings, RANK, "goal"),
    instrument: str | None = option(runs.rank_settings, RANK, "instrument"),
    instruments_file: Path | None = option(runs.rank_settings, RANK, "instruments_file"),
    sigma_ref: str | None = option(runs.rank_settings, RANK, "sigma_ref"),
    exptime: float = option(runs.rank_settings, RANK, "exptime"),
    readout: float | None = option(runs.rank_settings, RANK, "readout"),
    overhead: float | None = option(runs.rank_settings, RANK, "overhead"),
    visit: float = option(runs.rank_settings, RANK, "visit"),
    catalog: Path | None = typer.Option(
        None, "--catalog", help="The forecast's catalog (default: the path in its meta)."
    ),
    *,
    shared: PopulationArgs,
    overwrite: Overwrite = False,
) -> None:
    """Order sources by a stated figure of merit; target files for the top N (for `plan`)."""
    ranked_path = out_dir / "ranked.ecsv"
    _check_out_dir(out_dir, ranked_path, overwrite)
    executor = shared.executor()
    ropts = runs.rank_settings(
        top=top,
        goal=goal,
        instrument=instrument,
        instruments_file=instruments_file,
        sigma_ref=sigma_ref,
        exptime=exptime,
        readout=readout,
        overhead=overhead,
        visit=visit,
    )
    tab, cat, fopts = _ranked_source(source, catalog, out_dir, shared, executor)
    ranked = runs.rank_sources(tab, cat, ropts)
    with _made_folder(out_dir):
        paths = runs.write_ranked(ranked, cat, fopts, out_dir, top=top, overwrite=overwrite)
    err_console.print(
        f"wrote {escape(str(ranked_path))} ({ranked.meta['figure_of_merit']}) and "
        f"{len(paths)} target file(s) in {escape(str(out_dir))}"
    )


@population_app.command("simulate")
@population_options()
def simulate(
    catalog: CatalogArg,
    output: TableOut,
    out_dir: Path = typer.Option(..., "--out-dir", help="Folder for the posterior targets."),
    seed: int = option(runs.simulation_settings, SIM, "seed"),
    walkers: int = option(runs.simulation_settings, SIM, "walkers"),
    steps: int = option(runs.simulation_settings, SIM, "steps"),
    until_converged: bool = option(runs.simulation_settings, SIM, "until_converged"),
    max_steps: int = option(runs.simulation_settings, SIM, "max_steps"),
    no_noise: bool = option(runs.simulation_settings, SIM, "no_noise"),
    *,
    shared: PopulationArgs,
    overwrite: Overwrite = False,
) -> None:
    """Simulate LISA per source → summary ECSV (posterior vs Fisher σ) + a target file each."""
    control = _control(output, overwrite, shared)
    sampling = runs.simulation_settings(  # the options first, then the files, then the work
        seed=seed,
        walkers=walkers,
        steps=steps,
        until_converged=until_converged,
        max_steps=max_steps,
        no_noise=no_noise,
    )
    _check_out_dir(out_dir, None, overwrite)
    cat, fopts = _inputs(catalog, shared)
    opts = dataclasses.replace(sampling, forecast=fopts)
    _announce(cat, catalog, control)
    with _made_folder(out_dir):
        run = _run("simulate", cat, control, lambda c: runs.run_simulations(cat, opts, out_dir, c))
    _finish(run, output, control, shared.keep_parts)
    for f in run.table.meta["failed"]:
        err_console.print(f"[yellow]failed {escape(f['source_id'])}: {escape(f['error'])}[/yellow]")


@population_app.command("semester")
def semester(
    name: str = typer.Argument(..., help="2041A, 2041B or an ESO period like P147."),
) -> None:
    """Print the dates of a semester (A: Feb–Jul, B: Aug–Jan) or ESO period (P110 = 2022-10)."""
    first, end = api.semester(name)
    typer.echo(f"{name.strip().upper()}: {first.isoformat()} .. {end.isoformat()} (end exclusive)")


def register(app: typer.Typer) -> None:
    """Add the ``population`` command group to the ucbplan app."""
    app.add_typer(population_app, name="population")
