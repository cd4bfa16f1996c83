"""``ucbplan reduce``: measured radial velocities → K_j, γ_j, masses, Δκ and Δv_CM (thin shell
over :func:`ucbplan.api.reduction.reduce`, whose options it derives from
:data:`~ucbplan.api.reduction.REDUCE_FLAGS`)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from ucbplan.api import reduction as api
from ucbplan.api.shell_files import file_format
from ucbplan.cli._console import check_output_path, err_console, literal, pick_format, write_output
from ucbplan.cli._derive import argument, option
from ucbplan.cli._options import OverwriteAllOpt
from ucbplan.errors import InputError, UcbplanError

_FORMATS = ("table", "json", "yaml")
FLAGS = api.REDUCE_FLAGS

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
EmPriorOpt = Annotated[
    Path | None, typer.Option("--em-prior", help="Also write an EM prior YAML (q, M_tot, a_los …).")
]


def reduce_cmd(
    target: Path = argument(FLAGS, "target"),
    velocities: Path = argument(FLAGS, "velocities"),
    fmt: FormatOpt = None,
    output: ReportOutputOpt = None,
    plots: PlotsOpt = None,
    samples: int = option(api.reduce, FLAGS, "samples"),
    seed: int | None = option(api.reduce, FLAGS, "seed"),
    light_time: bool = option(api.reduce, FLAGS, "light_time"),
    mass_radius: str | None = option(api.reduce, FLAGS, "mass_radius"),
    cos_i_sigma: float = option(api.reduce, FLAGS, "cos_i_sigma"),
    em_prior: EmPriorOpt = None,
    site: str | None = option(api.reduce, FLAGS, "site"),
    overwrite: OverwriteAllOpt = False,
) -> None:
    """Reduce measured velocities against a target: K_j, γ_j, masses, Δκ, Δv_CM (Secs. 3–5)."""
    machine = pick_format(output, fmt, _FORMATS)
    api.reduce_options(  # the options before the files
        seed=seed,
        samples=samples,
        light_time=light_time,
        mass_radius=mass_radius,
        cos_i_sigma=cos_i_sigma,
    )
    _check_outputs(output, em_prior, overwrite)
    if plots is not None and not plots.is_dir():
        raise UcbplanError(f"--plots: folder {plots} does not exist; create it first")
    try:
        report = api.reduce(
            target,
            velocities,
            seed,
            samples=samples,
            light_time=light_time,
            mass_radius=mass_radius,
            cos_i_sigma=cos_i_sigma,
            site=site,
            warn=False,
        )
    except InputError as exc:
        if exc.parameter != "site":
            raise
        raise UcbplanError(
            f"{velocities}: times are UTC at the telescope; pass --site NAME to convert them"
        ) from None
    report.print(err_console)
    if machine != "table" and output is None:
        write_output(None, lambda handle: report.dump(handle, machine))
    report.write(
        output if machine != "table" else None, machine, em_prior=em_prior, overwrite=overwrite
    )
    if em_prior is not None:
        err_console.print(f"EM prior written to {literal(em_prior)}")
    if plots is not None:
        for p in report.save_plots(plots, overwrite=overwrite):
            err_console.print(f"figure: {literal(p)}")


def _check_outputs(output: Path | None, em_prior: Path | None, overwrite: bool) -> None:
    """-o and --em-prior: distinct files that may be written; the EM prior is YAML."""
    if em_prior is not None:
        if output is not None and output.resolve() == em_prior.resolve():
            raise InputError(f"{output}: -o and --em-prior name the same file; rename one")
        if file_format(em_prior) != "yaml":
            raise InputError(f"--em-prior {em_prior}: the EM prior is YAML; name it .yaml")
    for path in (output, em_prior):
        if path is not None:
            check_output_path(path, overwrite)


def register(app: typer.Typer) -> None:
    """Add the ``reduce`` command to the app."""
    app.command("reduce")(reduce_cmd)
