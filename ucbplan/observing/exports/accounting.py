"""Telescope time a plan asks for: shutter, overheads and idle time per target and in total.

The plan writes its own accounting into the blocks table ``meta['time_accounting']`` as
``{"total": {...}, "targets": {NAME: {...}}}`` with the keys of :data:`ACCOUNTING_KEYS`; the
proposal export uses it as written. A table without it (an older planner, a hand-made table) is
accounted from its blocks (:func:`accounting_from_blocks`, docs/exports.md "Time accounting"):

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
from collections.abc import Mapping
from dataclasses import dataclass
from datetime import datetime
from itertools import pairwise
from typing import Any

import numpy as np
from astropy.table import Table

from ucbplan.errors import InputFileError, shorten
from ucbplan.inputs import is_number
from ucbplan.observing.exports.columns import (
    acquisition_s,
    floats,
    readout_total_s,
    required_times,
    strings,
)
from ucbplan.observing.exports.interface import ExportOptions
from ucbplan.observing.exports.provenance import meta

__all__ = ["ACCOUNTING_KEYS", "TimeAccount", "accounting_from_blocks", "plan_accounting"]

#: Keys of one ``meta['time_accounting']`` entry (counts, then seconds, then a fraction).
ACCOUNTING_KEYS = ("visits", "exposures", "shutter_s", "overhead_s", "idle_s", "efficiency")


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


def _idle_s(
    rows: list[int], starts: list[datetime], ends: list[datetime], readout_after: np.ndarray
) -> float:
    """Waits between the blocks of one visit [s]: gap minus the readout that ends a block."""
    order = sorted(rows, key=lambda i: starts[i])
    return sum(
        max((starts[b] - ends[a]).total_seconds() - readout_after[a], 0.0)
        for a, b in pairwise(order)
    )


def accounting_from_blocks(
    table: Table, options: ExportOptions, notes: list[str]
) -> dict[str, TimeAccount]:
    """Per-target :class:`TimeAccount` computed from the blocks (rules in the module docstring).

    Returns
    -------
    dict
        Target name → account, in order of first appearance.
    """
    names, sessions = strings(table, "target"), strings(table, "session_id")
    blocks = strings(table, "block_id")
    starts, ends = required_times(table, "t_start_utc"), required_times(table, "t_end_utc")
    n_exp = floats(table, "n_exp")
    shutter = n_exp * floats(table, "exptime_s", unit="s")
    readout = readout_total_s(table, notes)
    width = np.array([(e - s).total_seconds() for s, e in zip(starts, ends, strict=True)])
    readout_after = np.maximum(readout - (width - shutter), 0.0)  # after the block's end
    acq = acquisition_s(table, options, notes)
    visits: dict[tuple[str, str], list[int]] = {}
    for i, (name, session) in enumerate(zip(names, sessions, strict=True)):
        visits.setdefault((name, session or f"block {blocks[i]}"), []).append(i)
    out: dict[str, TimeAccount] = {}
    for (name, _), rows in visits.items():
        first = min(rows, key=lambda i: starts[i])
        account = TimeAccount(
            1,
            int(sum(n_exp[i] for i in rows)),
            float(sum(shutter[i] for i in rows)),
            float(acq[first]) + float(sum(readout[i] for i in rows)),
            _idle_s(rows, starts, ends, readout_after),
        )
        out[name] = out[name] + account if name in out else account
    return out


def _number(where: str, value: Any, integer: bool) -> float:
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


def _account(where: str, entry: Any) -> TimeAccount:
    if not isinstance(entry, Mapping):
        raise InputFileError(
            f"blocks table meta time_accounting: {where}: expected a mapping with "
            f"{', '.join(ACCOUNTING_KEYS)}; regenerate the table with `ucbplan plan`"
        )
    v = {
        k: _number(f"{where}.{k}", entry.get(k), k in ("visits", "exposures"))
        for k in ACCOUNTING_KEYS[:5]
    }
    return TimeAccount(
        int(v["visits"]), int(v["exposures"]), v["shutter_s"], v["overhead_s"], v["idle_s"]
    )


def plan_accounting(
    table: Table, options: ExportOptions, notes: list[str]
) -> tuple[dict[str, TimeAccount], str]:
    """Per-target accounts and where they come from (``"plan"`` or ``"blocks"``).

    The plan's own ``meta['time_accounting']`` when it covers every target of the table, else
    :func:`accounting_from_blocks` (with a note). A plan account whose shutter time differs from
    the blocks' by more than 1 % gets a note (the table was edited after planning).

    Raises
    ------
    InputFileError
        A ``time_accounting`` entry that is not a mapping of non-negative numbers.
    """
    from_blocks = accounting_from_blocks(table, options, notes)
    given = meta(table).get("time_accounting")
    targets = given.get("targets") if isinstance(given, Mapping) else None
    if not isinstance(targets, Mapping) or not set(from_blocks) <= set(map(str, targets)):
        notes.append(
            "proposal: no time_accounting for every target in the plan's metadata: time "
            "computed from the blocks (idle gaps within a visit included; docs/exports.md)"
        )
        return from_blocks, "blocks"
    out = {name: _account(f"targets.{shorten(name, 40)}", targets[name]) for name in from_blocks}
    for name, account in out.items():
        ref = from_blocks[name].shutter_s
        if abs(account.shutter_s - ref) > 0.01 * max(ref, 1.0):
            notes.append(
                f"proposal: {shorten(name, 40)}: the plan accounts {account.shutter_s:.0f} s "
                f"shutter time but its blocks hold {ref:.0f} s (table edited after planning?)"
            )
    return out, "plan"
