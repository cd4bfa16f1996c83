"""``ucbplan feasibility``: expected signal sizes (paper Sec. 3).

A thin shell: parse options, call :func:`ucbplan.feasibility.report_for_target`, print the report
(rich on stderr, JSON on stdout or -o) and draw it with :func:`ucbplan.feasibility.plot_report`.
The option types are module-level aliases so the command reads as its parameter list.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.table import Table as RichTable

from ucbplan.api.signal_sizes import DAY_S, FEASIBILITY_FLAGS, MONTH_S, YEAR_S, feasibility
from ucbplan.cli._console import (
    check_output_path,
    dump_json,
    err_console,
    literal,
    pick_format,
    write_output,
)
from ucbplan.cli._derive import option
from ucbplan.cli._flags import cli_text
from ucbplan.cli._options import OverwriteAllOpt, TargetArg
from ucbplan.cli._strategies import print_comparison

PlotOpt = Annotated[Path | None, typer.Option("--plot", help="Write Δv_aps vs baseline PNG here.")]
FormatOpt = Annotated[
    str | None,
    typer.Option("--format", help="table (stderr) | json (stdout or -o; default with -o)."),
]
OutputOpt = Annotated[Path | None, typer.Option("-o", "--output", help="JSON output file.")]


def _opt(parameter: str) -> Any:
    """The option of ``parameter``: flag, help (:data:`FEASIBILITY_FLAGS`) and default
    (:func:`ucbplan.api.signal_sizes.feasibility`), declared once there."""
    return option(feasibility, FEASIBILITY_FLAGS, parameter)


def feasibility_command(
    target: TargetArg,
    m1: float | None = _opt("m1"),
    m2: float | None = _opt("m2"),
    sigma_v: str | None = _opt("sigma_v"),
    n_spectra: int = _opt("n_spectra"),
    baseline: str = _opt("baseline"),
    m3: float = _opt("m3"),
    a_out: float = _opt("a_out"),
    optical_sigma_phase: float | None = _opt("optical_sigma_phase"),
    optical_sigma_f_rel: float | None = _opt("optical_sigma_f_rel"),
    optical_sigma_fdot_rel: float | None = _opt("optical_sigma_fdot_rel"),
    optical_sigma_p: float | None = _opt("optical_sigma_p"),
    optical_sigma_pdot: float | None = _opt("optical_sigma_pdot"),
    optical_sigma_t0: float | None = _opt("optical_sigma_t0"),
    optical_epoch: str | None = _opt("optical_epoch"),
    plot: PlotOpt = None,
    fmt: FormatOpt = None,
    output: OutputOpt = None,
    overwrite: OverwriteAllOpt = False,
    sigma_floor: float = _opt("sigma_floor"),
    extinction: float | None = _opt("extinction"),
    readout: float = _opt("readout"),
    overhead: float = _opt("overhead"),
    visit: str | None = _opt("visit"),
    max_visit: str | None = _opt("max_visit"),
    goal: str | None = _opt("goal"),
    min_lambda_k: float | None = _opt("min_lambda_k"),
    allow_smeared: bool = _opt("allow_smeared"),
    compare_strategies: bool = _opt("compare_strategies"),
) -> None:
    """Expected signal sizes (paper Section 3): K_j, apsidal rates, ΔK, Δv_aps, e floor, Δv_CM,
    and GW vs optical timing errors."""
    given = dict(locals())  # the parameters, named as the API's (but fmt, output)
    fmt = pick_format(output, fmt, ("table", "json"))
    if output is not None:
        _check_output(output, plot, overwrite)
    got = feasibility(**{k: v for k, v in given.items() if k not in ("fmt", "output")})
    if plot is not None:
        err_console.print(f"wrote {literal(plot)}")
    if fmt == "json":
        write_output(output, lambda h: dump_json(got.to_dict(), h), overwrite=overwrite)
        return
    _print_report(got.report)
    if got.strategies is not None:
        print_comparison(got.strategies)


def _check_output(output: Path, plot: Path | None, overwrite: bool) -> None:
    """Refuse -o and --plot naming one file, or an existing -o, before any work."""
    from ucbplan.errors import InputError

    if plot is not None and output.resolve() == plot.resolve():
        raise InputError(f"-o, --plot: both name {output}; give two different files")
    check_output_path(output, overwrite)


def _fmt(value: float | None, fmt: str) -> str:
    if value is None or not math.isfinite(value):
        return "—"
    return format(value, fmt)


def _print_report(rep: Any) -> None:
    """The quantity table, the timing table (when there is one) and the notes, on stderr."""
    err_console.print(_quantity_table(rep))
    if rep.gw_timing_s is not None or rep.optical_timing_s is not None:
        err_console.print(_timing_table(rep))
    for note in rep.notes:
        err_console.print(f"[yellow]note:[/] {cli_text(note)}", soft_wrap=True)


def _quantity_table(rep: Any) -> RichTable:
    """One row per Sec. 3 magnitude: quantity, value, unit, the paper's equation label."""
    t = RichTable(title=f"Feasibility: {rep.name} (paper Sec. 3)")
    for col in ("quantity", "value", "unit", "Eq."):
        t.add_column(col)
    kms = 1e-3

    def row(q: str, v: float | None, fmt: str, unit: str, eq: str, scale: float = 1.0) -> None:
        t.add_row(q, _fmt(None if v is None else v * scale, fmt), unit, eq)

    row("P_b", rep.period_s / 60.0, ".4f", "min", "")
    row("e", rep.e, ".4g", "", "")
    row("ω0 at the reference epoch", rep.omega0_rad, ".4g", "rad", "")
    row("K1", rep.k1_m_s, ".1f", "km/s", "semiamp_est", kms)
    row("K2", rep.k2_m_s, ".1f", "km/s", "semiamp_est", kms)
    row("ω̇_GR", rep.omega_dot_gr, ".4g", "rad/s", "omega_dot_GR")
    row("Δω_GR per month", rep.omega_dot_gr, ".3g", "rad", "omega_dot_GR", MONTH_S)
    row("ω̇_tide", rep.omega_dot_tide, ".4g", "rad/s", "del_om_tide")
    row("Δω_tide per month", rep.omega_dot_tide, ".3g", "rad", "del_om_tide", MONTH_S)
    row(f"ω̇ used ({rep.omega_dot_source})", rep.omega_dot_used, ".4g", "rad/s", "")
    row("apsidal period", rep.apsidal_period_s / DAY_S, ".3g", "d", "")
    row(f"τ_chirp ({rep.tau_chirp_source})", rep.tau_chirp_s, ".3g", "yr", "tau_chirp", 1 / YEAR_S)
    base = f"over ΔT = {rep.baseline_s / DAY_S:.4g} d"
    row(f"|ΔK cos u★| {base}", rep.delta_k_m_s, ".3g", "km/s", "DeltaK_bound", kms)
    row("max |Δv_aps| = 2K1e", rep.delta_v_aps_max_m_s, ".3g", "km/s", "apsidal_drift_est0", kms)
    row(f"Δv_aps(ω0) {base}", rep.delta_v_aps_m_s, ".3g", "km/s", "apsidal_drift_est0", kms)
    floor_label = f"e floor (σ_v = {rep.sigma_v_m_s * kms:.3g} km/s, N = {rep.n_spectra})"
    row(floor_label, rep.e_floor, ".3g", "", "apsidal_drift_est0")
    row(f"Δv_CM Galactic {base}", rep.delta_v_cm_galactic_m_s, ".3g", "m/s", "DeltaVcm_est")
    tertiary = f"Δv_CM tertiary {rep.m3_msun:g} M☉ at {rep.a_out_au:g} AU {base}"
    row(tertiary, rep.delta_v_cm_tertiary_m_s, ".3g", "km/s", "DeltaVcm_est", kms)
    return t


def _timing_table(rep: Any) -> RichTable:
    """Target-ephemeris δt_u and optical δt per row of ΔT after the reference epoch."""
    tt = RichTable(title="Timing error after the reference epoch (LISA midpoint or T0), 1σ")
    tt.add_column("ΔT (yr)")
    tt.add_column("target δt_u (s)")
    tt.add_column("optical δt (s), Eq. optical_timing_prec")
    for i, y in enumerate(rep.timing_years):
        gw = rep.gw_timing_s[i] if rep.gw_timing_s is not None else None
        op = rep.optical_timing_s[i] if rep.optical_timing_s is not None else None
        tt.add_row(f"{y:g}", _fmt(gw, ".3g"), _fmt(op, ".3g"))
    return tt


def register(app: typer.Typer) -> None:
    """Add ``feasibility`` to the ucbplan app."""
    app.command("feasibility")(feasibility_command)
