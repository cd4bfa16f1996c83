"""``ucbplan ephemeris``: predict epochs, compare two ephemerides, fit eclipse times.

``ephemeris`` is a command group whose default sub-command is ``predict``:
``ucbplan ephemeris TARGET --start … --end …`` is ``ucbplan ephemeris predict TARGET …``
(:class:`EphemerisGroup`); ``compare A B`` offsets two ephemerides of one system
(:func:`ucbplan.core.timing.compare_sources`); ``fit TIMES`` fits T0, P, Ṗ to eclipse times
(:mod:`ucbplan.cli.timing` over :mod:`ucbplan.timing`).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import typer
import typer.core
from rich.markup import escape

from ucbplan import __version__
from ucbplan.cli._console import (
    TABLE_FORMATS,
    dump_json,
    err_console,
    pick_format,
    rich_table,
    write_output,
    write_table_output,
)
from ucbplan.cli._epochs import epoch_option
from ucbplan.cli._options import (
    AnchorOpt,
    AtOpt,
    CompareAArg,
    CompareBArg,
    CompareFormatOpt,
    EndOpt,
    MaxEpochsOpt,
    OutputOpt,
    OverwriteOutputOpt,
    StarOpt,
    StartOpt,
    TableFormatOpt,
    TargetArg,
)
from ucbplan.cli.timing import ephemeris_fit
from ucbplan.core.constants import DAY_S
from ucbplan.errors import UcbplanError, shorten

if TYPE_CHECKING:  # ucbplan.target pulls in astropy: imported inside the commands
    from ucbplan.target import Target

__all__ = ["EphemerisGroup", "ephemeris_app", "register"]


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

    fmt = pick_format(output, fmt, TABLE_FORMATS)
    if star not in (1, 2):
        raise UcbplanError(f"--star must be 1 or 2, got {star}")
    from ucbplan.target import load_target

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
    write_table_output(table, fmt, output, overwrite)


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
    import numpy as np

    from ucbplan.core.phase import u_cycles

    m0, g0 = u_cycles(t.params, np.array([0.0]))
    eps = 0.0 if es.star == 1 else 0.5
    cycles = es.k + (es.u_star_rad / (2 * math.pi) - eps) - (m0[0] + g0[0])
    return np.round(cycles, 9)


def _iso_us(t: Any) -> list[str]:
    """TDB ISO strings with microseconds."""
    import numpy as np

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
    from ucbplan.target import load_target

    ta, tb = load_target(a), load_target(b)
    epoch = epoch_option(at, "--at") if at is not None else None
    _warn_different_systems(ta, tb)
    report = compare_sources(ta, tb, epoch)
    doc = _comparison_doc(ta, tb, report)
    if fmt == "table":
        _print_comparison(doc)
        return
    write_output(output, lambda h: dump_json(doc, h), overwrite=overwrite)


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
ephemeris_app.command("fit")(ephemeris_fit)


def register(app: typer.Typer) -> None:
    """Add the ``ephemeris`` group (predict, compare, fit) to ``app``."""
    app.add_typer(ephemeris_app, name="ephemeris")
