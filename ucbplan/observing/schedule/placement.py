"""Placement: sessions put into nights by target priority, and the reason for what does not fit.

Targets are taken in priority order (highest first; ties keep the input order). In each night a
target gets its best sessions (lowest worst-airmass first) that keep the slew/acquisition
overhead clear of everything placed before, up to ``sessions_per_night``. A target/night that
gets fewer is reported as :class:`Unplaced` with the reason in words a user can act on.
"""

from __future__ import annotations

import bisect
import math
from collections import Counter
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from ucbplan.observing.observatory.sky import airmass_from_alt
from ucbplan.observing.schedule.candidates import Candidates, PlanFrame, TargetRun
from ucbplan.observing.schedule.nights import NightSpan
from ucbplan.observing.schedule.settings import PlanSettings

FloatArray = NDArray[np.float64]

#: Sampling step of the night when explaining why nothing fits [s].
_REASON_STEP_S = 300.0


@dataclass(frozen=True, slots=True)
class Unplaced:
    """A target/night for which nothing (or less than asked) could be placed, and why."""

    target: str
    night: str
    reason: str


@dataclass(frozen=True, slots=True)
class Session:
    """Placed blocks of one target in one night: candidate indices and span [s on the axis]."""

    target_i: int
    night_i: int
    idx: tuple[int, ...]
    x0: float
    x1: float


@dataclass
class Allowance:
    """What a target may still be given over the run: information on K (a ``--goal``)
    [(km/s)⁻²] and wall time (``--budget``) [s]; None = no limit. ``smallest_s`` is the wall
    time of the shortest visit or session (acquisition + one exposure): a budget with less left
    is spent. ``exposures`` limits the number of exposures (library callers)."""

    exposures: int | None = None
    seconds: float | None = None
    smallest_s: float = 0.0
    info: float | None = None
    per_spectrum: float = 0.0
    visits_left: int = 1

    def __post_init__(self) -> None:
        self.info_asked = self.info or 0.0

    def share(self, pattern: int) -> int | None:
        """Exposures the next visit of a goal should hold so that the visits left share the
        spectra still needed evenly (whole anchor patterns); None without a goal estimate."""
        if self.info is None or self.per_spectrum <= 0:
            return None
        need = math.ceil(self.info / self.per_spectrum * (1.0 - 1e-12))
        groups = math.ceil(need / pattern)
        return pattern * math.ceil(groups / max(1, self.visits_left))

    @property
    def spent(self) -> bool:
        """Nothing more may be planned (less time left than the shortest visit/session)."""
        return (
            (self.exposures is not None and self.exposures <= 0)
            or (self.info is not None and self.info <= 0)
            or (self.seconds is not None and self.seconds < max(self.smallest_s, 1e-9))
        )

    def fits(self, n_exposures: int, wall_s: float) -> bool:
        """Whether a visit or session of ``n_exposures`` and ``wall_s`` fits."""
        return (self.exposures is None or n_exposures <= self.exposures) and (
            self.seconds is None or wall_s <= self.seconds + 1e-6
        )

    def charge(self, n_exposures: int, wall_s: float, info: float = 0.0) -> None:
        """Spend a placed visit or session (``info``: the information it collects)."""
        if self.exposures is not None:
            self.exposures -= n_exposures
        if self.seconds is not None:
            self.seconds -= wall_s
        if self.info is not None:
            self.visits_left = max(1, self.visits_left - 1)
            self.info -= info
            if self.info <= INFO_RTOL * self.info_asked:
                self.info = 0.0


#: Relative shortfall of a goal's information counted as reached (rounding of the sums).
INFO_RTOL = 1e-9


@dataclass
class Timeline:
    """Sessions placed so far and the taken intervals of the whole run [s on the plan's axis].

    Taken intervals are kept sorted and pairwise apart by at least the overhead, so a new
    session is checked against its two neighbours only (placement stays fast for thousands of
    sessions), and no two placed sessions ever overlap, whatever their night or target.
    """

    overhead_s: float
    starts: list[float] = field(default_factory=list)
    ends: list[float] = field(default_factory=list)
    placed: list[Session] = field(default_factory=list)

    def free(self, x0: float, x1: float) -> bool:
        """Whether [x0, x1], with the overhead before it and before the next, is free."""
        gap = max(self.overhead_s, 0.0)
        k = bisect.bisect_left(self.starts, x1 + gap)  # intervals starting before our end
        return not (k > 0 and self.ends[k - 1] > x0 - gap)

    def take(self, x0: float, x1: float) -> None:
        """Mark [x0, x1] as taken (the caller checked :meth:`free`)."""
        k = bisect.bisect_left(self.starts, x0)
        self.starts.insert(k, x0)
        self.ends.insert(k, x1)

    def block_out(self, intervals: Sequence[tuple[float, float]]) -> None:
        """Mark ``intervals`` (e.g. blocks planned earlier) as taken, merging any that touch."""
        merged: list[list[float]] = []
        for x0, x1 in sorted([*zip(self.starts, self.ends, strict=True), *intervals]):
            if merged and x0 <= merged[-1][1]:
                merged[-1][1] = max(merged[-1][1], x1)
            else:
                merged.append([x0, x1])
        self.starts = [m[0] for m in merged]
        self.ends = [m[1] for m in merged]

    def add(self, s: Session) -> bool:
        """Place ``s`` unless it (with its overhead before the start) overlaps a taken interval."""
        if not self.free(s.x0, s.x1):
            return False
        self.take(s.x0, s.x1)
        self.placed.append(s)
        return True


class NightSun:
    """What the targets of a run share about its nights: the Sun's altitude [deg] at the
    samples of each night window that explain why nothing fits (every :data:`_REASON_STEP_S`
    [s on the axis]), found for every window of ``windows`` at once when one is first asked
    for (any other window on its own); and each target's usable candidates of every night, or
    why it has none (:func:`night_usable`), found for all of them at once."""

    def __init__(self, frame: PlanFrame, windows: Sequence[tuple[float, float]] = ()) -> None:
        self.frame = frame
        self.windows = list(windows)
        self._known = set(self.windows)
        self._found: dict[tuple[float, float], tuple[FloatArray, FloatArray]] = {}
        self._usable: dict[int, tuple[TargetRun, dict[tuple[float, float], Usable]]] = {}

    def knows(self, span: NightSpan, frame: PlanFrame | None) -> bool:
        """Whether ``span`` is one of ``windows`` (on ``frame``'s axis)."""
        return frame is self.frame and (span.x0, span.x1) in self._known

    def samples(self, window: tuple[float, float]) -> tuple[FloatArray, FloatArray]:
        """(sample times [s on the axis], the Sun's altitude there [deg]); read only."""
        if window not in self._found:
            ask = [w for w in self.windows if w not in self._found]
            ask = ask if window in ask else [window]
            xs = [np.arange(w[0], w[1], _REASON_STEP_S) for w in ask]
            suns = at_once(self.frame.sky.sun_alt_deg, xs)
            self._found.update(zip(ask, zip(xs, suns, strict=True), strict=True))
        return self._found[window]

    def usable(self, run: TargetRun, settings: PlanSettings) -> dict[tuple[float, float], Usable]:
        """{window: :func:`night_usable`} of ``run`` for every one of ``windows``; read only."""
        kept = self._usable.get(run.index)
        if kept is None or kept[0] is not run:
            kept = self._usable[run.index] = run, _usable_by_night(run, self, settings)
        return kept[1]


#: A night's usable candidates (indices, read only) or why there are none.
Usable = NDArray[np.int64] | str


def at_once(f: Callable[[FloatArray], NDArray[Any]], parts: list[FloatArray]) -> list[NDArray[Any]]:
    """``[f(p) for p in parts]`` for an elementwise ``f`` (the sky model's evaluations: bit for
    bit the same whatever the points around, tests compare), from one call on all the points."""
    if not parts:
        return []
    return np.split(f(np.concatenate(parts)), np.cumsum([p.size for p in parts])[:-1])


def _usable_by_night(
    run: TargetRun, sun: NightSun, settings: PlanSettings
) -> dict[tuple[float, float], Usable]:
    """:func:`night_usable` of ``run`` in each of ``sun.windows``: its candidates found by one
    search, the reasons of the nights without one by :func:`_no_session_reasons`."""
    frame, wins = sun.frame, sun.windows
    bounds = np.searchsorted(run.cand.x_mid, np.array(wins, dtype=np.float64).reshape(-1, 2))
    good = (run.ok > 0) & run.valid
    out: dict[tuple[float, float], Usable] = {}
    empty: list[tuple[float, float]] = []
    for w, (j0, j1) in zip(wins, bounds.tolist(), strict=True):
        usable = np.flatnonzero(good[j0:j1]) + j0
        if usable.size:
            usable.flags.writeable = False  # shared by every caller
            out[w] = usable
        elif not run.exposure.floor_ok or (j1 > j0 and not run.valid[j0:j1].any()):
            span = NightSpan("", w[0], w[1])
            out[w] = unusable_reason(run, np.arange(j0, j1), span, frame, settings, sun)
        else:
            empty.append(w)
    if empty:  # (a frame's sky and constraints are read only here)
        out.update(zip(empty, _no_session_reasons(run, sun, empty), strict=True))
    return out


def _no_session_reasons(
    run: TargetRun, sun_at: NightSun, windows: list[tuple[float, float]]
) -> list[str]:
    """Why no usable session exists in each night window (inside T_valid), the sky evaluated
    once for all of them."""
    c: Candidates = run.cand
    frame = sun_at.frame
    night, limit = frame.constraints.night, frame.constraints.airmass
    why: dict[int, str] = {}
    dark: dict[int, FloatArray] = {}
    for k, w in enumerate(windows):
        xs, sun = sun_at.samples(w)
        if sun.min() > night.sun_alt_max_deg:
            why[k] = (
                f"no {night.twilight} night: the Sun stays above {night.sun_alt_max_deg:g} deg "
                f"(lowest {sun.min():.1f} deg; polar day or summer at high latitude)"
            )
        else:
            dark[k] = xs[sun <= night.sun_alt_max_deg]
    alts = at_once(lambda x: frame.sky.target_alt_deg(run.index, x), list(dark.values()))
    low = at_once(lambda alt: airmass_from_alt(alt) > limit.max_airmass, alts)
    inside: dict[int, NDArray[np.int64]] = {}
    for k, alt, too_low in zip(dark, alts, low, strict=True):
        if too_low.all():
            why[k] = (
                f"never at airmass <= {limit.max_airmass:g} during {night.twilight} night "
                f"(highest altitude {alt.max():.1f} deg)"
            )
        else:  # blocks centred in the window (x_mid in order)
            inside[k] = np.arange(*np.searchsorted(c.x_mid, windows[k]))
    # blocks centred at night: the same whether epochs were searched at night or all day
    dark_ok = at_once(
        lambda x: night.ok(frame.sky, run.index, x), [c.x_mid[j] for j in inside.values()]
    )
    for k, in_win, ok in zip(inside, inside.values(), dark_ok, strict=True):
        why[k] = _failed_reason(run, frame, in_win[ok])
    return [why[k] for k in range(len(windows))]


def _failed_reason(run: TargetRun, frame: PlanFrame, in_win: NDArray[np.int64]) -> str:
    """Why none of the night-time blocks ``in_win`` of a window is usable."""
    if not in_win.size:
        return "no anchor epoch in the night window"
    first = run.cand.first_failed[in_win]
    fails = Counter(first[first >= 0].tolist())  # in order of first appearance
    if not fails:
        return "no session fits: the second block of each pair fails the constraints"
    worst = fails.most_common(1)[0][0]
    return f"every block {frame.constraints.active[worst].reason()}"


def unusable_reason(
    run: TargetRun,
    js: np.ndarray,
    span: NightSpan,
    frame: PlanFrame,
    settings: PlanSettings,
    sun: NightSun | None = None,
) -> str:
    """Why none of the sessions ``js`` of a night can be used (``sun``: the run's, shared by
    its targets; None: this night's alone)."""
    if not run.exposure.floor_ok:
        return (
            f"smearing floor: no exposure keeps Lambda_K >= {settings.lambda_k_floor:g}; lower "
            "--min-lambda-k or pass --allow-smeared"
        )
    if js.size and not np.any(run.valid[js]):
        if span.x1 <= frame.axis.x(run.since) and run.target.kind != "timing":
            return (
                f"before the LISA observation starts ({run.since.tdb.iso[:10]} TDB): a LISA "
                "ephemeris predicts the orbit from then on; pick a later night"
            )
        if span.x1 <= frame.axis.x(run.since):
            return (
                f"before the validity window: {frame.mode.label} epochs are valid from "
                f"{run.since.utc.iso[:16]} UTC (alpha={settings.alpha:g}); pick a later night "
                "or a larger --alpha"
            )
        return (
            f"past T_valid: {frame.mode.label} epochs are valid until "
            f"{run.until.utc.iso[:16]} UTC (alpha={settings.alpha:g}); pick an "
            "earlier night or a larger --alpha"
        )
    return _no_session_reasons(run, sun or NightSun(frame), [(span.x0, span.x1)])[0]


def night_usable(
    run: TargetRun,
    span: NightSpan,
    frame: PlanFrame,
    settings: PlanSettings,
    sun: NightSun | None = None,
) -> NDArray[np.int64] | str:
    """Indices of ``run``'s usable candidates in the night ``span`` (read only), or why there
    are none (:func:`unusable_reason`); ``sun``: the run's, which finds every night of its
    windows at once."""
    if sun is not None and sun.knows(span, frame):
        return sun.usable(run, settings)[(span.x0, span.x1)]
    j0, j1 = np.searchsorted(run.cand.x_mid, [span.x0, span.x1])
    js = np.arange(j0, j1)
    usable = js[(run.ok[js] > 0) & run.valid[js]]
    if usable.size == 0:
        return unusable_reason(run, js, span, frame, settings, sun)
    return usable


def _place_night(run: TargetRun, night: NightTask) -> str | None:
    """Place one target's best sessions in a night; the reason if fewer than asked fit."""
    n, span, timeline, frame, settings, allowance, sun = night
    c = run.cand
    usable = night_usable(run, span, frame, settings, sun)
    if isinstance(usable, str):
        return usable
    usable = usable[np.argsort(run.score[usable], kind="stable")]
    wanted, count, n_exp = settings.sessions_per_night, 0, run.exposure.plan.n_exp
    over_budget = False
    partner = run.partner[usable]
    ends = np.where(partner < 0, usable, partner)  # a pair ends with its second block
    firsts, lasts = c.x_start[usable].tolist(), c.x_end[ends].tolist()
    rows = zip(usable.tolist(), partner.tolist(), firsts, lasts, strict=True)
    for j, k, x0, x1 in rows:
        idx = (j,) if k < 0 else (j, k)
        wall = settings.overhead_s + x1 - x0
        if not allowance.fits(len(idx) * n_exp, wall):
            over_budget = True
            continue
        if timeline.add(Session(run.index, n, idx, x0, x1)):
            allowance.charge(len(idx) * n_exp, wall)
            count += 1
            if count == wanted:
                return None
    if over_budget:
        return f"time budget spent after {count} session(s)"
    if count == 0:
        return (
            f"all {usable.size} usable sessions overlap higher-priority blocks "
            f"(with {settings.overhead_s:g} s slew/acquisition overhead)"
        )
    return f"only {count} of {wanted} sessions fit"


def place_sessions(
    runs: list[TargetRun],
    spans: list[NightSpan],
    frame: PlanFrame,
    settings: PlanSettings,
    busy: Sequence[tuple[float, float]] = (),
    allowances: Mapping[int, Allowance] | None = None,
) -> tuple[list[Session], list[Unplaced]]:
    """Greedy night schedule: targets by priority, each night's best sessions (lowest airmass)
    that keep the overhead gap to everything already placed (and to the ``busy`` intervals
    [s on the plan's axis], e.g. blocks of an earlier plan).

    Returns
    -------
    placed : list of Session
        In placement order.
    unplaced : list of Unplaced
        One entry per target and night that got fewer sessions than asked.
    """
    timeline = Timeline(settings.overhead_s)
    return place_by_priority(
        runs, spans, frame, settings, timeline, busy, allowances, _place_night, quiet_goals=False
    )


class NightTask(NamedTuple):
    """What placing one target in one night takes: the night's index and span, the timeline
    shared by all targets, the plan's frame and settings, the target's allowance, and the
    nights' Sun shared by all targets."""

    n: int
    span: NightSpan
    timeline: Timeline
    frame: PlanFrame
    settings: PlanSettings
    allowance: Allowance
    sun: NightSun


#: Places one target's sessions or visits in one night; returns why fewer than asked fit.
NightPlacer = Callable[[TargetRun, NightTask], "str | None"]

#: The order in which one target's nights are filled (indices into its tasks, one per night).
NightOrder = Callable[[TargetRun, Sequence[NightTask]], list[int]]


def place_by_priority(
    runs: list[TargetRun],
    spans: list[NightSpan],
    frame: PlanFrame,
    settings: PlanSettings,
    timeline: Timeline,
    busy: Sequence[tuple[float, float]],
    allowances: Mapping[int, Allowance] | None,
    place_night: NightPlacer,
    quiet_goals: bool,
    order: NightOrder | None = None,
) -> tuple[list[Session], list[Unplaced]]:
    """The greedy loop of sessions and visits alike: targets by priority (ties in input order),
    nights in order (``order``: in the order it gives), ``place_night`` filling ``timeline``
    (the ``busy`` intervals blocked out).

    A target whose allowance is spent gets no more; each later night is noted as "time budget
    spent", except, with ``quiet_goals`` (visits), when the allowance was a goal's (its
    exposures or information): the goal is planned, nothing is missing. The reasons come in
    night order whatever the order of filling.
    """
    timeline.block_out(busy)
    unplaced: list[Unplaced] = []
    sun = NightSun(frame, [(sp.x0, sp.x1) for sp in spans])
    for run in sorted(runs, key=lambda r: -r.target.priority):
        allowance = (allowances or {}).get(run.index) or Allowance()
        tasks = [
            NightTask(n, sp, timeline, frame, settings, allowance, sun)
            for n, sp in enumerate(spans)
        ]
        mine: dict[int, Unplaced] = {}
        for n in range(len(tasks)) if order is None else order(run, tasks):
            if allowance.spent:
                goal = allowance.exposures is not None or allowance.info is not None
                if not (quiet_goals and goal):
                    mine[n] = Unplaced(run.target.name, spans[n].label, "time budget spent")
                continue
            reason = place_night(run, tasks[n])
            if reason is not None:
                mine[n] = Unplaced(run.target.name, spans[n].label, reason)
        unplaced += [mine[n] for n in sorted(mine)]
    return timeline.placed, unplaced
