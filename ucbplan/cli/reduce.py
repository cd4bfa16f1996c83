"""``ucbplan reduce``: measured radial velocities → K_j, γ_j, masses, Δκ and Δv_CM (thin shell)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

import typer

from ucbplan.cli._console import check_output_path, err_console, literal, pick_format, write_output
from ucbplan.errors import InputError, UcbplanError, shorten
from ucbplan.io import write_file_set

if TYPE_CHECKING:
    from ucbplan.reduce.velocities import VelocityTable
    from ucbplan.target import Target

__all__ = ["reduce_cmd", "register"]

_FORMATS = ("table", "json", "yaml")
#: Most Monte-Carlo samples: above 250 000 they run in chunks; 10⁷ take ~0.65 GB peak resident
#: memory and ~20 s (benchmarks/reduce_scaling.py).
MAX_SAMPLES = 10_000_000


def reduce_cmd(
    target: Path = typer.Argument(..., help="Target YAML file (LISA ephemeris and posterior)."),
    velocities: Path = typer.Argument(
        ..., help="Velocity table (CSV or ECSV): bjd_tdb, exptime_s, v1, sigma_v1, v2, sigma_v2."
    ),
    fmt: str | None = typer.Option(
        None,
        "--format",
        help="table (rich, stderr) | json | yaml (default: the -o suffix, else table).",
    ),
    output: Path | None = typer.Option(
        None, "-o", "--output", help="Write the report here (.json or .yaml)."
    ),
    plots: Path | None = typer.Option(None, "--plots", help="Folder for PNG figures."),
    samples: int = typer.Option(
        20000, "--samples", min=100, max=MAX_SAMPLES, help="Monte-Carlo samples."
    ),
    seed: int | None = typer.Option(None, "--seed", min=0, help="Random seed (reported)."),
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

    machine = pick_format(output, fmt, _FORMATS)
    relation = _check_mass_radius(mass_radius)
    _check_cos_i_sigma(cos_i_sigma)
    _check_outputs(output, em_prior, overwrite)
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
    if machine != "table" and output is None:
        write_output(None, _doc_writer(doc, machine))
    files = {output: _doc_writer(doc, machine)} if machine != "table" and output else {}
    if em_prior is not None:
        files[em_prior] = _doc_writer(rep.em_prior(red), "yaml")
    if files:
        write_file_set(files, overwrite=overwrite)  # the report and EM prior: both or neither
    if em_prior is not None:
        err_console.print(f"EM prior written to {literal(em_prior)}")
    if plots is not None:
        from ucbplan.reduce.plots import plot_all

        for p in plot_all(red, plots, overwrite=overwrite):
            err_console.print(f"figure: {literal(p)}")


def _check_cos_i_sigma(value: float) -> None:
    if not 0.0 <= value <= 2.0:
        raise InputError(f"--cos-i-sigma: expected a 1σ of cos ι in [0, 2], got {value}")


def _check_outputs(output: Path | None, em_prior: Path | None, overwrite: bool) -> None:
    """-o and --em-prior: distinct files that may be written; the EM prior is YAML."""
    from ucbplan.io import output_format

    if em_prior is not None:
        if output is not None and output.resolve() == em_prior.resolve():
            raise InputError(f"{output}: -o and --em-prior name the same file; rename one")
        if output_format(em_prior, None, ("yaml", "json", "ecsv", "csv"), "yaml") != "yaml":
            raise InputError(f"--em-prior {em_prior}: the EM prior is YAML; name it .yaml")
    for path in (output, em_prior):
        if path is not None:
            check_output_path(path, overwrite)


def _check_mass_radius(mass_radius: str | None) -> str | None:
    """The relation's key (lower case), or None."""
    from ucbplan.reduce.masses import MASS_RADIUS_MODELS

    if mass_radius is not None and mass_radius.lower() not in MASS_RADIUS_MODELS:
        raise InputError(
            f"--mass-radius: got {shorten(mass_radius)}, expected one of "
            f"{', '.join(MASS_RADIUS_MODELS)}"
        )
    return mass_radius.lower() if mass_radius else None


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


def _doc_writer(doc: dict[str, Any], fmt: str) -> Callable[[IO[Any]], None]:
    """Writer of a report dict as JSON or YAML."""
    from ucbplan.reduce import report as rep

    writer = rep.write_json if fmt == "json" else rep.write_yaml

    def _write(handle: IO[Any]) -> None:
        writer(doc, handle)

    return _write


def register(app: typer.Typer) -> None:
    """Add the ``reduce`` command to the app."""
    app.command("reduce")(reduce_cmd)
