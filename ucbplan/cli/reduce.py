"""``ucbplan reduce``: measured radial velocities → K_j, γ_j, masses, Δκ and Δv_CM (thin shell)."""

from __future__ import annotations

from pathlib import Path
from typing import IO, Any

import typer

from ucbplan.cli._console import check_output_path, err_console, write_output
from ucbplan.errors import UcbplanError

__all__ = ["reduce_cmd", "register"]

_FORMATS = ("table", "json", "yaml")


def reduce_cmd(
    target: Path = typer.Argument(..., help="Target YAML file (LISA ephemeris and posterior)."),
    velocities: Path = typer.Argument(
        ..., help="Velocity table (CSV or ECSV): bjd_tdb, exptime_s, v1, sigma_v1, v2, sigma_v2."
    ),
    fmt: str = typer.Option("table", "--format", help="table (rich, stderr) | json | yaml."),
    output: Path | None = typer.Option(None, "-o", "--output", help="Write the report here."),
    plots: Path | None = typer.Option(None, "--plots", help="Folder for PNG figures."),
    samples: int = typer.Option(20000, "--samples", min=100, help="Monte-Carlo samples."),
    seed: int | None = typer.Option(None, "--seed", help="Random seed (reported)."),
    light_time: bool = typer.Option(
        False, "--light-time", help="Correct for the light travel time across the orbit."
    ),
    mass_radius: str | None = typer.Option(
        None,
        "--mass-radius",
        help="WD mass–radius relation for the redshift check: "
        "eggleton (Verbunt & Rappaport 1988) | nauenberg (Nauenberg 1972).",
    ),
    cos_i_sigma: float = typer.Option(
        0.0,
        "--cos-i-sigma",
        min=0.0,
        help="1σ of cos ι if neither covariance nor samples carry it (default: held fixed).",
    ),
    em_prior: Path | None = typer.Option(
        None, "--em-prior", help="Also write an EM prior YAML (q, M_tot, a_los …)."
    ),
    site: str | None = typer.Option(
        None, "--site", help="Observatory (bundled site table) for jd_utc/mjd_utc time columns."
    ),
    overwrite: bool = typer.Option(False, "--overwrite", help="Replace existing output files."),
) -> None:
    """Reduce measured velocities against a target: K_j, γ_j, masses, Δκ, Δv_CM (Secs. 3–5)."""
    from ucbplan.reduce import report as rep
    from ucbplan.reduce.masses import MASS_RADIUS_MODELS
    from ucbplan.reduce.pipeline import ReduceOptions, read_velocities, reduce
    from ucbplan.target import load_target

    fmt = fmt.lower()
    if fmt not in _FORMATS:
        raise UcbplanError(f"--format: got {fmt!r}, expected one of {', '.join(_FORMATS)}")
    if mass_radius is not None and mass_radius.lower() not in MASS_RADIUS_MODELS:
        raise UcbplanError(
            f"--mass-radius: got {mass_radius!r}, expected one of {', '.join(MASS_RADIUS_MODELS)}"
        )
    machine = fmt
    if output is not None and fmt == "table":
        suffix = output.suffix.lower()
        if suffix not in (".json", ".yaml", ".yml"):
            raise UcbplanError(
                f"{output}: -o with --format table needs a .json or .yaml name, or pass --format"
            )
        machine = "json" if suffix == ".json" else "yaml"
    for path in (output, em_prior):
        if path is not None:
            check_output_path(path, overwrite)
    if plots is not None and not plots.is_dir():
        raise UcbplanError(f"--plots: folder {plots} does not exist; create it first")
    tgt = load_target(target)
    table = read_velocities(velocities)
    if table.site_utc:
        if site is None:
            raise UcbplanError(
                f"{velocities}: times are UTC at the telescope; pass --site NAME to convert them"
            )
        from ucbplan.observing.sites import get_site
        from ucbplan.reduce.velocities import to_barycentric

        table = to_barycentric(table, tgt.coord, get_site(site).location)
    red = reduce(
        tgt,
        table,
        ReduceOptions(
            n_samples=samples,
            seed=seed,
            light_time=light_time,
            mass_radius=mass_radius.lower() if mass_radius else None,
            cos_i_sigma=cos_i_sigma,
        ),
    )
    doc = rep.build_report(red)
    rep.print_report(doc, err_console)
    writer = rep.write_json if machine == "json" else rep.write_yaml
    if machine != "table":

        def _write(handle: IO[Any]) -> None:
            writer(doc, handle)

        write_output(output, _write, overwrite=overwrite)
    if em_prior is not None:
        prior = rep.em_prior(red)
        write_output(em_prior, lambda h: rep.write_yaml(prior, h), overwrite=overwrite)
        err_console.print(f"EM prior written to {em_prior}")
    if plots is not None:
        from ucbplan.reduce.plots import plot_all

        for p in plot_all(red, plots, overwrite=overwrite):
            err_console.print(f"figure: {p}")


def register(app: typer.Typer) -> None:
    """Add the ``reduce`` command to the app."""
    app.command("reduce")(reduce_cmd)
