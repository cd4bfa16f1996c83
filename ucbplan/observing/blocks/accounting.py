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
from dataclasses import dataclass, field
from datetime import datetime
from itertools import pairwise
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


def _groups(cols: BlockColumns) -> dict[tuple[str, str], list[int]]:
    """Block indices per visit (``(target, visit_id)``; a block without one is its own visit),
    each in time order of the block starts (the Julian dates of the times as stored)."""
    groups: dict[tuple[str, str], list[int]] = {}
    targets, visits = cols.lists("target", "visit_id")
    for k, (target, visit) in enumerate(zip(targets, visits, strict=True)):
        groups.setdefault((target, visit or f"#{k}"), []).append(k)
    start = cols.times["t_start_utc"]
    keys = list(zip(start.jd1.tolist(), start.jd2.tolist(), strict=True))
    return {g: sorted(ks, key=keys.__getitem__) for g, ks in groups.items()}


def visit_summaries(
    blocks: Sequence[Block], acquisition_s: float, trailing_readout: bool
) -> list[VisitSummary]:
    """One :class:`VisitSummary` per visit of ``blocks`` (grouped by ``visit_id``; a block
    without one is a visit of its own), in time order.

    The times of all visits are converted together (one astropy call per quantity, not per
    visit); sums over a visit's blocks run in time order, as they always did."""
    if not blocks:
        return []
    cols = block_columns(blocks)
    groups = _groups(cols)
    starts, ends = cols.times["t_start_utc"], cols.times["t_end_utc"]
    end_jd = ends.jd
    first = [ks[0] for ks in groups.values()]
    # the latest end (the first of equal ones, in time order of the starts)
    last = [max(ks, key=end_jd.__getitem__) for ks in groups.values()]
    start, end = starts[first], ends[last]
    spans = np.atleast_1d((end - start).to_value("s")).tolist()
    acq = start - TimeDelta(acquisition_s, format="sec")
    iso = [isot(t.utc, 0) for t in (acq, start, end)]
    cells = _VisitCells(*cols.lists("target", "night", "n_exp", "exptime_s", "readout_s"))
    out = [
        _summary(cells, ks, vid, span, (a, s, e), acquisition_s, trailing_readout)
        for ((_, vid), ks), span, a, s, e in zip(groups.items(), spans, *iso, strict=True)
    ]
    out.sort(key=lambda v: v.acq_start_utc)
    return out


class _VisitCells(NamedTuple):
    """The block columns a visit summary reads, as lists of plain values."""

    target: list[str]
    night: list[str]
    n_exp: list[int]
    exptime_s: list[float]
    readout_s: list[float]


def _summary(
    c: _VisitCells,
    ks: list[int],
    vid: str,
    span_s: float,
    iso: tuple[str, str, str],
    acquisition_s: float,
    trailing_readout: bool,
) -> VisitSummary:
    """One visit from its blocks ``ks`` (in time order), first start to latest end [s] and the
    ISO times of its acquisition start, first start and latest end."""
    drop = 0 if trailing_readout else 1
    if len(ks) == 1:  # the sums of one block, as sum() makes them (0 + x: -0.0 becomes 0.0)
        k = ks[0]
        readout = float(0 + (c.n_exp[k] - drop) * c.readout_s[k])
        shutter = float(0 + c.n_exp[k] * c.exptime_s[k])
    else:
        readout = float(sum((c.n_exp[k] - drop) * c.readout_s[k] for k in ks))
        shutter = float(sum(c.n_exp[k] * c.exptime_s[k] for k in ks))
    last_readout = c.readout_s[ks[-1]] if trailing_readout else 0.0
    span = span_s + last_readout
    overhead = acquisition_s + readout
    wall = acquisition_s + span
    return VisitSummary(
        visit_id=vid if not vid.startswith("#") else "",
        target=c.target[ks[0]],
        night=c.night[ks[0]],
        acq_start_utc=str(iso[0]),
        start_utc=str(iso[1]),
        end_utc=str(iso[2]),
        exposures=sum(c.n_exp[k] for k in ks) if len(ks) > 1 else c.n_exp[ks[0]],
        shutter_s=shutter,
        overhead_s=overhead,
        idle_s=max(0.0, wall - shutter - overhead),
    )


def _account(visits: Sequence[VisitSummary]) -> TimeAccount:
    """The sum of ``visits`` (an empty sum is 0, as ``sum`` makes it)."""
    return TimeAccount(
        len(visits),
        sum(v.exposures for v in visits),
        sum(v.shutter_s for v in visits),
        sum(v.overhead_s for v in visits),
        sum(v.idle_s for v in visits),
    )


def time_accounting(visits: Sequence[VisitSummary]) -> PlanAccount:
    """The plan's :class:`PlanAccount`: the total of ``visits`` and one account per target."""
    names = list(dict.fromkeys(v.target for v in visits))
    return PlanAccount(
        _account(visits), {n: _account([v for v in visits if v.target == n]) for n in names}
    )


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
