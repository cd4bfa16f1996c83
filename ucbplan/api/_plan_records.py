"""The typed records of a :class:`~ucbplan.api.plan_result.Plan`, read from its table's meta.

A plan's meta (``ucbplan plan -o plan.ecsv``) holds the exposure-strategy comparison and the goal's
promised precision per target (``planning.targets.NAME``); :func:`strategies_of` and
:func:`goals_of` turn them into frozen records with astropy quantities, the same for a plan just
made and one read back from its file. :func:`as_qtable` gives the blocks table with ``Time`` and
``Quantity`` columns. Nothing heavy is imported until a function runs.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from ucbplan.errors import InputFileError

if TYPE_CHECKING:
    from astropy.table import QTable, Table
    from astropy.units import Quantity

#: The unit of the information on K [(km/s)⁻²].
_INFO_UNIT = "km-2 s2"


@dataclass(frozen=True, slots=True)
class StrategyRecord:
    """One exposure strategy of one target, as the planner compared them (``plan``'s "Exposure
    strategy" table).

    Attributes
    ----------
    target : str
        Target name.
    strategy : str
        ``targeted``, ``phase-locked`` or ``untargeted``.
    chosen : bool
        The strategy planned.
    exptime : Quantity or None
        Its best exposure time [s]; None when the strategy is not possible (see ``note``).
    lambda_k : float or None
        Smearing factor Λ_K of one exposure (None: not possible).
    exposures_per_visit : int
        Exposures in one full visit.
    info_per_visit : Quantity
        Information on K per full visit [(km/s)⁻²].
    info_per_hour : Quantity
        Information on K per hour of the visit's wall time [(km/s)⁻² h⁻¹].
    fraction_of_best : float
        ``info_per_visit`` over the best strategy's (1 for the best).
    goal_hours : Quantity or None
        With a goal: the hours this strategy needs to reach it [h] (None: no goal, or never).
    note : str
        Why the strategy is not possible ('' when it is).
    """

    target: str
    strategy: str
    chosen: bool
    exptime: Quantity | None
    lambda_k: float | None
    exposures_per_visit: int
    info_per_visit: Quantity
    info_per_hour: Quantity
    fraction_of_best: float
    goal_hours: Quantity | None
    note: str

    @property
    def possible(self) -> bool:
        """Whether the strategy can be observed at all (an exposure keeps the Λ_K floor)."""
        return self.exptime is not None


@dataclass(frozen=True, slots=True)
class GoalRecord:
    """A target's precision goal (``plan --goal``) and what the plan promises for it.

    Attributes
    ----------
    target : str
        Target name.
    goal : str
        The goal as given (``sigma_K=5km/s``).
    description : str
        The goal in words (``σ(K) ≤ 5 km/s``).
    quantity : str
        What the goal bounds (``sigma_K``, ``K1``, ``K2``, ``q``, ``M1``, ``M2``).
    relative : bool
        Whether the bound is a fraction of the quantity's value.
    n_spectra : int
        Spectra the goal plan needs.
    expected : Quantity
        The σ the planned spectra are expected to reach: km/s, Msun or dimensionless (a fraction
        of the value when ``relative``).
    """

    target: str
    goal: str
    description: str
    quantity: str
    relative: bool
    n_spectra: int
    expected: Quantity


def planning_targets(meta: Mapping[str, Any]) -> dict[str, Any]:
    """``meta['planning']['targets']``: the per-target planning facts ({} when absent), in the
    order of the meta's ``targets`` list (a file's YAML header sorts the keys of a mapping).

    Raises
    ------
    InputFileError
        When ``planning`` is there but is not a mapping with a ``targets`` mapping.
    """
    planning = meta.get("planning")
    if planning is None:
        return {}
    targets = planning.get("targets") if isinstance(planning, Mapping) else None
    if not isinstance(targets, Mapping):
        raise InputFileError(
            "blocks table meta planning: expected a mapping with targets; regenerate the table "
            "with `ucbplan plan`"
        )
    listed = meta.get("targets")
    names = (
        [t.get("name") for t in listed if isinstance(t, Mapping)]
        if isinstance(listed, list)
        else []
    )
    order = {name: k for k, name in enumerate(names)}
    return dict(sorted(targets.items(), key=lambda item: order.get(item[0], len(order))))


def _quantity(value: Any, unit: str) -> Quantity | None:
    """``value`` in ``unit`` (None stays None)."""
    if value is None:
        return None
    from astropy import units as u

    return float(value) * u.Unit(unit)


def _strategy(target: str, name: str, row: Mapping[str, Any], chosen: str) -> StrategyRecord:
    hours = row.get("goal_hours")
    return StrategyRecord(
        target=target,
        strategy=name,
        chosen=name == chosen,
        exptime=_quantity(row.get("exptime_s"), "s"),
        lambda_k=None if row.get("lambda_k") is None else float(row["lambda_k"]),
        exposures_per_visit=int(row.get("exposures_per_visit", 0)),
        info_per_visit=_quantity(row.get("info_per_visit", 0.0), _INFO_UNIT),
        info_per_hour=_quantity(row.get("info_per_hour", 0.0), f"{_INFO_UNIT} h-1"),
        fraction_of_best=float(row.get("fraction_of_best", 0.0)),
        goal_hours=_quantity(hours if hours is None or math.isfinite(hours) else None, "h"),
        note=str(row.get("note", "")),
    )


def _strategy_rank(name: str) -> tuple[int, str]:
    """The planner's order of the strategies (a file's YAML header sorts them by name)."""
    from ucbplan.observing.precision.strategy import STRATEGIES

    order = list(STRATEGIES)
    return (order.index(name) if name in order else len(order), name)


def strategies_of(meta: Mapping[str, Any]) -> tuple[StrategyRecord, ...]:
    """Every target's strategy comparison, in the meta's order (targets whose exposure time was
    chosen for information per visit; none otherwise)."""
    out = []
    for target, entry in planning_targets(meta).items():
        facts = entry.get("strategy") if isinstance(entry, Mapping) else None
        if not isinstance(facts, Mapping):
            continue
        chosen = str(facts.get("chosen", ""))
        rows = dict(facts.get("strategies", {}))
        for name in sorted(rows, key=_strategy_rank):
            out.append(_strategy(str(target), str(name), rows[name], chosen))
    return tuple(out)


def goals_of(meta: Mapping[str, Any]) -> tuple[GoalRecord, ...]:
    """Every target's goal and its promised σ (none without ``--goal``)."""
    from astropy import units as u

    from ucbplan.observing.precision.goals import GOAL_QUANTITIES, parse_goal

    text = (meta.get("planning") or {}).get("goal")
    if not text:
        return ()
    goal = parse_goal(str(text))
    unit = u.dimensionless_unscaled if goal.relative else u.Unit(GOAL_QUANTITIES[goal.quantity])
    return tuple(
        GoalRecord(
            target=str(target),
            goal=goal.text,
            description=goal.describe(),
            quantity=goal.quantity,
            relative=goal.relative,
            n_spectra=int(entry["goal_spectra"]),
            expected=float(entry["goal_expected"]) * unit,
        )
        for target, entry in planning_targets(meta).items()
        if isinstance(entry, Mapping) and "goal_spectra" in entry
    )


def _time_column(column: Any, scale: str, precision: int) -> Any:
    """ISO text → ``Time`` in ``scale`` (blank cells masked)."""
    import numpy as np
    from astropy.time import Time

    text = np.asarray(column, dtype=str)
    blank = (np.char.str_len(np.char.strip(text)) == 0) | np.ma.getmaskarray(column)
    filled = np.where(blank, "2000-01-01T00:00:00", text) if blank.any() else text
    times = Time(filled.tolist() if len(text) else [], format="isot", scale=scale)
    times.precision = precision
    if blank.any():
        times[blank] = np.ma.masked
    return times


def as_qtable(table: Table) -> QTable:
    """A copy of a blocks table with ``Time`` columns for the UTC and TDB times (ms and µs
    precision, as written) and ``Quantity`` columns for those with a unit; names, local times
    and sexagesimal text stay text. The meta is copied."""
    from astropy.table import QTable

    from ucbplan.observing.blocks.schema import COLUMNS

    scales = {c.name: (c.kind, 3 if c.kind == "utc" else 6) for c in COLUMNS}
    out = QTable(table, copy=True)
    for name in table.colnames:
        kind, precision = scales.get(name, ("", 0))
        if kind in ("utc", "tdb"):
            out[name] = _time_column(table[name], kind, precision)
    return out
