"""``ucbplan plan``: phase-targeted blocks at an observatory (a thin shell over ucbplan.plan).

Parse the options, make one call (:func:`ucbplan.api.planning.plan`, with the options the user
gave: every default is the API's), print the nights and write the blocks table, the night
charts and the night sheet. Each option of :func:`~ucbplan.api.planning.plan` is declared there
(:data:`~ucbplan.api.plan_options.PLAN_FLAGS`: default, unit, flag, help); the command line
declares only its own (output and view).
"""

from __future__ import annotations

import inspect
import warnings
from pathlib import Path
from typing import IO, Annotated, Any

import typer
from rich.markup import escape

from ucbplan.api import planning as api
from ucbplan.api import terminal
from ucbplan.api.plan_options import PLAN_FLAGS
from ucbplan.cli._console import (
    check_output_path,
    err_console,
    pick_format,
    write_output,
)
from ucbplan.cli._derive import argument, flag, option
from ucbplan.cli._plan_view import report
from ucbplan.errors import UcbplanWarning

_MACHINE = ("ecsv", "csv", "json")

_Wide = Annotated[bool, typer.Option("--wide", help="Print every column of the plan table.")]
_Verbose = Annotated[
    bool, typer.Option("--verbose", help="Print every night's table, however long the plan.")
]
_Output = Annotated[Path | None, typer.Option("-o", "--output", help="Write the blocks table.")]
_Format = Annotated[
    str | None,
    typer.Option("--format", help="table | ecsv | csv | json (default: the -o suffix, else table)"),
]
_Plot = Annotated[
    Path | None,
    typer.Option(
        "--plot",
        help="Night charts of every night: .png/.svg (up to 7 panels) or .pdf (a page each).",
    ),
]
_Sheet = Annotated[
    Path | None,
    typer.Option(
        "--sheet",
        help="Night sheet (.pdf or self-contained .html): chart and visits of each night.",
    ),
]
_Overwrite = Annotated[bool, typer.Option("--overwrite", help="Replace existing output files.")]
#: The keywords of ucbplan.plan (the command's other parameters are its own).
_API = frozenset(inspect.signature(api.plan).parameters)


def _given(ctx: typer.Context, name: str) -> bool:
    """Whether the user gave option ``name`` (not its default). Compared by name: typer may
    carry its own copy of click's ``ParameterSource`` enum."""
    source = ctx.get_parameter_source(name)
    return source is not None and getattr(source, "name", "") != "DEFAULT"


def _write(
    result: Any,
    fmt: str,
    output: Path | None,
    figures: tuple[Path | None, Path | None],
    overwrite: bool,
) -> None:
    """The blocks table (stdout or ``output``), the night charts and the night sheet."""
    plot, sheet = figures
    if fmt in _MACHINE or plot is not None or sheet is not None:
        table = result.text_table  # the text the files hold (.table has Time columns)
    if fmt in _MACHINE:

        def _write_table(handle: IO[str]) -> None:
            terminal.write_table(table, handle, fmt, json_meta=True)

        write_output(output, _write_table, overwrite=overwrite)
        if output is not None:
            err_console.print(f"wrote {len(table)} blocks to {escape(str(output))} ({fmt})")
    if plot is not None:
        n = terminal.night_charts(result, plot, overwrite)
        err_console.print(f"wrote night charts of {n} night(s) to {escape(str(plot))}")
    if sheet is not None:
        n = terminal.night_sheet(result, sheet, overwrite)
        err_console.print(f"wrote the night sheet of {n} night(s) to {escape(str(sheet))}")


# ``plan`` is long only by its parameters, one line each (their defaults and help declared by
# ucbplan.plan); the work is in :func:`_plan_command`.
def plan(
    ctx: typer.Context,
    targets: list[Path] = argument(PLAN_FLAGS, "targets"),
    site: str | None = flag(PLAN_FLAGS, "site"),
    site_lonlat: str | None = option(api.plan, PLAN_FLAGS, "site_lonlat"),
    sites_file: Path | None = option(api.plan, PLAN_FLAGS, "sites_file"),
    night: str = flag(PLAN_FLAGS, "night", ...),
    nights: int = option(api.plan, PLAN_FLAGS, "nights"),
    mode: str = option(api.plan, PLAN_FLAGS, "mode"),
    twilight: str = option(api.plan, PLAN_FLAGS, "twilight"),
    airmass_max: float = option(api.plan, PLAN_FLAGS, "airmass_max"),
    moon_sep: float = option(api.plan, PLAN_FLAGS, "moon_sep"),
    moon_illum: float | None = option(api.plan, PLAN_FLAGS, "moon_illum"),
    zenith_hole: float | None = option(api.plan, PLAN_FLAGS, "zenith_hole"),
    exptime: float = option(api.plan, PLAN_FLAGS, "exptime"),
    n_exp: int = option(api.plan, PLAN_FLAGS, "n_exp"),
    readout: float | None = option(api.plan, PLAN_FLAGS, "readout"),
    alpha: float = option(api.plan, PLAN_FLAGS, "alpha"),
    sigma_v: str | None = option(api.plan, PLAN_FLAGS, "sigma_v"),
    sigma_floor: float = option(api.plan, PLAN_FLAGS, "sigma_floor"),
    extinction: float | None = option(api.plan, PLAN_FLAGS, "extinction"),
    k_eff: float | None = option(api.plan, PLAN_FLAGS, "k_eff"),
    max_smear: str | None = option(api.plan, PLAN_FLAGS, "max_smear"),
    max_bin_fraction: float | None = option(api.plan, PLAN_FLAGS, "max_bin_fraction"),
    overhead: float | None = option(api.plan, PLAN_FLAGS, "overhead"),
    sessions: int = option(api.plan, PLAN_FLAGS, "sessions"),
    visit: str | None = option(api.plan, PLAN_FLAGS, "visit"),
    max_visit: str | None = option(api.plan, PLAN_FLAGS, "max_visit"),
    cadence: str = option(api.plan, PLAN_FLAGS, "cadence"),
    service_mode: bool = option(api.plan, PLAN_FLAGS, "service_mode"),
    instrument: str | None = option(api.plan, PLAN_FLAGS, "instrument"),
    instruments_file: Path | None = option(api.plan, PLAN_FLAGS, "instruments_file"),
    goal: str | None = option(api.plan, PLAN_FLAGS, "goal"),
    observed: Path | None = option(api.plan, PLAN_FLAGS, "observed"),
    sigma_v_scale: float | None = option(api.plan, PLAN_FLAGS, "sigma_v_scale"),
    min_lambda_k: float | None = option(api.plan, PLAN_FLAGS, "min_lambda_k"),
    allow_smeared: bool = option(api.plan, PLAN_FLAGS, "allow_smeared"),
    budgets: list[str] = option(api.plan, PLAN_FLAGS, "budgets"),
    wide: _Wide = False,
    verbose: _Verbose = False,
    priorities: list[str] = option(api.plan, PLAN_FLAGS, "priorities"),
    output: _Output = None,
    fmt: _Format = None,
    plot: _Plot = None,
    sheet: _Sheet = None,
    timezone: str | None = option(api.plan, PLAN_FLAGS, "timezone"),
    overwrite: _Overwrite = False,
) -> None:
    """Plan phase-targeted observing blocks (UTC at the site) for one or more nights."""
    _plan_command(ctx, dict(locals()))


def _plan_command(ctx: typer.Context, o: dict[str, Any]) -> None:
    """``plan`` with its parameters ``o`` by name: check the outputs, plan (one call, with the
    options the user gave), print the nights and write the files."""
    fmt = _check_outputs(o["output"], o["fmt"], (o["plot"], o["sheet"]), o["overwrite"])
    given = {k: v for k, v in o.items() if k in _API and _given(ctx, k)}
    with warnings.catch_warnings():  # the report prints them, once, in its words
        warnings.simplefilter("ignore", UcbplanWarning)
        result = api.plan(**{**given, "site": o["site"]})
    report(result.run, o["wide"], o["verbose"])
    _write(result, fmt, o["output"], (o["plot"], o["sheet"]), o["overwrite"])


def _check_outputs(
    output: Path | None,
    fmt: str | None,
    figures: tuple[Path | None, Path | None],
    overwrite: bool,
) -> str:
    """The output format; every output path writable and every figure suffix known, before
    the planning rather than after it."""
    picked = pick_format(output, fmt, ("table", *_MACHINE))
    plot, sheet = figures
    for path in (output, plot, sheet):
        if path is not None:
            check_output_path(path, overwrite)
    if plot is not None:
        terminal.chart_format(plot)
    if sheet is not None:
        terminal.sheet_format(sheet)
    return picked


def register(app: typer.Typer) -> None:
    """Add ``plan`` to the app."""
    app.command("plan")(plan)
