"""``ucbplan ephemeris``: predict epochs, compare two ephemerides, fit eclipse times.

``ephemeris`` is a command group whose default sub-command is ``predict``:
``ucbplan ephemeris TARGET --start … --end …`` is ``ucbplan ephemeris predict TARGET …``
(:class:`EphemerisGroup`, over :func:`ucbplan.api.ephemeris.predict`); ``compare A B`` offsets
two ephemerides of one system (:func:`ucbplan.api.ephemeris.compare_ephemerides`); ``fit TIMES``
fits T0, P, Ṗ to eclipse times (:mod:`ucbplan.cli.timing` over
:func:`ucbplan.api.timing.fit_ephemeris`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import typer
import typer.core
from rich.markup import escape

from ucbplan.api.ephemeris import COMPARE_FLAGS, EPHEMERIS_FLAGS, compare_ephemerides, predict
from ucbplan.api.ephemeris import ephemeris as _epochs  # its signature declares the defaults
from ucbplan.cli._console import (
    TABLE_FORMATS,
    dump_json,
    err_console,
    pick_format,
    rich_table,
    write_output,
    write_table_output,
)
from ucbplan.cli._derive import argument, option
from ucbplan.cli._flags import cli_text
from ucbplan.cli._options import (
    CompareFormatOpt,
    OutputOpt,
    OverwriteOutputOpt,
    TableFormatOpt,
    TargetArg,
)
from ucbplan.cli.timing import ephemeris_fit


def _required(parameter: str) -> Any:
    """A required option (no default) with the flag and help :data:`EPHEMERIS_FLAGS` declares."""
    spec = EPHEMERIS_FLAGS[parameter]
    return typer.Option(..., *spec.decls, help=spec.help)


def ephemeris(
    target: TargetArg,
    start: str = _required("start"),
    end: str = _required("end"),
    anchor: str = option(_epochs, EPHEMERIS_FLAGS, "anchor"),
    star: int = option(_epochs, EPHEMERIS_FLAGS, "star"),
    fmt: TableFormatOpt = None,
    output: OutputOpt = None,
    overwrite: OverwriteOutputOpt = False,
    max_epochs: int = option(_epochs, EPHEMERIS_FLAGS, "max_epochs"),
) -> None:
    """Barycentric epochs t★ (TDB) where u = u★, with σ_t and the φ_ref π-mode alternative.

    A timing ephemeris has no π mode; its epochs carry the cycle number n of its polynomial.
    `--anchor eclipse` gives primary and secondary eclipses.
    """
    fmt = pick_format(output, fmt, TABLE_FORMATS)
    got = predict(target, start, end, anchor, star, max_epochs)
    for line in got.warnings:
        err_console.print(f"[yellow]warning:[/] {escape(cli_text(line))}")
    if fmt == "table":
        _print_epochs(got.target, got.table)
        return
    write_table_output(got.table, fmt, output, overwrite)


def _print_epochs(t: Any, tab: Any) -> None:
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


def _print_timing_epochs(t: Any, tab: Any) -> None:
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
    a: Path = argument(COMPARE_FLAGS, "a"),
    b: Path = argument(COMPARE_FLAGS, "b"),
    at: str | None = option(compare_ephemerides, COMPARE_FLAGS, "at"),
    fmt: CompareFormatOpt = None,
    output: OutputOpt = None,
    overwrite: OverwriteOutputOpt = False,
) -> None:
    """Phase and time offset of two ephemerides of one system (A − B, star 1) at an epoch.

    With σ from both covariances, the significance, and the cycles from A's reference epoch to
    B's as each counts them (a whole-cycle disagreement the wrapped phase offset hides).
    """
    fmt = pick_format(output, fmt, ("table", "json"))
    got = compare_ephemerides(a, b, at)
    for line in got.warnings:
        err_console.print(f"[yellow]warning:[/] {escape(cli_text(line))}")
    if fmt == "table":
        _print_comparison(got.doc)
        return
    write_output(output, lambda h: dump_json(got.doc, h), overwrite=overwrite)


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
