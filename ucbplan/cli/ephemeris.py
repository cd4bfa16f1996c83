"""``ucbplan ephemeris``: predict epochs, compare two ephemerides, fit eclipse times.

``ephemeris`` is a command group whose default sub-command is ``predict``:
``ucbplan ephemeris TARGET --start … --end …`` is ``ucbplan ephemeris predict TARGET …``
(:class:`EphemerisGroup`); ``compare A B`` offsets two ephemerides of one system
(:func:`ucbplan.core.timing.compare_sources`); ``fit TIMES`` fits T0, P, Ṗ to eclipse times
(:mod:`ucbplan.cli.timing` over :mod:`ucbplan.timing`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import typer
import typer.core
from rich.markup import escape

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
from ucbplan.errors import UcbplanError

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
    from ucbplan.api.ephemeris import epoch_table, epoch_window, horizon_warnings
    from ucbplan.core.ephemeris import find_epochs

    fmt = pick_format(output, fmt, TABLE_FORMATS)
    if star not in (1, 2):
        raise UcbplanError(f"--star must be 1 or 2, got {star}")
    from ucbplan.target import load_target

    t = load_target(target)
    tau0, tau1 = epoch_window(t, start, end, anchor, max_epochs)
    es = find_epochs(t, tau0, tau1, anchor, star)
    for line in horizon_warnings(t, tau0, tau1):
        err_console.print(f"[yellow]warning:[/] {escape(line)}")
    table = epoch_table(t, es)
    if fmt == "table":
        _print_epochs(t, table)
        return
    write_table_output(table, fmt, output, overwrite)


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
    from ucbplan.core.timing_epochs import format_bjd_tdb

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

    ``ucbplan ephemeris TARGET --start … --end …`` and ``ucbplan ephemeris predict TARGET …``
    are therefore the same command.
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
