"""What ``ucbplan plan`` prints: the night tables (100 columns, or all with --wide), the per-night
summary of long plans, visits, time accounting and the reasons anchors were not planned."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

from rich.markup import escape

from ucbplan.api import terminal
from ucbplan.cli._console import alert, err_console, rich_table
from ucbplan.cli._flags import cli_text
from ucbplan.errors import UcbplanError

if TYPE_CHECKING:
    from rich.table import Table as RichTable

    from ucbplan.api.plan_result import PlanAccount, VisitSummary


def _local(blocks: list[Any]) -> list[str]:
    """Local civil time of each block centre, ``HH:MM:SS TZ`` (one conversion for the night)."""
    times = terminal.local_datetimes([b.t_mid_utc for b in blocks], [b.timezone for b in blocks])
    return [dt.strftime("%H:%M:%S %Z") for dt in times]


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

    def make() -> RichTable:
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
        return table

    rows = [
        (
            *([escape(b.target[:12])] if len(names) > 1 else []),
            label,
            f"{b.t_start_utc.iso[:19]}–{b.t_end_utc.iso[11:19]}",
            f"{b.u_star_rad:.4f}",
            f"{b.airmass:.2f}",
            f"{b.lambda_k:.3f}",
            f"{b.sigma_t_s:.2f}",
        )
        for b, label in zip(blocks, _exposure_labels(blocks), strict=True)
    ]
    err_console.print_table(make, rows)


def _print_summary(run: Any) -> None:
    """One row per night: visits, exposures and hours (a long plan, without --verbose)."""
    visits = run.visit_columns  # one list per field: no object per visit
    by_night: dict[str, list[int]] = {}
    for k, night in enumerate(visits.night):
        by_night.setdefault(night, []).append(k)
    exposures, walls = visits.exposures, visits.wall_s()
    rows = []
    for night in (d.isoformat() for d in run.nights):  # nights without a visit too
        ks = by_night.get(night, [])
        rows.append(
            (
                night,
                str(len(ks)),
                str(sum(exposures[k] for k in ks)),
                f"{sum(walls[k] for k in ks) / 3600:.2f}",
            )
        )
    title = f"Plan at {run.site.name}, per night (the full table: -o FILE or --verbose)"
    err_console.print_table(
        lambda: rich_table(title, ["night", "visits", "exposures", "hours (wall)"]), rows
    )


#: A plan longer than this many nights or rows prints the per-night summary (issue 15).
SUMMARY_NIGHTS, SUMMARY_ROWS = 3, 60


def _print_night(blocks: list[Any], night: str, site: Any) -> None:
    paired = any(b.pair_id for b in blocks)
    # the φ_ref π-mode exists only for LISA posteriors; a night of timing targets has none
    pi_mode = any(b.t_alt_utc is not None for b in blocks)
    title = (
        f"Night of {night} at {site.name} — times are UTC at the site (light time removed); "
        "±σ is the 1σ timing uncertainty"
    )
    columns = [
        "target",
        "block",
        "visit/exp",
        "anchor",
        "u★ [rad]",
        "UTC mid ± σ",
        "local mid",
        "UTC start–end",
        "airmass s/m/e",
        "Moon [deg]",
        "Λ_K",
        "σ_v [km/s]",
        *(["π-mode alt. UTC"] if pi_mode else []),
        *(["pair: Δκ_LISA"] if paired else []),
    ]
    rows = [
        (
            escape(b.target),
            escape(b.block_id.rsplit("-", 1)[-1]),
            label,
            escape(b.anchor),
            f"{b.u_star_rad:.4f}",
            f"{b.t_mid_utc.iso[11:23]} ± {b.sigma_t_s:.2f} s",
            local,
            f"{b.t_start_utc.iso[:19]}–{b.t_end_utc.iso[11:19]}",
            f"{b.airmass_start:.2f}/{b.airmass:.2f}/{b.airmass_end:.2f}",
            f"{b.moon_sep_deg:.0f}",
            f"{b.lambda_k:.4f}",
            f"{b.sigma_v_kms:.2f}",
            *([b.t_alt_utc.iso[11:21] if b.t_alt_utc is not None else "—"] if pi_mode else []),
            *([f"{escape(b.pair_id)}: {b.delta_kappa:+.2e}"] if paired else []),
        )
        for b, label, local in zip(blocks, _exposure_labels(blocks), _local(blocks), strict=True)
    ]
    err_console.print_table(lambda: rich_table(title, columns), rows)


def report(run: Any, wide: bool = False, verbose: bool = False) -> None:
    """Warnings and what was not placed (grouped over nights), then one table per night."""
    for t in run.targets:
        if t.covariance_source.startswith("samples"):
            err_console.print(f"{t.name}: covariance from the {t.covariance_source}", markup=False)
    err_console.print_messages([alert("warning", cli_text(w)) for w in run.result.warnings])
    failure = run.failure()
    if failure is not None:  # the error line says what was not placed, once
        raise UcbplanError(failure)
    grouped: dict[tuple[str, str], list[str]] = {}
    for miss in run.result.unplaced:
        grouped.setdefault((miss.target, miss.reason), []).append(miss.night)
    lines = []
    for (name, reason), when in grouped.items():
        span = when[0] if len(when) == 1 else f"{len(when)} nights {when[0]}..{when[-1]}"
        text, markup = f"{name} ({span}): {reason}", f"{escape(name)} ({span}): {escape(reason)}"
        lines.append(alert("not placed", text, markup))
    err_console.print_messages(lines)
    blocks = run.result.blocks
    labels = terminal.block_columns(blocks).values["night"]
    if not verbose and (len(set(labels.tolist())) > SUMMARY_NIGHTS or len(blocks) > SUMMARY_ROWS):
        _print_summary(run)
    else:
        nights: dict[str, list[Any]] = {}
        for b in blocks:
            nights.setdefault(b.night, []).append(b)
        show = _print_night if wide else _print_compact
        for label, night_blocks in nights.items():
            show(night_blocks, label, run.site)
    _print_accounting(run, verbose)


def _print_reasons(run: Any) -> None:
    """Night-time anchor epochs not planned, by reason, summed over the nights (one line per
    target; per night in the table meta ``not_planned``)."""
    lines = []
    for name, nights in run.result.reasons.items():
        total: dict[str, int] = {}
        for counts in nights.values():
            for why, k in counts.items():
                total[why] = total.get(why, 0) + k
        if not total:
            continue
        span = f"{len(nights)} night{'s' if len(nights) > 1 else ''}"
        parts = ", ".join(f"{k} {why}" for why, k in total.items())
        lines.append(f"night-time anchors not planned: {escape(name)} ({span}): {escape(parts)}")
    err_console.print_messages(lines)


def _hours(seconds: float) -> str:
    return f"{seconds / 3600:.2f} h"


def _print_accounting(run: Any, verbose: bool = False) -> None:
    """Visits (with --visit) and the time accounting, per target and in total; then the
    strategies, the anchors not planned and the goals."""
    if run.settings.visit_s is not None and (verbose or len(run.visit_columns) <= SUMMARY_ROWS):
        _print_visits(run.visits())
    account: PlanAccount = run.time_account
    accounts = [
        *account.targets.items(),
        *([("total", account.total)] if len(account.targets) > 1 else []),
    ]
    rows = []
    for name, a in accounts:
        e = a.as_meta()  # the figures as the table meta records them (1 ms; efficiency 1e-6)
        rows.append(
            (
                escape(name),
                str(a.visits),
                str(a.exposures),
                _hours(e["shutter_s"]),
                _hours(e["overhead_s"]),
                _hours(e["idle_s"]),
                f"{e['efficiency']:.1%}",
            )
        )
    title = "Time accounting — efficiency = shutter / (shutter + overheads + idle)"
    columns = ["target", "visits", "exposures", "shutter", "overheads", "idle", "efficiency"]
    err_console.print_table(lambda: rich_table(title, columns), rows)
    _print_strategies(run)
    _print_reasons(run)
    _print_goals(run, account)


def _print_visits(visits: list[VisitSummary]) -> None:
    """One row per visit: its acquisition start and last end (UTC at the site), exposures, idle."""

    def make() -> RichTable:
        table = rich_table(
            "Visits — one acquisition, then exposures centred on anchors (UTC at the site)",
            ["visit", "target", "acq. start UTC", "last end UTC", "exp.", "idle [s]"],
        )
        for i, column in enumerate(table.columns):
            column.no_wrap = i != 1  # a long target name wraps; times are never cut
        return table

    rows = [
        (
            escape("-".join(v.visit_id.rsplit("-", 2)[-2:])),
            escape(v.target),
            v.acq_start_utc[:19].replace("T", " "),  # its UTC date: the night label is local
            v.end_utc[11:19],
            str(v.exposures),
            f"{v.idle_s:.0f}",
        )
        for v in visits
    ]
    err_console.print_table(make, rows)


def _print_goals(run: Any, account: PlanAccount) -> None:
    """Per goal: the spectra planned, at which phases, the visits and hours they take, and the
    σ the goal plan expects."""
    if not run.result.goals:
        return
    targets, u_stars, n_exps = terminal.block_columns(run.result.blocks).lists(
        "target", "u_star_rad", "n_exp"
    )
    _print_sigma_v_ratio(run)
    for name, goal in run.result.goals.items():
        if goal.collected_spectra:
            _print_collected(name, goal)
        if goal.collected_spectra and not goal.n_spectra:
            continue
        at: dict[float, int] = {}
        for target, u_star, n_exp in zip(targets, u_stars, n_exps, strict=True):
            if target == name:
                at[round(u_star, 4)] = at.get(round(u_star, 4), 0) + n_exp
        split = ", ".join(f"{k} at u★ = {u:.4f}" for u, k in sorted(at.items()))
        if len(at) > 4:
            split = "untargeted phases"
        spent = account.targets.get(name)
        recorded = spent.as_meta() if spent is not None else {}  # as the table meta records it
        wall = sum(recorded.get(k, 0.0) for k in ("shutter_s", "overhead_s", "idle_s"))
        err_console.print(
            f"goal {escape(goal.goal.describe())}: {escape(name)}: {sum(at.values())} spectra "
            f"in {recorded.get('visits', 0)} visit(s), {_hours(wall)} "
            f"({split}), expected {escape(_expected(goal))}",
            soft_wrap=True,
        )


def _print_collected(name: str, goal: Any) -> None:
    """What the spectra already taken give a goal's target, and what is still needed (or, in
    one line, that they reach the goal)."""
    head = f"goal {escape(goal.goal.describe())}: {escape(name)}:"
    taken = f"{goal.collected_spectra} spectra taken"
    got = "no σ_K alone (γ and K not separated)"  # one anchor: they count with the plan's
    if goal.collected_info > 0:
        got = f"σ_K = {goal.collected_info**-0.5:.3g} km/s"
    if not goal.n_spectra:
        err_console.print(
            f"{head} already reached by the {taken} ({got}, expected "
            f"{escape(_expected(goal))}): no visits planned",
            soft_wrap=True,
        )
        return
    err_console.print(
        f"{head} collected so far {got} from the {taken}; still needed "
        f"{goal.info_needed:.4g} (km/s)^-2 of information on K (σ_K = "
        f"{goal.info_needed**-0.5:.3g} km/s alone); the plan below adds it",
        soft_wrap=True,
    )


def _print_sigma_v_ratio(run: Any) -> None:
    """One line: the measured σ_v of the spectra taken against the law's, and the factor the
    remainder is planned with."""
    note = terminal.sigma_v_note(run.settings)
    if note is not None:
        err_console.print(f"observed: {escape(cli_text(note))}", soft_wrap=True)


def _print_strategies(run: Any) -> None:
    """Per target whose exposure time was chosen: every strategy's best exposure time and the
    information on K it buys per visit, the chosen one marked, and what the plan collects."""
    chosen = {n: te for n, te in run.result.exposures.items() if te.results}
    if not chosen:
        return
    goal = any(te.goal_hours for te in chosen.values())
    last = "hours to goal" if goal else "of best"
    rows = []
    for name, te in chosen.items():
        top = max((r.info_per_visit for r in te.results), default=0.0)
        hours = te.goal_hours or (math.nan,) * len(te.results)
        for r, h in zip(te.results, hours, strict=True):
            mark = "*" if r.name == te.strategy else ""
            share = f"{r.info_per_visit / top:.0%}" if top > 0 and r.possible else "-"
            rows.append(
                (
                    escape(name),
                    f"{r.name}{mark}",
                    f"{r.exptime_s:.0f}" if r.possible else "-",
                    f"{r.lambda_k:.3f}" if r.possible else "-",
                    str(r.n_exposures) if r.possible else "-",
                    f"{r.info_per_visit:.4g}" if r.possible else "-",
                    (f"{h:.2f} h" if math.isfinite(h) else "-") if goal else share,
                )
            )
    title = "Exposure strategy — information on K per full visit, * = planned"
    columns = ["target", "strategy", "exp. [s]", "Λ_K", "exp./visit", "info [km⁻²s²]", last]
    err_console.print_table(lambda: rich_table(title, columns), rows)
    for name, te in chosen.items():
        for r in te.results:
            if not r.possible and r.note:
                err_console.print(f"{escape(name)}: {r.name}: {escape(r.note)}", soft_wrap=True)
    for name, info in run.collected_info().items():
        if name in chosen and info > 0:
            err_console.print(
                f"{escape(name)}: the planned spectra collect {info:.4g} (km/s)^-2 of information "
                f"on K (σ_K ≥ {info**-0.5:.3g} km/s)",
                soft_wrap=True,
            )


def _expected(goal: Any) -> str:
    """The σ a goal plan reaches, in the goal's unit."""
    if goal.goal.relative:
        return f"{100 * goal.expected:.3g} %"
    unit = {"q": "", "M1": " Msun", "M2": " Msun"}.get(goal.goal.quantity, " km/s")
    return f"{goal.expected:.3g}{unit}"
