"""Constraints given as objects: the CLI's defaults, a list → a run's set, astroplan's classes.

A plan's constraints are a list of objects (as astroplan's are): ucbplan's own vectorised
classes (:mod:`ucbplan.observing.constraints`), a user's :class:`~ucbplan.observing.
constraints.Constraint` subclass, or astroplan constraint instances. :func:`default_constraints`
is the list the command line uses (its ``--twilight``, ``--airmass-max``, ``--moon-sep``,
``--moon-illum`` and ``--zenith-hole`` build exactly these objects); :func:`constraint_set`
turns any list into the run's :class:`~ucbplan.observing.constraints.ConstraintSet`.

astroplan's own ``AtNightConstraint`` (civil, nautical or astronomical), ``AirmassConstraint``
(``max``, ``min=1``), ``AltitudeConstraint`` (``min`` only), ``MoonSeparationConstraint``
(``min`` only) and ``MoonIlluminationConstraint`` (``max`` only), boolean and without an
ephemeris, are evaluated by ucbplan's vectorised classes with astroplan's meaning (e.g. the
Moon separation counts while the Moon is down). Any other astroplan constraint, custom
subclasses included, is evaluated by astroplan itself (:class:`AstroplanConstraint`): one
astropy ``AltAz`` transformation of every sample per target and call, and no screening, so it
costs more than a native constraint (``benchmarks/bench_plan.py`` measures astroplan's
cost against ucbplan's kernel). astroplan is imported only when one of its constraints is
given.
"""

from __future__ import annotations

import datetime as dt
from collections.abc import Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from ucbplan.core.constants import DAY_S, HOUR_S
from ucbplan.errors import InputError, shorten
from ucbplan.observing.constraints import (
    TWILIGHT_SUN_ALT_DEG,
    AirmassConstraint,
    AltitudeConstraint,
    Constraint,
    ConstraintSet,
    MoonIlluminationConstraint,
    MoonSeparationConstraint,
    NightConstraint,
    ZenithHoleConstraint,
    check_airmass,
    check_moon_illum,
    check_moon_sep,
    check_zenith_hole,
)
from ucbplan.observing.constraints.checks import BoolArray, FloatArray

if TYPE_CHECKING:
    from ucbplan.observing.observatory.sites import Site
    from ucbplan.observing.observatory.sky import SkyModel

#: The slot of each native class in a :class:`ConstraintSet` (the first of a kind fills it).
_SLOTS: dict[type[Constraint], str] = {
    NightConstraint: "night",
    AirmassConstraint: "airmass",
    AltitudeConstraint: "altitude",
    ZenithHoleConstraint: "zenith_hole",
    MoonSeparationConstraint: "moon_sep",
    MoonIlluminationConstraint: "moon_illum",
}


def default_constraints(
    site: Site | None = None,
    *,
    twilight: str = "nautical",
    airmass_max: float = 2.0,
    moon_sep_deg: float = 30.0,
    moon_illum_max: float | None = None,
    zenith_hole_deg: float | None = None,
) -> list[Constraint]:
    """The constraints the command line plans with (its defaults, or its options' values).

    Parameters
    ----------
    site : Site, optional
        Its zenith hole applies unless ``zenith_hole_deg`` is given.
    twilight : str
        ``civil``, ``nautical`` or ``astronomical`` night (Sun below −6, −12, −18 deg).
    airmass_max : float
        Largest airmass (sec z), in [1, 100].
    moon_sep_deg : float
        Smallest Moon separation [deg] while the Moon is up; 0 switches it off.
    moon_illum_max : float, optional
        Largest illuminated fraction of the Moon while it is up (None: no limit).
    zenith_hole_deg : float, optional
        Zenith-hole radius [deg]; None takes the site's, 0 switches it off.

    Returns
    -------
    list of Constraint
        Night, airmass, then the zenith hole, Moon separation and Moon illumination that apply.

    Raises
    ------
    InputError
        For a value out of range (naming the parameter).
    """
    check_airmass(airmass_max, "airmass_max")
    check_moon_sep(moon_sep_deg, "moon_sep_deg")
    out: list[Constraint] = [NightConstraint(twilight), AirmassConstraint(airmass_max)]
    hole = zenith_hole_deg
    if hole is None and site is not None:
        hole = site.zenith_hole_deg
    if hole is not None and check_zenith_hole(hole, "zenith_hole_deg") > 0:
        out.append(ZenithHoleConstraint(hole))
    if moon_sep_deg > 0:
        out.append(MoonSeparationConstraint(moon_sep_deg))
    if moon_illum_max is not None:
        out.append(MoonIlluminationConstraint(check_moon_illum(moon_illum_max, "moon_illum_max")))
    return out


def constraint_set(items: Iterable[Any], site: Site | None = None) -> ConstraintSet:
    """A run's :class:`ConstraintSet` from a list of constraint objects (``site``: its time zone
    serves astroplan's ``LocalTimeConstraint``; None: UTC).

    The list replaces the defaults, with two floors the planner always keeps: a list without a
    night constraint is planned for nautical night (ucbplan plans nights), and one without an
    airmass constraint only asks the target to be above the horizon (airmass ≤ 100).

    Raises
    ------
    InputError
        For an item that is not a constraint (naming ``constraints``).
    """
    if isinstance(items, ConstraintSet):
        return items
    if isinstance(items, str | bytes) or not isinstance(items, Iterable):
        raise InputError(
            f"constraints: expected a list of constraint objects, got {shorten(items, 60)}",
            parameter="constraints",
        )
    slots: dict[str, Constraint] = {}
    extra: list[Constraint] = []
    for item in items:
        c = as_constraint(item, site)
        if isinstance(c, LocalTimeConstraint) and c.zone is None and site is not None:
            c = LocalTimeConstraint(c.start, c.end, site.zone)  # translated before the site
        slot = _SLOTS.get(type(c))
        if slot is not None and slot not in slots:
            slots[slot] = c
        else:
            extra.append(c)
    slots.setdefault("night", NightConstraint())
    slots.setdefault("airmass", AirmassConstraint(100.0))
    return ConstraintSet(**slots, extra=tuple(extra))  # type: ignore[arg-type]


def as_constraint(item: Any, site: Site | None = None) -> Constraint:
    """A ucbplan constraint for ``item``: itself, or an astroplan constraint translated or
    wrapped (module docstring; ``site``: the zone of a ``LocalTimeConstraint``).

    Raises
    ------
    InputError
        For anything else (naming ``constraints``).
    """
    if isinstance(item, Constraint):
        if type(item).ok is Constraint.ok:
            raise InputError(
                f"constraints: {type(item).__name__} defines no ok(sky, i, x); expected a method "
                "returning a boolean array of x's shape, True where the constraint holds",
                parameter="constraints",
            )
        return item
    if _is_astroplan(item):
        native = _native(item, site)
        return native if native is not None else AstroplanConstraint(item)
    raise InputError(
        f"constraints: expected ucbplan or astroplan constraint objects (e.g. "
        f"ucbplan.AirmassConstraint(1.8)), got {shorten(item, 60)}; a constraint of your own "
        "subclasses ucbplan.Constraint and defines ok(sky, i, x)",
        parameter="constraints",
    )


def _is_astroplan(item: Any) -> bool:
    """Whether ``item`` is an astroplan constraint (without importing astroplan otherwise)."""
    if not type(item).__module__.startswith("astroplan") and not any(
        k.__module__.startswith("astroplan") for k in type(item).__mro__
    ):
        return False
    from astroplan import Constraint as ApConstraint

    return isinstance(item, ApConstraint)


def _deg(c: Any, field: str) -> float | None:
    """The angle ``field`` of astroplan's constraint ``c`` (Quantity or None) in degrees.

    Raises
    ------
    InputError
        Not an angle (``min=30*u.m``); one line naming the constraint and the field.
    """
    q = getattr(c, field)
    if q is None:
        return None
    from astropy import units as u

    try:
        return float(u.Quantity(q, u.deg).value)
    except (u.UnitsError, TypeError, ValueError):
        raise InputError(
            f"constraints: astroplan {type(c).__name__}: {field}: expected an angle (e.g. "
            f"30*u.deg), got {shorten(str(q), 40)}",
            parameter="constraints",
        ) from None


def _native(c: Any, site: Site | None = None) -> Constraint | None:
    """The native constraint with the meaning of astroplan's ``c``, or None (evaluate it
    through astroplan). Exact classes only: a subclass may override anything."""
    import astroplan

    kind = type(c)
    if kind is astroplan.LocalTimeConstraint:  # astroplan 0.10.1 compares UTC clock times
        limit = c.min if c.min is not None else c.max
        zone = getattr(limit, "tzinfo", None) or (site.zone if site is not None else None)
        return LocalTimeConstraint(c.min, c.max, zone)
    if kind is astroplan.AtNightConstraint and getattr(c, "force_pressure_zero", False):
        sun = _deg(c, "max_solar_altitude")
        for name, limit in TWILIGHT_SUN_ALT_DEG.items():
            if sun == limit:
                return NightConstraint(name)
        return None
    boolean = getattr(c, "boolean_constraint", True)
    if kind is astroplan.AirmassConstraint and boolean and c.max is not None and c.min == 1:
        return AirmassConstraint(float(c.max))
    if kind is astroplan.AltitudeConstraint and boolean and _deg(c, "max") == 90.0:
        return AltitudeConstraint(_deg(c, "min"))  # type: ignore[arg-type]
    no_eph = getattr(c, "ephemeris", None) is None
    if kind is astroplan.MoonSeparationConstraint and no_eph and c.max is None:
        return MoonSeparationConstraint(_deg(c, "min"), moon_down_ok=False)  # type: ignore[arg-type]
    if kind is astroplan.MoonIlluminationConstraint and no_eph and c.min is None:
        return MoonIlluminationConstraint(float(c.max))
    return None


@dataclass(frozen=True, eq=False)
class AstroplanConstraint(Constraint):
    """An astroplan constraint evaluated by astroplan, at the samples of each block.

    astroplan's answer is taken as is; a score (``boolean_constraint=False``) counts as met
    where it is above 0.
    """

    constraint: Any
    name: ClassVar[str] = "astroplan"

    def ok(self, sky: SkyModel, i: int, x: FloatArray) -> BoolArray:
        from astroplan import FixedTarget, Observer

        xs = np.asarray(x, dtype=np.float64)
        if xs.size == 0:
            return np.zeros(xs.shape, dtype=bool)
        observer = Observer(location=sky.location)
        target = FixedTarget(sky.coords[i])
        got = np.asarray(self.constraint(observer, target, times=sky.time(xs.ravel())))
        return np.asarray(got.reshape(xs.shape) > 0, dtype=bool)

    def describe(self) -> str:
        return f"astroplan {type(self.constraint).__name__}"


@dataclass(frozen=True)
class LocalTimeConstraint(Constraint):
    """Local clock time between ``start`` and ``end`` (inclusive; across midnight when
    ``start`` > ``end``; None: no limit) in ``zone``: astroplan's ``LocalTimeConstraint`` with
    the meaning its documentation gives (the limits' zone, else the observer's, here the
    site's), which astroplan 0.10.1 does not apply (it compares UTC clock times)."""

    start: dt.time | None
    end: dt.time | None
    zone: dt.tzinfo | None = None  # None: the site's, once the run's set is made (else UTC)
    name: ClassVar[str] = "local-time"

    def ok(self, sky: SkyModel, i: int, x: FloatArray) -> BoolArray:
        xs = np.asarray(x, dtype=np.float64)
        if xs.size == 0:
            return np.zeros(xs.shape, dtype=bool)
        unix = np.asarray(sky.time(xs.ravel()).utc.unix, dtype=np.float64)
        minutes, at = np.unique(np.floor(unix / 60.0), return_inverse=True)
        offset = np.array([self._offset_s(m * 60.0) for m in minutes])[at]
        clock = np.mod(unix + offset, DAY_S)
        lo = _seconds(self.start, 0.0)
        hi = _seconds(self.end, 86399.0)
        inside = (clock >= lo) & (clock <= hi) if lo < hi else (clock >= lo) | (clock <= hi)
        return np.asarray(inside.reshape(xs.shape), dtype=bool)

    def _offset_s(self, unix_s: float) -> float:
        """UTC offset of ``zone`` at a UNIX instant [s] (summer time included)."""
        moment = dt.datetime.fromtimestamp(unix_s, tz=dt.UTC).astimezone(self.zone or dt.UTC)
        offset = moment.utcoffset()
        return offset.total_seconds() if offset is not None else 0.0

    def describe(self) -> str:
        start = self.start.replace(tzinfo=None) if self.start else dt.time(0, 0)
        end = self.end.replace(tzinfo=None) if self.end else dt.time(23, 59, 59)
        return f"local time {start}-{end} ({self.zone or 'UTC'})"


def _seconds(t: dt.time | None, default: float) -> float:
    """Seconds since midnight of a clock time (``default`` for None)."""
    if t is None:
        return default
    return t.hour * HOUR_S + t.minute * 60.0 + t.second + t.microsecond * 1e-6
