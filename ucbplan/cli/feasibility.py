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

from ucbplan.cli._console import (
    check_output_and_plot,
    dump_json,
    err_console,
    literal,
    pick_format,
    write_output,
)
from ucbplan.cli._epochs import epoch_option
from ucbplan.cli._options import (
    ExtinctionOpt,
    MaxVisitOpt,
    OverwriteAllOpt,
    SigmaFloorOpt,
    SigmaLawOpt,
    TargetArg,
)
from ucbplan.cli._strategies import print_comparison
from ucbplan.core.constants import DAY_S, MONTH_S, YEAR_S
from ucbplan.errors import UcbplanError, shorten

__all__ = ["feasibility_command", "register"]

_OptFloat = float | None
M1Opt = Annotated[_OptFloat, typer.Option("--m1", help="Mass of star 1 (M_sun) (else file).")]
M2Opt = Annotated[_OptFloat, typer.Option("--m2", help="Mass of star 2 (M_sun) (else file).")]
ReadoutOpt = Annotated[float, typer.Option("--readout", help="Readout per exposure (s).")]
OverheadOpt = Annotated[float, typer.Option("--overhead", help="Acquisition per visit (s).")]
VisitOpt = Annotated[
    str | None, typer.Option("--visit", help="Visit length (1h); default --max-visit.")
]
GoalOpt = Annotated[
    str | None,
    typer.Option("--goal", help="Precision goal (sigma_K=2km/s, K1=1%, q=1%): hours to reach it."),
]
MinLambdaOpt = Annotated[
    _OptFloat, typer.Option("--min-lambda-k", help="Smallest Λ_K of an exposure (0.9).")
]
SmearedOpt = Annotated[
    bool, typer.Option("--allow-smeared", help="Allow exposures below the Λ_K floor.")
]
CompareOpt = Annotated[
    bool,
    typer.Option(
        "--compare-strategies",
        help="Compare targeted, phase-locked and untargeted exposures (implied by a law "
        "--sigma-v T@REF or --goal).",
    ),
]
NSpectraOpt = Annotated[int, typer.Option("--n-spectra", help="Spectra co-added per epoch.")]
BaselineOpt = Annotated[str, typer.Option("--baseline", help="Baseline ΔT ('30 d', '1 yr', days).")]
M3Opt = Annotated[float, typer.Option("--m3", help="Tertiary mass (M_sun) for Δv_CM.")]
AOutOpt = Annotated[float, typer.Option("--a-out", help="Tertiary separation (AU) for Δv_CM.")]
OptPhaseOpt = Annotated[
    _OptFloat, typer.Option("--optical-sigma-phase", help="Optical ephemeris σ(φ0) (cycles).")
]
OptFRelOpt = Annotated[_OptFloat, typer.Option("--optical-sigma-f-rel", help="σ_f/f (1).")]
OptFdotRelOpt = Annotated[_OptFloat, typer.Option("--optical-sigma-fdot-rel", help="σ_ḟ/f (1/s).")]
OptPOpt = Annotated[_OptFloat, typer.Option("--optical-sigma-p", help="σ(P_orb) (s).")]
OptPdotOpt = Annotated[_OptFloat, typer.Option("--optical-sigma-pdot", help="σ(Ṗ_orb) (s/s).")]
OptT0Opt = Annotated[_OptFloat, typer.Option("--optical-sigma-t0", help="σ(T0) (s).")]
OptEpochOpt = Annotated[
    str | None,
    typer.Option(
        "--optical-epoch",
        help=(
            "Optical ephemeris reference epoch: ISO (TDB unless labelled UTC) or BJD_TDB; "
            "default: the target's reference epoch (LISA midpoint or timing T0)."
        ),
    ),
]
PlotOpt = Annotated[Path | None, typer.Option("--plot", help="Write Δv_aps vs baseline PNG here.")]
FormatOpt = Annotated[
    str | None,
    typer.Option("--format", help="table (stderr) | json (stdout or -o; default with -o)."),
]
OutputOpt = Annotated[Path | None, typer.Option("-o", "--output", help="JSON output file.")]


def feasibility_command(
    target: TargetArg,
    m1: M1Opt = None,
    m2: M2Opt = None,
    sigma_v: SigmaLawOpt = None,
    n_spectra: NSpectraOpt = 1,
    baseline: BaselineOpt = "1 yr",
    m3: M3Opt = 1.0,
    a_out: AOutOpt = 5.0,
    opt_phase: OptPhaseOpt = None,
    opt_f_rel: OptFRelOpt = None,
    opt_fdot_rel: OptFdotRelOpt = None,
    opt_p: OptPOpt = None,
    opt_pdot: OptPdotOpt = None,
    opt_t0: OptT0Opt = None,
    opt_epoch: OptEpochOpt = None,
    plot: PlotOpt = None,
    fmt: FormatOpt = None,
    output: OutputOpt = None,
    overwrite: OverwriteAllOpt = False,
    sigma_floor: SigmaFloorOpt = 0.0,
    extinction: ExtinctionOpt = None,
    readout: ReadoutOpt = 0.0,
    overhead: OverheadOpt = 300.0,
    visit: VisitOpt = None,
    max_visit: MaxVisitOpt = None,
    goal: GoalOpt = None,
    min_lambda_k: MinLambdaOpt = None,
    allow_smeared: SmearedOpt = False,
    compare_strategies: CompareOpt = False,
) -> None:
    """Expected signal sizes (paper Section 3): K_j, apsidal rates, ΔK, Δv_aps, e floor, Δv_CM,
    and GW vs optical timing errors."""
    from ucbplan.observing.schedule.options import plan_settings
    from ucbplan.target import load_target

    fmt = pick_format(output, fmt, ("table", "json"))
    settings = plan_settings(
        sigma_v_kms=sigma_v,
        sigma_floor_kms=sigma_floor,
        extinction_k=extinction,
        readout_s=readout,
        overhead_s=overhead,
        visit=visit,
        max_visit=max_visit,
        goal=goal,
        min_lambda_k=min_lambda_k,
        allow_smeared=allow_smeared,
    )
    sigma_ref = _checked_options(settings, n_spectra, m1, m2, m3, a_out)
    check_output_and_plot(output, plot, overwrite)
    tgt = load_target(target)
    law = settings.sigma_model
    compare = compare_strategies or goal is not None or (law is not None and law.follows_exposure)
    optical = _optical(tgt, opt_phase, opt_f_rel, opt_fdot_rel, opt_p, opt_pdot, opt_t0)
    offset = _optical_offset(opt_epoch, tgt.t_ref) if opt_epoch else 0.0
    report = _report(tgt, m1, m2, sigma_ref, n_spectra, baseline, m3, a_out, optical, offset)
    _emit(report, tgt, settings if compare else None, fmt, output, plot, overwrite)


def _optical(
    tgt: Any,
    sigma_phase: float | None,
    sigma_f_rel: float | None,
    sigma_fdot_rel: float | None,
    sigma_p: float | None,
    sigma_pdot: float | None,
    sigma_t0: float | None,
) -> Any:
    """The optical ephemeris of the ``--optical-sigma-*`` options, at the target's period."""
    from ucbplan.feasibility import optical_ephemeris

    return optical_ephemeris(
        tgt.params.nodal_period_s,
        sigma_phase_cycles=sigma_phase,
        sigma_f_rel=sigma_f_rel,
        sigma_fdot_rel_s=sigma_fdot_rel,
        sigma_p_s=sigma_p,
        sigma_pdot=sigma_pdot,
        sigma_t0_s=sigma_t0,
    )


def _report(
    tgt: Any,
    m1: float | None,
    m2: float | None,
    sigma_kms: float | None,
    n_spectra: int,
    baseline: str,
    m3: float,
    a_out: float,
    optical: Any,
    offset_s: float,
) -> Any:
    """:func:`ucbplan.feasibility.report_for_target` in SI units from the options."""
    from ucbplan.feasibility import report_for_target

    return report_for_target(
        tgt,
        m1_msun=m1,
        m2_msun=m2,
        sigma_v_m_s=sigma_kms * 1e3 if sigma_kms is not None else None,
        n_spectra=n_spectra,
        baseline_s=_parse_baseline(baseline),
        m3_msun=m3,
        a_out_au=a_out,
        optical=optical,
        optical_offset_s=offset_s,
    )


def _emit(
    report: Any,
    tgt: Any,
    compare: Any,
    fmt: str,
    output: Path | None,
    plot: Path | None,
    overwrite: bool,
) -> None:
    """The figure (--plot), then the report and, with the plan settings ``compare``, the
    comparison of exposure strategies, as JSON or tables."""
    from ucbplan.feasibility import plot_report

    if plot is not None:
        plot_report(report, plot, overwrite=overwrite)
        err_console.print(f"wrote {literal(plot)}")
    comparison = _comparison(tgt, compare) if compare is not None else None
    if fmt == "json":
        doc = {"units": "SI (m/s, s, rad, rad/s); masses M_sun", **report.to_dict()}
        if comparison is not None:
            doc["strategies"] = comparison.to_dict()
        write_output(output, lambda h: dump_json(doc, h), overwrite=overwrite)
    else:
        _print_report(report)
        if comparison is not None:
            print_comparison(comparison)


def _comparison(target: Any, settings: Any) -> Any:
    from ucbplan.observing.schedule.compare import compare_target_strategies

    return compare_target_strategies(target, settings)


def _checked_options(
    settings: Any,
    n_spectra: int,
    m1: float | None,
    m2: float | None,
    m3: float,
    a_out: float,
) -> float | None:
    """Reject bad option values with the option's name (before any file is read).

    Returns the reference σ_v [km/s]: the σ_v law's at its reference exposure, else --sigma-v.
    """
    law = settings.sigma_model
    sigma_v = law.sigma_kms if law is not None else settings.sigma_v_kms
    check_number("--n-spectra", n_spectra, 0, 1e9, "spectra")
    wd = "white dwarfs weigh between ~0.05 M_sun and the Chandrasekhar mass"
    check_number("--m1", m1, 0.05, 1.5, "M_sun", wd)
    check_number("--m2", m2, 0.05, 1.5, "M_sun", wd)
    check_number("--sigma-v", sigma_v, 0.0, 1e4, "km/s")
    check_number("--m3", m3, 0.0, 1e3, "M_sun")
    check_number("--a-out", a_out, 0.0, 1e6, "AU")
    return sigma_v


def _parse_baseline(text: str) -> float:
    """Baseline as an astropy quantity string (``"30 d"``, ``"1 yr"``) or bare days → seconds."""
    import astropy.units as u

    try:
        seconds = float(text) * DAY_S
    except ValueError:
        try:
            seconds = float(u.Quantity(text).to_value(u.s))
        except (ValueError, TypeError, u.UnitsError):
            raise UcbplanError(
                f"--baseline: got {shorten(text, 40)}, expected a time like '30 d', '1 yr' or "
                "bare days"
            ) from None
    check_number("--baseline", seconds / YEAR_S, 0.0, 100.0, "yr", "at most a century")
    return seconds


def _optical_offset(text: str, t_ref: Any) -> float:
    """Seconds from the optical reference epoch (bare number = BJD_TDB) to the target's
    reference epoch."""
    from astropy.time import Time

    try:
        jd = float(text)
    except ValueError:
        epoch = epoch_option(text, "--optical-epoch")
    else:
        # a bare number is a BJD_TDB between the years 1000 and 3000
        check_number("--optical-epoch", jd, 2086302.5, 2816787.5, "BJD_TDB")
        epoch = Time(jd, format="jd", scale="tdb")
    return float((t_ref - epoch).to_value("s"))


def check_number(*args: Any, **kwargs: Any) -> Any:
    """:func:`ucbplan.inputs.check_number`, imported on first use (it pulls in numpy/yaml; the
    module is imported for every ``--help``)."""
    from ucbplan.inputs import check_number as check

    return check(*args, **kwargs)


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
        err_console.print(f"[yellow]note:[/] {note}", soft_wrap=True)


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
