"""Does the phase model save telescope time? The three strategies compared for one target.

For a target, a σ_v law that follows the exposure time and the overheads of a run
(:class:`~ucbplan.observing.schedule.PlanSettings`), each strategy of
:mod:`ucbplan.observing.precision.strategy` is given its best exposure time: the most information on
K per visit, or, with a goal, the fewest hours to reach it in balanced visits. ``targeted`` and
``phase-locked`` need the phase model; ``untargeted`` is what an observer does without it. The ratio
of their information per hour (or of their hours to the goal) answers the paper's question for that
target.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from ucbplan.errors import InputError
from ucbplan.observing.precision.goals import goal_info_needed, parse_goal
from ucbplan.observing.precision.strategy import compare_strategies, goal_times
from ucbplan.observing.schedule.exposure import (
    check_visit_holds_an_exposure,
    sigma_law,
    visit_shape,
)
from ucbplan.observing.schedule.settings import PlanSettings

if TYPE_CHECKING:
    from ucbplan.targets import Target


@dataclass(frozen=True)
class StrategyRow:
    """One strategy at its best exposure time (NaN / None where it is not possible)."""

    name: str
    exptime_s: float
    lambda_k: float
    exposures_per_visit: int
    info_per_visit: float
    info_per_hour: float
    spectra: int | None
    visits: int | None
    hours: float | None
    note: str


@dataclass(frozen=True)
class StrategyComparison:
    """The strategies of one target, best first by the figure of merit."""

    target: str
    sigma_v: str
    visit_s: float
    readout_s: float
    acquisition_s: float
    goal: str | None
    rows: tuple[StrategyRow, ...]

    @property
    def best(self) -> StrategyRow:
        """Fewest hours to the goal, else the most information per hour."""
        ok = [r for r in self.rows if r.info_per_visit > 0]
        if not ok:
            raise InputError(f"{self.target}: no strategy fits a visit; lengthen `visit`")
        if self.goal is not None:
            return min(ok, key=lambda r: r.hours if r.hours is not None else math.inf)
        return max(ok, key=lambda r: r.info_per_hour)

    def ratio(self) -> float | None:
        """Targeted over untargeted: hours of untargeted / hours of targeted to the goal, else
        information per hour of targeted / untargeted (None when one is not possible)."""
        by = {r.name: r for r in self.rows}
        t, u = by["targeted"], by["untargeted"]
        if self.goal is not None:
            if t.hours is None or u.hours is None:
                return None
            return u.hours / t.hours
        if t.info_per_hour <= 0 or u.info_per_hour <= 0:
            return None
        return t.info_per_hour / u.info_per_hour

    def to_dict(self) -> dict[str, Any]:
        """Plain values for JSON (NaN → None)."""

        def clean(v: Any) -> Any:
            return None if isinstance(v, float) and not math.isfinite(v) else v

        return {
            "target": self.target,
            "sigma_v": self.sigma_v,
            "visit_s": self.visit_s,
            "readout_s": self.readout_s,
            "acquisition_s": self.acquisition_s,
            "goal": self.goal,
            "units": {"info": "(km/s)^-2", "info_per_hour": "(km/s)^-2 / h", "hours": "h"},
            "strategies": [{k: clean(v) for k, v in vars(r).items()} for r in self.rows],
            "best": self.best.name,
            "targeted_over_untargeted": clean(self.ratio()),
        }


def compare_target_strategies(target: Target, settings: PlanSettings) -> StrategyComparison:
    """Every strategy's best exposure time for ``target`` under ``settings`` (module notes).

    The visit is ``settings.visit_s``, else ``settings.max_visit_s``; σ_v is evaluated at
    airmass 1.

    Raises
    ------
    InputError
        σ_v does not follow the exposure time (give ``30km/s@600s``); the target has no
        magnitude in the band of the σ_v reference; a goal the target file cannot serve; a
        visit that holds no exposure (checked before anything is printed).
    """
    law = sigma_law(target, settings)
    if law is None:
        raise InputError(
            "sigma_v: expected the RV precision of one spectrum of a given length, e.g. "
            "30km/s@600s, so that exposure times can be compared"
        )
    mag = law.target_mag(target.magnitudes, target.name)

    def sigma(t: NDArray[np.float64]) -> NDArray[np.float64]:
        return law.sigma(t, 1.0, mag)

    check_visit_holds_an_exposure(target, settings)
    visit = settings.visit_s if settings.visit_s is not None else settings.max_visit_s
    shape = visit_shape(target, settings, visit)
    rows: list[StrategyRow] = []
    if settings.goal is not None:
        need = goal_info_needed(parse_goal(settings.goal), target)
        for g in goal_times(need, shape, sigma, settings.goal):
            ok = g.strategy.possible
            rows.append(_row(g.strategy, g.n_spectra if ok else None, g.n_visits if ok else None,
                             g.hours if ok else None))  # fmt: skip
    else:
        for r in compare_strategies(shape, sigma):
            rows.append(_row(r, None, None, None))
    comparison = StrategyComparison(
        target.name,
        law.describe(),
        visit,
        shape.readout_s,
        shape.acquisition_s,
        settings.goal,
        tuple(rows),
    )
    _ = comparison.best  # refused now (no strategy fits), not later when printed
    return comparison


def _row(r: Any, spectra: int | None, visits: int | None, hours: float | None) -> StrategyRow:
    return StrategyRow(
        r.name,
        r.exptime_s,
        r.lambda_k,
        r.n_exposures,
        r.info_per_visit,
        r.info_per_hour,
        spectra,
        visits,
        hours,
        r.note,
    )
