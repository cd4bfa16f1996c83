"""``ucbplan plan`` as one library call: target files, site and nights in; blocks table out.

:func:`plan_files` resolves the site, the nights and the targets (with priority overrides) the
way the ``plan`` command spells them, runs :func:`~ucbplan.observing.schedule.plan_nights`, and
returns a :class:`PlanRun` that builds the master blocks table with its provenance.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from datetime import date
from functools import cached_property
from pathlib import Path
from typing import Any

from astropy.table import Table

from ucbplan.errors import InputError, shorten
from ucbplan.inputs import check_range
from ucbplan.observing.blocks.accounting import (
    PlanAccount,
    VisitColumns,
    VisitSummary,
    visit_columns,
)
from ucbplan.observing.blocks.arrays import block_columns
from ucbplan.observing.blocks.block import ExposurePlan
from ucbplan.observing.blocks.make import blocks_to_table, make_meta
from ucbplan.observing.observatory.sites import Site, resolve_site
from ucbplan.observing.precision.goals import GoalPlan
from ucbplan.observing.schedule.exposure import strategy_facts
from ucbplan.observing.schedule.goalplan import info_of_columns
from ucbplan.observing.schedule.nights import night_dates
from ucbplan.observing.schedule.planner import PlanSchedule, plan_nights
from ucbplan.observing.schedule.records import slug
from ucbplan.observing.schedule.settings import PlanSettings
from ucbplan.targets import Target, load_targets

#: Largest |priority| (priorities only order the targets).
MAX_PRIORITY = 1.0e9


def parse_priorities(items: Sequence[str]) -> dict[str, float]:
    """``NAME=NUMBER`` overrides → {lower-case name: priority}.

    Raises
    ------
    InputError
        For an item that is not ``NAME=NUMBER`` with a finite number.
    """
    values: dict[str, float] = {}
    for item in items:
        name, sep, value = item.rpartition("=") if isinstance(item, str) else ("", "", "")
        try:
            number = float(value) if len(value) <= 40 else math.nan
        except ValueError:
            number = math.nan
        if not sep or not name.strip() or not math.isfinite(number):
            raise InputError(
                "priority: expected NAME=NUMBER (a target name and a finite number, e.g. "
                f"'HM Cnc=2'), got {shorten(item, 80)}"
            )
        values[name.strip().lower()] = check_range(
            f"priority {shorten(name.strip(), 40)}", number, -MAX_PRIORITY, MAX_PRIORITY
        )
    return values


def with_priorities(
    targets: Sequence[Target], priorities: Mapping[str, float] | Sequence[str]
) -> list[Target]:
    """``targets`` with priorities overridden by name (case-insensitive).

    Parameters
    ----------
    targets : sequence of Target
        Loaded targets.
    priorities : mapping or sequence of str
        {name: priority}, or ``NAME=NUMBER`` strings as ``--priority`` takes them.

    Raises
    ------
    UcbplanError
        For a malformed override or a name that is not one of the targets.
    """
    if isinstance(priorities, Mapping):
        values = parse_priorities([f"{k}={v}" for k, v in priorities.items()])
    else:
        values = parse_priorities(priorities)
    known = {t.name.lower() for t in targets}
    unknown = sorted(set(values) - known)
    if unknown:
        names = ", ".join(t.name for t in targets)
        names = names if len(names) <= 200 else f"{names[:199]}…"
        raise InputError(f"priority: no target named {shorten(unknown[0], 60)}; targets: {names}")
    return [replace(t, priority=values.get(t.name.lower(), t.priority)) for t in targets]


def planned_exposure(
    plans: Sequence[ExposurePlan], requested: ExposurePlan
) -> dict[str, float | int | None]:
    """The table meta's ``exposure``: what the run planned, not what was asked for.

    Each of the exposure time, exposures per block and readout is the value every target's
    exposure plan shares (the exposure time chosen for information per visit, or capped at the
    smearing floor), or None where the targets' plans differ (each target's is in the meta's
    ``planning.targets``); ``requested`` (the options) when no target has a plan.
    """
    plans = list(plans) or [requested]
    out: dict[str, float | int | None] = {}
    for key in ("exptime_s", "n_exp", "readout_s"):
        values = {getattr(p, key) for p in plans}
        out[key] = values.pop() if len(values) == 1 else None
    return out


@dataclass(frozen=True)
class PlanRun:
    """A finished ``plan``: its inputs and :class:`PlanSchedule`, and the blocks table."""

    targets: list[Target]
    site: Site
    nights: list[date]
    settings: PlanSettings
    result: PlanSchedule

    def failure(self) -> str | None:
        """Why no block at all could be planned (None if some were), grouped by target and
        reason over the nights; None too when the spectra already taken reach every target's
        goal)."""
        goals = self.result.goals
        reached = len(goals) == len(self.targets) and all(g.n_spectra == 0 for g in goals.values())
        if self.result.blocks or reached:
            return None
        grouped: dict[tuple[str, str], list[str]] = {}
        for m in self.result.unplaced:
            grouped.setdefault((m.target, m.reason), []).append(m.night)
        parts = []
        for (name, reason), nights in grouped.items():
            when = (
                nights[0] if len(nights) == 1 else f"{len(nights)} nights {nights[0]}..{nights[-1]}"
            )
            parts.append(f"{name} ({when}): {reason}")
        return f"no block could be planned at {self.site.name}: {'; '.join(parts)}"

    @cached_property
    def visit_columns(self) -> VisitColumns:
        """The visits as columns, computed once per run (the table meta, the accounting and the
        terminal report all read them)."""
        trailing = self.settings.plans_visits
        return visit_columns(self.result.blocks, self.settings.overhead_s, trailing)

    @cached_property
    def _visits(self) -> tuple[VisitSummary, ...]:
        return tuple(self.visit_columns.summaries())

    def visits(self) -> list[VisitSummary]:
        """One summary per visit (acquisition + exposures), in time order."""
        return list(self._visits)

    @cached_property
    def time_account(self) -> PlanAccount:
        """The time accounting, summed once per run (the table meta and the report read it)."""
        return self.visit_columns.account()

    def accounting(self) -> dict[str, Any]:
        """Time accounting as the table meta holds it, ``{"total": {...}, "targets": {NAME:
        {...}}}`` (:meth:`~ucbplan.observing.blocks.accounting.PlanAccount.as_meta`); a new dict."""
        return self.time_account.as_meta()

    def _planning(self) -> dict[str, Any]:
        """Visit, instrument, cadence and goal facts of the run, per target."""
        s = self.settings
        out: dict[str, Any] = {
            "visit_s": s.visit_s,
            "cadence": s.cadence,
            "min_lambda_k": s.lambda_k_floor,
            "allow_smeared": s.allow_smeared,
            "instrument": s.instrument.name if s.instrument is not None else None,
            "goal": s.goal,
        }
        if s.service_mode:  # only when asked: plans without it keep their meta
            out["service_mode"] = True
        per_target = {}
        for name, te in self.result.exposures.items():
            entry: dict[str, Any] = {
                "exptime_s": te.plan.exptime_s,
                "readout_s": te.plan.readout_s,
                "step_s": round(te.step_s, 6),
                "duty_cycle": round(te.duty_cycle, 6),
                "lambda_k": round(te.lambda_k, 6),
            }
            goal = self.result.goals.get(name)
            if goal is not None:
                entry["goal_spectra"] = goal.n_spectra
                entry["goal_expected"] = goal.expected
                if goal.collected_spectra:
                    entry.update(_collected_facts(goal))
            if te.results:
                entry["strategy"] = strategy_facts(te, self.collected_info().get(name, 0.0))
            per_target[name] = entry
        out["targets"] = per_target
        if self.result.shortfalls:  # a replan's goals out of reach
            out["shortfalls"] = self.shortfall_lines()
        if s.observed or s.sigma_v_scale != 1.0:
            out["sigma_v_scale"] = s.sigma_v_scale
            spectra = [str(x.source) for x in s.observed]
            out["observed"] = list(dict.fromkeys(spectra))
        return out

    def shortfall_lines(self) -> list[str]:
        """One line per goal the nights do not reach (a replan's): how far short, and the hours
        and nights more that would reach it (:meth:`GoalShortfall.line`)."""
        targets = self.time_account.targets
        return [
            s.line(targets[s.target].total_s if s.target in targets else 0.0, len(self.nights))
            for s in self.result.shortfalls
        ]

    def collected_info(self) -> dict[str, float]:
        """Information on K each target's planned spectra collect [(km/s)⁻²], from the rows
        (Σ (Λ_K cos u)²/σ_v²)."""
        cols = block_columns(self.result.blocks)
        names = cols.values["target"]
        return {
            k: info_of_columns(cols, self.settings.spec.u_values, names == k)
            for k in dict.fromkeys(names.tolist())
        }

    def meta(self) -> dict[str, Any]:
        """Provenance of the run for the table ``meta`` (see :func:`make_meta`)."""
        res = self.result
        plans = [te.plan for te in res.exposures.values()]
        valid_until = {k: v.tdb.isot for k, v in res.valid_until.items()}
        return make_meta(
            site=self.site.as_dict(),
            targets=[
                {"name": t.name, "file": str(t.source), "sha256": t.sha256} for t in self.targets
            ],
            constraints=res.constraints,
            mode=self.settings.mode,
            extra={
                "nights": [d.isoformat() for d in self.nights],
                "alpha": self.settings.alpha,
                "exposure": planned_exposure(plans, self.settings.exposure),
                "overhead_s": self.settings.overhead_s,
                "valid_until_tdb": valid_until,
                "warnings": res.warnings,
                "unplaced": [f"{m.target} {m.night}: {m.reason}" for m in res.unplaced],
                "planning": self._planning(),
                "not_planned": res.reasons,
                "visits": self.visit_columns.records(),
                "time_accounting": self.accounting(),
            },
        )

    def table(self) -> Table:
        """The master blocks table (:mod:`ucbplan.observing.blocks.schema`) with provenance."""
        meta = self.meta()
        visits, meta["visits"] = meta["visits"], []
        table = blocks_to_table(self.result.blocks, meta)  # copies the meta it is given
        table.meta["visits"] = visits  # made for this table alone: not copied again
        return table


def _collected_facts(goal: GoalPlan) -> dict[str, Any]:
    """What the spectra already taken give a goal (table meta): their number, information on K
    [(km/s)⁻²] and σ_K [km/s], and the information still needed."""
    return {
        "observed_spectra": goal.collected_spectra,
        "observed_info": goal.collected_info,
        "observed_sigma_K_kms": goal.collected_info**-0.5 if goal.collected_info > 0 else None,
        "info_still_needed": goal.info_needed,
    }


def _check_budget_names(targets: Sequence[Target], settings: PlanSettings) -> None:
    """Every ``--budget`` names a target of the run (case-insensitive)."""
    known = {t.name.lower() for t in targets}
    for name, _ in settings.budgets:
        if name not in known:
            names = ", ".join(t.name for t in targets)
            names = names if len(names) <= 200 else f"{names[:199]}…"
            raise InputError(f"budget: no target named {shorten(name, 60)}; targets: {names}")


def plan_files(
    target_files: Sequence[Path | str],
    *,
    first_night: date | str,
    n_nights: int = 1,
    site: str | None = None,
    site_lonlat: str | None = None,
    sites_file: Path | None = None,
    settings: PlanSettings | None = None,
    priorities: Mapping[str, float] | Sequence[str] = (),
    timezone: str | None = None,
) -> PlanRun:
    """Plan blocks for target files at a site on ``n_nights`` nights from ``first_night``.

    Parameters
    ----------
    target_files : sequence of path
        Target YAML files.
    first_night : date or str
        Local date of the first evening (``YYYY-MM-DD``).
    n_nights : int
        Number of consecutive nights.
    site, site_lonlat, sites_file
        Site by name (``sites_file`` searched first) or by ``LON,LAT,HEIGHT``.
    settings : PlanSettings, optional
        Mode, constraints, exposures ... (defaults: :class:`PlanSettings`).
    priorities : mapping or sequence of str
        Priority overrides by target name (see :func:`with_priorities`).
    timezone : str, optional
        IANA zone replacing the site's (``--tz``): the local evening of ``first_night`` and the
        local-time columns.

    Returns
    -------
    PlanRun

    Raises
    ------
    UcbplanError
        For a bad site, date, target file, override or planning input (one line each).
    """
    # every option first (cheap, one line each), then the files, then the work
    settings = settings if settings is not None else PlanSettings()
    dates = night_dates(first_night, n_nights)
    if not isinstance(priorities, Mapping):
        parse_priorities(priorities)
    the_site = resolve_site(site, site_lonlat, sites_file, timezone)
    return plan_targets(load_targets(target_files, slug), the_site, dates, settings, priorities)


def plan_targets(
    targets: Sequence[Target],
    site: Site,
    nights: Sequence[date],
    settings: PlanSettings,
    priorities: Mapping[str, float] | Sequence[str] = (),
) -> PlanRun:
    """Plan loaded targets at a resolved site on the given nights (:func:`plan_files` after
    reading its inputs; ``ucbplan.plan`` calls it with targets, sites and dates as objects).

    Raises
    ------
    UcbplanError
        For a bad override, a budget naming no target, or a planning input (one line each).
    """
    chosen = with_priorities(list(targets), priorities)
    _check_budget_names(chosen, settings)
    result = plan_nights(chosen, site, list(nights), settings)
    return PlanRun(chosen, site, list(nights), settings, result)
