"""``ucbplan plan``: phase-targeted blocks at an observatory (thin shell over ucbplan.observing).

Parse the options into :class:`~ucbplan.observing.schedule.PlanSettings`, make one library call
(:func:`~ucbplan.observing.schedule.plan_files`), print the nights and write the blocks table and
the night chart.
"""

from __future__ import annotations

from pathlib import Path
from typing import IO, Annotated, Any

import typer
from rich.markup import escape

from ucbplan.cli._console import (
    check_output_path,
    err_console,
    pick_format,
    rich_table,
    write_output,
)
from ucbplan.errors import UcbplanError

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
        "--mode", help="quadrature | conjunction | zero-crossing | fixed-u-pairs | u=VALUE [rad]."
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
_SigmaV = Annotated[float | None, typer.Option("--sigma-v", help="RV precision σ_v [km/s].")]
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
        help="anchor (wait for the next anchor) | phase-locked (exposure + readout = anchor "
        "spacing, no waiting).",
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
_Plot = Annotated[Path | None, typer.Option("--plot", help="Night chart PNG (first night).")]
_Overwrite = Annotated[bool, typer.Option("--overwrite", help="Replace existing output files.")]


def _local(b: Any) -> str:
    from datetime import UTC
    from zoneinfo import ZoneInfo

    dt = b.t_mid_utc.to_datetime(timezone=UTC).astimezone(ZoneInfo(b.timezone))
    return dt.strftime("%H:%M:%S %Z")


def _exposure_labels(blocks: list[Any]) -> list[str]:
    """``V01/03``: visit and exposure number inside it, per block (blocks in time order)."""
    count: dict[tuple[str, str], int] = {}
    out = []
    for b in blocks:
        key = (b.target, b.visit_id)
        count[key] = count.get(key, 0) + 1
        visit = b.visit_id.rsplit("-", 1)[-1] if b.visit_id else "—"
        out.append(f"{visit}/{count[key]:02d}")
    return out


def _print_compact(blocks: list[Any], night: str, site: Any) -> None:
    """The essential columns of a night, fitting 100 terminal columns (``--wide``: all)."""
    names = list(dict.fromkeys(b.target for b in blocks))
    who = f"{names[0]}, " if len(names) == 1 else ""
    table = rich_table(
        f"{who}night of {night} at {site.name} — UTC at the site (light time removed)",
        [
            *(["target"] if len(names) > 1 else []),
            "visit/exp",
            "UTC start–end",
            "u★ [rad]",
            "airmass",
            "Λ_K",
            "σ_t [s]",
        ],
    )
    for column in table.columns:
        column.no_wrap = True
    for b, label in zip(blocks, _exposure_labels(blocks), strict=True):
        table.add_row(
            *([escape(b.target[:12])] if len(names) > 1 else []),
            label,
            f"{b.t_start_utc.iso[:19]}–{b.t_end_utc.iso[11:19]}",
            f"{b.u_star_rad:.4f}",
            f"{b.airmass:.2f}",
            f"{b.lambda_k:.3f}",
            f"{b.sigma_t_s:.2f}",
        )
    err_console.print(table)


def _print_summary(run: Any) -> None:
    """One row per night: visits, exposures and hours (a long plan, without --verbose)."""
    visits = run.visits()
    table = rich_table(
        f"Plan at {run.site.name}, per night (the full table: -o FILE or --verbose)",
        ["night", "visits", "exposures", "hours"],
    )
    for night in dict.fromkeys(b.night for b in run.result.blocks):
        vs = [v for v in visits if v.night == night]
        table.add_row(
            night,
            str(len(vs)),
            str(sum(v.exposures for v in vs)),
            f"{sum(v.wall_s for v in vs) / 3600:.2f}",
        )
    err_console.print(table)


#: A plan longer than this many nights or rows prints the per-night summary (issue 15).
SUMMARY_NIGHTS, SUMMARY_ROWS = 3, 60


def _print_night(blocks: list[Any], night: str, site: Any) -> None:
    paired = any(b.pair_id for b in blocks)
    # the φ_ref π-mode exists only for LISA posteriors; a night of timing targets has none
    pi_mode = any(b.t_alt_utc is not None for b in blocks)
    table = rich_table(
        f"Night of {night} at {site.name} — times are UTC at the site (light time removed); "
        "±σ is the 1σ timing uncertainty",
        [
            "target",
            "block",
            "anchor",
            "u★ [rad]",
            "UTC mid ± σ",
            "local mid",
            "UTC start–end",
            "airmass s/m/e",
            "Moon [deg]",
            "Λ_K",
            *(["π-mode alt. UTC"] if pi_mode else []),
            *(["pair: Δκ_LISA"] if paired else []),
        ],
    )
    for b in blocks:
        table.add_row(
            escape(b.target),
            escape(b.block_id.rsplit("-", 1)[-1]),
            escape(b.anchor),
            f"{b.u_star_rad:.4f}",
            f"{b.t_mid_utc.iso[11:23]} ± {b.sigma_t_s:.2f} s",
            _local(b),
            f"{b.t_start_utc.iso[11:19]}–{b.t_end_utc.iso[11:19]}",
            f"{b.airmass_start:.2f}/{b.airmass:.2f}/{b.airmass_end:.2f}",
            f"{b.moon_sep_deg:.0f}",
            f"{b.lambda_k:.4f}",
            *([b.t_alt_utc.iso[11:21] if b.t_alt_utc is not None else "—"] if pi_mode else []),
            *([f"{escape(b.pair_id)}: {b.delta_kappa:+.2e}"] if paired else []),
        )
    err_console.print(table)


def _report(run: Any, wide: bool = False, verbose: bool = False) -> None:
    """Warnings and what was not placed (grouped over nights), then one table per night."""
    for w in run.result.warnings:
        err_console.print(f"[yellow]warning:[/] {escape(w)}", soft_wrap=True)
    grouped: dict[tuple[str, str], list[str]] = {}
    for miss in run.result.unplaced:
        grouped.setdefault((miss.target, miss.reason), []).append(miss.night)
    for (name, reason), when in grouped.items():
        span = when[0] if len(when) == 1 else f"{len(when)} nights {when[0]}..{when[-1]}"
        err_console.print(
            f"[yellow]not placed:[/] {escape(name)} ({span}): {escape(reason)}", soft_wrap=True
        )
    failure = run.failure()
    if failure is not None:
        raise UcbplanError(failure)
    blocks = run.result.blocks
    nights = list(dict.fromkeys(b.night for b in blocks))
    if not verbose and (len(nights) > SUMMARY_NIGHTS or len(blocks) > SUMMARY_ROWS):
        _print_summary(run)
    else:
        show = _print_night if wide else _print_compact
        for label in nights:
            show([b for b in blocks if b.night == label], label, run.site)
    _print_accounting(run, verbose)


def _print_reasons(run: Any) -> None:
    """Night-time anchor epochs not planned, by reason, summed over the nights (one line per
    target; per night in the table meta ``not_planned``)."""
    for name, nights in run.result.reasons.items():
        total: dict[str, int] = {}
        for counts in nights.values():
            for why, k in counts.items():
                total[why] = total.get(why, 0) + k
        if not total:
            continue
        span = f"{len(nights)} night{'s' if len(nights) > 1 else ''}"
        parts = ", ".join(f"{k} {why}" for why, k in total.items())
        err_console.print(
            f"night-time anchors not planned: {escape(name)} ({span}): {escape(parts)}",
            soft_wrap=True,
        )


def _given(ctx: typer.Context, name: str) -> bool:
    """Whether the user gave option ``name`` (not its default)."""
    from click.core import ParameterSource

    return ctx.get_parameter_source(name) not in (ParameterSource.DEFAULT, None)


def _hours(seconds: float) -> str:
    return f"{seconds / 3600:.2f} h"


def _print_accounting(run: Any, verbose: bool = False) -> None:
    """Visits (with --visit) and the time accounting, per target and in total."""
    visits = run.visits()
    if run.settings.visit_s is not None and (verbose or len(visits) <= SUMMARY_ROWS):
        table_v = rich_table(
            "Visits — one acquisition each, then exposures centred on anchors (UTC)",
            ["visit", "target", "acquisition starts", "first exposure", "last ends", "n", "idle"],
        )
        for v in visits:
            table_v.add_row(
                escape(v.visit_id.rsplit("-", 1)[-1]),
                escape(v.target),
                v.acq_start_utc.replace("T", " "),
                v.start_utc[11:],
                v.end_utc[11:],
                str(v.exposures),
                f"{v.idle_s:.0f} s",
            )
        err_console.print(table_v)
    acc = run.accounting()
    table = rich_table(
        "Time accounting — efficiency = shutter / (shutter + overheads + idle)",
        ["target", "visits", "exposures", "shutter", "overheads", "idle", "efficiency"],
    )
    rows = [
        *acc["targets"].items(),
        *([("total", acc["total"])] if len(acc["targets"]) > 1 else []),
    ]
    for name, e in rows:
        table.add_row(
            escape(name),
            str(e["visits"]),
            str(e["exposures"]),
            _hours(e["shutter_s"]),
            _hours(e["overhead_s"]),
            _hours(e["idle_s"]),
            f"{e['efficiency']:.1%}",
        )
    err_console.print(table)
    _print_reasons(run)
    for name, goal in run.result.goals.items():
        err_console.print(
            f"goal {escape(goal.goal.describe())}: {escape(name)} needs {goal.n_spectra} spectra "
            f"({', '.join(f'{n} x {a}' for a, n in goal.per_anchor)}); planned",
            soft_wrap=True,
        )


def _write(run: Any, fmt: str, output: Path | None, plot: Path | None, overwrite: bool) -> None:
    """The blocks table (stdout or ``output``) and the night chart of the first night."""
    if fmt in _MACHINE:
        from ucbplan.observing.blocktable import write_table

        table = run.table()

        def _write_table(handle: IO[str]) -> None:
            write_table(table, handle, fmt)

        write_output(output, _write_table, overwrite=overwrite)
        if output is not None:
            err_console.print(f"wrote {len(table)} blocks to {escape(str(output))} ({fmt})")
    if plot is not None:
        from ucbplan.observing.nightplot import plot_night
        from ucbplan.plotting import save_figure

        airmass_max = run.settings.airmass_max
        fig = plot_night(run.targets, run.site, run.nights[0], run.result.blocks, airmass_max)
        save_figure(fig, plot, overwrite=overwrite, dpi=120)
        err_console.print(f"wrote night chart to {escape(str(plot))}")


# ``plan`` is long only by its 27 options and their one-to-one mapping into PlanSettings.
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
    sigma_v: _SigmaV = None,
    k_eff: _KEff = None,
    max_smear: _MaxSmear = None,
    max_bin_fraction: _MaxBinFraction = None,
    overhead: _Overhead = None,
    sessions: _Sessions = 1,
    visit: _Visit = None,
    cadence: _Cadence = "anchor",
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
    overwrite: _Overwrite = False,
) -> None:
    """Plan phase-targeted observing blocks (UTC at the site) for one or more nights."""
    from ucbplan.observing.schedule import plan_files, plan_settings
    from ucbplan.observing.timeconv import quiet_erfa

    fmt = pick_format(output, fmt, ("table", *_MACHINE))
    for path in (output, plot):
        if path is not None:
            check_output_path(path, overwrite)
    with quiet_erfa():
        settings = plan_settings(
            instrument=instrument,
            instruments_file=instruments_file,
            # a default exposure is capped at the smearing floor, a given one refused below it
            exptime_s=exptime if _given(ctx, "exptime") else None,
            n_exp=n_exp,
            readout_s=readout,
            overhead_s=overhead,
            visit=visit,
            sigma_v_kms=sigma_v,
            cadence=cadence,
            goal=goal,
            min_lambda_k=min_lambda_k,
            allow_smeared=allow_smeared,
            budgets=budget,
            mode=mode,
            twilight=twilight,
            airmass_max=airmass_max,
            moon_sep_deg=moon_sep,
            moon_illum_max=moon_illum,
            zenith_hole_deg=zenith_hole,
            alpha=alpha,
            k_eff_kms=k_eff,
            max_smear=max_smear,
            max_bin_fraction=max_bin_fraction,
            sessions_per_night=sessions,
        )
        run = plan_files(
            targets,
            first_night=night,
            n_nights=nights,
            site=site,
            site_lonlat=site_lonlat,
            sites_file=sites_file,
            settings=settings,
            priorities=priority,
        )
        _report(run, wide, verbose)
        _write(run, fmt, output, plot, overwrite)


def register(app: typer.Typer) -> None:
    """Add ``plan`` to the app."""
    app.command("plan")(plan)
