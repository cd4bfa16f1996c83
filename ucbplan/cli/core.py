"""Core commands: ``validate`` and ``horizon`` (thin shells over the library).

Each command parses its options, calls :mod:`ucbplan.core` (:func:`~ucbplan.core.forecast.
horizon_table`, the validate summary numbers) and prints or writes the result. The option types
are module-level aliases so each command reads as its parameter list; :mod:`ucbplan.cli.ephemeris`
shares them.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer
import typer.core
from rich.markup import escape

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
from ucbplan.cli._options import (
    AlphaOpt,
    AnchorsOpt,
    EpochsOpt,
    KEffOpt,
    OutputOpt,
    OverwriteAllOpt,
    PlotOpt,
    SigmaVOpt,
    TableFormatOpt,
    TargetsArg,
    ValidateFormatOpt,
)
from ucbplan.cli.ephemeris import register as register_ephemeris
from ucbplan.errors import UcbplanError

if TYPE_CHECKING:
    from ucbplan.target import Target

# numpy, ucbplan.target (astropy) and ucbplan.inputs (yaml) are imported inside the commands:
# `ucbplan --help` must not pay for them (benchmarks/startup.py).

__all__ = ["horizon", "register", "validate"]


def _resolve_k_sigma(
    target: Target, sigma_v: float | None, k_eff: float | None
) -> tuple[float, float]:
    """σ_v and K from the options, else the target file (:func:`ucbplan.api.ephemeris.
    resolve_k_sigma`; its errors name sigma_v / k_eff, printed as --sigma-v / --k-eff)."""
    from ucbplan.api.ephemeris import resolve_k_sigma

    return resolve_k_sigma(target, sigma_v, k_eff)


def validate(targets: TargetsArg, fmt: ValidateFormatOpt = "table") -> None:
    """Check target files and print a summary (period, e, ω, T_asc, σ's).

    For a timing ephemeris: T0, P, Ṗ with their σ, and σ_u one year before and after T0.
    """
    from ucbplan.target import load_target

    fmt = pick_format(None, fmt, ("table", "json"))
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
    if t.samples_covariance is not None and t.covariance_source.startswith("samples"):
        sigmas |= _samples_sigmas(t.covariance)
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
        "covariance_from": t.covariance_source,
    }


def _samples_sigmas(cov: Any) -> dict[str, float]:
    """σ of each sampled phase-model parameter from the samples' covariance (SI)."""
    from ucbplan.core.params import PARAM_NAMES

    return {n: float(math.sqrt(cov[k, k])) for k, n in enumerate(PARAM_NAMES) if cov[k, k] > 0}


def _timing_summary(t: Target) -> dict[str, Any]:
    """The validate row of a timing ephemeris: T0, P, Ṗ (P̈) with σ, σ_u at ±1 yr."""
    import numpy as np

    from ucbplan.core.constants import YEAR_S
    from ucbplan.core.forecast import anchor_sigma_u
    from ucbplan.core.timing_epochs import format_bjd_tdb

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


def _expand_targets(names: list[str]) -> list[Path | str]:
    """Files as given (text: the reader makes the path, ~2 µs each); a directory contributes its
    *.yaml and *.yml files, sorted."""
    import os

    out: list[Path | str] = []
    for name in names:
        if os.path.isdir(name or "."):  # Path("") is ".", as before
            path = Path(name)
            found = sorted([*path.glob("*.yaml"), *path.glob("*.yml")])
            if not found:
                raise UcbplanError(f"{path}: no *.yaml target files in this directory")
            out.extend(found)
        else:
            out.append(name)
    return out


def horizon(
    target: HorizonTargetsArg,
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

    For a timing ephemeris: T_valid before and after T0, separately. Several targets (files,
    folders or a catalog) give one table, a row per target × anchor × α, computed in one
    vectorised pass.
    """
    fmt = pick_format(output, fmt, TABLE_FORMATS)
    from ucbplan.inputs import check_alpha
    from ucbplan.target import check_distinct_files, load_target_files

    for a in alpha:
        check_alpha(a)
    paths = _expand_targets(target)
    check_distinct_files(paths)  # one rule for a repeated target (as plan)
    if plot is not None:
        from ucbplan.plotting import check_figure_path

        check_figure_path(plot, overwrite)
        if output is not None:
            check_output_path(output, overwrite)
    targets = load_target_files(paths)
    if len(targets) > 1:
        if plot is not None:
            raise UcbplanError("--plot takes one target; give a single target file")
        _horizon_many(targets, sigma_v, k_eff, alpha, epochs, anchor, fmt, output, overwrite)
        return
    from ucbplan.core.forecast import horizon_table

    t = targets[0]
    sv, k = _resolve_k_sigma(t, sigma_v, k_eff)
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
        write_table_output(_horizon_table(t, rows, sv, k, epochs), fmt, output, overwrite)


#: Above this many targets the terminal gets a summary instead of the full table.
_MANY_ROWS = 40


def _horizon_many(
    targets: list[Target],
    sigma_v: float | None,
    k_eff: float | None,
    alpha: list[float],
    epochs: int,
    anchor: list[str],
    fmt: str,
    output: Path | None,
    overwrite: bool,
) -> None:
    """The long horizon table of many targets (:func:`ucbplan.core.horizon_batch.horizons`)."""
    from ucbplan.core.horizon_batch import horizon_json, horizons

    _check_k_sigma(targets, sigma_v, k_eff)
    tab = horizons(targets, sigma_v, k_eff, alphas=alpha, anchors=anchor, n_epochs=epochs)
    if fmt == "json":
        text = horizon_json(tab)

        def write(handle: Any) -> None:
            handle.write(text)

        write_output(output, write, overwrite=overwrite)
    elif fmt != "table":
        write_table_output(tab, fmt, output, overwrite)
    else:
        _print_many(tab)


def _check_k_sigma(targets: list[Target], sigma_v: float | None, k_eff: float | None) -> None:
    """:func:`_resolve_k_sigma` of every target (one-line errors naming the option; the library
    names its parameter), once per distinct (σ_v, K) a target would use, on which alone its
    outcome depends, and only where a plain float pair is not plainly in range: the first
    target that fails is still the one named."""
    pairs: dict[tuple[Any, Any], Target] = {}
    for t in targets:
        spec = t.spectroscopy
        sv = sigma_v if sigma_v is not None else (spec.sigma_v_kms if spec else None)
        k = k_eff if k_eff is not None else (spec.k_for_tolerance if spec else None)
        pairs.setdefault((sv, k), t)
    for (sv, k), t in pairs.items():
        plain = type(sv) is float and type(k) is float
        if not (plain and 0.0 < sv <= 1e4 and 0.1 < k <= 1e4 and sv < k):
            _resolve_k_sigma(t, sigma_v, k_eff)


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
    _say_samples_covariance(t)


def _say_samples_covariance(t: Target) -> None:
    """One line when the covariance came from a samples file (issue 26: say which was used)."""
    if t.covariance_source.startswith("samples"):
        err_console.print(f"{t.name}: covariance from the {t.covariance_source}", markup=False)


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


def register(app: typer.Typer) -> None:
    """Add the core commands to ``app``."""
    app.command("validate")(validate)
    register_ephemeris(app)
    app.command("horizon")(horizon)
