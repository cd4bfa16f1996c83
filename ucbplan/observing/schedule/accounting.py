"""Time accounting of a plan: visits, exposures, shutter-open time, overheads, idle time.

A visit (``visit_id``) is one acquisition of ``acquisition_s`` that ends when its first exposure
starts, then its blocks. Its wall time runs from the acquisition start to the end of the last
exposure, plus that exposure's readout when exposures are read out one by one inside a visit
(``--visit``; a co-added block of ``n_exp`` exposures has ``n_exp − 1`` readouts inside it):

    shutter  = Σ n_exp · exptime
    overhead = acquisition + Σ (readouts) · readout
    idle     = wall − shutter − overhead          (waiting for the next anchor's phase)
    efficiency = shutter / (shutter + overhead + idle) = shutter / wall

These are the numbers the proposal export reads from the ECSV meta (``time_accounting``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
from astropy.time import TimeDelta

from ucbplan.observing.blockcolumns import BlockColumns, block_columns, isot
from ucbplan.observing.blocks import Block
from ucbplan.observing.timeconv import quiet_erfa

__all__ = ["ACCOUNT_KEYS", "VisitSummary", "time_accounting", "visit_summaries"]

#: Keys of one time-accounting entry (the proposal export reads exactly these).
ACCOUNT_KEYS = ("visits", "exposures", "shutter_s", "overhead_s", "idle_s", "efficiency")


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
    with quiet_erfa():
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


def _entry(visits: Sequence[VisitSummary]) -> dict[str, Any]:
    shutter = sum(v.shutter_s for v in visits)
    overhead = sum(v.overhead_s for v in visits)
    idle = sum(v.idle_s for v in visits)
    wall = shutter + overhead + idle
    return {
        "visits": len(visits),
        "exposures": sum(v.exposures for v in visits),
        "shutter_s": round(shutter, 3),
        "overhead_s": round(overhead, 3),
        "idle_s": round(idle, 3),
        "efficiency": round(shutter / wall, 6) if wall > 0 else 0.0,
    }


def time_accounting(visits: Sequence[VisitSummary]) -> dict[str, Any]:
    """``{"total": {...}, "targets": {NAME: {...}}}`` with the :data:`ACCOUNT_KEYS` each."""
    names = list(dict.fromkeys(v.target for v in visits))
    return {
        "total": _entry(visits),
        "targets": {n: _entry([v for v in visits if v.target == n]) for n in names},
    }
