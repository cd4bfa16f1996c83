"""``ucbplan.plan``: targets, a site and nights in; a :class:`Plan` out (the ``plan`` command)."""

from __future__ import annotations

import dataclasses
import inspect
from collections.abc import Mapping, Sequence
from datetime import date
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ucbplan.api._convert import as_date, as_float, scope
from ucbplan.api.ephemeris import TargetLike, get_site, load_target
from ucbplan.api.plan_options import (
    DEFAULT_EXPTIME,
    accept_old_names,
    recorded_options,
    settings_from,
)
from ucbplan.api.plan_options import (
    OLD_NAMES as OLD_NAMES,
)
from ucbplan.api.plan_options import (
    PLAN_FLAGS as PLAN_FLAGS,
)
from ucbplan.api.plan_result import Plan
from ucbplan.errors import InputError, emit, shorten

if TYPE_CHECKING:
    from astropy.table import Table
    from astropy.units import Quantity

    from ucbplan.observing.constraints import Constraint
    from ucbplan.observing.observatory.sites import Site
    from ucbplan.observing.schedule import PlanRun
    from ucbplan.targets import Target

#: The keywords of :func:`plan` that a ``constraints`` list replaces (giving both is an error).
_CONSTRAINT_OPTIONS = ("twilight", "airmass_max", "moon_sep", "moon_illum", "zenith_hole")


@accept_old_names
def default_constraints(
    site: Any = None,
    *,
    twilight: str | None = None,
    airmass_max: float | None = None,
    moon_sep: float | Quantity | None = None,
    moon_illum: float | None = None,
    zenith_hole: float | Quantity | None = None,
) -> list[Constraint]:
    """The constraints ``ucbplan plan`` uses at ``site``: nautical night, airmass ≤ 2, the
    site's zenith hole, Moon separation ≥ 30° while the Moon is up; each keyword as
    :func:`plan`'s (None: :func:`plan`'s default).

    Parameters
    ----------
    site : str, Site, EarthLocation or astroplan Observer, optional
        Where (its zenith hole); see :func:`ucbplan.get_site`.
    twilight : str, optional
        ``civil``, ``nautical`` or ``astronomical`` night.
    airmass_max : float, optional
        Largest airmass (sec z).
    moon_sep, zenith_hole : float or Quantity, optional
        Smallest Moon separation; zenith-hole radius (None: the site's; 0: none) [deg].
    moon_illum : float, optional
        Largest illuminated fraction of the Moon (0-1) while it is up (None: no limit).

    Returns
    -------
    list of Constraint

    Raises
    ------
    InputError
        An unknown keyword or a bad value: one line naming it.

    Examples
    --------
    >>> import ucbplan
    >>> ucbplan.default_constraints("paranal")
    [NightConstraint(twilight='nautical'), AirmassConstraint(max_airmass=2.0),
     ZenithHoleConstraint(radius_deg=4.0),
     MoonSeparationConstraint(min_deg=30.0, moon_down_ok=True)]
    """
    from ucbplan.observing.constraints.objects import default_constraints as _defaults

    given = {
        "twilight": twilight,
        "airmass_max": airmass_max,
        "moon_sep_deg": as_float(moon_sep, "deg", "moon_sep"),
        "moon_illum_max": moon_illum,
        "zenith_hole_deg": as_float(zenith_hole, "deg", "zenith_hole"),
    }
    limits = {k: v for k, v in given.items() if v is not None}
    with scope():
        return _defaults(get_site(site) if site is not None else None, **limits)


@accept_old_names
def plan(
    targets: TargetLike | Sequence[TargetLike],
    site: Any,
    night: Any,
    nights: int = 1,
    constraints: Sequence[Any] | None = None,
    *,
    mode: str = "quadrature",
    twilight: str = "nautical",
    airmass_max: float = 2.0,
    moon_sep: float | Quantity = 30.0,
    moon_illum: float | None = None,
    zenith_hole: float | Quantity | None = None,
    exptime: float | Quantity = DEFAULT_EXPTIME,
    n_exp: int = 1,
    readout: float | Quantity | None = None,
    alpha: float = 1.0,
    sigma_v: str | float | Quantity | None = None,
    sigma_floor: float | Quantity = 0.0,
    extinction: float | None = None,
    k_eff: float | Quantity | None = None,
    max_smear: str | float | Quantity | None = None,
    max_bin_fraction: float | None = None,
    overhead: float | Quantity | None = None,
    sessions: int = 1,
    visit: str | float | Quantity | None = None,
    max_visit: str | float | Quantity | None = None,
    cadence: str = "auto",
    service_mode: bool = False,
    instrument: str | None = None,
    instruments_file: str | Path | None = None,
    goal: str | None = None,
    observed: str | Path | Table | None = None,
    sigma_v_scale: float | None = None,
    min_lambda_k: float | None = None,
    allow_smeared: bool = False,
    budgets: Mapping[str, Any] | Sequence[str] | None = None,
    priorities: Mapping[str, float] | Sequence[str] | None = None,
    timezone: str | None = None,
    site_lonlat: str | None = None,
    sites_file: str | Path | None = None,
) -> Plan:
    """Plan phase-targeted blocks (UTC at the site) for one or more nights: ``ucbplan plan``.

    Every keyword is the ``plan`` option of the same name (:data:`PLAN_FLAGS` gives its flag);
    times, speeds and angles may be astropy quantities, else numbers in the unit in brackets.
    The names before issue 30 (``exptime_s``, ``max_visit_s``, ``moon_sep_deg`` …,
    :data:`OLD_NAMES`) still work, with the same numbers.

    Parameters
    ----------
    targets : target or list of targets
        Paths, target documents or ``Target`` objects (see :func:`ucbplan.load_target`); a file
        or a target given twice is refused.
    site : str, Site, EarthLocation or astroplan Observer
        The observatory (see :func:`ucbplan.get_site`); None with ``site_lonlat``.
    night : str, datetime.date, datetime or Time
        Local date of the first evening (``YYYY-MM-DD``).
    nights : int
        Number of consecutive nights.
    constraints : list, optional
        Constraint objects replacing the defaults (:func:`default_constraints`) and the five
        constraint keywords: ucbplan's (``ucbplan.AirmassConstraint(1.8)`` …), your own
        :class:`ucbplan.Constraint` subclasses or astroplan's. A list without a night
        constraint is planned for nautical night; one without an airmass constraint only keeps
        the target above the horizon.
    mode : str
        ``quadrature``, ``conjunction``, ``zero-crossing``, ``fixed-u-pairs``,
        ``quadrature+conjunction`` or ``u=VALUE`` [rad].
    twilight, airmass_max : str, float
        ``civil``, ``nautical`` or ``astronomical`` night; largest airmass (sec z).
    moon_sep, zenith_hole : float or Quantity
        Smallest Moon separation; zenith-hole radius (None: the site's; 0: none) [deg].
    moon_illum : float, optional
        Largest illuminated fraction of the Moon (0-1) while it is up.
    exptime : float or Quantity
        Single-exposure time [s]. Left out, 60 s capped at the smearing floor (or chosen for
        information per hour when σ_v follows the exposure time); given, it is kept (and
        refused below the floor).
    n_exp, sessions : int
        Exposures per block (co-added); sessions per target and night.
    readout, overhead : float or Quantity, optional
        Readout after each exposure; slew + acquisition before each visit or session [s]
        (None: the instrument's, else 0 and 300 s).
    alpha : float
        Planning margin α of T_valid.
    sigma_v : str, float or Quantity, optional
        RV precision: fixed per exposure [km/s], or a law ``30km/s@600s[,V=20.0]`` of one
        spectrum of that length (then the exposure time and cadence are chosen).
    sigma_floor, k_eff : float or Quantity
        Systematic σ_v floor added in quadrature; semi-amplitude K_eff (None: the target's)
        [km/s].
    extinction : float, optional
        Extinction k [mag/airmass] of the σ_v law (None: the instrument's, else 0).
    max_smear : str, float or Quantity, optional
        Smearing budget, ``0.5*sigma_v`` or a speed [km/s]; exceeding it is an error.
    max_bin_fraction : float, optional
        Largest block span as a fraction of the orbital period.
    visit, max_visit : str, float or Quantity, optional
        Visit length, acquisition included (``1h``, ``45min``, or [s]); the longest visit a
        ``goal`` plans (None: 2 h; refused without a goal, or shorter than ``visit``).
    cadence : str
        ``auto``, ``targeted``, ``phase-locked`` or ``untargeted``.
    service_mode : bool
        Plan only what a service-mode queue executes: visits of back-to-back exposures
        (``phase-locked`` or ``untargeted``; docs/exports.md, "Service mode").
    instrument, instruments_file : str, path, optional
        Spectrograph (its overheads and σ reference); a YAML table searched first.
    goal : str, optional
        Precision goal (``sigma_K=2km/s``, ``K1=1%``, ``q=1%``): plans the spectra it needs.
    observed : str, path or Table, optional
        Spectra already taken, counted toward ``goal``: a velocities file as :func:`reduce`
        takes it (the one target planned; epochs, exposure times and measured σ_v), or a blocks
        table (a file from ``plan -o``, or a table in memory) with a ``status`` column (``taken``,
        ``missed``, ``skipped``; only ``taken`` rows count, their ``sigma_v_kms`` as measured). The
        goal plans only the information still missing.
    sigma_v_scale : float, optional
        Factor on every σ_v of the law (None: the median measured / predicted σ_v of
        ``observed`` when it differs from 1 by more than 5 %, else 1; ``1`` keeps the law).
    min_lambda_k : float, optional
        Smallest smearing factor Λ_K of an exposure (None: 0.9).
    allow_smeared : bool
        Plan exposures below the Λ_K floor.
    budgets, priorities : mapping or list of str, optional
        Wall time per target over all nights (``{"HM Cnc": 2 * u.h}`` or ``["HM Cnc=2h"]``);
        priority overrides by target name (higher first).
    timezone : str, optional
        IANA zone replacing the site's.
    site_lonlat, sites_file : str, path, optional
        ``LON,LAT,HEIGHT`` (deg, deg, m) instead of ``site``; a YAML site table searched first.

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

    Examples
    --------
    One night at Paranal for the bundled simulated HM Cnc (a night after 2027 also warns that the
    bundled Earth-orientation tables end before it):

    >>> import ucbplan
    >>> run = ucbplan.plan("catalogs/hm-cnc-simulated.yaml", site="paranal", night="2040-02-15")
    >>> run
    <Plan at Paranal: 1 target, 1 night, 1 visit, 2 exposures, 0.14 h>
    >>> run.table["block_id", "anchor", "t_mid_utc"]
    <QTable length=2>
              block_id             anchor          t_mid_utc
               str28               str10              Time
    ---------------------------- ---------- -----------------------
    HM_Cnc_simulated-20400215-01 quadrature 2040-02-16T03:05:33.800
    HM_Cnc_simulated-20400215-02 quadrature 2040-02-16T03:08:14.564
    >>> doc = run.to_dict()  # what ``plan --format json`` prints, as Python values
    >>> len(doc["rows"]), doc["rows"][0]["t_mid_utc"]
    (2, '2040-02-16T03:05:33.800')
    """
    o = dict(locals())
    run = plan_run(o)
    emit(
        list(run.result.warnings), run.result.warning_categories, stacklevel=4
    )  # warn, emit, plan, its alias
    return Plan(run, options=recorded_options(o, plan))


def plan_run(o: dict[str, Any]) -> PlanRun:
    """The planner's run of :func:`plan`'s arguments ``o`` by name: every option checked first
    (cheap, one line each), then the site, then the files, then the work."""
    return plan_run_on(o, None)


def plan_run_on(o: dict[str, Any], nights: Sequence[date] | None) -> PlanRun:
    """:func:`plan_run` on the given nights (None: ``o``'s ``night`` and ``nights``)."""
    from ucbplan.api._observed import observed_settings
    from ucbplan.observing.schedule import night_dates
    from ucbplan.observing.schedule.run import parse_priorities, plan_targets

    with scope():
        settings = settings_from(o, _constraints(o))
        dates = night_dates(as_date(o["night"], "night"), _nights(o["nights"]))
        dates = dates if nights is None else list(nights)
        priorities = _priorities(o["priorities"])
        if not isinstance(priorities, Mapping):
            parse_priorities(priorities)
        where = _site(o)
        loaded = _load_all(o["targets"])
        if o["observed"] is not None or o["sigma_v_scale"] is not None:
            settings = observed_settings(o["observed"], o["sigma_v_scale"], loaded, where, settings)
        if o.get("short_goals"):  # replan: a goal out of reach is stated, not refused
            pinned = o.get("pinned", ())
            settings = dataclasses.replace(
                settings, short_goals=True, goal_slack=o["goal_slack"], pinned=pinned
            )
        return plan_targets(loaded, where, dates, settings, priorities)


def _nights(value: Any) -> Any:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise InputError(
            f"nights: expected a whole number of nights, got {shorten(value, 40)}", "nights"
        )
    return value


def _priorities(value: Any) -> Mapping[str, float] | Sequence[str]:
    """``priorities``: None, a mapping, or ``NAME=NUMBER`` texts."""
    if value is None:
        return ()
    if isinstance(value, Mapping) or (
        isinstance(value, Sequence)
        and not isinstance(value, str | bytes)
        and all(isinstance(v, str) for v in value)
    ):
        return value
    raise InputError(
        f"priorities: expected a {{name: priority}} mapping or NAME=NUMBER texts, got "
        f"{shorten(value, 60)}",
        parameter="priorities",
    )


def _site(o: Mapping[str, Any]) -> Site:
    """The site: a name (``sites_file`` searched first) or ``site_lonlat`` as the command line
    gives them, else an astropy or astroplan location (:func:`get_site`)."""
    from ucbplan.observing.observatory.sites import resolve_site

    zone = o["timezone"]
    if zone is not None and not isinstance(zone, str):
        raise InputError(
            f"timezone: expected an IANA zone name, got {shorten(zone, 40)}", "timezone"
        )
    site, lonlat = o["site"], o["site_lonlat"]
    if lonlat is not None and not isinstance(lonlat, str):
        raise InputError(
            f"site_lonlat: expected LON,LAT,HEIGHT text, got {shorten(lonlat, 40)}", "site_lonlat"
        )
    if site is None or isinstance(site, str):
        sites_file = o["sites_file"]
        if sites_file is not None and not isinstance(sites_file, str | Path):
            raise InputError(
                f"sites_file: expected a path, got {shorten(sites_file, 40)}", "sites_file"
            )
        return resolve_site(site, lonlat, Path(sites_file) if sites_file else None, zone)
    if lonlat is not None:
        raise InputError("site, site_lonlat: give one site, not both", parameter="site_lonlat")
    return get_site(site, zone)


def _load_all(targets: Any) -> list[Target]:
    """The targets, each once: files by the command line's rule (a file twice, or two files
    naming one target, refused), and the same rule for documents and ``Target`` objects."""
    from ucbplan.errors import TargetFileError
    from ucbplan.observing.schedule.records import slug
    from ucbplan.targets import load_targets
    from ucbplan.targets.parse import check_distinct_files

    many = isinstance(targets, Sequence) and not isinstance(targets, str)
    items = list(targets) if many else [targets]
    if all(isinstance(t, str | Path) for t in items):
        return load_targets(items, slug)
    check_distinct_files([t for t in items if isinstance(t, str | Path)])
    loaded = [load_target(t) for t in items]
    seen: set[str] = set()
    for t in loaded:
        if slug(t.name) in seen:
            raise TargetFileError(
                f"targets: target {shorten(t.name, 40)} is given twice; give each target once"
            )
        seen.add(slug(t.name))
    return loaded


def _constraints(o: Mapping[str, Any]) -> tuple[Any, ...] | None:
    """``constraints`` checked; they replace the default set, so no constraint keyword may
    come too."""
    if o["constraints"] is None:
        return None
    defaults = inspect.signature(plan).parameters
    given = [k for k in _CONSTRAINT_OPTIONS if o[k] is not defaults[k].default]
    if given:
        raise InputError(
            f"{given[0]}: give it as a constraint object in constraints (which replaces "
            "the default set), or leave constraints out",
            parameter=given[0],
        )
    return _constraint_tuple(o["constraints"])


def _constraint_tuple(constraints: Any) -> tuple[Any, ...]:
    """``constraints`` as a tuple, each item checked (:func:`as_constraint`)."""
    from ucbplan.observing.constraints.objects import as_constraint

    if isinstance(constraints, str | bytes) or not isinstance(constraints, Sequence):
        raise InputError(
            f"constraints: expected a list of constraint objects, got {shorten(constraints, 60)}",
            parameter="constraints",
        )
    return tuple(as_constraint(c) for c in constraints)
