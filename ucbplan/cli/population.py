"""``ucbplan population …``: whole LISA catalogs (issue 13).

Thin shells: read the catalog, run one library function of :mod:`ucbplan.population` through
the executor seam (serial, ``--workers N`` processes, ``--scheduler tcp://HOST:PORT`` Dask, or a
``--cluster slurm|pbs`` started with dask-jobqueue), show a progress line on stderr, write the
ECSV table (and figures or target files).
"""

from __future__ import annotations

import contextlib
import dataclasses
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.markup import escape

from ucbplan.cli._console import check_output_path, err_console
from ucbplan.errors import UcbplanError

__all__ = ["register"]

population_app = typer.Typer(
    help="Whole LISA catalogs: forecasts, visibility, ranking and simulations per source.",
    no_args_is_help=True,
)

CatalogArg = Annotated[Path, typer.Argument(help="LDC-style catalog: ECSV, CSV or HDF5 (.h5).")]
TableOut = Annotated[Path, typer.Option("-o", "--output", help="Output table (ECSV).")]
SigmaV = Annotated[float, typer.Option("--sigma-v", help="RV precision per epoch [km/s].")]
KEff = Annotated[
    float | None,
    typer.Option("--k-eff", help="K for the tolerance [km/s] (default: K1+K2 from Mass1, Mass2)."),
]
TObs = Annotated[str | None, typer.Option("--t-obs", help="LISA observation, e.g. '4yr'.")]
TStart = Annotated[str, typer.Option("--t-start", help="LISA start (TDB): the catalog's t = 0.")]
NBins = Annotated[int, typer.Option("--n-bins", help="Band width N of the Fisher model.")]
Columns = Annotated[
    str | None, typer.Option("--columns", help="Column map old=new,... onto the LDC names.")
]
Hdf5Path = Annotated[str | None, typer.Option("--hdf5-path", help="Table inside an HDF5 file.")]
SkipBad = Annotated[bool, typer.Option("--skip-bad", help="Skip bad rows (listed in meta).")]
Workers = Annotated[int, typer.Option("--workers", help="Local processes (1 = serial).")]
Scheduler = Annotated[
    str | None,
    typer.Option("--scheduler", help="Existing Dask scheduler, tcp://HOST:PORT (ucbplan[dask])."),
]
Cluster = Annotated[
    str | None,
    typer.Option(
        "--cluster", help="Start Dask workers on a batch system: slurm | pbs (dask-jobqueue)."
    ),
]
Jobs = Annotated[int, typer.Option("--jobs", help="Batch jobs to start with --cluster.")]
Chunk = Annotated[int | None, typer.Option("--chunk", help="Sources per task (default ≥ ~1 s).")]
Resume = Annotated[bool, typer.Option("--resume", help="Reuse finished part files.")]
KeepParts = Annotated[bool, typer.Option("--keep-parts", help="Keep part files after merging.")]
Overwrite = Annotated[bool, typer.Option("--overwrite", help="Replace existing outputs.")]
DEFAULT_T_START = "2035-01-01T00:00:00"


def _catalog(path: Path, columns: str | None, hdf5_path: str | None, skip_bad: bool) -> Any:
    """The catalog, with its skipped rows printed (one yellow line each)."""
    from ucbplan.population.catalog import parse_column_map, read_catalog

    cat = read_catalog(path, parse_column_map(columns), skip_bad=skip_bad, hdf5_path=hdf5_path)
    for row, msg in cat.bad:
        err_console.print(f"[yellow]skipped row {row}: {escape(msg)}[/yellow]")
    return cat


def _spec(workers: int, scheduler: str | None, cluster: str | None, jobs: int) -> Any:
    from ucbplan.population.execute import ExecutorSpec

    return ExecutorSpec(workers=workers, scheduler=scheduler, cluster=cluster, jobs=jobs)


def _forecast_opts(
    cat: Any, sigma_v: float, k_eff: float | None, t_obs: str | None, t_start: str, n_bins: int
) -> Any:
    from ucbplan.population.forecast import forecast_options

    opts = forecast_options(
        sigma_v_kms=sigma_v, k_eff_kms=k_eff, t_obs=t_obs, t_start=t_start, n_bins=n_bins
    )
    if k_eff is None and not {"Mass1", "Mass2"} <= set(cat.optional):
        raise UcbplanError(f"--k-eff: needed: {cat.path.name} has no Mass1 and Mass2 columns")
    return opts


def _with_progress(label: str, total: int, run: Callable[[Any], Any]) -> Any:
    """``run(progress)`` under a progress line on stderr (sources done, rate, ETA)."""
    from rich.progress import BarColumn, Progress, TextColumn

    from ucbplan.population.execute import Rate

    rate = Rate()
    with Progress(
        TextColumn(label),
        BarColumn(),
        TextColumn(
            "{task.completed}/{task.total} sources {task.fields[rate]} ETA {task.fields[eta]}"
        ),
        console=err_console,
        transient=True,
    ) as prog:
        task = prog.add_task(label, total=total, rate="", eta="?")

        def _progress(done: int, n: int) -> None:
            r, eta = rate.eta(done, n)
            eta_text = "?" if eta != eta else f"{eta:.0f} s"
            prog.update(task, completed=done, rate=f"{r:.1f}/s", eta=eta_text)

        return run(_progress)


def _finish(run: Any, output: Path, overwrite: bool, keep_parts: bool) -> None:
    """Write the merged table, remove the parts (unless kept), print the summary line."""
    from ucbplan.population.execute import remove_parts
    from ucbplan.population.run import parts_folder, write_table

    write_table(run.table, output, overwrite)
    if not keep_parts:
        remove_parts(parts_folder(output))
    meta = run.table.meta
    err_console.print(
        f"wrote {escape(str(output))}: {meta['n_ok']} ok, {meta['n_unconstrained']} unconstrained, "
        f"{meta['n_failed']} failed; chunk {run.chunk}, {run.reused}/{run.n_chunks} parts reused"
    )


@population_app.command("forecast")
def forecast(
    catalog: CatalogArg,
    output: TableOut,
    sigma_v: SigmaV = 15.0,
    k_eff: KEff = None,
    t_obs: TObs = None,
    t_start: TStart = DEFAULT_T_START,
    n_bins: NBins = 512,
    columns: Columns = None,
    hdf5_path: Hdf5Path = None,
    skip_bad: SkipBad = False,
    workers: Workers = 1,
    scheduler: Scheduler = None,
    cluster: Cluster = None,
    jobs: Jobs = 2,
    chunk: Chunk = None,
    resume: Resume = False,
    keep_parts: KeepParts = False,
    plots: Path | None = typer.Option(None, "--plots", help="Folder for the summary plots."),
    overwrite: Overwrite = False,
) -> None:
    """Per-source Fisher forecast of a catalog → ECSV (σ_u at the end, T_valid, SNR, status)."""
    from ucbplan.population.plots import forecast_plots
    from ucbplan.population.run import parts_folder, run_forecast

    check_output_path(output, overwrite)
    spec = _spec(workers, scheduler, cluster, jobs)
    if plots is not None and not plots.is_dir():
        raise UcbplanError(f"--plots: folder {plots} does not exist; create it first")
    cat = _catalog(catalog, columns, hdf5_path, skip_bad)
    opts = _forecast_opts(cat, sigma_v, k_eff, t_obs, t_start, n_bins)
    err_console.print(f"{len(cat.sources)} sources from {escape(str(catalog))}; {spec.describe()}")
    parts = parts_folder(output)
    run = _with_progress(
        "forecast",
        len(cat.sources),
        lambda p: run_forecast(
            cat,
            opts,
            spec=spec,
            parts=parts,
            chunk=chunk,
            resume=resume,
            overwrite=overwrite,
            progress=p,
        ),
    )
    _finish(run, output, overwrite, keep_parts)
    if plots is not None:
        for path in forecast_plots(run.table, plots, overwrite=overwrite):
            err_console.print(f"wrote {escape(str(path))}")


@population_app.command("visibility")
def visibility(
    catalog: CatalogArg,
    output: TableOut,
    semester: str = typer.Option(..., "--semester", help="2041A, 2041B or an ESO period P147."),
    site: str | None = typer.Option(None, "--site", help="Site name or alias (e.g. paranal)."),
    site_lonlat: str | None = typer.Option(
        None, "--site-lonlat", help="LON,LAT,HEIGHT (deg east, deg north, m) instead of --site."
    ),
    sites_file: Path | None = typer.Option(None, "--sites-file", help="YAML site table."),
    airmass_max: float = typer.Option(2.0, "--airmass-max", help="Largest airmass (sec z)."),
    twilight: str = typer.Option("nautical", "--twilight", help="civil|nautical|astronomical"),
    moon_sep: float = typer.Option(30.0, "--moon-sep", help="Smallest Moon separation [deg]."),
    min_hours: float = typer.Option(1.0, "--min-hours", help="Usable hours of a usable night."),
    exptime: float = typer.Option(60.0, "--exptime", help="Block (exposure) length [s]."),
    alpha: float = typer.Option(1.0, "--alpha", help="Planning margin α of T_valid."),
    sigma_v: SigmaV = 15.0,
    k_eff: KEff = None,
    t_obs: TObs = None,
    t_start: TStart = DEFAULT_T_START,
    n_bins: NBins = 512,
    columns: Columns = None,
    hdf5_path: Hdf5Path = None,
    skip_bad: SkipBad = False,
    workers: Workers = 1,
    scheduler: Scheduler = None,
    cluster: Cluster = None,
    jobs: Jobs = 2,
    chunk: Chunk = None,
    resume: Resume = False,
    keep_parts: KeepParts = False,
    overwrite: Overwrite = False,
) -> None:
    """Per source: usable nights, hours at airmass < X, anchor epochs inside T_valid → ECSV."""
    from ucbplan.observing.blocks import ExposurePlan
    from ucbplan.observing.schedule.settings import PlanSettings
    from ucbplan.observing.sites import resolve_site
    from ucbplan.population.run import parts_folder, run_visibility
    from ucbplan.population.visibility import VisibilityOptions

    check_output_path(output, overwrite)
    spec = _spec(workers, scheduler, cluster, jobs)
    where = resolve_site(site, site_lonlat, sites_file)
    settings = PlanSettings(
        twilight=twilight,
        airmass_max=airmass_max,
        moon_sep_deg=moon_sep,
        exposure=ExposurePlan(exptime_s=exptime),
        alpha=alpha,
    )
    cat = _catalog(catalog, columns, hdf5_path, skip_bad)
    fopts = _forecast_opts(cat, sigma_v, k_eff, t_obs, t_start, n_bins)
    opts = VisibilityOptions(
        site=where, semester=semester, settings=settings, min_hours=min_hours, forecast=fopts
    )
    err_console.print(
        f"{len(cat.sources)} sources from {escape(str(catalog))}; {escape(where.name)}, "
        f"{opts.semester.upper()}; {spec.describe()}"
    )
    parts = parts_folder(output)
    run = _with_progress(
        "visibility",
        len(cat.sources),
        lambda p: run_visibility(
            cat,
            opts,
            spec=spec,
            parts=parts,
            chunk=chunk,
            resume=resume,
            overwrite=overwrite,
            progress=p,
        ),
    )
    _finish(run, output, overwrite, keep_parts)


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


@population_app.command("rank")
def rank(
    source: Path = typer.Argument(..., help="Forecast table (ECSV) or an LDC-style catalog."),
    out_dir: Path = typer.Option(..., "--out-dir", help="Folder for ranked.ecsv and targets."),
    top: int = typer.Option(10, "--top", help="Write target files for the best N."),
    goal: str = typer.Option("K1=5%", "--goal", help="Precision goal (K1=5%, M1=2%, q=3%…)."),
    instrument: str | None = typer.Option(None, "--instrument", help="σ_ref and overheads."),
    instruments_file: Path | None = typer.Option(None, "--instruments-file", help="YAML table."),
    sigma_ref: str | None = typer.Option(
        None, "--sigma-ref", help="SIGMA_KMS,MAG,EXPTIME_S: σ_v of one exposure at V = MAG."
    ),
    exptime: float = typer.Option(60.0, "--exptime", help="One exposure [s]."),
    readout: float | None = typer.Option(None, "--readout", help="Readout per exposure [s]."),
    overhead: float | None = typer.Option(None, "--overhead", help="Acquisition per visit [s]."),
    visit: float = typer.Option(3600.0, "--visit", help="Visit length [s]."),
    catalog: Path | None = typer.Option(
        None, "--catalog", help="The forecast's catalog (default: the path in its meta)."
    ),
    sigma_v: SigmaV = 15.0,
    k_eff: KEff = None,
    t_obs: TObs = None,
    t_start: TStart = DEFAULT_T_START,
    n_bins: NBins = 512,
    columns: Columns = None,
    hdf5_path: Hdf5Path = None,
    skip_bad: SkipBad = False,
    workers: Workers = 1,
    scheduler: Scheduler = None,
    cluster: Cluster = None,
    jobs: Jobs = 2,
    overwrite: Overwrite = False,
) -> None:
    """Order sources by a stated figure of merit; target files for the top N (for `plan`)."""
    from ucbplan.population import rank as rk
    from ucbplan.population.execute import remove_parts
    from ucbplan.population.run import parts_folder, run_forecast, write_table

    ranked_path = out_dir / "ranked.ecsv"
    _check_out_dir(out_dir, ranked_path, overwrite)
    spec = _spec(workers, scheduler, cluster, jobs)
    ropts = rk.rank_options(
        top=top,
        goal=goal,
        instrument=instrument,
        instruments_file=instruments_file,
        sigma_ref=sigma_ref,
        exptime_s=exptime,
        readout_s=readout,
        acquisition_s=overhead,
        visit_s=visit,
    )
    tab = rk.read_forecast_table(source)
    if tab is None:
        cat = _catalog(source, columns, hdf5_path, skip_bad)
        fopts = _forecast_opts(cat, sigma_v, k_eff, t_obs, t_start, n_bins)
        with _made_folder(out_dir):
            parts = parts_folder(out_dir / "forecast.ecsv")
            try:
                tab = _with_progress(
                    "forecast",
                    len(cat.sources),
                    lambda p: run_forecast(
                        cat, fopts, spec=spec, parts=parts, overwrite=True, progress=p
                    ),
                ).table
            finally:
                remove_parts(parts)
    else:
        fopts = rk.forecast_options_of(tab.meta, source)
        cat_path = catalog or Path(str(tab.meta.get("catalog_path", tab.meta.get("catalog"))))
        cat = _catalog(cat_path, columns, hdf5_path, skip_bad)
        rk.check_catalog_of(tab, cat, source)
    ranked = rk.rank_table(tab, cat, ropts)
    with _made_folder(out_dir):
        paths = rk.write_top_targets(ranked, cat, fopts, out_dir, top, overwrite)
        write_table(ranked, ranked_path, overwrite)
    err_console.print(
        f"wrote {escape(str(ranked_path))} ({ranked.meta['figure_of_merit']}) and "
        f"{len(paths)} target file(s) in {escape(str(out_dir))}"
    )


@population_app.command("simulate")
def simulate(
    catalog: CatalogArg,
    output: TableOut,
    out_dir: Path = typer.Option(..., "--out-dir", help="Folder for the posterior targets."),
    seed: int = typer.Option(0, "--seed", help="Global seed (per source: seed + source id)."),
    walkers: int = typer.Option(32, "--walkers", help="emcee walkers (≥ 12)."),
    steps: int = typer.Option(2000, "--steps", help="Chain steps (minimum with --until-conv.)."),
    until_converged: bool = typer.Option(
        False, "--until-converged", help="Extend each chain to ≥ 50 τ (or --max-steps)."
    ),
    max_steps: int = typer.Option(50000, "--max-steps", help="Cap for --until-converged."),
    no_noise: bool = typer.Option(False, "--no-noise", help="Zero-noise data."),
    sigma_v: SigmaV = 15.0,
    k_eff: KEff = None,
    t_obs: TObs = None,
    t_start: TStart = DEFAULT_T_START,
    n_bins: NBins = 512,
    columns: Columns = None,
    hdf5_path: Hdf5Path = None,
    skip_bad: SkipBad = False,
    workers: Workers = 1,
    scheduler: Scheduler = None,
    cluster: Cluster = None,
    jobs: Jobs = 2,
    chunk: Chunk = None,
    resume: Resume = False,
    keep_parts: KeepParts = False,
    overwrite: Overwrite = False,
) -> None:
    """Simulate LISA per source → summary ECSV (posterior vs Fisher σ) + a target file each."""
    from ucbplan.population.run import parts_folder
    from ucbplan.population.simulate import PopulationSimulateOptions, run_simulate

    check_output_path(output, overwrite)
    spec = _spec(workers, scheduler, cluster, jobs)
    sampling = PopulationSimulateOptions(  # the options first, then the files, then the work
        seed=seed,
        walkers=walkers,
        steps=steps,
        until_converged=until_converged,
        max_steps=max_steps,
        noise=not no_noise,
    )
    _check_out_dir(out_dir, None, overwrite)
    cat = _catalog(catalog, columns, hdf5_path, skip_bad)
    fopts = _forecast_opts(cat, sigma_v, k_eff, t_obs, t_start, n_bins)
    opts = dataclasses.replace(sampling, forecast=fopts)
    err_console.print(f"{len(cat.sources)} sources from {escape(str(catalog))}; {spec.describe()}")
    parts = parts_folder(output)
    with _made_folder(out_dir):
        run = _with_progress(
            "simulate",
            len(cat.sources),
            lambda p: run_simulate(
                cat,
                opts,
                out_dir=out_dir,
                spec=spec,
                parts=parts,
                chunk=chunk,
                resume=resume,
                overwrite=overwrite,
                progress=p,
            ),
        )
    _finish(run, output, overwrite, keep_parts)
    for f in run.table.meta["failed"]:
        err_console.print(f"[yellow]failed {escape(f['source_id'])}: {escape(f['error'])}[/yellow]")


@population_app.command("semester")
def semester(
    name: str = typer.Argument(..., help="2041A, 2041B or an ESO period like P147."),
) -> None:
    """Print the dates of a semester (A: Feb–Jul, B: Aug–Jan) or ESO period (P110 = 2022-10)."""
    from ucbplan.population.semesters import semester_dates

    first, end = semester_dates(name)
    typer.echo(f"{name.strip().upper()}: {first.isoformat()} .. {end.isoformat()} (end exclusive)")


def register(app: typer.Typer) -> None:
    """Add the ``population`` command group to the ucbplan app."""
    app.add_typer(population_app, name="population")
