"""Night schedules: anchor epochs → site UTC → constraint-checked blocks → sessions per night.

Pipeline for every target (all vectorised over epochs; :mod:`.candidates`): the planning modes name
the anchors (Appendix A2); :func:`~ucbplan.core.ephemeris.find_epochs` gives the barycentric epochs
t★ with σ_t and the φ_ref π-mode alternative; the light time is removed with one shared site track
(:mod:`ucbplan.observing.observatory.barycentric`); blocks are checked against every constraint over
their whole length (:mod:`ucbplan.observing.constraints.checks`). Sessions (a u = 0 / π pair, both
RV zero crossings, or single blocks) are then placed night by night in priority order without
overlaps, with a slew/acquisition overhead before each session (:mod:`.placement`), and become block
records (:mod:`.records`); fixed-u pairs get their second epoch (:mod:`.pairs`). Whatever could not
be
placed is reported with the reason."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from datetime import date
from typing import TYPE_CHECKING, Any

import numpy as np
from astropy.time import Time

from ucbplan.errors import EarthOrientationWarning, UcbplanError, UcbplanWarning
from ucbplan.observing.blocks.arrays import BlockList
from ucbplan.observing.blocks.block import MAX_BLOCK_S, Block
from ucbplan.observing.observatory.barycentric import coverage_warnings
from ucbplan.observing.observatory.sites import Site
from ucbplan.observing.observatory.time_axis import TimeAxis
from ucbplan.observing.precision.goals import GoalPlan
from ucbplan.observing.schedule.candidates import PlanFrame, TargetRun, Warned, prepare_runs
from ucbplan.observing.schedule.exposure import TargetCadence
from ucbplan.observing.schedule.goalplan import (
    GoalShortfall,
    as_placed,
    as_planned,
    balanced_runs,
    check_goals,
    goal_plans,
    goal_shortfalls,
)
from ucbplan.observing.schedule.nights import NightSpan, NightWindow, night_spans, night_windows
from ucbplan.observing.schedule.pairs import SecondEpoch, pair_blocks, pair_targets
from ucbplan.observing.schedule.placement import Allowance, Unplaced, place_sessions
from ucbplan.observing.schedule.reasons import not_planned
from ucbplan.observing.schedule.records import block_records
from ucbplan.observing.schedule.settings import PlanSettings
from ucbplan.observing.schedule.visits import place_visits

if TYPE_CHECKING:
    from ucbplan.targets import Target


@dataclass(frozen=True)
class PlanSchedule:
    """Blocks (sorted by time), what could not be placed, warnings, provenance facts.

    Attributes
    ----------
    blocks : sequence of Block
        Planned blocks in time order (a :class:`~ucbplan.observing.blocks.arrays.BlockList`:
        columns, with the records made on first access).
    unplaced : list of Unplaced
        Target/nights with fewer sessions than asked, and why.
    warnings : list of str
        Exposure, smearing and time-table coverage warnings.
    constraints : list of str
        One line per applied constraint (provenance).
    valid_until : dict of str to Time
        End of each target's validity T_valid (TDB).
    goals : dict of str to GoalPlan
        Each target's goal plan (``--goal``; empty without).
    exposures : dict of str to TargetCadence
        Each target's exposure plan and cadence.
    reasons : dict
        {target: {night: {reason: count}}}: night-time anchor epochs not planned, by reason
        (:mod:`.reasons`).
    warning_categories : tuple of type
        The class of each warning (its cause: :class:`~ucbplan.errors.SmearingWarning` …).
    shortfalls : list of GoalShortfall
        Goals the nights do not reach (``short_goals`` settings only; otherwise an error).
    """

    blocks: Sequence[Block]
    unplaced: list[Unplaced]
    warnings: list[str]
    constraints: list[str]
    valid_until: dict[str, Time]
    goals: dict[str, GoalPlan] = field(default_factory=dict)
    exposures: dict[str, TargetCadence] = field(default_factory=dict)
    reasons: dict[str, dict[str, dict[str, int]]] = field(default_factory=dict)
    warning_categories: tuple[type[UcbplanWarning], ...] = ()
    shortfalls: list[GoalShortfall] = field(default_factory=list)


def _check_inputs(targets: list[Target], nights: list[date], settings: PlanSettings) -> None:
    """Fail early, in words, on inputs no schedule can come from."""
    if not targets:
        raise UcbplanError("no targets given; pass one or more target YAML files")
    if not nights:
        raise UcbplanError("nights must be >= 1")


def _second_epoch(site: Site, settings: PlanSettings) -> SecondEpoch:
    """The single u★ = 0 block of a target on one night clear of ``busy`` (for fixed-u pairs)."""
    single = replace(settings, mode="u=0", sessions_per_night=1)

    def plan_one(target: Target, night: date, busy: Sequence[Block]) -> Block | None:
        res = plan_nights([target], site, [night], single, busy=busy)
        return res.blocks[0] if res.blocks else None

    return plan_one


#: Padding of blocks planned earlier when a new plan must keep clear of them [s]: covers the
#: UTC↔axis round trip (≤ 30 µs per day of span, see TimeAxis.x).
_BUSY_PAD_S = 1e-3


def _busy_x(axis: TimeAxis, busy: Sequence[Block]) -> list[tuple[float, float]]:
    """Blocks planned earlier as intervals on ``axis`` [s], padded by :data:`_BUSY_PAD_S`."""
    if not busy:
        return []
    x0 = (Time([b.t_start_utc for b in busy]) - axis.origin).to_value("s")
    x1 = (Time([b.t_end_utc for b in busy]) - axis.origin).to_value("s")
    return [
        (float(a) - _BUSY_PAD_S, float(b) + _BUSY_PAD_S)
        for a, b in zip(np.atleast_1d(x0), np.atleast_1d(x1), strict=True)
    ]


def _allowances(
    runs: Sequence[TargetRun], settings: PlanSettings, goals: dict[int, GoalPlan]
) -> dict[int, Allowance]:
    """Information (``--goal``) and wall time (``--budget``) each target may be given."""
    budgets = dict(settings.budgets)
    out = {}
    for r in runs:
        goal = goals.get(r.index)
        seconds = budgets.get(r.target.name.lower())
        if goal is not None or seconds is not None:
            plan = r.exposure.plan
            smallest = settings.overhead_s + plan.span_s
            if settings.plans_visits:
                smallest += plan.readout_s
            if goal is None:
                out[r.index] = Allowance(None, seconds, smallest)
                continue
            per = goal.info_needed / goal.n_spectra if goal.info_needed else 0.0
            visits = goal.time.n_visits if goal.time is not None else 1
            out[r.index] = Allowance(None, seconds, smallest, goal.info_needed, per, visits)
    return out


def plan_nights(
    targets: list[Target],
    site: Site,
    nights: list[date],
    settings: PlanSettings,
    busy: Sequence[Block] = (),
) -> PlanSchedule:
    """Plan blocks for ``targets`` at ``site`` on the given local evening dates.

    No two blocks of the result overlap, whatever their targets, and each session keeps the
    slew/acquisition overhead clear of every other block.

    Parameters
    ----------
    targets : list of Target
        Loaded targets (priorities from the files).
    site : Site
        Observatory.
    nights : list of date
        Local dates of the evenings the nights start.
    settings : PlanSettings
        Mode, constraints, exposure plan, tolerance inputs, overheads.
    busy : sequence of Block
        Blocks planned earlier that the new blocks (and their overheads) must keep clear of.

    Returns
    -------
    PlanSchedule

    Raises
    ------
    UcbplanError
        For missing tolerance inputs, exceeded smearing budgets or bad options.

    Notes
    -----
    Anchor epochs: Eq. u_precessing_app (Appendix A2); σ_t: Eq. sigma_tstar; validity: Eq.
    T_valid_alpha; smearing: Eqs. Lambda_K, Lambda_kappa; fixed-u pairs: Eq. delta_kappa_rewrite.
    """
    _check_inputs(targets, nights, settings)
    targets, infeasible = _plannable(targets, nights, settings)
    windows = night_windows(site, nights)
    frame, runs, warns = prepare_runs(targets, site, windows, settings)
    return _schedule(runs, frame, windows, warns, site, nights, settings, busy, infeasible)


def _plannable(
    targets: list[Target], nights: list[date], settings: PlanSettings
) -> tuple[list[Target], list[Unplaced]]:
    """The targets that can be planned, and the reasons the others cannot (fixed-u pairs
    report a circular target instead of failing on it)."""
    infeasible: list[Unplaced] = []
    if settings.spec.label == "fixed-u-pairs":
        targets, infeasible = pair_targets(targets, nights[0].isoformat())
        if not targets:
            raise UcbplanError(f"fixed-u pairs: no target can be planned: {infeasible[0].reason}")
    return targets, infeasible


def _longest_night_s(spans: list[NightSpan], frame: PlanFrame) -> float:
    """The longest dark stretch of the nights (to the minute) [s]: the longest visit they
    allow (at most ``MAX_BLOCK_S``)."""
    longest = 0
    for sp in spans:
        dark = frame.constraints.night.ok(frame.sky, 0, np.arange(sp.x0, sp.x1, 60.0))
        edges = np.flatnonzero(np.diff(np.concatenate(([0], dark.astype(np.int8), [0]))))
        runs = edges[1::2] - edges[::2]
        longest = max(longest, int(runs.max()) if runs.size else 0)
    return min(60.0 * longest, MAX_BLOCK_S)


def _longer_visits(
    runs: list[TargetRun],
    spans: list[NightSpan],
    frame: PlanFrame,
    site: Site,
    settings: PlanSettings,
    busy_x: list[tuple[float, float]],
) -> tuple[float, float, Callable[[], Sequence[Block]]] | None:
    """For a goal's shortfall message: (max_visit, the longest visit the nights allow [s], a
    replanning with visits that long), when visits were capped by max_visit; else None."""
    if not settings.plans_visits or settings.visit_s is not None:
        return None
    longest = _longest_night_s(spans, frame)
    if longest <= settings.max_visit_s:
        return None

    def replan() -> Sequence[Block]:
        wide = replace(settings, max_visit_s=longest)
        ex = [replace(r, exposure=replace(r.exposure, visit_s=longest)) for r in runs]
        more = goal_plans(ex, wide)
        ex = balanced_runs(ex, more)
        got, _ = place_visits(ex, spans, frame, wide, busy_x, _allowances(ex, wide, more))
        return block_records(got, ex, spans, frame, site, wide)

    return settings.max_visit_s, longest, replan


def _placed(
    runs0: list[TargetRun],
    goals: dict[int, GoalPlan],
    spans: list[NightSpan],
    frame: PlanFrame,
    settings: PlanSettings,
    busy_x: list[tuple[float, float]],
    full: bool,
) -> tuple[list[TargetRun], Any, Any]:
    """(runs, placed, unplaced): the goals' balanced visits placed (``full``: every visit as
    full as its length allows, for goals the nights cannot reach)."""
    runs = runs0 if full else balanced_runs(runs0, goals)
    allowances = _allowances(runs, settings, goals)
    for allowance in allowances.values() if full else ():
        allowance.visits_left = 1
    place = place_visits if settings.plans_visits else place_sessions
    placed, unplaced = place(runs, spans, frame, settings, busy_x, allowances)
    return runs, placed, unplaced


def _schedule(
    runs: list[TargetRun],
    frame: PlanFrame,
    windows: list[NightWindow],
    warns: list[Warned],
    site: Site,
    nights: list[date],
    settings: PlanSettings,
    busy: Sequence[Block],
    infeasible: list[Unplaced],
    full: bool = False,
) -> PlanSchedule:
    """Goals, then sessions or visits placed night by night, then the block records in time
    order (fixed-u pairs with their second epochs), as a :class:`PlanSchedule`. A goal the nights
    cannot reach (``short_goals``) is planned again in visits as full as they may be."""
    spans = night_spans(windows, frame.axis)
    busy_x = _busy_x(frame.axis, busy)
    goals = goal_plans(runs, settings)
    runs0 = runs
    runs, placed, unplaced = _placed(runs0, goals, spans, frame, settings, busy_x, full)
    gap = 0.0 if settings.plans_visits else settings.overhead_s
    reasons = not_planned(runs, spans, frame, placed, unplaced, gap)
    records = block_records(placed, runs, spans, frame, site, settings)
    blocks: Sequence[Block]
    if frame.mode.label == "fixed-u-pairs":
        second = _second_epoch(site, settings)
        pairs, more = pair_blocks(
            list(records), runs, settings.max_pair_baseline_days, second, nights=nights
        )
        unplaced += more + infeasible
        blocks = sorted(pairs, key=lambda b: (b.t_mid_utc.jd1, b.t_mid_utc.jd2))
    else:  # the same order, sorted on the columns
        blocks = BlockList(records.columns.take(records.columns.time_order()))
    shortfalls = []
    if settings.short_goals:
        shortfalls = goal_shortfalls(goals, runs, blocks, frame.mode.u_values)
        if shortfalls and not full:  # the even split assumed nights that hold every visit
            args = (windows, warns, site, nights, settings, busy, infeasible)
            return _schedule(runs0, frame, *args, full=True)
        if settings.goal_slack > 0:  # a changed replan: the fewest spectra that reach it
            goals = as_placed(goals, runs, blocks, frame.mode.u_values)
        goals = as_planned(goals, runs, shortfalls)
    else:
        longer = _longer_visits(runs0, spans, frame, site, settings, busy_x) if goals else None
        check_goals(goals, runs, blocks, frame.mode.u_values, longer)
    coverage = coverage_warnings(windows[0].start, windows[-1].end)
    return PlanSchedule(
        blocks=blocks,
        unplaced=unplaced,
        warnings=[w for _, w in warns] + coverage,
        warning_categories=(*(c for c, _ in warns), *[EarthOrientationWarning] * len(coverage)),
        constraints=frame.constraints.describe(),
        valid_until={r.target.name: r.until for r in runs},
        goals={runs[i].target.name: g for i, g in goals.items()},
        exposures={r.target.name: r.exposure for r in runs},
        reasons=reasons,
        shortfalls=shortfalls,
    )
