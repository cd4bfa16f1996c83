"""Time accounting of a plan, in one place: the planner's visits, the table meta and its reader.

A :class:`TimeAccount` holds the time of one target (or of the whole plan): visits, exposures,
shutter-open time, overheads and idle time [s]; its efficiency is shutter / total. A
:class:`PlanAccount` holds one per target and the total; its meta form (``time_accounting`` in the
blocks table meta and in ``--format json``) is written by :meth:`PlanAccount.as_meta` and read
back, with validation, by :meth:`TimeAccount.from_meta`; :data:`ACCOUNT_KEYS` names its keys.

The planner's accounting (:func:`visit_summaries`, :func:`time_accounting`). A visit
(``visit_id``) is one acquisition of ``acquisition_s`` that ends when its first exposure starts,
then its blocks. Its wall time runs from the acquisition start to the end of the last exposure,
plus that exposure's readout when exposures are read out one by one inside a visit (``--visit``;
a co-added block of ``n_exp`` exposures has ``n_exp − 1`` readouts inside it):

    shutter  = Σ n_exp · exptime
    overhead = acquisition + Σ (readouts) · readout
    idle     = wall − shutter − overhead          (waiting for the next anchor's phase)
    efficiency = shutter / (shutter + overhead + idle) = shutter / wall

The accounting of a table without it (an older planner, a hand-made table;
:func:`accounts_from_blocks`, docs/exports.md "Time accounting"), which the proposal export falls
back on:

- a visit is a planner session (blocks sharing ``session_id``: one acquisition) or a lone block;
- shutter = Σ n_exp · exptime;
- overheads = one acquisition per visit + every exposure's readout (n_exp · ``readout_s``; without
  that column, the block's width minus its shutter time);
- idle = within each visit, the gaps between one block's end (+ the readout of its last
  exposure) and the next block's start: the telescope waits on target for the next phase;
- so that shutter + overheads + idle = Σ_visits (acquisition + last end − first start + the last
  readout), the wall time the visits hold the telescope; efficiency = shutter / that total.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields
from datetime import datetime
from itertools import pairwise, starmap
from typing import Any, NamedTuple

import numpy as np
from astropy.time import TimeDelta

from ucbplan.errors import InputFileError, shorten
from ucbplan.inputs import is_number
from ucbplan.observing.blocks.arrays import BlockColumns, block_columns, isot
from ucbplan.observing.blocks.block import Block

#: Keys of one ``time_accounting`` entry, in the order written (counts, then seconds, then a
#: fraction); the proposal export reads exactly these.
ACCOUNT_KEYS = ("visits", "exposures", "shutter_s", "overhead_s", "idle_s", "efficiency")


@dataclass(frozen=True, slots=True)
class TimeAccount:
    """Time of one target (or of the whole plan).

    Attributes
    ----------
    visits, exposures : int
        Acquisitions and exposures.
    shutter_s, overhead_s, idle_s : float
        Open-shutter time, acquisition + readout, and waits on target for the next phase [s].
    """

    visits: int
    exposures: int
    shutter_s: float
    overhead_s: float
    idle_s: float

    @property
    def total_s(self) -> float:
        """shutter + overheads + idle [s]."""
        return self.shutter_s + self.overhead_s + self.idle_s

    @property
    def efficiency(self) -> float:
        """shutter / total (0 for an empty account)."""
        return self.shutter_s / self.total_s if self.total_s > 0 else 0.0

    def __add__(self, other: TimeAccount) -> TimeAccount:
        return TimeAccount(
            self.visits + other.visits,
            self.exposures + other.exposures,
            self.shutter_s + other.shutter_s,
            self.overhead_s + other.overhead_s,
            self.idle_s + other.idle_s,
        )

    def as_meta(self) -> dict[str, Any]:
        """The meta entry: :data:`ACCOUNT_KEYS` in order, seconds to 1 ms, efficiency to 1e-6."""
        return {
            "visits": self.visits,
            "exposures": self.exposures,
            "shutter_s": round(self.shutter_s, 3),
            "overhead_s": round(self.overhead_s, 3),
            "idle_s": round(self.idle_s, 3),
            "efficiency": round(self.efficiency, 6) if self.total_s > 0 else 0.0,
        }

    @classmethod
    def from_meta(cls, where: str, entry: Any) -> TimeAccount:
        """The account a meta entry holds (its efficiency is recomputed from the times).

        Raises
        ------
        InputFileError
            ``entry`` is not a mapping of non-negative numbers (whole ones for the counts);
            ``where`` names it in the message.
        """
        if not isinstance(entry, Mapping):
            raise InputFileError(
                f"blocks table meta time_accounting: {where}: expected a mapping with "
                f"{', '.join(ACCOUNT_KEYS)}; regenerate the table with `ucbplan plan`"
            )
        v = {
            k: _meta_number(f"{where}.{k}", entry.get(k), k in ("visits", "exposures"))
            for k in ACCOUNT_KEYS[:5]
        }
        return cls(
            int(v["visits"]), int(v["exposures"]), v["shutter_s"], v["overhead_s"], v["idle_s"]
        )


def _meta_number(where: str, value: Any, integer: bool) -> float:
    if not is_number(value) or not math.isfinite(float(value)) or float(value) < 0:
        raise InputFileError(
            f"blocks table meta time_accounting: {where}: expected a number >= 0, got "
            f"{shorten(value, 40)}; regenerate the table with `ucbplan plan`"
        )
    if integer and float(value) != int(value):
        raise InputFileError(
            f"blocks table meta time_accounting: {where}: expected a whole number, got "
            f"{shorten(value, 40)}; regenerate the table with `ucbplan plan`"
        )
    return float(value)


@dataclass(frozen=True, slots=True)
class PlanAccount:
    """A plan's time: the total and one :class:`TimeAccount` per target (in order of first
    visit)."""

    total: TimeAccount
    targets: dict[str, TimeAccount] = field(default_factory=dict)

    def as_meta(self) -> dict[str, Any]:
        """``{"total": {...}, "targets": {NAME: {...}}}``, each entry :meth:`TimeAccount.as_meta`
        (the blocks table's ``meta['time_accounting']``)."""
        return {
            "total": self.total.as_meta(),
            "targets": {name: a.as_meta() for name, a in self.targets.items()},
        }


@dataclass(frozen=True, slots=True)
class VisitSummary:
    """One visit: its acquisition, exposures and time split [s]."""

    visit_id: str
    target: str
    night: str
    acq_start_utc: str
    start_utc: str
    end_utc: str
    exposures: int
    shutter_s: float
    overhead_s: float
    idle_s: float

    @property
    def wall_s(self) -> float:
        """Acquisition start to the end of the last readout [s]."""
        return self.shutter_s + self.overhead_s + self.idle_s

    def as_dict(self) -> dict[str, Any]:
        """Plain values for the table meta and JSON."""
        return {
            "visit_id": self.visit_id,
            "target": self.target,
            "night": self.night,
            "acq_start_utc": self.acq_start_utc,
            "start_utc": self.start_utc,
            "end_utc": self.end_utc,
            "exposures": self.exposures,
            "shutter_s": round(self.shutter_s, 3),
            "overhead_s": round(self.overhead_s, 3),
            "idle_s": round(self.idle_s, 3),
        }


#: The fields of a :class:`VisitSummary`, in order: the keys of :meth:`VisitSummary.as_dict`.
VISIT_KEYS = tuple(f.name for f in fields(VisitSummary))


@dataclass(frozen=True)
class VisitColumns:
    """A plan's visits as columns, one list per :class:`VisitSummary` field (in time order):
    the summaries, their meta records and the time accounting are read from the columns, and a
    plan of thousands of one-exposure visits makes no object per visit until asked for one."""

    visit_id: list[str]
    target: list[str]
    night: list[str]
    acq_start_utc: list[str]
    start_utc: list[str]
    end_utc: list[str]
    exposures: list[int]
    shutter_s: list[float]
    overhead_s: list[float]
    idle_s: list[float]

    def __len__(self) -> int:
        return len(self.visit_id)

    @classmethod
    def of(cls, visits: Sequence[VisitSummary]) -> VisitColumns:
        """The columns of summaries, in their order."""
        return cls(*([getattr(v, key) for v in visits] for key in VISIT_KEYS))

    def _columns(self) -> list[list[Any]]:
        return [getattr(self, key) for key in VISIT_KEYS]

    def summaries(self) -> list[VisitSummary]:
        """One :class:`VisitSummary` per visit."""
        return list(starmap(VisitSummary, zip(*self._columns(), strict=True)))

    def records(self) -> list[dict[str, Any]]:
        """:meth:`VisitSummary.as_dict` of each visit (seconds to 1 ms), for the table meta."""
        seconds = [_rounded(x, 3) for x in (self.shutter_s, self.overhead_s, self.idle_s)]
        rows = zip(*self._columns()[:7], *seconds, strict=True)
        return [dict(zip(VISIT_KEYS, row, strict=True)) for row in rows]

    def wall_s(self) -> list[float]:
        """:attr:`VisitSummary.wall_s` of each visit [s]."""
        parts = [np.asarray(x, dtype=float) for x in (self.shutter_s, self.overhead_s)]
        return (parts[0] + parts[1] + np.asarray(self.idle_s, dtype=float)).tolist()

    def account(self) -> PlanAccount:
        """The plan's :class:`PlanAccount`: the total and one account per target (in order of
        first visit), each sum running over the visits in time order."""
        rows: dict[str, list[int]] = {}
        for k, name in enumerate(self.target):
            rows.setdefault(name, []).append(k)
        total = _account(self._columns()[6:])
        return PlanAccount(
            total,
            {
                name: total if len(ks) == len(self) else _account(self._columns()[6:], ks)
                for name, ks in rows.items()
            },
        )


def _account(columns: list[list[Any]], rows: list[int] | None = None) -> TimeAccount:
    """The sums of the exposures, shutter, overhead and idle ``columns`` over ``rows`` (all:
    None), in order (an empty sum is 0, as ``sum`` makes it)."""
    picked = columns if rows is None else [[c[k] for k in rows] for c in columns]
    exposures, shutter, overhead, idle = picked
    n = len(exposures)
    return TimeAccount(n, sum(exposures), sum(shutter), sum(overhead), sum(idle))


def _rounded(values: list[float], digits: int) -> list[float]:
    """``round(v, digits)`` of each value, found once per distinct value (bit for bit: -0.0
    is not 0.0); a plan's visits repeat a handful of durations."""
    if not values or set(map(type, values)) != {float}:
        return [round(v, digits) for v in values]
    bits = np.asarray(values, dtype=np.float64).view(np.int64)
    distinct, inverse = np.unique(bits, return_inverse=True)
    rounded = [round(v, digits) for v in distinct.view(np.float64).tolist()]
    return np.asarray(rounded, dtype=np.float64)[inverse.ravel()].tolist()


def _visit_order(cols: BlockColumns) -> tuple[list[tuple[str, str]], np.ndarray, np.ndarray]:
    """The visits of the blocks (``(target, visit_id)``; a block without one is a visit of its
    own, ``#k``) in order of first appearance; the block indices visit by visit, each visit's in
    time order of the block starts (the Julian dates as stored; equal starts keep their order);
    and the number of blocks of each visit."""
    targets, visits = cols.lists("target", "visit_id")
    ids: dict[tuple[str, str], int] = {}
    codes = [
        ids.setdefault((target, visit or f"#{k}"), len(ids))
        for k, (target, visit) in enumerate(zip(targets, visits, strict=True))
    ]
    code = np.asarray(codes, dtype=np.int64)
    start = cols.times["t_start_utc"]
    order = np.lexsort((np.atleast_1d(start.jd2), np.atleast_1d(start.jd1), code))
    return list(ids), order, np.bincount(code, minlength=len(ids))


def visit_columns(
    blocks: Sequence[Block], acquisition_s: float, trailing_readout: bool
) -> VisitColumns:
    """The visits of ``blocks`` (grouped by ``visit_id``; a block without one is a visit of its
    own) as :class:`VisitColumns`, in time order of their acquisition starts.

    A visit's times run from the acquisition start to the latest end (the first of equal ones,
    in time order), all visits' converted together; its sums run over its blocks in time
    order, those of one-block visits over whole columns at once."""
    if not blocks:
        return VisitColumns.of([])
    cols = block_columns(blocks)
    keys, order, counts = _visit_order(cols)
    heads = np.cumsum(counts) - counts
    first = order[heads]
    n_exp, exptime, readout_s = (cols.values[k] for k in ("n_exp", "exptime_s", "readout_s"))
    drop = 0 if trailing_readout else 1
    # one-block visits: the sums of one term, as sum() makes them (0 + x: -0.0 becomes 0.0)
    readout = (n_exp[first] - drop) * readout_s[first] + 0.0
    shutter = n_exp[first] * exptime[first] + 0.0
    exposures, last = n_exp[first], first.copy()
    _longer_visits(cols, (order, heads, counts), drop, (readout, shutter, exposures, last))
    start, end = cols.times["t_start_utc"][first], cols.times["t_end_utc"][last]
    last_readout = readout_s[order[heads + counts - 1]] if trailing_readout else 0.0
    span = np.atleast_1d((end - start).to_value("s")) + last_readout
    overhead = acquisition_s + readout
    idle = acquisition_s + span - shutter - overhead  # wall − shutter − overhead
    acq = start - TimeDelta(acquisition_s, format="sec")
    texts = [cols.values[k][first].tolist() for k in ("target", "night")]
    numbers = [exposures, shutter, overhead, np.where(idle > 0.0, idle, 0.0)]  # max(0.0, idle)
    columns = [[vid if not vid.startswith("#") else "" for _, vid in keys], *texts]
    columns += [*(isot(t.utc, 0) for t in (acq, start, end)), *(x.tolist() for x in numbers)]
    rank = sorted(range(len(keys)), key=columns[3].__getitem__)  # by acquisition start
    if rank == list(range(len(keys))):  # already in time order (a plan's blocks are)
        return VisitColumns(*columns)
    return VisitColumns(*([c[k] for k in rank] for c in columns))


def _longer_visits(
    cols: BlockColumns,
    grouping: tuple[np.ndarray, np.ndarray, np.ndarray],
    drop: int,
    out: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
) -> None:
    """The readout, shutter and exposure sums and the block of the latest end (the first of
    equal ones) of each visit of several blocks, into ``out``: sums over the blocks in time
    order (``grouping``: the blocks visit by visit, each visit's first and count), as ``sum``
    makes them over plain Python numbers."""
    order, heads, counts = grouping
    readout, shutter, exposures, last = out
    longer = np.flatnonzero(counts > 1).tolist()
    if not longer:
        return
    n_exp, exptime, readout_s = cols.lists("n_exp", "exptime_s", "readout_s")
    end_jd = cols.times["t_end_utc"].jd
    for g in longer:
        ks = order[heads[g] : heads[g] + counts[g]].tolist()
        last[g] = max(ks, key=end_jd.__getitem__)
        readout[g] = float(sum((n_exp[k] - drop) * readout_s[k] for k in ks))
        shutter[g] = float(sum(n_exp[k] * exptime[k] for k in ks))
        exposures[g] = sum(n_exp[k] for k in ks)


def visit_summaries(
    blocks: Sequence[Block], acquisition_s: float, trailing_readout: bool
) -> list[VisitSummary]:
    """One :class:`VisitSummary` per visit of ``blocks`` (grouped by ``visit_id``; a block
    without one is a visit of its own), in time order (:func:`visit_columns`)."""
    return visit_columns(blocks, acquisition_s, trailing_readout).summaries()


def time_accounting(visits: Sequence[VisitSummary]) -> PlanAccount:
    """The plan's :class:`PlanAccount`: the total of ``visits`` and one account per target."""
    return VisitColumns.of(visits).account()


class BlockRows(NamedTuple):
    """The columns of a blocks table :func:`accounts_from_blocks` reads, one value per row."""

    names: list[str]
    sessions: list[str]
    block_ids: list[str]
    starts: list[datetime]
    ends: list[datetime]
    n_exp: np.ndarray
    shutter_s: np.ndarray
    readout_s: np.ndarray
    acquisition_s: np.ndarray


def _idle_s(
    rows: list[int], starts: list[datetime], ends: list[datetime], readout_after: np.ndarray
) -> float:
    """Waits between the blocks of one visit [s]: gap minus the readout that ends a block."""
    order = sorted(rows, key=lambda i: starts[i])
    return sum(
        max((starts[b] - ends[a]).total_seconds() - readout_after[a], 0.0)
        for a, b in pairwise(order)
    )


def accounts_from_blocks(rows: BlockRows) -> dict[str, TimeAccount]:
    """Per-target :class:`TimeAccount` of a table's blocks, for a table without the plan's
    accounting (rules in the module docstring).

    Returns
    -------
    dict
        Target name → account, in order of first appearance.
    """
    starts, ends, n_exp, shutter = rows.starts, rows.ends, rows.n_exp, rows.shutter_s
    width = np.array([(e - s).total_seconds() for s, e in zip(starts, ends, strict=True)])
    readout_after = np.maximum(rows.readout_s - (width - shutter), 0.0)  # after the block's end
    visits: dict[tuple[str, str], list[int]] = {}
    for i, (name, session) in enumerate(zip(rows.names, rows.sessions, strict=True)):
        visits.setdefault((name, session or f"block {rows.block_ids[i]}"), []).append(i)
    out: dict[str, TimeAccount] = {}
    for (name, _), ks in visits.items():
        first = min(ks, key=lambda i: starts[i])
        account = TimeAccount(
            1,
            int(sum(n_exp[i] for i in ks)),
            float(sum(shutter[i] for i in ks)),
            float(rows.acquisition_s[first]) + float(sum(rows.readout_s[i] for i in ks)),
            _idle_s(ks, starts, ends, readout_after),
        )
        out[name] = out[name] + account if name in out else account
    return out
