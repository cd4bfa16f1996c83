"""``ucbplan reduce``: measured radial velocities → K_j, γ_j, masses, Δκ and Δv_CM (thin shell)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import IO, TYPE_CHECKING, Annotated, Any

import typer

from ucbplan.cli._console import check_output_path, err_console, literal, pick_format, write_output
from ucbplan.cli._options import OverwriteAllOpt
from ucbplan.errors import InputError, UcbplanError
from ucbplan.io import write_file_set

if TYPE_CHECKING:
    from ucbplan.reduce.pipeline import Reduction
    from ucbplan.reduce.velocities import VelocityTable
    from ucbplan.target import Target

__all__ = ["reduce_cmd", "register"]

_FORMATS = ("table", "json", "yaml")
#: Most Monte-Carlo samples: above 250 000 they run in chunks; 10⁷ take ~0.65 GB peak resident
#: memory and ~20 s (benchmarks/reduce_scaling.py).
MAX_SAMPLES = 10_000_000

TargetArg = Annotated[Path, typer.Argument(help="Target YAML file (LISA ephemeris and posterior).")]
VelocitiesArg = Annotated[
    Path,
    typer.Argument(
        help="Velocity table (CSV or ECSV): bjd_tdb, exptime_s, v1, sigma_v1, v2, sigma_v2."
    ),
]
FormatOpt = Annotated[
    str | None,
    typer.Option(
        "--format", help="table (rich, stderr) | json | yaml (default: the -o suffix, else table)."
    ),
]
ReportOutputOpt = Annotated[
    Path | None, typer.Option("-o", "--output", help="Write the report here (.json or .yaml).")
]
PlotsOpt = Annotated[Path | None, typer.Option("--plots", help="Folder for PNG figures.")]
SamplesOpt = Annotated[
    int, typer.Option("--samples", min=100, max=MAX_SAMPLES, help="Monte-Carlo samples.")
]
SeedOpt = Annotated[int | None, typer.Option("--seed", min=0, help="Random seed (reported).")]
LightTimeOpt = Annotated[
    bool, typer.Option("--light-time", help="Correct for the light travel time across the orbit.")
]
MassRadiusOpt = Annotated[
    str | None,
    typer.Option(
        "--mass-radius",
        help="WD mass–radius relation for the redshift check: "
        "eggleton (Verbunt & Rappaport 1988) | nauenberg (Nauenberg 1972).",
    ),
]
CosISigmaOpt = Annotated[
    float,
    typer.Option(
        "--cos-i-sigma",
        min=0.0,
        help="1σ of cos ι if neither covariance nor samples carry it (default: held fixed).",
    ),
]
EmPriorOpt = Annotated[
    Path | None, typer.Option("--em-prior", help="Also write an EM prior YAML (q, M_tot, a_los …).")
]
SiteOpt = Annotated[
    str | None,
    typer.Option(
        "--site", help="Observatory (bundled site table) for jd_utc/mjd_utc time columns."
    ),
]


def reduce_cmd(
    target: TargetArg,
    velocities: VelocitiesArg,
    fmt: FormatOpt = None,
    output: ReportOutputOpt = None,
    plots: PlotsOpt = None,
    samples: SamplesOpt = 20000,
    seed: SeedOpt = None,
    light_time: LightTimeOpt = False,
    mass_radius: MassRadiusOpt = None,
    cos_i_sigma: CosISigmaOpt = 0.0,
    em_prior: EmPriorOpt = None,
    site: SiteOpt = None,
    overwrite: OverwriteAllOpt = False,
) -> None:
    """Reduce measured velocities against a target: K_j, γ_j, masses, Δκ, Δv_CM (Secs. 3–5)."""
    from ucbplan.reduce import report as rep
    from ucbplan.reduce.pipeline import reduce, reduce_options

    machine = pick_format(output, fmt, _FORMATS)
    options = reduce_options(
        samples=samples,
        seed=seed,
        light_time=light_time,
        mass_radius=mass_radius,
        cos_i_sigma=cos_i_sigma,
    )
    _check_outputs(output, em_prior, overwrite)
    if plots is not None and not plots.is_dir():
        raise UcbplanError(f"--plots: folder {plots} does not exist; create it first")
    red = reduce(*_load(target, velocities, site), options)
    doc = rep.build_report(red)
    rep.print_report(doc, err_console)
    _write(red, doc, machine, output, em_prior, overwrite)
    if plots is not None:
        from ucbplan.reduce.plots import plot_all

        for p in plot_all(red, plots, overwrite=overwrite):
            err_console.print(f"figure: {literal(p)}")


def _write(
    red: Reduction,
    doc: dict[str, Any],
    machine: str,
    output: Path | None,
    em_prior: Path | None,
    overwrite: bool,
) -> None:
    """The report (stdout or -o) and the EM prior: the files both or neither."""
    from ucbplan.reduce.report import em_prior as em_prior_doc

    if machine != "table" and output is None:
        write_output(None, _doc_writer(doc, machine))
    files = {output: _doc_writer(doc, machine)} if machine != "table" and output else {}
    if em_prior is not None:
        files[em_prior] = _doc_writer(em_prior_doc(red), "yaml")
    if files:
        write_file_set(files, overwrite=overwrite)
    if em_prior is not None:
        err_console.print(f"EM prior written to {literal(em_prior)}")


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
