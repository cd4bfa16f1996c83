"""``ucbplan.plan``: targets, a site and nights in; a :class:`Plan` out (the ``plan`` command)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

from ucbplan.api._convert import as_date, as_float, scope
from ucbplan.api.ephemeris import TargetLike, get_site, load_target
from ucbplan.errors import InputError, emit, shorten

if TYPE_CHECKING:
    from astropy.table import Table

    from ucbplan.observing.accounting import PlanAccount, VisitSummary
    from ucbplan.observing.constraints import Constraint
    from ucbplan.observing.schedule import PlanRun

__all__ = ["Plan", "default_constraints", "plan"]

#: Keyword options that are quantities, with the unit the planner takes them in.
_UNITS = {
    "exptime_s": "s",
    "readout_s": "s",
    "overhead_s": "s",
    "sigma_v_kms": "km/s",
    "k_eff_kms": "km/s",
    "moon_sep_deg": "deg",
    "zenith_hole_deg": "deg",
}
#: Options that a ``constraints`` list replaces (giving both is an error).
_CONSTRAINT_OPTIONS = (
    "twilight",
    "airmass_max",
    "moon_sep_deg",
    "moon_illum_max",
    "zenith_hole_deg",
)


def default_constraints(site: Any = None, **limits: Any) -> list[Constraint]:
    """The constraints ``ucbplan plan`` uses at ``site``: nautical night, airmass ≤ 2, the
    site's zenith hole, Moon separation ≥ 30° (or Moon down); ``limits`` as in
    :func:`ucbplan.observing.constraint_objects.default_constraints` (``airmass_max=1.5`` …).

    Parameters
    ----------
    site : str, Site, EarthLocation or astroplan Observer, optional
        Where (its zenith hole); see :func:`ucbplan.get_site`.
    **limits
        ``twilight``, ``airmass_max``, ``moon_sep_deg`` [deg or Quantity], ``moon_illum_max``,
        ``zenith_hole_deg`` [deg or Quantity].

    Returns
    -------
    list of Constraint
    """
    from ucbplan.observing.constraint_objects import default_constraints as _defaults

    for key in ("moon_sep_deg", "zenith_hole_deg"):
        if key in limits:
            limits[key] = as_float(limits[key], "deg", key)
    return _defaults(get_site(site) if site is not None else None, **limits)


@dataclass(frozen=True)
class Plan:
    """A finished plan: the blocks table, visits, time accounting and what was not planned.

    Attributes
    ----------
    run : PlanRun
        The planner's record (targets, site, nights, settings and result).
    """

    run: PlanRun

    @cached_property
    def table(self) -> Table:
        """The blocks table, identical to ``ucbplan plan -o plan.ecsv`` (times UTC at the site
        and TDB at the barycentre; columns in docs/blocks-table.md)."""
        with scope():
            return self.run.table()

    @property
    def visits(self) -> list[VisitSummary]:
        """One summary per visit (acquisition + exposures), in time order."""
        with scope():
            return self.run.visits()

    @property
    def time_account(self) -> PlanAccount:
        """Time accounting, typed: the total and per target (visits, exposures, shutter,
        overheads, idle [s]; efficiency)."""
        with scope():
            return self.run.time_account

    @property
    def accounting(self) -> dict[str, Any]:
        """Time accounting as the table meta holds it: ``{"total": {...}, "targets": {NAME:
        {...}}}`` [s] (:attr:`time_account` as a dict)."""
        with scope():
            return self.run.accounting()

    @property
    def not_planned(self) -> dict[str, dict[str, dict[str, int]]]:
        """``{target: {night: {reason: count}}}`` of the night-time anchors not planned."""
        return dict(self.run.result.reasons)

    @property
    def warnings(self) -> list[str]:
        """The plan's warnings (also emitted as :class:`ucbplan.PlanWarning`)."""
        return list(self.run.result.warnings)

    def write(self, path: str | Path, fmt: str | None = None, overwrite: bool = False) -> Path:
        """Write the blocks table (``.ecsv``, ``.csv`` or ``.json``, as ``plan -o``), atomically.

        Raises
        ------
        OutputExistsError
            ``path`` exists and ``overwrite`` is false.
        """
        from ucbplan.io import output_format, write_output
        from ucbplan.observing.tablewrite import write_table

        out = Path(path)
        kind = output_format(out, fmt, ("ecsv", "csv", "json"), "ecsv")
        table = self.table

        def _write(handle: IO[str]) -> None:
            write_table(table, handle, kind, json_meta=True)

        with scope():
            write_output(out, _write, overwrite=overwrite)
        return out

    def plot(self, path: str | Path, overwrite: bool = False) -> int:
        """Night charts (``.png``/``.svg`` panels or a ``.pdf`` page per night); the number of
        nights charted."""
        from ucbplan.observing.nightplot import write_night_charts

        constraints = self.run.settings.constraints(self.run.site)
        with scope():
            return write_night_charts(
                self.table, self.run.site, Path(path), constraints=constraints, overwrite=overwrite
            )

    def to_astroplan(self) -> Any:
        """The plan as an ``astroplan.Schedule`` (one ``ObservingBlock`` per visit or block)."""
        from ucbplan.observing.astroplan_bridge import to_astroplan

        with scope():
            return to_astroplan(self.table, self.run.site)


def plan(
    targets: TargetLike | Sequence[TargetLike],
    site: Any,
    night: Any,
    nights: int = 1,
    constraints: Sequence[Any] | None = None,
    *,
    priorities: Mapping[str, float] | None = None,
    timezone: str | None = None,
    **options: Any,
) -> Plan:
    """Plan phase-targeted blocks (UTC at the site) for one or more nights.

    Parameters
    ----------
    targets : target or list of targets
        Paths, target documents or ``Target`` objects (see :func:`ucbplan.load_target`).
    site : str, Site, EarthLocation or astroplan Observer
        The observatory (see :func:`ucbplan.get_site`).
    night : str, datetime.date or Time
        Local date of the first evening (``YYYY-MM-DD``).
    nights : int
        Number of consecutive nights.
    constraints : list, optional
        Constraint objects replacing the defaults (:func:`default_constraints`): ucbplan's
        (``ucbplan.AirmassConstraint(1.8)`` …), your own :class:`ucbplan.Constraint` subclasses
        or astroplan's. A list without a night constraint is planned for nautical night; one
        without an airmass constraint only keeps the target above the horizon.
    priorities : mapping, optional
        Priority overrides by target name (higher first).
    timezone : str, optional
        IANA zone replacing the site's.
    **options
        The ``plan`` command's options by their library names: ``mode``, ``exptime_s``,
        ``n_exp``, ``readout_s``, ``overhead_s``, ``visit``, ``cadence``, ``instrument``,
        ``sigma_v_kms``, ``k_eff_kms``, ``alpha``, ``goal``, ``budgets``, ``twilight``,
        ``airmass_max``, ``moon_sep_deg``, ``moon_illum_max``, ``zenith_hole_deg`` …
        (:class:`~ucbplan.observing.schedule.PlanSettings`); times, speeds and angles may be
        astropy quantities.

    Returns
    -------
    Plan

    Raises
    ------
    InputError
        Any bad option (one line naming the parameter), TargetFileError, SiteError.

    Warns
    -----
    PlanWarning, EarthOrientationWarning
        What the plan's ``warnings`` list holds, each with its cause's class:
        :class:`~ucbplan.errors.SmearingWarning`, :class:`~ucbplan.errors.ExposureWarning`
        (PlanWarnings), EarthOrientationWarning (nights past the bundled IERS tables).
    """
    from ucbplan.observing.schedule import night_dates, plan_settings
    from ucbplan.observing.schedule.run import plan_targets

    _settings_options(options, constraints)
    many = isinstance(targets, Sequence) and not isinstance(targets, str)
    with scope():
        settings = plan_settings(**options)
        dates = night_dates(as_date(night, "night"), nights)
        where = get_site(site, timezone)
        loaded = [load_target(t) for t in (targets if many else [targets])]
        run = plan_targets(loaded, where, dates, settings, dict(priorities or {}))
    emit(list(run.result.warnings), run.result.warning_categories)
    return Plan(run)


def _settings_options(options: dict[str, Any], constraints: Sequence[Any] | None) -> None:
    """``options`` made the keywords of ``plan_settings``: names checked, quantities in SI, and
    ``constraints`` (which replace the default set, so no constraint option may come too)."""
    _check_option_names(options)
    for key, unit in _UNITS.items():
        if key in options:
            options[key] = as_float(options[key], unit, key)
    if "visit" in options and hasattr(options["visit"], "unit"):
        options["visit"] = as_float(options["visit"], "s", "visit")
    if constraints is not None:
        given = [k for k in _CONSTRAINT_OPTIONS if k in options]
        if given:
            raise InputError(
                f"{given[0]}: give it as a constraint object in constraints (which replaces "
                "the default set), or leave constraints out",
                parameter=given[0],
            )
        options["custom_constraints"] = _constraint_tuple(constraints)


def _check_option_names(options: Mapping[str, Any]) -> None:
    """Every keyword is a ``plan`` option (a :class:`PlanSettings` field or a
    :func:`plan_settings` argument).

    Raises
    ------
    InputError
        For an unknown keyword, with the closest known ones.
    """
    import inspect

    from ucbplan.observing.schedule import PlanSettings, plan_settings
    from ucbplan.target.values import did_you_mean

    known = set(inspect.signature(plan_settings).parameters)
    known |= set(PlanSettings.__dataclass_fields__)
    known -= {"options", "exposure", "exptime_explicit", "custom_constraints"}
    for key in options:
        if key not in known:
            hint = did_you_mean(key, sorted(known))
            raise InputError(
                f"{key}: not an option of ucbplan.plan; {hint}see help(ucbplan.plan)",
                parameter=key,
            )


def _constraint_tuple(constraints: Any) -> tuple[Any, ...]:
    """``constraints`` as a tuple, each item checked (:func:`as_constraint`)."""
    from ucbplan.observing.constraint_objects import as_constraint

    if isinstance(constraints, str | bytes) or not isinstance(constraints, Sequence):
        raise InputError(
            f"constraints: expected a list of constraint objects, got {shorten(constraints, 60)}",
            parameter="constraints",
        )
    return tuple(as_constraint(c) for c in constraints)
