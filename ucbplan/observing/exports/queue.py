"""What a service-mode queue can execute, said in one line (docs/exports.md).

A queue runs a unit's exposures back to back after one acquisition
(:class:`~ucbplan.observing.exports.visitgroups.ExportUnit`); a targeted visit, which waits
between exposures for the next orbital phase, runs as planned only in visitor mode. Exporting it
to a queue format is not an error: one note names the units that wait and the remedy — the
back-to-back cadences of the same visit, with their information per hour from the plan's
strategy table (so the observer sees the cost), ``ucbplan plan --service-mode`` (which plans only
those), or visitor mode. ``--strict`` makes it an error (no file) for pipelines that must not
submit a degraded plan.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from astropy.table import Table

from ucbplan.errors import InputError, shorten
from ucbplan.inputs import is_number
from ucbplan.observing.exports.interface import ExportOptions
from ucbplan.observing.exports.provenance import meta
from ucbplan.observing.exports.visitgroups import ExportUnit

#: The cadences a service-mode queue executes: exposures back to back after one acquisition.
BACK_TO_BACK = ("phase-locked", "untargeted")


class ServiceModeError(InputError):
    """``--strict``: a unit waits between exposures, which a service-mode queue cannot."""


def untargeted(table: Table, target: str) -> bool:
    """Whether the plan took ``target``'s exposures at any phase (untargeted cadence, from
    ``meta['planning']``): no window rounding can then cost it a phase."""
    planning = meta(table).get("planning")
    if not isinstance(planning, dict):
        return False
    targets = planning.get("targets")
    entry = targets.get(target) if isinstance(targets, dict) else None
    strategy = entry.get("strategy") if isinstance(entry, dict) else None
    if isinstance(strategy, dict):
        return strategy.get("chosen") == "untargeted"
    return planning.get("cadence") == "untargeted"


def _strategies(table: Table, target: str) -> dict[str, Any]:
    """The plan's strategy table of ``target`` (``meta['planning']``), or an empty dict."""
    planning = meta(table).get("planning")
    targets = planning.get("targets") if isinstance(planning, dict) else None
    entry = targets.get(target) if isinstance(targets, dict) else None
    strategy = entry.get("strategy") if isinstance(entry, dict) else None
    rows = strategy.get("strategies") if isinstance(strategy, dict) else None
    return rows if isinstance(rows, dict) else {}


def alternatives(table: Table, target: str) -> str:
    """The back-to-back cadences of ``target``'s visit with their exposures and information per
    hour as a fraction of the best strategy's, from the plan's strategy table; else the
    options."""
    facts = _strategies(table, target)
    parts = []
    for name in BACK_TO_BACK:
        row = facts.get(name)
        if not isinstance(row, dict):
            continue
        n, t, best = (
            row.get("exposures_per_visit"),
            row.get("exptime_s"),
            row.get("fraction_of_best"),
        )
        if is_number(n) and is_number(t) and is_number(best) and float(n) >= 1:
            parts.append(f"{name} {int(n)} x {float(t):g} s, {float(best):.0%} of the best info/h")
        else:
            parts.append(f"{name} impossible")
    return "; ".join(parts) if parts else "--cadence phase-locked or untargeted"


def _rate(row: Any) -> float:
    """Information per hour of one strategy-table row (0 when it has none)."""
    rate = row.get("info_per_hour") if isinstance(row, dict) else None
    return float(rate) if is_number(rate) and float(rate) > 0 else 0.0


def queue_note(
    table: Table, units: Sequence[ExportUnit], fmt: str, options: ExportOptions
) -> list[str]:
    """One note on the units a queue cannot execute as planned (module notes), or none.

    Raises
    ------
    ServiceModeError
        ``options.strict`` and some unit waits between its exposures.
    """
    waiting = [u for u in units if not u.back_to_back]
    if not waiting:
        return []
    first = waiting[0]
    text = (
        f"{fmt}: {len(waiting)} of {len(units)} visits ({shorten(first.unit_id, 40)}) wait up "
        f"to {first.max_wait_s:.0f} s ({first.drift_s:.0f} s in all) between exposures for their "
        "phases; a service-mode queue "
        "runs them back to back. Queue-executable: re-planned with `service_mode` "
        f"({alternatives(table, first.target)}), or visitor mode"
    )
    if options.strict:
        raise ServiceModeError(f"{text} (`strict`: no file written)")
    return [text]
