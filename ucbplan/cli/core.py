"""Core commands: ``validate``, ``ephemeris`` and ``horizon`` (thin shell over the library).

Each command parses its options, calls :mod:`ucbplan.core` (:func:`~ucbplan.core.ephemeris.
find_epochs`, :func:`~ucbplan.core.forecast.horizon_table`, :func:`~ucbplan.core.timing.
compare_sources`, the validate summary numbers) and prints or writes the result. The option
types are module-level aliases so each command reads as its parameter list.

``ephemeris`` is a command group whose default sub-command is ``predict``:
``ucbplan ephemeris TARGET --start … --end …`` is ``ucbplan ephemeris predict TARGET …``
(:class:`EphemerisGroup`); ``ucbplan ephemeris compare A B`` compares two ephemerides, and
``ucbplan ephemeris fit`` is mounted by :func:`register` (see the marked place there).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import IO, Annotated, Any

import numpy as np
import typer
import typer.core
from rich.markup import escape

from ucbplan import __version__
from ucbplan.cli._console import dump_json, err_console, pick_format, rich_table, write_output
from ucbplan.core.constants import DAY_S
from ucbplan.errors import UcbplanError, shorten
from ucbplan.inputs import check_number
from ucbplan.target import Target, load_target

__all__ = ["EphemerisGroup", "ephemeris_app", "register"]

TargetArg = Annotated[Path, typer.Argument(help="Target YAML file.")]
TargetsArg = Annotated[list[Path], typer.Argument(help="Target YAML files to check.")]
ValidateFormatOpt = Annotated[str, typer.Option("--format", help="table | json")]
TableFormatOpt = Annotated[
    str | None,
    typer.Option("--format", help="table | ecsv | csv | json (default: the -o suffix, else table)"),
]
OutputOpt = Annotated[Path | None, typer.Option("-o", "--output", help="Write here (else stdout).")]
OverwriteOutputOpt = Annotated[
    bool, typer.Option("--overwrite", help="Replace an existing -o file.")
]
OverwriteAllOpt = Annotated[
    bool, typer.Option("--overwrite", help="Replace existing output files.")
]
StartOpt = Annotated[str, typer.Option("--start", help="Window start, ISO, TDB at the barycentre.")]
EndOpt = Annotated[str, typer.Option("--end", help="Window end, ISO, TDB at the barycentre.")]
AnchorOpt = Annotated[
    str,
    typer.Option(
        "--anchor",
        help="quadrature | conjunction | eclipse (primary and secondary) | zero-crossing | U_RAD",
    ),
]
StarOpt = Annotated[
    int, typer.Option("--star", help="Component whose argument of latitude (1 or 2).")
]
MaxEpochsOpt = Annotated[
    int, typer.Option("--max-epochs", help="Refuse windows with more epochs than this.")
]
SigmaVOpt = Annotated[
    float | None,
    typer.Option("--sigma-v", help="RV precision per epoch σ_v [km/s] (default: target file)."),
]
KEffOpt = Annotated[
    float | None,
    typer.Option(
        "--k-eff", help="Semi-amplitude of the observable [km/s] (default: K_eff or K1+K2)."
    ),
]
AlphaOpt = Annotated[list[float], typer.Option("--alpha", help="Margin α (repeatable).")]
EpochsOpt = Annotated[
    int, typer.Option("--epochs", help="1: single epoch, 2: two-epoch difference.")
]
AnchorsOpt = Annotated[list[str], typer.Option("--anchor", help="Anchors (repeatable).")]
PlotOpt = Annotated[Path | None, typer.Option("--plot", help="Write the σ_u(t) horizon figure.")]
CompareAArg = Annotated[Path, typer.Argument(help="Target YAML file A (e.g. a LISA posterior).")]
CompareBArg = Annotated[Path, typer.Argument(help="Target YAML file B (e.g. a timing ephemeris).")]
AtOpt = Annotated[
    str | None,
    typer.Option(
        "--at",
        help='Epoch, "BJD_TDB …" or ISO TDB (default: midway between the two reference epochs).',
    ),
]
CompareFormatOpt = Annotated[
    str | None,
    typer.Option("--format", help="table | json (default: the -o suffix, else table)"),
]


_TABLE_FORMATS = ("table", "ecsv", "csv", "json")


def _check_format(fmt: str, allowed: tuple[str, ...]) -> str:
    fmt = fmt.lower()
    if fmt not in allowed:
        raise UcbplanError(f"--format {fmt!r}: expected one of {', '.join(allowed)}")
    return fmt


def _resolve_k_sigma(
    target: Target, sigma_v: float | None, k_eff: float | None
) -> tuple[float, float]:
    spec = target.spectroscopy
    sv = sigma_v if sigma_v is not None else (spec.sigma_v_kms if spec else None)
    k = k_eff if k_eff is not None else (spec.k_for_tolerance if spec else None)
    if sv is None:
        raise UcbplanError(
            f"{target.name}: no RV precision; pass --sigma-v KM_S or add spectroscopy.sigma_v "
            "to the target file"
        )
    if k is None:
        raise UcbplanError(
            f"{target.name}: no semi-amplitude; pass --k-eff KM_S or add spectroscopy.K1/K2 "
            "(or K_eff) to the target file"
        )
    check_number("--sigma-v", sv, 0.0, 1e4, "km/s")
    check_number("--k-eff", k, 0.1, 1e4, "km/s", "a binary's velocity semi-amplitude")
    if sv >= k:
        raise UcbplanError(
            f"--sigma-v ({sv:g} km/s) must be smaller than --k-eff ({k:g} km/s): with "
            "σ_v ≥ K no phase tolerance exists"
        )
    return sv, k


def validate(targets: TargetsArg, fmt: ValidateFormatOpt = "table") -> None:
    """Check target files and print a summary (period, e, ω, T_asc, σ's).

    For a timing ephemeris: T0, P, Ṗ with their σ, and σ_u one year before and after T0.
    """
    _check_format(fmt, ("table", "json"))
    summaries = [_summary(load_target(path)) for path in targets]
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


def _summary(t: Target) -> dict[str, Any]:
    """The validate row of one target: times as TDB ISO strings, the rest SI floats."""
    from astropy.time import TimeDelta

    if t.kind == "timing":
        return _timing_summary(t)
    from ucbplan.core.forecast import sigma_u_end
    from ucbplan.core.phase import ascending_node_s, sigma_ascending_node_s

    p = t.params
    t_asc = t.t_ref + TimeDelta(ascending_node_s(p), format="sec")
    sigmas = {n: float(math.sqrt(t.cov_matrix[i, i])) for i, n in enumerate(t.cov_names)}
    return {
        "name": t.name,
        "file": str(t.source.name) if t.source else "",
        "t_ref_tdb": t.t_ref.tdb.isot,
        "t_end_tdb": t.t_end.tdb.isot,
        "period_s": p.period_s,
        "period_asc_s": 2 / p.f_gw,
        "eccentricity": p.eccentricity,
        "omega_deg": math.degrees(p.omega_rad),
        "omega_dot_rad_s": p.omega_dot,
        "t_asc_tdb": t_asc.tdb.isot,
        "sigma_t_asc_s": sigma_ascending_node_s(p, t.covariance),
        "sigma_u_end_mrad": 1e3 * sigma_u_end(t, "quadrature"),
        "sigmas": sigmas,
    }


def _timing_summary(t: Target) -> dict[str, Any]:
    """The validate row of a timing ephemeris: T0, P, Ṗ (P̈) with σ, σ_u at ±1 yr."""
    from ucbplan.core.constants import YEAR_S
    from ucbplan.core.forecast import anchor_sigma_u
    from ucbplan.core.timescale import format_bjd_tdb

    assert t.timing is not None  # kind == "timing" guarantees the section
    sec, e, p = t.timing, t.timing.ephemeris, t.params
    tau = np.array([-YEAR_S, YEAR_S])
    sig = np.maximum(
        anchor_sigma_u(p, t.covariance, tau, 0.0), anchor_sigma_u(p, t.covariance, tau, math.pi)
    )
    rate = math.pi * (p.f_gw + p.fdot * tau + p.fddot * tau**2 / 2)
    sig_t = sig / np.abs(rate)
    return {
        "name": t.name,
        "file": str(t.source.name) if t.source else "",
        "kind": "timing",
        "t0_tdb": t.t_ref.tdb.isot,
        "t0_bjd_tdb": format_bjd_tdb(t.t_ref).split()[1],
        "sigma_t0_s": sec.sigma("t0"),
        "t0_marks": e.mark,
        "period_s": e.period_s,
        "sigma_period_s": sec.sigma("period"),
        "pdot": e.pdot,
        "sigma_pdot": sec.sigma("pdot"),
        "pddot_per_s": e.pddot,
        "sigma_pddot_per_s": sec.sigma("pddot"),
        "eccentricity": p.eccentricity,
        "omega_deg": math.degrees(p.omega_rad),
        "omega_dot_rad_s": p.omega_dot,
        "sigma_u_before_1yr_mrad": 1e3 * float(sig[0]),
        "sigma_u_after_1yr_mrad": 1e3 * float(sig[1]),
        "sigma_t_before_1yr_s": float(sig_t[0]),
        "sigma_t_after_1yr_s": float(sig_t[1]),
        "source": sec.source,
    }


def ephemeris(
    target: TargetArg,
    start: StartOpt,
    end: EndOpt,
    anchor: AnchorOpt = "quadrature",
    star: StarOpt = 1,
    fmt: TableFormatOpt = None,
    output: OutputOpt = None,
    overwrite: OverwriteOutputOpt = False,
    max_epochs: MaxEpochsOpt = 2_000_000,
) -> None:
    """Barycentric epochs t★ (TDB) where u = u★, with σ_t and the φ_ref π-mode alternative.

    A timing ephemeris has no π mode; its epochs carry the cycle number n of its polynomial.
    `--anchor eclipse` gives primary and secondary eclipses.
    """
    from ucbplan.core.ephemeris import find_epochs

    fmt = pick_format(output, fmt, _TABLE_FORMATS)
    if star not in (1, 2):
        raise UcbplanError(f"--star must be 1 or 2, got {star}")
    t = load_target(target)
    tau0, tau1 = _window(t, start, end, anchor, max_epochs)
    es = find_epochs(t, tau0, tau1, anchor, star)
    if t.kind == "timing":
        _warn_timing_horizon(t, tau0, tau1)
    elif tau1 > t.t_obs_s / 2:
        _warn_horizon(t, tau1)
    table = _epoch_table(t, es)
    if fmt == "table":
        _print_epochs(t, table)
        return
    _write_table(table, fmt, output, overwrite)


def _window(t: Target, start: str, end: str, anchor: str, max_epochs: int) -> tuple[float, float]:
    """--start/--end as TDB seconds since the target's t_ref; refuse empty or huge windows."""
    from ucbplan.core.timescale import parse_tdb

    t0 = parse_tdb(start, "--start")
    t1 = parse_tdb(end, "--end")
    tau0, tau1 = float(t.tau(t0)), float(t.tau(t1))
    if tau1 <= tau0:
        raise UcbplanError(
            f"--end ({shorten(end, 60)}) must be after --start ({shorten(start, 60)})"
        )
    expected = (tau1 - tau0) / t.period_s * (2 if anchor != "u" else 1)
    if expected > max_epochs:
        raise UcbplanError(
            f"window holds ~{expected:.3g} epochs (> --max-epochs {max_epochs}); shorten it"
        )
    return tau0, tau1


def _warn_horizon(t: Target, tau_end: float) -> None:
    """Warn when the window reaches past T_valid(quadrature, α = 1) of the target file's σ_v, K."""
    spec = t.spectroscopy
    if spec is None or spec.sigma_v_kms is None or spec.k_for_tolerance is None:
        return
    from ucbplan.core.forecast import horizon_s

    tv = horizon_s(t, spec.sigma_v_kms, spec.k_for_tolerance, "quadrature")
    if tau_end > t.t_obs_s / 2 + tv:
        err_console.print(
            f"[yellow]warning:[/] epochs after T_valid(quadrature, α=1) = {tv / DAY_S:.0f} d past "
            "the LISA observation have σ_u above the phase tolerance; check σ_t before "
            "scheduling them (see `ucbplan horizon`)"
        )


def _warn_timing_horizon(t: Target, tau0: float, tau1: float) -> None:
    """Warn when the window reaches past T_valid(quadrature, α = 1) before or after T0."""
    spec = t.spectroscopy
    if spec is None or spec.sigma_v_kms is None or spec.k_for_tolerance is None:
        return
    from ucbplan.core.forecast import tolerance, valid_window_s

    tol = tolerance("quadrature", spec.sigma_v_kms, spec.k_for_tolerance)
    lo, hi = valid_window_s(t, tol, (0.0, math.pi))
    for outside, side, span in ((tau0 < lo, "before", -lo), (tau1 > hi, "after", hi)):
        if outside:
            err_console.print(
                f"[yellow]warning:[/] epochs more than T_valid(quadrature, α=1) = "
                f"{span / DAY_S:.0f} d {side} T0 have σ_u above the phase tolerance; check σ_t "
                "before scheduling them (see `ucbplan horizon`)"
            )


def _epoch_table(t: Target, es: Any) -> Any:
    from astropy.table import Table
    from astropy.time import TimeDelta

    from ucbplan.core.ephemeris import eclipse_kind

    t_star = t.t_ref + TimeDelta(es.origin_s, format="sec") + TimeDelta(es.dt_s, format="sec")
    tab = Table()
    tab["k"] = es.k
    if t.kind == "timing":
        tab["cycle"] = _cycles(t, es)
    tab["anchor"] = [es.anchor] * len(es)
    if es.anchor == "eclipse":
        tab["eclipse"] = eclipse_kind(es.u_star_rad, es.star) if len(es) else []
    tab["u_star_rad"] = es.u_star_rad
    tab["t_star_tdb"] = _iso_us(t_star)
    if t.kind == "timing":
        from ucbplan.core.timescale import bjd_tdb_numbers

        tab["t_star_bjd_tdb"] = bjd_tdb_numbers(t_star)
    tab["tau_s"] = es.tau_s
    tab["sigma_t_s"] = es.sigma_t_s
    tab["sigma_u_rad"] = es.sigma_u_rad
    units = [("u_star_rad", "rad"), ("tau_s", "s"), ("sigma_t_s", "s"), ("sigma_u_rad", "rad")]
    if t.has_pi_mode:
        t_alt = t.t_ref + TimeDelta(es.tau_alt_s, format="sec")
        tab["t_alt_tdb"] = _iso_us(t_alt)
        tab["tau_alt_s"] = es.tau_alt_s
        units.append(("tau_alt_s", "s"))
    for col, unit in units:
        tab[col].unit = unit
    tab.meta.update(
        {
            "ucbplan_version": __version__,
            "target": t.name,
            "target_file": str(t.source) if t.source else "",
            "target_sha256": t.sha256 or "",
            "time_scale": "TDB at the solar-system barycentre",
            "t_ref_tdb": t.t_ref.tdb.isot,
            "tau_origin": "seconds since t_ref (TDB)",
            "phase_convention": (
                "u = Phi_GW/2 + eps_j + 2 kappa sin Phi_asc - 2 eta cos Phi_asc; "
                "eps_1=0, eps_2=pi; u=0 ascending node (max recession of star 1)"
            ),
            "star": es.star,
        }
    )
    if t.has_pi_mode:
        tab.meta["alt_epoch"] = "solution of the phi_ref + pi posterior mode (about P_b/4 earlier)"
    if t.kind == "timing" and t.timing is not None:
        from ucbplan.core.timescale import format_bjd_tdb

        tab.meta.update(
            {
                "ephemeris": "timing",
                "t0_bjd_tdb": format_bjd_tdb(t.t_ref).split()[1],
                "t0_marks": t.timing.ephemeris.mark,
                "cycle": "ephemeris cycle n of t(n) = T0 + P n + P Pdot n^2/2 (+ P^2 Pddot n^3/6)"
                " for star 1: (u_1 - u_1(T0))/2pi, half-integer at the other conjunction",
                "source": t.timing.source,
            }
        )
    return tab


def _cycles(t: Target, es: Any) -> Any:
    """Ephemeris cycle number n of each epoch: (u₁ − u₁(T0))/2π (u₁ = u★ − ε of the star)."""
    from ucbplan.core.phase import u_cycles

    m0, g0 = u_cycles(t.params, np.array([0.0]))
    eps = 0.0 if es.star == 1 else 0.5
    cycles = es.k + (es.u_star_rad / (2 * math.pi) - eps) - (m0[0] + g0[0])
    return np.round(cycles, 9)


def _iso_us(t: Any) -> list[str]:
    """TDB ISO strings with microseconds."""
    tdb = t.tdb
    tdb.precision = 6
    return [str(x) for x in np.atleast_1d(tdb.isot)]


def _print_epochs(t: Target, tab: Any) -> None:
    if not t.has_pi_mode:
        _print_timing_epochs(t, tab)
        return
    rt = rich_table(
        f"{t.name}: {len(tab)} epochs (barycentric TDB)",
        ["k", "u★ [rad]", "t★ (TDB)", "σ_t [s]", "π-mode alt. (TDB)"],
    )
    n = len(tab)
    rows = range(n) if n <= 60 else [*range(30), -1, *range(n - 30, n)]
    for i in rows:
        if i == -1:
            rt.add_row("…", "…", f"({n - 60} more; use -o or --format)", "…", "…")
            continue
        r = tab[i]
        rt.add_row(
            str(r["k"]),
            f"{r['u_star_rad']:.6f}",
            str(r["t_star_tdb"]),
            f"±{r['sigma_t_s']:.3f}",
            str(r["t_alt_tdb"]),
        )
    err_console.print(rt)


def _print_timing_epochs(t: Target, tab: Any) -> None:
    """The epochs of a timing ephemeris: cycle n, u★, t★ (TDB ISO and BJD_TDB), σ_t."""
    eclipse = "eclipse" in tab.colnames
    cols = ["n", *(["eclipse"] if eclipse else []), "u★ [rad]", "t★ (TDB)", "BJD_TDB", "σ_t [s]"]
    rt = rich_table(f"{t.name}: {len(tab)} epochs (barycentric TDB)", cols)
    n = len(tab)
    rows = range(n) if n <= 60 else [*range(30), -1, *range(n - 30, n)]
    for i in rows:
        if i == -1:
            rt.add_row(*(["…"] * (len(cols) - 1)), f"({n - 60} more; use -o or --format)")
            continue
        r = tab[i]
        rt.add_row(
            f"{r['cycle']:.12g}",
            *([str(r["eclipse"])] if eclipse else []),
            f"{r['u_star_rad']:.6f}",
            str(r["t_star_tdb"]),
            str(r["t_star_bjd_tdb"]),
            f"±{r['sigma_t_s']:.3f}",
        )
    err_console.print(rt)


def _write_table(tab: Any, fmt: str, output: Path | None, overwrite: bool) -> None:
    if fmt == "json":
        rows = [
            {
                c: (v.item() if hasattr(v, "item") else v)
                for c, v in zip(tab.colnames, row, strict=True)
            }
            for row in tab.iterrows()
        ]
        doc = {"meta": dict(tab.meta), "rows": rows}
        write_output(output, lambda h: dump_json(doc, h), overwrite=overwrite)
        return
    fmt_name = "ascii.ecsv" if fmt == "ecsv" else "ascii.csv"

    def _w(handle: IO[str]) -> None:
        tab.write(handle, format=fmt_name)

    write_output(output, _w, overwrite=overwrite)


def horizon(
    target: TargetArg,
    sigma_v: SigmaVOpt = None,
    k_eff: KEffOpt = None,
    alpha: AlphaOpt = [0.5, 1.0],  # noqa: B006 (typer reads the default, never mutates it)
    epochs: EpochsOpt = 2,
    anchor: AnchorsOpt = ["conjunction", "quadrature"],  # noqa: B006
    fmt: TableFormatOpt = None,
    output: OutputOpt = None,
    plot: PlotOpt = None,
    overwrite: OverwriteAllOpt = False,
) -> None:
    """Phase-coherence horizons T_valid (paper Tables 4 and 7) and σ_u at the end of LISA.

    For a timing ephemeris: T_valid before and after T0, separately.
    """
    from ucbplan.core.forecast import horizon_table

    fmt = pick_format(output, fmt, _TABLE_FORMATS)
    t = load_target(target)
    sv, k = _resolve_k_sigma(t, sigma_v, k_eff)
    for a in alpha:
        if not (a > 0 and math.isfinite(a)):
            raise UcbplanError(f"--alpha must be positive, got {a}")
    rows = horizon_table(t, sv, k, alphas=alpha, anchors=anchor, n_epochs=epochs)
    if plot is not None:
        from ucbplan.plotting.horizon import horizon_plot

        horizon_plot(t, rows, plot, overwrite=overwrite)
    if fmt == "table":
        _print_horizon(t, rows, sv, k, epochs)
    elif fmt == "json":
        doc = [r.as_dict() | {"target": t.name} for r in rows]
        write_output(output, lambda h: dump_json(doc, h), overwrite=overwrite)
    else:
        _write_table(_horizon_table(t, rows, sv, k, epochs), fmt, output, overwrite)


def _horizon_table(t: Target, rows: list[Any], sv: float, k: float, epochs: int) -> Any:
    """The horizon rows as an astropy table with the inputs in its metadata."""
    from astropy.table import Table

    tab = Table(rows=[r.as_dict() for r in rows])
    tab.meta.update({"target": t.name, "sigma_v_kms": sv, "k_eff_kms": k, "n_epochs": epochs})
    return tab


def _print_horizon(t: Target, rows: list[Any], sv: float, k: float, epochs: int) -> None:
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


def _print_two_sided_horizon(t: Target, rows: list[Any], sv: float, k: float, epochs: int) -> None:
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


# ---------------------------------------------------------------------------------------------
# ephemeris compare
# ---------------------------------------------------------------------------------------------


def compare(
    a: CompareAArg,
    b: CompareBArg,
    at: AtOpt = None,
    fmt: CompareFormatOpt = None,
    output: OutputOpt = None,
    overwrite: OverwriteOutputOpt = False,
) -> None:
    """Phase and time offset of two ephemerides of one system (A − B, star 1) at an epoch.

    With σ from both covariances, the significance, and the cycles from A's reference epoch to
    B's as each counts them (a whole-cycle disagreement the wrapped phase offset hides).
    """
    from ucbplan.core.timing import compare_sources

    fmt = pick_format(output, fmt, ("table", "json"))
    ta, tb = load_target(a), load_target(b)
    epoch = _epoch_option(at, "--at") if at is not None else None
    _warn_different_systems(ta, tb)
    report = compare_sources(ta, tb, epoch)
    doc = _comparison_doc(ta, tb, report)
    if fmt == "table":
        _print_comparison(doc)
        return
    write_output(output, lambda h: dump_json(doc, h), overwrite=overwrite)


def _epoch_option(text: str, what: str) -> Any:
    """An epoch option: ``"BJD_TDB …"`` (full precision) or ISO/MJD/JD TDB (:func:`parse_tdb`)."""
    from ucbplan.core.timescale import TIMING_EPOCH_WORDS, parse_tdb, parse_timing_epoch
    from ucbplan.errors import InputError

    word = text.strip().split(" ", 1)[0].upper().replace("-", "_")
    if word in TIMING_EPOCH_WORDS or word.startswith(("BJD", "BMJD", "HJD", "HMJD")):
        try:
            return parse_timing_epoch(text)
        except ValueError as exc:
            raise InputError(f"{what}: {exc}") from None
    return parse_tdb(text, what)


def _warn_different_systems(ta: Target, tb: Target) -> None:
    """Warn when the two files look like different binaries (sky position, period)."""
    sep = float(ta.coord.separation(tb.coord).arcsec)
    dp = abs(ta.period_s - tb.period_s) / ta.period_s
    if sep > 5.0 or dp > 1e-3:
        err_console.print(
            f"[yellow]warning:[/] {escape(ta.name)} and {escape(tb.name)} are {sep:.1f}″ apart "
            f"and their periods differ by {100 * dp:.3g} %: compare two ephemerides of one system"
        )


def _comparison_doc(ta: Target, tb: Target, report: Any) -> dict[str, Any]:
    """JSON-ready comparison: the two files, the epoch, the offset (and π-mode alternatives)."""
    from ucbplan.core.timescale import format_bjd_tdb

    def side(t: Target) -> dict[str, Any]:
        return {
            "name": t.name,
            "file": str(t.source) if t.source else "",
            "kind": t.kind,
            "t_ref_tdb": t.t_ref.tdb.isot,
        }

    r = report.result
    return {
        "a": side(ta),
        "b": side(tb),
        "epoch_tdb": report.epoch.tdb.isot,
        "epoch_bjd_tdb": format_bjd_tdb(report.epoch).split()[1],
        **r.offsets(),
        "cycles_a": r.cycles_a,
        "cycles_b": r.cycles_b,
        "cycle_count_difference": r.cycle_difference,
        "sigma_cycle_count_difference": r.sigma_cycle_difference,
        "whole_cycle_difference": round(r.cycle_difference),
        "pi_mode": [{"side": s, **c.offsets()} for s, c in report.alternatives],
        "convention": (
            "A - B for star 1: phase offset u1_A - u1_B at the epoch wrapped to (-pi, pi]; time "
            "offset t_A - t_B of the same orbital phase (negative: A predicts it earlier); "
            "cycles_a/cycles_b: orbits from A's reference epoch to B's as counted by A and by B; "
            "pi_mode: the same with that side's phi_ref + pi (LISA posteriors)"
        ),
    }


def _print_comparison(doc: dict[str, Any]) -> None:
    a, b = doc["a"], doc["b"]
    rt = rich_table(
        f"{a['name']} ({a['kind']}) − {b['name']} ({b['kind']}) at {doc['epoch_tdb']} TDB",
        ["quantity", "value"],
    )
    sig = doc["significance"]
    rows = [
        ("phase offset u₁,A − u₁,B [mrad]", f"{1e3 * doc['phase_offset_rad']:.3f}"),
        ("σ [mrad]", f"{1e3 * doc['sigma_phase_offset_rad']:.3f}"),
        ("time offset t_A − t_B [s]", f"{doc['time_offset_s']:.4f}"),
        ("σ [s]", f"{doc['sigma_time_offset_s']:.4f}"),
        ("significance [σ]", "∞ (no uncertainty)" if sig is None else f"{sig:.2f}"),
        ("cycles from A's epoch to B's, by A", f"{doc['cycles_a']:.6f}"),
        ("cycles from A's epoch to B's, by B", f"{doc['cycles_b']:.6f}"),
        (
            "cycle count difference",
            f"{doc['cycle_count_difference']:.6f} ± {doc['sigma_cycle_count_difference']:.6f}",
        ),
    ]
    for alt in doc["pi_mode"]:
        rows.append(
            (
                f"with {alt['side'].upper()}'s φ_ref + π: time offset [s]",
                f"{alt['time_offset_s']:.4f} ± {alt['sigma_time_offset_s']:.4f}",
            )
        )
    for label, value in rows:
        rt.add_row(escape(label), escape(value))
    err_console.print(rt)


# ---------------------------------------------------------------------------------------------
# the ephemeris group and registration
# ---------------------------------------------------------------------------------------------


class EphemerisGroup(typer.core.TyperGroup):
    """A command group whose first argument, when it is not a sub-command, goes to ``predict``.

    ``ucbplan ephemeris TARGET --start … --end …`` therefore keeps working exactly as before
    the group existed; ``ucbplan ephemeris predict TARGET …`` is the same command.
    """

    default_command = "predict"

    def parse_args(self, ctx: Any, args: list[str]) -> list[str]:
        """Route ``ephemeris ARGS`` to ``ephemeris predict ARGS`` unless ARGS names a command."""
        if args and args[0] not in self.commands and args[0] not in ctx.help_option_names:
            args = [self.default_command, *args]
        return super().parse_args(ctx, args)


ephemeris_app = typer.Typer(
    cls=EphemerisGroup,
    name="ephemeris",
    no_args_is_help=True,
    add_completion=False,
    help=(
        "Ephemeris predictions and checks. `ucbplan ephemeris TARGET --start … --end …` is "
        "`ucbplan ephemeris predict …` (epochs t★ where u = u★); `compare` offsets two "
        "ephemerides of one system."
    ),
)
ephemeris_app.command("predict")(ephemeris)
ephemeris_app.command("compare")(compare)


def register(app: typer.Typer) -> None:
    """Add the core commands to ``app``."""
    app.command("validate")(validate)
    # ------------------------------------------------------------------------------------
    # MOUNT POINT for `ucbplan ephemeris fit` (issue 10, item 3). The eclipse-time fit is a
    # separate command function in ucbplan.cli.timing; the lead mounts it here, e.g.
    #
    #     from ucbplan.cli import timing
    #     if "fit" not in {c.name for c in ephemeris_app.registered_commands}:
    #         ephemeris_app.command("fit")(timing.fit)
    #
    # (any name other than `predict`/`compare` works: EphemerisGroup routes only arguments
    # that are not sub-command names to `predict`).
    # ------------------------------------------------------------------------------------
    app.add_typer(ephemeris_app, name="ephemeris")
    app.command("horizon")(horizon)
