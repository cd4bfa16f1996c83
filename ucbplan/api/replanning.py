"""``ucbplan.replan``: the nights of an existing plan planned again from an instant on (issue 32).

A plan records in its meta the options :func:`ucbplan.plan` was called with (``plan_options``),
its site, nights and target files with their sha256. :func:`replan` reads them back, keeps the
blocks of the nights before ``from_`` as they were (history), counts the spectra taken (an
``observed`` file, else the history's rows, those of lost nights missed), leaves the lost nights
out and plans the remaining nights with the plan's own settings and goals.
"""

from __future__ import annotations

import hashlib
import inspect
import math
from collections.abc import Sequence
from dataclasses import dataclass
from datetime import date, datetime, timedelta
from pathlib import Path
from typing import TYPE_CHECKING, Any
from zoneinfo import ZoneInfo

from ucbplan.api._convert import scope
from ucbplan.api.flagspec import Flag
from ucbplan.api.plan_result import Plan
from ucbplan.errors import InputError, InputFileError, shorten

if TYPE_CHECKING:
    from astropy.table import Table

#: How ``ucbplan replan`` spells :func:`replan`'s parameters (declared once).
REPLAN_FLAGS: dict[str, Flag] = {
    "plan": Flag((), "Plan to re-plan: an ECSV blocks table written by `ucbplan plan -o`."),
    "from_": Flag(
        ("--from",),
        "Re-plan from this instant on (ISO UTC): the nights before it are kept as they were.",
    ),
    "observed": Flag(
        ("--observed",),
        "Spectra already taken: a velocities file, or the plan with a status column "
        "(taken, missed, skipped). Default: the kept rows, those of lost nights missed.",
    ),
    "lost": Flag(
        ("--lost",),
        "A night of the plan lost (local date of its evening, YYYY-MM-DD); repeatable.",
    ),
}


@dataclass(frozen=True)
class PlanChanges:
    """What a replan changed, visit by visit (a visit is known by its ``visit_id``).

    Attributes
    ----------
    kept, moved, added, dropped : list of str
        Visit ids planned at the same start; at another start; only in the new plan; only in
        the old one (from ``from_`` on).
    """

    kept: list[str]
    moved: list[str]
    added: list[str]
    dropped: list[str]

    def line(self) -> str:
        """One line: the counts."""
        return (
            f"replan: {len(self.kept)} visit(s) kept, {len(self.moved)} moved, "
            f"{len(self.added)} added, {len(self.dropped)} dropped"
        )


def _visits(table: Table, nights: set[str] | None) -> dict[str, tuple[str, list[str]]]:
    """visit_id → (its target, the UTC starts of its blocks), over the rows of ``nights``
    (None: all)."""
    visits: dict[str, tuple[str, list[str]]] = {}
    for row in table:
        if nights is None or str(row["night"]) in nights:
            entry = visits.setdefault(str(row["visit_id"]), (str(row["target"]), []))
            entry[1].append(str(row["t_start_utc"]))
    return visits


def _visit_starts(table: Table, nights: set[str] | None = None) -> dict[str, str]:
    """visit_id → its first block start (UTC text), over the rows of ``nights`` (None: all)."""
    return {vid: min(starts) for vid, (_, starts) in _visits(table, nights).items()}


def plan_changes(old: Plan, new: Plan) -> PlanChanges:
    """The visits of ``old`` on the nights ``new`` did not keep as history (lost nights
    included), compared with ``new``'s."""
    kept = set() if new.history is None else {str(n) for n in new.history["night"]}
    first = min(str(n) for n in new.meta.get("nights", []))
    planned = {
        str(n)
        for n in old.meta.get("nights", [])
        if str(n) not in kept and (new.history is not None or str(n) >= first)
    }
    before = _visit_starts(old.text_table, planned)
    after = _visit_starts(new.text_table, planned)
    return PlanChanges(
        kept=[v for v in after if before.get(v) == after[v]],
        moved=[v for v in after if v in before and before[v] != after[v]],
        added=[v for v in after if v not in before],
        dropped=[v for v in before if v not in after],
    )


def replan(
    plan: Plan | str | Path,
    from_: Any,
    observed: str | Path | Table | None = None,
    lost: Sequence[Any] = (),
) -> Plan:
    """Plan the nights of ``plan`` again from ``from_`` on, with the plan's own site, settings,
    goals and targets (its meta): ``ucbplan replan``.

    Parameters
    ----------
    plan : Plan, str or path
        A plan just made, or its ECSV file (``ucbplan plan -o``).
    from_ : str, datetime or Time
        The instant (UTC) from which to plan again; the nights before the one it falls in are
        kept as they were (their rows come first in the new plan). It must come before the
        first block of its night.
    observed : str, path or Table, optional
        Spectra already taken (as :func:`ucbplan.plan`'s ``observed``). None: the kept rows
        count as taken, those of ``lost`` nights as missed.
    lost : list of str or date
        Nights of the plan lost (local date of the evening); nothing is planned on them.

    Returns
    -------
    Plan
        The kept rows and the new plan of the remaining nights (its meta: the remaining nights).
        A replan that changes nothing (no night lost, ``observed`` not given: the spectra taken
        as planned) is the plan itself, every visit kept: its visits reach the goals already.

    Raises
    ------
    InputError
        ``from_`` after the plan's last night or inside a night's blocks; a lost night not in
        the plan; a bad status in ``observed``; ``observed`` an observing log of another plan.
    InputFileError
        A plan without the recorded options, or whose target file is missing or changed.

    Examples
    --------
    Two nights planned, the second re-planned from its evening:

    >>> import ucbplan
    >>> run = ucbplan.plan(
    ...     "catalogs/hm-cnc-simulated.yaml", site="paranal", night="2040-02-15", nights=2
    ... )
    >>> ucbplan.replan(run, from_="2040-02-16T22:00")
    <Plan at Paranal: 1 target, 2 nights, 2 visits, 4 exposures, 0.29 h>
    """
    old = plan if isinstance(plan, Plan) else Plan.read(plan)
    options = _options(old)
    _check_log(observed, old)
    nights = [date.fromisoformat(str(n)) for n in old.meta.get("nights", [])]
    gone = _lost(lost, nights)
    start = _from_night(old, from_, nights)
    table = old.text_table
    kept_rows = table[[str(n) < start.isoformat() for n in table["night"]]]
    remaining = [n for n in nights if n >= start and n not in gone]
    if not remaining:
        raise InputError(
            "lost: every night from from_ on is lost; nothing is left to re-plan", "lost"
        )
    if not gone and observed is None:  # nothing changed: the plan stands, every visit kept
        return _plan_nights(old, options, nights, None, None, 0.0)
    if observed is None and len(kept_rows) and options.get("goal"):  # a changed plan
        observed = _history(kept_rows, gone, start)
    return _changed(old, options, remaining, observed, kept_rows)


#: How many more telescope hours (relative) a replan that keeps the old plan's visits may book
#: than one planned afresh on the same nights: beyond it the cheaper plan wins (issue 32: the
#: goal in no more than 5 % over the fewest hours; a schedule that moves little within that).
PIN_HOURS_RTOL = 0.05


def _changed(
    old: Plan, options: dict[str, Any], nights: list[date], observed: Any, kept: Table | None
) -> Plan:
    """The replan of ``nights`` keeping the old plan's visits on them that still serve
    (:mod:`ucbplan.observing.schedule.pinning`), unless it books more than
    :data:`PIN_HOURS_RTOL` more hours, or reaches fewer goals, than a plan afresh."""
    from ucbplan.observing.schedule.goalplan import REPLAN_INFO_SLACK

    free = _plan_nights(old, options, nights, observed, kept, REPLAN_INFO_SLACK)
    pins = _old_visits(old.text_table, nights)
    if not pins or not options.get("goal"):
        return free
    pinned = _plan_nights(old, options, nights, observed, kept, REPLAN_INFO_SLACK, pins)
    (short_p, hours_p), (short_f, hours_f) = _booked(pinned), _booked(free)
    if short_p <= short_f and hours_p <= (1.0 + PIN_HOURS_RTOL) * hours_f:
        return pinned
    return free


def _booked(plan: Plan) -> tuple[float, float]:
    """(goals not reached, telescope hours booked [s]) of a plan just made."""
    if plan.run is None:
        return math.inf, math.inf
    return len(plan.run.result.shortfalls), plan.run.time_account.total.total_s


def _old_visits(table: Table, nights: list[date]) -> tuple[tuple[str, tuple[str, ...]], ...]:
    """The visits of ``table`` on ``nights``: (target, UTC starts of its exposures) each."""
    visits = _visits(table, {n.isoformat() for n in nights})
    return tuple((name, tuple(sorted(starts))) for name, starts in visits.values())


def _options(old: Plan) -> dict[str, Any]:
    """The recorded options of ``old``, its target files checked unchanged."""
    meta = old.meta
    options = meta.get("plan_options")
    if not isinstance(options, dict):
        raise InputFileError(
            "plan meta: expected plan_options (written by `ucbplan plan` since issue 32), got a "
            "plan without; make the plan again with this version to re-plan it"
        )
    if options.get("unrecorded"):
        raise InputFileError(
            f"plan meta plan_options: {', '.join(options['unrecorded'])} were given as objects "
            "the file cannot hold; re-plan with ucbplan.plan and those objects instead"
        )
    if options.get("observed") is not None or options.get("sigma_v_scale") is not None:
        raise InputFileError(
            "plan meta plan_options: the plan counted observed spectra itself; re-plan the "
            "original plan with `observed` instead"
        )
    for entry in meta.get("targets", []):
        _check_target(entry)
    return dict(options)


def _check_log(observed: str | Path | Table | None, old: Plan) -> None:
    """An observing log given as ``observed`` is one of ``old``'s (another plan's is refused)."""
    from ucbplan.observing.night.observing_log import check_log_plan

    if isinstance(observed, str | Path):
        check_log_plan(observed, old.text_table)


def _check_target(entry: Any) -> None:
    """A target file of the meta: present and with the recorded sha256."""
    path = Path(str(entry.get("file", ""))) if isinstance(entry, dict) else None
    if path is None or not path.is_file() or "sha256" not in entry:
        raise InputFileError(
            f"plan meta targets: expected the target file {shorten(str(path), 80)} with its "
            "sha256, got none; re-plan from where the target files are"
        )
    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    if digest != entry["sha256"]:
        raise InputFileError(
            f"{shorten(str(path), 80)}: the target file changed since the plan was made "
            f"(sha256 {digest[:12]}…, the plan's {str(entry['sha256'])[:12]}…); make a new plan"
        )


def _lost(lost: Sequence[Any], nights: list[date]) -> set[date]:
    """The lost nights, each a night of the plan."""
    if isinstance(lost, str | date):
        lost = [lost]
    out: set[date] = set()
    for value in lost:
        try:
            night = value if isinstance(value, date) else date.fromisoformat(str(value))
        except ValueError:
            night = None
        if night not in nights:
            raise InputError(
                f"lost: expected a night of the plan ({', '.join(n.isoformat() for n in nights)}), "
                f"got {shorten(value, 40)}",
                "lost",
            )
        out.add(night)
    return out


def _from_night(old: Plan, from_: Any, nights: list[date]) -> date:
    """The night ``from_`` falls in (local date of the evening; noon to noon), checked: within
    the plan, and before that night's first block."""
    from astropy.time import Time

    try:
        with scope():
            when = from_ if isinstance(from_, Time) else Time(from_, scale="utc")
    except (TypeError, ValueError):
        raise InputError(
            f"from_: expected an ISO UTC instant (2040-02-16T20:00), got {shorten(from_, 40)}",
            "from_",
        ) from None
    utc = when.utc.to_datetime().replace(tzinfo=ZoneInfo("UTC"))
    local = utc.astimezone(ZoneInfo(old.site.timezone)) - timedelta(hours=12)
    night = local.date()
    if not nights or night > nights[-1]:
        raise InputError(
            f"from_: expected an instant before the plan's end (its last night "
            f"{nights[-1] if nights else '-'}), got {when.utc.isot[:19]}; nothing is left to "
            "re-plan",
            "from_",
        )
    night = max(night, nights[0])
    table = old.text_table
    inside = [
        str(s)
        for s, n in zip(table["t_start_utc"], table["night"], strict=True)
        if str(n) == night.isoformat() and _utc(str(s)) < utc
    ]
    if inside:
        raise InputError(
            f"from_: expected an instant before the first block of night {night} "
            f"({min(inside)[:19]}) or in a later night, got {when.utc.isot[:19]}; a night is "
            "re-planned whole",
            "from_",
        )
    return night


def _utc(text: str) -> datetime:
    return datetime.fromisoformat(text).replace(tzinfo=ZoneInfo("UTC"))


def _history(rows: Table, lost: set[date], start: date) -> Table:
    """The kept rows with a status column (``missed`` on lost nights, else ``taken``), named
    for messages and the plan's meta as the nights before ``start``."""
    import numpy as np

    from ucbplan.api._observed import SOURCE_KEY

    history = rows.copy()
    history["status"] = np.array(
        ["missed" if date.fromisoformat(str(n)) in lost else "taken" for n in rows["night"]],
        dtype=object,
    )
    history.meta[SOURCE_KEY] = f"the plan's nights before {start.isoformat()}"
    return history


def _plan_nights(
    old: Plan,
    options: dict[str, Any],
    nights: list[date],
    observed: Any,
    kept: Table | None,
    slack: float,
    pinned: tuple[tuple[str, tuple[str, ...]], ...] = (),
) -> Plan:
    """:func:`ucbplan.plan`'s run on ``nights`` (not necessarily consecutive) with ``options``,
    the rows ``kept`` first, each goal reached to ``slack`` of its information, the visits
    ``pinned`` kept where they still serve."""
    from ucbplan.api import planning

    call = inspect.signature(planning.plan).parameters
    o = {k: p.default for k, p in call.items() if p.default is not inspect.Parameter.empty}
    o.update(options)
    files = [str(t["file"]) for t in old.meta.get("targets", [])]
    o.update(targets=files, site=old.site, night=nights[0], nights=1, observed=observed)
    o.update(short_goals=True, goal_slack=slack, pinned=pinned)
    run = planning.plan_run_on(o, nights)
    return Plan(run, options={**options}, history=kept)
