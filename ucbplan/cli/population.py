"""``ucbplan population forecast``: whole LISA catalogs (issue 13).

A thin shell: read the catalog, run :func:`ucbplan.population.run.run_forecast` through the
executor seam (serial, ``--workers N`` processes, or ``--scheduler tcp://HOST:PORT`` Dask), show
a progress line on stderr, write the ECSV table and the summary plots.
"""

from __future__ import annotations

from pathlib import Path

import typer
from rich.markup import escape

from ucbplan.cli._console import check_output_path, configure_offline, err_console
from ucbplan.errors import UcbplanError

__all__ = ["register"]

population_app = typer.Typer(
    help="Whole LISA catalogs: population forecasts (T_valid, σ_u, SNR per source).",
    no_args_is_help=True,
)


def _t_obs_s(text: str | None, default_s: float) -> float:
    if text is None:
        return default_s
    import astropy.units as u

    try:
        val = float(u.Quantity(text.replace(" ", "")).to_value(u.s))
    except (TypeError, ValueError, u.UnitsError):
        raise UcbplanError(
            f"--t-obs: expected a duration like '4yr' or '1.2e8 s', got {text!r}"
        ) from None
    if not val > 0:
        raise UcbplanError(f"--t-obs: must be positive, got {text!r}")
    return val


@population_app.command("forecast")
def forecast(
    catalog: Path = typer.Argument(..., help="LDC-style catalog: ECSV, CSV or HDF5 (.h5)."),
    output: Path = typer.Option(..., "-o", "--output", help="Forecast table (ECSV)."),
    sigma_v: float = typer.Option(15.0, "--sigma-v", help="RV precision per epoch [km/s]."),
    k_eff: float | None = typer.Option(
        None, "--k-eff", help="K for the tolerance [km/s] (default: K1+K2 from Mass1, Mass2)."
    ),
    t_obs: str | None = typer.Option(None, "--t-obs", help="LISA observation, e.g. '4yr'."),
    t_start: str = typer.Option(
        "2035-01-01T00:00:00", "--t-start", help="LISA start (TDB): the catalog's t = 0."
    ),
    n_bins: int = typer.Option(512, "--n-bins", help="Band width N of the Fisher model."),
    columns: str | None = typer.Option(
        None, "--columns", help="Column map old=new,... onto the LDC names."
    ),
    hdf5_path: str | None = typer.Option(None, "--hdf5-path", help="Table inside an HDF5 file."),
    skip_bad: bool = typer.Option(False, "--skip-bad", help="Skip bad rows (listed in meta)."),
    workers: int = typer.Option(1, "--workers", help="Local processes (1 = serial)."),
    scheduler: str | None = typer.Option(
        None, "--scheduler", help="Existing Dask scheduler, tcp://HOST:PORT (ucbplan[dask])."
    ),
    chunk: int | None = typer.Option(None, "--chunk", help="Sources per task (default ≥ ~1 s)."),
    resume: bool = typer.Option(False, "--resume", help="Reuse finished part files."),
    keep_parts: bool = typer.Option(False, "--keep-parts", help="Keep part files after merging."),
    plots: Path | None = typer.Option(None, "--plots", help="Folder for the summary plots."),
    overwrite: bool = typer.Option(False, "--overwrite", help="Replace existing outputs."),
) -> None:
    """Per-source Fisher forecast of a catalog → ECSV (σ_u at the end, T_valid, SNR, status)."""
    from astropy.time import Time

    from ucbplan.population.catalog import parse_column_map, read_catalog
    from ucbplan.population.execute import ExecutorSpec, remove_parts
    from ucbplan.population.forecast import DEFAULT_T_OBS_S, ForecastOptions
    from ucbplan.population.plots import forecast_plots
    from ucbplan.population.run import parts_folder, write_table

    configure_offline()
    check_output_path(output, overwrite)
    if plots is not None and not plots.is_dir():
        raise UcbplanError(f"--plots: folder {plots} does not exist; create it first")
    if not sigma_v > 0:
        raise UcbplanError(f"--sigma-v: expected > 0 km/s, got {sigma_v}")
    if k_eff is not None and not k_eff > 0:
        raise UcbplanError(f"--k-eff: expected > 0 km/s, got {k_eff}")
    if n_bins < 16 or n_bins % 2:
        raise UcbplanError(f"--n-bins: expected an even number >= 16, got {n_bins}")
    try:
        t0 = Time(t_start, scale="tdb").isot
    except ValueError:
        raise UcbplanError(f"--t-start: expected an ISO time, got {t_start!r}") from None
    cat = read_catalog(catalog, parse_column_map(columns), skip_bad=skip_bad, hdf5_path=hdf5_path)
    if k_eff is None and not {"Mass1", "Mass2"} <= set(cat.optional):
        raise UcbplanError(f"--k-eff: needed: {catalog} has no Mass1 and Mass2 columns")
    for row, msg in cat.bad:
        err_console.print(f"[yellow]skipped row {row}: {escape(msg)}[/yellow]")
    opts = ForecastOptions(
        sigma_v_kms=sigma_v,
        k_eff_kms=k_eff,
        t_obs_s=_t_obs_s(t_obs, DEFAULT_T_OBS_S),
        t_start_tdb=t0,
        n_bins=n_bins,
    )
    spec = ExecutorSpec(workers=workers, scheduler=scheduler)
    parts = parts_folder(output)
    err_console.print(f"{len(cat.sources)} sources from {catalog}; {spec.describe()}")
    run = _run_with_progress(cat, opts, spec, parts, chunk, resume, overwrite)
    write_table(run.table, output, overwrite)
    if not keep_parts:
        remove_parts(parts)
    meta = run.table.meta
    err_console.print(
        f"wrote {output}: {meta['n_ok']} ok, {meta['n_unconstrained']} unconstrained, "
        f"{meta['n_failed']} failed; chunk {run.chunk}, {run.reused}/{run.n_chunks} parts reused"
    )
    if plots is not None:
        for p in forecast_plots(run.table, plots, overwrite=overwrite):
            err_console.print(f"wrote {p}")


def _run_with_progress(cat, opts, spec, parts, chunk, resume, overwrite):  # type: ignore[no-untyped-def]
    """:func:`run_forecast` under a progress line on stderr (sources done, rate, ETA)."""
    from rich.progress import BarColumn, Progress, TextColumn

    from ucbplan.population.execute import Rate
    from ucbplan.population.run import run_forecast

    rate = Rate()
    with Progress(
        TextColumn("forecast"),
        BarColumn(),
        TextColumn(
            "{task.completed}/{task.total} sources {task.fields[rate]} ETA {task.fields[eta]}"
        ),
        console=err_console,
        transient=True,
    ) as prog:
        task = prog.add_task("forecast", total=len(cat.sources), rate="", eta="?")

        def _progress(done: int, total: int) -> None:
            r, eta = rate.eta(done, total)
            eta_text = "?" if eta != eta else f"{eta:.0f} s"
            prog.update(task, completed=done, rate=f"{r:.1f}/s", eta=eta_text)

        return run_forecast(
            cat,
            opts,
            spec=spec,
            parts=parts,
            chunk=chunk,
            resume=resume,
            overwrite=overwrite,
            progress=_progress,
        )


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
