"""``ucbplan plan``: phase-targeted blocks at an observatory (thin shell over ucbplan.observing).

Parse the options into :class:`~ucbplan.observing.schedule.PlanSettings`, make one library call
(:func:`~ucbplan.observing.schedule.plan_files`), print the nights and write the blocks table and
the night chart.
"""

from __future__ import annotations

from pathlib import Path
from typing import IO, TYPE_CHECKING, Annotated, Any

import typer
from rich.markup import escape

from ucbplan.cli._console import (
    check_output_path,
    err_console,
    pick_format,
    write_output,
)
from ucbplan.cli._options import ExtinctionOpt, MaxVisitOpt, SigmaFloorOpt, SigmaLawOpt
from ucbplan.cli._plan_view import report

if TYPE_CHECKING:
    from ucbplan.observing.schedule import PlanSettings

__all__ = ["register"]

_MACHINE = ("ecsv", "csv", "json")

_Targets = Annotated[list[Path], typer.Argument(help="Target YAML files.")]
_SiteName = Annotated[str | None, typer.Option("--site", help="Site name or alias (e.g. paranal).")]
_SiteLonLat = Annotated[
    str | None,
    typer.Option(
        "--site-lonlat", help="LON,LAT,HEIGHT (deg east, deg north, m) instead of --site."
    ),
]
_SitesFile = Annotated[
    Path | None,
    typer.Option("--sites-file", help="YAML site table searched before the bundled one."),
]
_Night = Annotated[
    str, typer.Option("--night", help="Local date of the first evening, YYYY-MM-DD.")
]
_Nights = Annotated[int, typer.Option("--nights", help="Number of consecutive nights.")]
_Mode = Annotated[
    str,
    typer.Option(
        "--mode",
        help="quadrature | conjunction | zero-crossing | fixed-u-pairs | quadrature+conjunction "
        "| u=VALUE [rad].",
    ),
]
_Twilight = Annotated[str, typer.Option("--twilight", help="civil | nautical | astronomical")]
_AirmassMax = Annotated[float, typer.Option("--airmass-max", help="Largest airmass (sec z).")]
_MoonSep = Annotated[float, typer.Option("--moon-sep", help="Smallest Moon separation [deg].")]
_MoonIllum = Annotated[
    float | None,
    typer.Option(
        "--moon-illum", help="Largest Moon illuminated fraction (0-1) while the Moon is up."
    ),
]
_ZenithHole = Annotated[
    float | None,
    typer.Option("--zenith-hole", help="Zenith-hole radius [deg] (default: the site's; 0 = none)."),
]
_Exptime = Annotated[float, typer.Option("--exptime", help="Single-exposure time [s].")]
_NExp = Annotated[int, typer.Option("--n-exp", help="Exposures per block (co-added).")]
_Readout = Annotated[
    float | None,
    typer.Option(
        "--readout", help="Readout after each exposure [s] (default: the instrument's, else 0)."
    ),
]
_Alpha = Annotated[float, typer.Option("--alpha", help="Planning margin α of T_valid.")]
_KEff = Annotated[float | None, typer.Option("--k-eff", help="Semi-amplitude K_eff [km/s].")]
_MaxSmear = Annotated[
    str | None,
    typer.Option("--max-smear", help="Smearing budget: '0.5*sigma_v' or km/s; exceeded = error."),
]
_MaxBinFraction = Annotated[
    float | None,
    typer.Option("--max-bin-fraction", help="Largest block span as a fraction of P_b."),
]
_Overhead = Annotated[
    float | None,
    typer.Option(
        "--overhead",
        help="Slew + acquisition before each visit or session [s] (default: the instrument's, "
        "else 300).",
    ),
]
_Visit = Annotated[
    str | None,
    typer.Option(
        "--visit",
        help="Plan visits of this length (1h, 45min, 3600s; acquisition included): one "
        "acquisition, then exposures each centred on an anchor.",
    ),
]
_Cadence = Annotated[
    str,
    typer.Option(
        "--cadence",
        help="auto (most information per visit) | targeted (each exposure on an anchor) | "
        "phase-locked (exposure + readout = anchor spacing) | untargeted (back to back).",
    ),
]
_ServiceMode = Annotated[
    bool,
    typer.Option(
        "--service-mode",
        help="Plan only what a service-mode queue executes: visits of back-to-back exposures "
        "(phase-locked or untargeted cadence).",
    ),
]
_Instrument = Annotated[
    str | None,
    typer.Option("--instrument", help="Spectrograph (e.g. xshooter-vis, uves, esi): overheads."),
]
_InstrumentsFile = Annotated[
    Path | None,
    typer.Option("--instruments-file", help="YAML instrument table searched before the bundled."),
]
_Goal = Annotated[
    str | None,
    typer.Option(
        "--goal", help="Precision goal (sigma_K=2km/s, K1=1%, q=1%): plan the spectra it needs."
    ),
]
_MinLambdaK = Annotated[
    float | None,
    typer.Option(
        "--min-lambda-k",
        help="Smallest smearing factor Λ_K of an exposure (default 0.9 with --visit).",
    ),
]
_Budget = Annotated[
    list[str],
    typer.Option(
        "--budget", help="NAME=DURATION: wall time a target may get over all nights (e.g. 2h)."
    ),
]
_Wide = Annotated[bool, typer.Option("--wide", help="Print every column of the plan table.")]
_Verbose = Annotated[
    bool, typer.Option("--verbose", help="Print every night's table, however long the plan.")
]
_AllowSmeared = Annotated[
    bool, typer.Option("--allow-smeared", help="Plan exposures below the Λ_K floor.")
]
_Sessions = Annotated[int, typer.Option("--sessions", help="Sessions per target and night.")]
_Priority = Annotated[
    list[str],
    typer.Option("--priority", help="NAME=P overrides a target file's priority (higher first)."),
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
_Tz = Annotated[
    str | None,
    typer.Option("--tz", help="IANA time zone replacing the site's (e.g. America/Santiago)."),
]
_Overwrite = Annotated[bool, typer.Option("--overwrite", help="Replace existing output files.")]


def _given(ctx: typer.Context, name: str) -> bool:
    """Whether the user gave option ``name`` (not its default). Compared by name: typer may
    carry its own copy of click's ``ParameterSource`` enum."""
    source = ctx.get_parameter_source(name)
    return source is not None and getattr(source, "name", "") != "DEFAULT"


def _write(
    run: Any,
    fmt: str,
    output: Path | None,
    figures: tuple[Path | None, Path | None],
    overwrite: bool,
) -> None:
    """The blocks table (stdout or ``output``), the night charts and the night sheet."""
    plot, sheet = figures
    if fmt in _MACHINE or plot is not None or sheet is not None:
        table = run.table()
    if fmt in _MACHINE:
        from ucbplan.observing.tablewrite import write_table

        def _write_table(handle: IO[str]) -> None:
            write_table(table, handle, fmt, json_meta=True)

        write_output(output, _write_table, overwrite=overwrite)
        if output is not None:
            err_console.print(f"wrote {len(table)} blocks to {escape(str(output))} ({fmt})")
    constraints = run.settings.constraints(run.site)
    if plot is not None:
        from ucbplan.observing.nightplot import write_night_charts

        n = write_night_charts(table, run.site, plot, constraints=constraints, overwrite=overwrite)
        err_console.print(f"wrote night charts of {n} night(s) to {escape(str(plot))}")
    if sheet is not None:
        from ucbplan.observing.nightsheet import write_night_sheet

        n = write_night_sheet(table, run.site, sheet, constraints=constraints, overwrite=overwrite)
        err_console.print(f"wrote the night sheet of {n} night(s) to {escape(str(sheet))}")


# ``plan`` is long only by its parameters, one line each (their help in the aliases above);
# the work is in :func:`_plan_command`.
def plan(
    ctx: typer.Context,
    targets: _Targets,
    site: _SiteName = None,
    site_lonlat: _SiteLonLat = None,
    sites_file: _SitesFile = None,
    night: _Night = ...,  # type: ignore[assignment]  # required: typer reads ... as "no default"
    nights: _Nights = 1,
    mode: _Mode = "quadrature",
    twilight: _Twilight = "nautical",
    airmass_max: _AirmassMax = 2.0,
    moon_sep: _MoonSep = 30.0,
    moon_illum: _MoonIllum = None,
    zenith_hole: _ZenithHole = None,
    exptime: _Exptime = 60.0,
    n_exp: _NExp = 1,
    readout: _Readout = None,
    alpha: _Alpha = 1.0,
    sigma_v: SigmaLawOpt = None,
    sigma_floor: SigmaFloorOpt = 0.0,
    extinction: ExtinctionOpt = None,
    k_eff: _KEff = None,
    max_smear: _MaxSmear = None,
    max_bin_fraction: _MaxBinFraction = None,
    overhead: _Overhead = None,
    sessions: _Sessions = 1,
    visit: _Visit = None,
    max_visit: MaxVisitOpt = None,
    cadence: _Cadence = "auto",
    service_mode: _ServiceMode = False,
    instrument: _Instrument = None,
    instruments_file: _InstrumentsFile = None,
    goal: _Goal = None,
    min_lambda_k: _MinLambdaK = None,
    allow_smeared: _AllowSmeared = False,
    budget: _Budget = [],  # noqa: B006  # typer copies the default; never mutated
    wide: _Wide = False,
    verbose: _Verbose = False,
    priority: _Priority = [],  # noqa: B006  # typer copies the default; never mutated
    output: _Output = None,
    fmt: _Format = None,
    plot: _Plot = None,
    sheet: _Sheet = None,
    tz: _Tz = None,
    overwrite: _Overwrite = False,
) -> None:
    """Plan phase-targeted observing blocks (UTC at the site) for one or more nights."""
    _plan_command(ctx, dict(locals()))


def _plan_command(ctx: typer.Context, o: dict[str, Any]) -> None:
    """``plan`` with its parameters ``o`` by name: check the outputs, plan (one library call),
    print the nights and write the files."""
    from ucbplan.observing.schedule import plan_files

    fmt = _check_outputs(o["output"], o["fmt"], (o["plot"], o["sheet"]), o["overwrite"])
    run = plan_files(
        o["targets"],
        first_night=o["night"],
        n_nights=o["nights"],
        site=o["site"],
        site_lonlat=o["site_lonlat"],
        sites_file=o["sites_file"],
        settings=_settings(ctx, o),
        priorities=o["priority"],
        timezone=o["tz"],
    )
    report(run, o["wide"], o["verbose"])
    _write(run, fmt, o["output"], (o["plot"], o["sheet"]), o["overwrite"])


def _check_outputs(
    output: Path | None,
    fmt: str | None,
    figures: tuple[Path | None, Path | None],
    overwrite: bool,
) -> str:
    """The output format; every output path writable and every figure suffix known, before
    the planning rather than after it."""
    from ucbplan.observing.nightplot import chart_format
    from ucbplan.observing.nightsheet import sheet_format

    picked = pick_format(output, fmt, ("table", *_MACHINE))
    plot, sheet = figures
    for path in (output, plot, sheet):
        if path is not None:
            check_output_path(path, overwrite)
    if plot is not None:
        chart_format(plot)
    if sheet is not None:
        sheet_format(sheet)
    return picked


def _settings(ctx: typer.Context, o: dict[str, Any]) -> PlanSettings:
    """:class:`PlanSettings` from the ``plan`` parameters ``o`` (flags → library names)."""
    from ucbplan.observing.schedule import plan_settings

    return plan_settings(
        instrument=o["instrument"],
        instruments_file=o["instruments_file"],
        # a default exposure is capped at the smearing floor, a given one refused below it
        exptime_s=o["exptime"] if _given(ctx, "exptime") else None,
        n_exp=o["n_exp"],
        readout_s=o["readout"],
        overhead_s=o["overhead"],
        visit=o["visit"],
        max_visit=o["max_visit"],
        sigma_v_kms=o["sigma_v"],
        sigma_floor_kms=o["sigma_floor"],
        extinction_k=o["extinction"],
        cadence=o["cadence"],
        service_mode=o["service_mode"],
        goal=o["goal"],
        min_lambda_k=o["min_lambda_k"],
        allow_smeared=o["allow_smeared"],
        budgets=o["budget"],
        mode=o["mode"],
        twilight=o["twilight"],
        airmass_max=o["airmass_max"],
        moon_sep_deg=o["moon_sep"],
        moon_illum_max=o["moon_illum"],
        zenith_hole_deg=o["zenith_hole"],
        alpha=o["alpha"],
        k_eff_kms=o["k_eff"],
        max_smear=o["max_smear"],
        max_bin_fraction=o["max_bin_fraction"],
        sessions_per_night=o["sessions"],
    )


def register(app: typer.Typer) -> None:
    """Add ``plan`` to the app."""
    app.command("plan")(plan)
