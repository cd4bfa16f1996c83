"""``ucbplan reduce``: measured radial velocities → K_j, γ_j, masses, Δκ and Δv_CM (thin shell)."""

from __future__ import annotations

from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

import typer

from ucbplan.cli._console import check_output_path, err_console, write_output
from ucbplan.errors import UcbplanError

if TYPE_CHECKING:
    from ucbplan.reduce.velocities import VelocityTable
    from ucbplan.target import Target

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
    # Long only by its option declarations: parse, call ucbplan.reduce, print and write.
    from ucbplan.reduce import report as rep
    from ucbplan.reduce.pipeline import ReduceOptions, reduce

    fmt = _check_format(fmt)
    relation = _check_mass_radius(mass_radius)
    machine = _machine_format(fmt, output)
    for path in (output, em_prior):
        if path is not None:
            check_output_path(path, overwrite)
    if plots is not None and not plots.is_dir():
        raise UcbplanError(f"--plots: folder {plots} does not exist; create it first")
    tgt, table = _load(target, velocities, site)
    options = ReduceOptions(
        n_samples=samples,
        seed=seed,
        light_time=light_time,
        mass_radius=relation,
        cos_i_sigma=cos_i_sigma,
    )
    red = reduce(tgt, table, options)
    doc = rep.build_report(red)
    rep.print_report(doc, err_console)
    if machine != "table":
        _write_doc(doc, output, machine, overwrite)
    if em_prior is not None:
        _write_doc(rep.em_prior(red), em_prior, "yaml", overwrite)
        err_console.print(f"EM prior written to {em_prior}")
    if plots is not None:
        from ucbplan.reduce.plots import plot_all

        for p in plot_all(red, plots, overwrite=overwrite):
            err_console.print(f"figure: {p}")


def _check_format(fmt: str) -> str:
    fmt = fmt.lower()
    if fmt not in _FORMATS:
        raise UcbplanError(f"--format: got {fmt!r}, expected one of {', '.join(_FORMATS)}")
    return fmt


def _check_mass_radius(mass_radius: str | None) -> str | None:
    """The relation's key (lower case), or None."""
    from ucbplan.reduce.masses import MASS_RADIUS_MODELS

    if mass_radius is not None and mass_radius.lower() not in MASS_RADIUS_MODELS:
        raise UcbplanError(
            f"--mass-radius: got {mass_radius!r}, expected one of {', '.join(MASS_RADIUS_MODELS)}"
        )
    return mass_radius.lower() if mass_radius else None


def _machine_format(fmt: str, output: Path | None) -> str:
    """Format of the written report: --format, or from the -o suffix with --format table."""
    if output is None or fmt != "table":
        return fmt
    suffix = output.suffix.lower()
    if suffix not in (".json", ".yaml", ".yml"):
        raise UcbplanError(
            f"{output}: -o with --format table needs a .json or .yaml name, or pass --format"
        )
    return "json" if suffix == ".json" else "yaml"


def _load(target: Path, velocities: Path, site: str | None) -> tuple[Target, VelocityTable]:
    """Target and velocity table; site-UTC times converted to barycentric TDB with --site."""
    from ucbplan.reduce.velocities import read_velocities, to_barycentric
    from ucbplan.target import load_target

    tgt = load_target(target)
    table = read_velocities(velocities)
    if table.site_utc:
        if site is None:
            raise UcbplanError(
                f"{velocities}: times are UTC at the telescope; pass --site NAME to convert them"
            )
        from ucbplan.observing.sites import get_site

        table = to_barycentric(table, tgt.coord, get_site(site).location)
    return tgt, table


def _write_doc(doc: dict[str, Any], path: Path | None, fmt: str, overwrite: bool) -> None:
    """Write a report dict as JSON or YAML to ``path`` (stdout if None), atomically."""
    from ucbplan.reduce import report as rep

    writer = rep.write_json if fmt == "json" else rep.write_yaml

    def _write(handle: IO[Any]) -> None:
        writer(doc, handle)

    write_output(path, _write, overwrite=overwrite)


def register(app: typer.Typer) -> None:
    """Add the ``reduce`` command to the app."""
    app.command("reduce")(reduce_cmd)
