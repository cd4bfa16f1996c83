"""``ucbplan ephemeris fit TIMES.csv``: fit a timing ephemeris to measured eclipse times.

A thin shell over :mod:`ucbplan.timing`: read the table, count cycles if needed (from
``--period`` or ``--initial``), fit, then print the summary (stderr), the JSON report
(``--format json``) or the timing target file (``-o target.yaml``), and draw the O − C figure
(``--plot``). Outputs are written as a unit: all of them or none.

Registered as ``ephemeris-fit`` by :func:`register`; the ``ephemeris`` command group mounts
:func:`ephemeris_fit` as ``ephemeris fit``.
"""

from __future__ import annotations

import io
from pathlib import Path
from typing import IO, Annotated, Any

import typer
from rich.markup import escape

from ucbplan.cli._console import (
    check_output_and_plot,
    dump_json,
    err_console,
    pick_format,
    rich_table,
    write_output,
)
from ucbplan.cli._options import OverwriteAllOpt
from ucbplan.errors import InputError

__all__ = ["ephemeris_fit"]

TimesArg = Annotated[
    Path,
    typer.Argument(
        metavar="TIMES",
        help="Eclipse times: CSV or ECSV with bjd_tdb (or bmjd_tdb), sigma_s [, kind, cycle].",
    ),
]
TermsOpt = Annotated[int, typer.Option("--terms", help="2: T0, P; 3: + Pdot; 4: + Pddot.")]
PeriodOpt = Annotated[
    str | None,
    typer.Option(
        "--period",
        help=(
            "First period guess for counting cycles, e.g. '414.79 s' (trusted to its last "
            "digit); default: from the best-covered night's eclipses."
        ),
    ),
]
InitialOpt = Annotated[
    Path | None,
    typer.Option(
        "--initial", help="Earlier ephemeris (target YAML with timing: t0, period[, pdot])."
    ),
]
ClipOpt = Annotated[
    float | None,
    typer.Option("--clip", help="Drop times more than K (rescaled) sigma from the fit; reported."),
]
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
LikeOpt = Annotated[
    Path | None,
    typer.Option(
        "--like",
        help="Copy name, sky, masses, spectroscopy, magnitudes from this target YAML.",
    ),
]
NameOpt = Annotated[str | None, typer.Option("--name", help="Target name (overrides --like).")]
RaOpt = Annotated[str | None, typer.Option("--ra", help="ICRS right ascension, e.g. 15h39m32.16s.")]
DecOpt = Annotated[str | None, typer.Option("--dec", help="ICRS declination, e.g. +50d27m38.8s.")]

_FORMATS = ("table", "yaml", "json")


def ephemeris_fit(
    times_path: TimesArg,
    terms: TermsOpt = 3,
    period: PeriodOpt = None,
    initial: InitialOpt = None,
    clip: ClipOpt = None,
    fmt: FormatOpt = None,
    output: OutputOpt = None,
    overwrite: OverwriteAllOpt = False,
    plot: PlotOpt = None,
    like: LikeOpt = None,
    name: NameOpt = None,
    ra: RaOpt = None,
    dec: DecOpt = None,
) -> None:
    """Fit T0, P, Pdot (--terms) to eclipse times; write a timing target, report and O-C plot."""
    from ucbplan.inputs import check_number
    from ucbplan.timing import fit_times, period_guess, read_initial, read_times
    from ucbplan.timing.document import fit_report, target_document, write_yaml

    fmt = pick_format(output, fmt, _FORMATS)
    if terms not in (2, 3, 4):
        raise InputError(f"--terms: expected 2, 3 or 4, got {terms}")
    check_number("--clip", clip, 1.0, 1e6, "σ", "times within 1σ are never outliers")
    if period is not None and initial is not None:
        raise InputError("--period, --initial: give one first ephemeris, not both")
    ident = _identity(fmt, like, name, ra, dec)
    check_output_and_plot(output, plot, overwrite)
    guess = read_initial(initial) if initial is not None else None
    if period is not None:
        guess = period_guess(period)
    times = read_times(times_path)
    if times.cycle is not None and guess is not None:
        err_console.print(
            f"note: {guess.origin} ignored: the table has a cycle column", markup=False
        )
    fit = fit_times(times, guess, terms, clip)
    for note in fit.notes:
        err_console.print(f"note: {note}", markup=False)
    if fmt == "table" or output is not None:
        _print_summary(fit)
    text: str | None = None
    buf = io.StringIO()
    if fmt == "json":
        dump_json(fit_report(fit, times), buf)
        text = buf.getvalue()
    elif ident is not None:  # fmt == "yaml"
        write_yaml(target_document(fit, ident, times_path.name), buf)
        text = buf.getvalue()
    _write(text, output, plot, fit, times, overwrite)


def _identity(
    fmt: str, like: Path | None, name: str | None, ra: str | None, dec: str | None
) -> Any:
    """Name and sky of the timing target (``--format yaml`` only; else a note if given)."""
    from ucbplan.timing.document import identity

    ident = identity(like, name, ra, dec) if fmt == "yaml" else None
    if ident is None and any(x is not None for x in (like, name, ra, dec)):
        err_console.print(
            "note: --like/--name/--ra/--dec only shape the timing target (-o FILE.yaml or "
            "--format yaml); ignored",
            markup=False,
        )
    return ident


def _write(
    text: str | None,
    output: Path | None,
    plot: Path | None,
    fit: Any,
    times: Any,
    overwrite: bool,
) -> None:
    """Write the text output and the figure as a unit (both or neither)."""
    from ucbplan.io import write_file_set

    files: dict[Path, Any] = {}
    if text is not None and output is None:
        stdout_text = text

        def _stdout(handle: IO[str]) -> None:
            handle.write(stdout_text)

        write_output(None, _stdout)
    elif text is not None and output is not None:
        data = text.encode("utf-8")

        def _file(handle: IO[bytes]) -> None:
            handle.write(data)

        files[output] = _file
    if plot is not None:
        from ucbplan.plotting import figure_format, pyplot
        from ucbplan.timing.plots import oc_figure

        fmt = figure_format(plot)
        fig = oc_figure(fit, times)

        def _figure(handle: IO[bytes]) -> None:
            fig.savefig(handle, format=fmt, dpi=120)

        files[plot] = _figure
        try:
            write_file_set(files, overwrite=overwrite, binary=True)
        finally:
            pyplot().close(fig)
    elif files:
        write_file_set(files, overwrite=overwrite, binary=True)
    for path in files:
        err_console.print(f"wrote {escape(str(path))}")


def _print_summary(fit: Any) -> None:
    from ucbplan.core.timing_epochs import format_bjd
    from ucbplan.timing.fit import UNITS

    sig = fit.sigmas
    ratio = f"{fit.chi2 / fit.dof:.3g}" if fit.dof > 0 else "n/a"
    title = (
        f"{fit.source}: {fit.n_used} times, chi2/dof = {ratio}"
        f"{' (σ rescaled)' if fit.rescaled else ''}; cycles {fit.cycles_origin}"
    )
    tab = rich_table(title, ["parameter", "value", "σ", "unit"])
    tab.add_row("t0 (primary eclipse)", format_bjd(fit.t0_jd), f"{sig[0]:.3g}", "s (σ)")
    for i in range(1, fit.terms):
        tab.add_row(fit.names[i], f"{fit.values[i]:.12g}", f"{sig[i]:.3g}", UNITS[i])
    err_console.print(tab)
