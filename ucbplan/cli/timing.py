"""``ucbplan ephemeris fit TIMES.csv``: fit a timing ephemeris to measured eclipse times.

A thin shell over :func:`ucbplan.api.timing.fit_ephemeris`: fit (counting cycles if needed, from
``--period`` or ``--initial``), then print the summary (stderr), the JSON report
(``--format json``) or the timing target file (``-o target.yaml``), and draw the O − C figure
(``--plot``). Outputs are written as a unit: all of them or none. The options that are
parameters of the API take their flag, help and default from it
(:data:`ucbplan.api.timing.FIT_FLAGS`).

The ``ephemeris`` command group mounts :func:`ephemeris_fit` as ``ephemeris fit``.
"""

from __future__ import annotations

import io
from pathlib import Path
from typing import IO, Annotated, Any

import typer
from rich.markup import escape

from ucbplan.api.timing import FIT_FLAGS, TimingFit, fit_ephemeris, target_identity
from ucbplan.cli._console import (
    check_output_and_plot,
    dump_json,
    err_console,
    pick_format,
    rich_table,
    write_output,
)
from ucbplan.cli._derive import option
from ucbplan.cli._flags import cli_text
from ucbplan.cli._options import OverwriteAllOpt

TimesArg = Annotated[Path, typer.Argument(metavar="TIMES", help=FIT_FLAGS["times"].help)]
FormatOpt = Annotated[
    str | None,
    typer.Option(
        "--format",
        help="table (stderr) | yaml (timing target) | json (report); default: the -o suffix.",
    ),
]
OutputOpt = Annotated[
    Path | None,
    typer.Option("-o", "--output", help="Write the timing target (.yaml) or report (.json) here."),
]
PlotOpt = Annotated[Path | None, typer.Option("--plot", help="Write the O-C figure (.png/.pdf).")]

_FORMATS = ("table", "yaml", "json")


def ephemeris_fit(
    times_path: TimesArg,
    terms: int = option(fit_ephemeris, FIT_FLAGS, "terms"),
    period: str | None = option(fit_ephemeris, FIT_FLAGS, "period"),
    initial: Path | None = option(fit_ephemeris, FIT_FLAGS, "initial"),
    clip: float | None = option(fit_ephemeris, FIT_FLAGS, "clip"),
    fmt: FormatOpt = None,
    output: OutputOpt = None,
    overwrite: OverwriteAllOpt = False,
    plot: PlotOpt = None,
    like: Path | None = option(TimingFit.to_target, FIT_FLAGS, "like"),
    name: str | None = option(TimingFit.to_target, FIT_FLAGS, "name"),
    ra: str | None = option(TimingFit.to_target, FIT_FLAGS, "ra"),
    dec: str | None = option(TimingFit.to_target, FIT_FLAGS, "dec"),
) -> None:
    """Fit T0, P, Pdot (--terms) to eclipse times; write a timing target, report and O-C plot."""
    fmt = pick_format(output, fmt, _FORMATS)
    ident = _identity(fmt, like, name, ra, dec)
    check_output_and_plot(output, plot, overwrite)
    fit = fit_ephemeris(times_path, period, initial, terms, clip)
    for note in fit.notes:
        err_console.print(f"note: {cli_text(note)}", markup=False)
    if fmt == "table" or output is not None:
        _print_summary(fit)
    text: str | None = None
    if fmt == "json":
        buf = io.StringIO()
        dump_json(fit.to_dict(), buf)
        text = buf.getvalue()
    elif ident is not None:  # fmt == "yaml"
        text = fit.target_yaml(like=like, **ident)
    _write(text, output, plot, fit, overwrite)


def _identity(
    fmt: str, like: Path | None, name: str | None, ra: str | None, dec: str | None
) -> dict[str, Any] | None:
    """Name and sky of the timing target (``--format yaml`` only; else a note if given):
    checked before any work, given back as ``to_target``'s keywords."""
    if fmt == "yaml":
        target_identity(like, name, ra, dec)
        return {"name": name, "ra": ra, "dec": dec}
    if any(x is not None for x in (like, name, ra, dec)):
        err_console.print(
            "note: --like/--name/--ra/--dec only shape the timing target (-o FILE.yaml or "
            "--format yaml); ignored",
            markup=False,
        )
    return None


def _write(
    text: str | None, output: Path | None, plot: Path | None, fit: TimingFit, overwrite: bool
) -> None:
    """Write the text output and the figure as a unit (both or neither)."""
    if text is not None and output is None:
        stdout_text = text

        def _stdout(handle: IO[str]) -> None:
            handle.write(stdout_text)

        write_output(None, _stdout)
    for path in fit.write(text, output, plot, overwrite):
        err_console.print(f"wrote {escape(str(path))}")


def _print_summary(result: TimingFit) -> None:
    fit = result.fit
    sig = fit.sigmas
    ratio = f"{fit.chi2 / fit.dof:.3g}" if fit.dof > 0 else "n/a"
    title = (
        f"{fit.source}: {fit.n_used} times, chi2/dof = {ratio}"
        f"{' (σ rescaled)' if fit.rescaled else ''}; cycles {fit.cycles_origin}"
    )
    tab = rich_table(title, ["parameter", "value", "σ", "unit"])
    tab.add_row("t0 (primary eclipse)", result.t0_text, f"{sig[0]:.3g}", "s (σ)")
    for i in range(1, fit.terms):
        tab.add_row(fit.names[i], f"{fit.values[i]:.12g}", f"{sig[i]:.3g}", result.units[i])
    err_console.print(tab)
