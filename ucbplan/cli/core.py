"""Core commands: ``validate`` and ``horizon`` (thin shells over the public API).

Each command parses its options, calls one function of :mod:`ucbplan.api`
(:func:`~ucbplan.api.targets.validate`, :func:`~ucbplan.api.validity.horizon_report`) and prints
or writes the result. Options that are parameters of the API take their flag, help and default
from it (:data:`ucbplan.api.validity.HORIZON_FLAGS`); :mod:`ucbplan.cli.ephemeris` adds the
``ephemeris`` group.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any

import typer
import typer.core
from rich.markup import escape

from ucbplan.api.validity import HORIZON_FLAGS, horizon_report
from ucbplan.api.validity import horizon as _horizons  # its signature declares the defaults
from ucbplan.cli._console import (
    TABLE_FORMATS,
    check_output_path,
    dump_json,
    err_console,
    pick_format,
    rich_table,
    write_output,
    write_table_output,
)
from ucbplan.cli._derive import option
from ucbplan.cli._options import (
    OutputOpt,
    OverwriteAllOpt,
    PlotOpt,
    TableFormatOpt,
    TargetsArg,
    ValidateFormatOpt,
)
from ucbplan.cli.ephemeris import register as register_ephemeris

# numpy and astropy are imported by the API inside the commands: `ucbplan --help` must not pay
# for them (benchmarks/startup.py).


def validate(targets: TargetsArg, fmt: ValidateFormatOpt = "table") -> None:
    """Check target files and print a summary (period, e, ω, T_asc, σ's).

    For a timing ephemeris: T0, P, Ṗ with their σ, and σ_u one year before and after T0.
    """
    from ucbplan.api.targets import validate as summaries_of

    fmt = pick_format(None, fmt, ("table", "json"))
    summaries = summaries_of(targets)
    if fmt == "json":
        write_output(None, lambda h: dump_json(summaries, h))
        return
    for s in summaries:
        tab = rich_table(f"{s['name']}  ({s['file']})", ["quantity", "value"])
        labels = _TIMING_LABELS if s.get("kind") == "timing" else _SUMMARY_LABELS
        for key, label in labels:
            tab.add_row(escape(label), escape(_fmt(s[key])))
        err_console.print(tab)
    err_console.print(f"[green]ok[/]: {len(summaries)} target file(s) valid")


_SUMMARY_LABELS = (
    ("t_ref_tdb", "t_ref (TDB, barycentre, LISA midpoint)"),
    ("t_end_tdb", "end of LISA observation (TDB)"),
    ("period_s", "P_b anomalistic [s]"),
    ("period_asc_s", "2π/n̄_b from the node [s]"),
    ("eccentricity", "e"),
    ("omega_deg", "ω of star 1 at t_ref [deg]"),
    ("omega_dot_rad_s", "ω̇ [rad/s]"),
    ("t_asc_tdb", "T_asc nearest t_ref (TDB)"),
    ("sigma_t_asc_s", "σ(T_asc) [s]"),
    ("sigma_u_end_mrad", "σ_u at end of LISA obs. [mrad]"),
    ("sigmas", "σ's (SI)"),
    ("covariance_from", "covariance from"),
)


_TIMING_LABELS = (
    ("kind", "ephemeris"),
    ("t0_tdb", "T0 (TDB, barycentre)"),
    ("t0_bjd_tdb", "T0 [BJD_TDB]"),
    ("sigma_t0_s", "σ(T0) [s]"),
    ("t0_marks", "T0 marks"),
    ("period_s", "P [s]"),
    ("sigma_period_s", "σ(P) [s]"),
    ("pdot", "Ṗ [s/s]"),
    ("sigma_pdot", "σ(Ṗ) [s/s]"),
    ("pddot_per_s", "P̈ [1/s]"),
    ("sigma_pddot_per_s", "σ(P̈) [1/s]"),
    ("eccentricity", "e"),
    ("omega_deg", "ω of star 1 at T0 [deg]"),
    ("omega_dot_rad_s", "ω̇ [rad/s]"),
    ("sigma_u_before_1yr_mrad", "σ_u 1 yr before T0 [mrad]"),
    ("sigma_u_after_1yr_mrad", "σ_u 1 yr after T0 [mrad]"),
    ("sigma_t_before_1yr_s", "σ_t 1 yr before T0 [s]"),
    ("sigma_t_after_1yr_s", "σ_t 1 yr after T0 [s]"),
    ("source", "source"),
)


def _fmt(v: Any) -> str:
    if v is None:
        return "—"
    if isinstance(v, float):
        return f"{v:.10g}"
    if isinstance(v, dict):
        return ", ".join(f"{k}={x:.3g}" for k, x in v.items())
    return str(v)


#: Plain text, turned into paths by the command: typer's Path type costs ~0.1 ms per value (a
#: validator built per argument), as much as the whole horizon of a target.
HorizonTargetsArg = Annotated[
    list[str],
    typer.Argument(
        help="Target YAML file(s), folders of them (*.yaml, *.yml), or a catalog: one YAML "
        "file of several target documents separated by '---' lines.",
        metavar="TARGET",
        show_default=False,
    ),
]


def horizon(
    target: HorizonTargetsArg,
    sigma_v: float | None = option(_horizons, HORIZON_FLAGS, "sigma_v"),
    k_eff: float | None = option(_horizons, HORIZON_FLAGS, "k_eff"),
    alpha: list[float] = option(_horizons, HORIZON_FLAGS, "alpha"),
    epochs: int = option(_horizons, HORIZON_FLAGS, "n_epochs"),
    anchor: list[str] = option(_horizons, HORIZON_FLAGS, "anchors"),
    fmt: TableFormatOpt = None,
    output: OutputOpt = None,
    plot: PlotOpt = None,
    overwrite: OverwriteAllOpt = False,
) -> None:
    """Phase-coherence horizons T_valid (paper Tables 4 and 7) and σ_u at the end of LISA.

    For a timing ephemeris: T_valid before and after T0, separately. Several targets (files,
    folders or a catalog) give one table, a row per target × anchor × α, computed in one
    vectorised pass.
    """
    fmt = pick_format(output, fmt, TABLE_FORMATS)
    if plot is not None and output is not None:
        check_output_path(output, overwrite)
    got = horizon_report(target, sigma_v, k_eff, alpha, epochs, anchor, plot, overwrite)
    if len(got.targets) > 1:
        _show_many(got.table, fmt, output, overwrite)
        return
    t, rows = got.targets[0], list(got.rows)
    if fmt == "table":
        _print_horizon(t, rows, got.sigma_v, got.k_eff, got.n_epochs)
    elif fmt == "json":
        doc = [r.as_dict() | {"target": t.name} for r in rows]
        write_output(output, lambda h: dump_json(doc, h), overwrite=overwrite)
    else:
        write_table_output(got.table, fmt, output, overwrite)


#: Above this many targets the terminal gets a summary instead of the full table.
_MANY_ROWS = 40


def _show_many(tab: Any, fmt: str, output: Path | None, overwrite: bool) -> None:
    """The long horizon table of many targets, as JSON, a table file or on the terminal."""
    from ucbplan.api.validity import horizon_json

    if fmt == "json":
        text = horizon_json(tab)

        def write(handle: Any) -> None:
            handle.write(text)

        write_output(output, write, overwrite=overwrite)
    elif fmt != "table":
        write_table_output(tab, fmt, output, overwrite)
    else:
        _print_many(tab)


def _print_many(tab: Any) -> None:
    """The long table on the terminal (T_valid per target, anchor and α), or a summary of it."""
    import numpy as np

    n = len(set(tab["target"]))
    if n <= _MANY_ROWS:
        heads = ["target", "anchor", "α", "T_valid [d]", "T_valid before T0 [d]"]
        two = bool(np.any(tab["kind"] == "timing"))  # the before column only if a row has it
        rt = rich_table(
            f"horizons of {n} targets (after the end of the information)", heads[: 4 + two]
        )
        cols = ("target", "anchor", "alpha", "t_valid_days", "t_valid_before_days")
        for row in tab.iterrows(*cols):
            before = [f"{row[4]:.0f}" if np.isfinite(row[4]) else "—"] if two else []
            rt.add_row(row[0], row[1], f"{row[2]:g}", f"{row[3]:.0f}", *before)
        err_console.print(rt)
        return
    for a in dict.fromkeys(tab["anchor"]):
        for al in dict.fromkeys(tab["alpha"]):
            v = np.asarray(tab["t_valid_days"][(tab["anchor"] == a) & (tab["alpha"] == al)])
            err_console.print(
                escape(
                    f"T_valid {a}, α={al:g}: median {np.median(v):.0f} d, min {v.min():.0f} d, "
                    f"max {v.max():.0f} d"
                )
            )
    err_console.print(f"{n} targets: write the full table with -o FILE.ecsv")


def _print_horizon(t: Any, rows: list[Any], sv: float, k: float, epochs: int) -> None:
    if t.kind == "timing":
        _print_two_sided_horizon(t, rows, sv, k, epochs)
        return
    rt = rich_table(
        f"{t.name}: horizons after the end of the LISA observation "
        f"({t.t_end.tdb.isot[:10]} TDB), σ_v = {sv:g} km/s, K = {k:g} km/s, N = {epochs}",
        ["anchor", "α", "α·δu_tol [mrad]", "T_valid [d]", "T_valid [yr]", "δt_u(T_valid) [s]"],
    )
    for r in rows:
        rt.add_row(
            r.anchor,
            f"{r.alpha:g}",
            f"{1e3 * r.tolerance_rad:.2f}",
            f"{r.t_valid_days:.0f}",
            f"{r.t_valid_days / 365.25:.2f}",
            f"{r.dt_u_s:.2f}",
        )
    err_console.print(rt)
    ends = {r.anchor: r.sigma_u_end_rad for r in rows}
    txt = ", ".join(
        f"{a}: {1e3 * s:.2f} mrad (±{s / (math.pi * t.params.f_gw):.2f} s)" for a, s in ends.items()
    )
    err_console.print(escape(f"σ_u at the end of the LISA observation — {txt}"))
    _say_samples_covariance(t)


def _say_samples_covariance(t: Any) -> None:
    """One line when the covariance came from a samples file (issue 26: say which was used)."""
    if t.covariance_source.startswith("samples"):
        err_console.print(f"{t.name}: covariance from the {t.covariance_source}", markup=False)


def _print_two_sided_horizon(t: Any, rows: list[Any], sv: float, k: float, epochs: int) -> None:
    """Horizons of a timing ephemeris: T_valid before and after T0, each with δt_u."""
    rt = rich_table(
        f"{t.name}: horizons before and after T0 ({t.t_ref.tdb.isot[:10]} TDB), "
        f"σ_v = {sv:g} km/s, K = {k:g} km/s, N = {epochs}",
        [
            "anchor",
            "α",
            "α·δu_tol [mrad]",
            "T_valid before [d]",
            "T_valid after [d]",
            "δt_u before [s]",
            "δt_u after [s]",
        ],
    )
    for r in rows:
        rt.add_row(
            r.anchor,
            f"{r.alpha:g}",
            f"{1e3 * r.tolerance_rad:.2f}",
            f"{r.t_valid_before_days:.0f}",
            f"{r.t_valid_days:.0f}",
            f"{r.dt_u_before_s:.2f}",
            f"{r.dt_u_s:.2f}",
        )
    err_console.print(rt)
    ends = {r.anchor: r.sigma_u_end_rad for r in rows}
    txt = ", ".join(
        f"{a}: {1e3 * s:.2f} mrad (±{s / (math.pi * t.params.f_gw):.2f} s)" for a, s in ends.items()
    )
    err_console.print(escape(f"σ_u at T0 — {txt}"))


def register(app: typer.Typer) -> None:
    """Add the core commands to ``app``."""
    app.command("validate")(validate)
    register_ephemeris(app)
    app.command("horizon")(horizon)
