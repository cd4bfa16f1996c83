"""Observability constraints: small classes registered by name, grouped by name for a run.

Each constraint returns a boolean mask over times of a
:class:`~ucbplan.observing.observatory.sky.SkyModel` and a short reason; they are registered by name
in :data:`CONSTRAINTS` (like astroplan's composable constraints). A run's constraints form a
:class:`ConstraintSet`, whose fields name them (``night``, ``airmass``, ``zenith_hole`` ...) so that
no code reads a constraint by its position; constraints of the user's own (a :class:`Constraint`
subclass with one vectorised method, ``ok``, or an astroplan constraint:
:mod:`ucbplan.observing.constraints.objects`) go into its ``extra`` field.
:mod:`ucbplan.observing.constraints.checks` checks whole blocks against a set.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from ucbplan.errors import InputError, shorten
from ucbplan.inputs import check_range
from ucbplan.observing.observatory.sky import SkyModel, airmass_from_alt

__all__ = [
    "CONSTRAINTS",
    "TWILIGHT_SUN_ALT_DEG",
    "AirmassConstraint",
    "AltitudeConstraint",
    "AtNightConstraint",
    "Constraint",
    "ConstraintSet",
    "MoonIlluminationConstraint",
    "MoonSeparationConstraint",
    "NightConstraint",
    "ZenithHoleConstraint",
    "holds",
    "make_constraint",
]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
Int8Array = NDArray[np.int8]

#: Sun altitude [deg] that ends each twilight.
TWILIGHT_SUN_ALT_DEG = {"civil": -6.0, "nautical": -12.0, "astronomical": -18.0}

#: Largest airmass limit: sec z = 100 is 0.6 deg above the horizon.
MAX_AIRMASS = 100.0
#: Largest zenith-hole radius [deg] (alt-az telescopes have holes of a few degrees).
MAX_ZENITH_HOLE_DEG = 45.0

#: Bounds on how fast the screened quantities of the sky model change (with ≥ 5 % to spare):
#: an altitude by the Earth's rotation (15.04 deg/h = 0.00418 deg/s) plus the body's own
#: motion and topocentric parallax (Moon: ≤ 0.0002 deg/s more); the Moon's distance from a
#: fixed target by its orbital motion (≤ 0.6 deg/h) and parallax (≤ 1 deg turning once a day);
#: its (geocentric) illuminated fraction by ≤ ½ of its phase-angle rate (≤ 16 deg/day).
ALT_RATE_DEG_S = 0.0045
MOON_ALT_RATE_DEG_S = 0.005
MOON_SEP_RATE_DEG_S = 5e-4
MOON_ILLUM_RATE_S = 5e-6

#: Margin beyond the rate bound that a screened answer keeps from a limit (absorbs the
#: rounding of the limit itself, e.g. airmass 2 ↔ altitude 30 deg) [deg or 1].
_SCREEN_EPS = 1e-6


def _certain(margin: FloatArray, rate: float, slack_s: float) -> Int8Array:
    """+1 / −1 where ``margin`` (positive = ok) keeps its sign for ``slack_s`` at ``rate``."""
    reach = rate * slack_s + _SCREEN_EPS
    out = np.zeros(np.shape(margin), dtype=np.int8)
    out[margin > reach] = 1
    out[margin < -reach] = -1
    return out


def _either(a: Int8Array, b: Int8Array) -> Int8Array:
    """Screen of ``ok_a | ok_b``: certain if either is certainly ok, or both certainly fail."""
    out = np.zeros(a.shape, dtype=np.int8)
    out[(a == 1) | (b == 1)] = 1
    out[(a == -1) & (b == -1)] = -1
    return out


def _degrees(value: Any) -> Any:
    """An angle given as an astropy ``Quantity`` → degrees (float); anything else unchanged
    (the range check then judges it)."""
    to_value = getattr(value, "to_value", None)
    if to_value is None:
        return value
    from astropy import units as u

    try:
        return float(to_value(u.deg))
    except (u.UnitsError, TypeError, ValueError):
        return value


class Constraint:
    """Base class of the observability constraints; subclass it for a constraint of your own.

    A constraint needs one vectorised method, :meth:`ok`: given the run's sky model, the target
    index and an array of times, return a boolean array of the same shape, True where the
    constraint holds. A block is planned only if every constraint holds at all its samples
    (start, middle, end and every ≤ 5 min). :meth:`describe` and :meth:`reason` have defaults;
    :meth:`screen` is an optional speed-up.

    Examples
    --------
    No observing while the telescope is closed for maintenance, 02:00–04:00 UTC:

    >>> class Closed(Constraint):
    ...     def ok(self, sky, i, x):
    ...         hour = (sky.time(x).utc.mjd % 1.0) * 24.0
    ...         return (hour < 2.0) | (hour >= 4.0)
    """

    name: ClassVar[str] = ""

    def ok(self, sky: SkyModel, i: int, x: FloatArray) -> BoolArray:
        """True where the constraint holds.

        Parameters
        ----------
        sky : SkyModel
            The run's sky: ``sky.time(x)`` (astropy ``Time``), ``sky.target_alt_deg(i, x)``,
            ``sky.sun_alt_deg(x)``, ``sky.moon_alt_deg(x)``, ``sky.moon_sep_deg(i, x)``,
            ``sky.moon_illum(x)``, ``sky.coords[i]`` (``SkyCoord``) and ``sky.location``.
        i : int
            Index of the target in ``sky.coords``.
        x : ndarray of float
            Times [s after ``sky.origin``, TDB], any shape.

        Returns
        -------
        ndarray of bool
            ``x.shape``.
        """
        raise NotImplementedError(f"{type(self).__name__} defines no ok(sky, i, x)")

    def describe(self) -> str:
        """One-line human description (goes into the table provenance).

        Returns
        -------
        str
            The default: the class name.
        """
        return type(self).__name__

    def screen(self, sky: SkyModel, i: int, x: FloatArray, slack_s: float) -> Int8Array:
        """Where the answer is certain near ``x`` (an optional speed-up of the exact check).

        Parameters
        ----------
        sky, i, x
            As :meth:`ok`.
        slack_s : float
            Half-width [s] of the interval around each ``x`` the answer must hold on.

        Returns
        -------
        ndarray of int8
            ``x.shape``: +1 if ``ok`` holds at every time within ``slack_s`` of each ``x``, −1
            if it fails at every such time, 0 if it may change (the exact check decides). The
            default screens nothing (all 0).
        """
        return np.zeros(np.shape(x), dtype=np.int8)

    def reason(self) -> str:
        """Why a block fails this constraint (for the 'not placed' report).

        Returns
        -------
        str
            The default: ``"violates "`` and :meth:`describe`'s text.
        """
        return f"violates {self.describe()}"


def holds(c: Constraint, sky: SkyModel, i: int, x: FloatArray) -> BoolArray:
    """``c.ok(sky, i, x)``, checked to be what a constraint must return (a user's may not be).

    Raises
    ------
    InputError
        ``ok`` returned None, a scalar, another shape than ``x``'s or values that are not
        booleans (integers are read as booleans); one line naming the constraint.
    """
    got = c.ok(sky, i, x)
    shape = np.shape(x)
    if isinstance(got, np.ndarray) and got.shape == shape and got.dtype.kind == "b":
        return got
    arr = np.asarray(got) if got is not None else None
    if arr is not None and arr.shape == shape and arr.dtype.kind in "biu":
        return arr.astype(bool)
    what = "None"
    if arr is not None:
        what = f"a scalar ({shorten(got, 40)})" if arr.ndim == 0 else f"shape {arr.shape}"
        what = f"{arr.dtype} values" if arr.shape == shape else what
    raise InputError(
        f"constraints: {type(c).__name__}.ok(sky, i, x) returned {what}; expected a boolean "
        f"array of x's shape {shape}, True where the constraint holds",
        parameter="constraints",
    )


@dataclass(frozen=True)
class NightConstraint(Constraint):
    """Sun below the twilight limit (civil −6°, nautical −12°, astronomical −18°).

    Parameters
    ----------
    twilight : str
        ``civil``, ``nautical`` (the default) or ``astronomical``.

    Raises
    ------
    InputError
        Any other ``twilight``.
    """

    twilight: str = "nautical"
    name: ClassVar[str] = "night"

    def __post_init__(self) -> None:
        if not isinstance(self.twilight, str) or self.twilight not in TWILIGHT_SUN_ALT_DEG:
            raise InputError(
                f"twilight: expected {', '.join(TWILIGHT_SUN_ALT_DEG)} (Sun below -6, -12 or "
                f"-18 deg), got {shorten(self.twilight, 40)}",
                parameter="twilight",
            )

    @classmethod
    def twilight_civil(cls) -> NightConstraint:
        """Sun below −6° (astroplan's ``AtNightConstraint.twilight_civil()``).

        Returns
        -------
        NightConstraint
            ``NightConstraint("civil")``.
        """
        return cls("civil")

    @classmethod
    def twilight_nautical(cls) -> NightConstraint:
        """Sun below −12° (the default).

        Returns
        -------
        NightConstraint
            ``NightConstraint("nautical")``.
        """
        return cls("nautical")

    @classmethod
    def twilight_astronomical(cls) -> NightConstraint:
        """Sun below −18°.

        Returns
        -------
        NightConstraint
            ``NightConstraint("astronomical")``.
        """
        return cls("astronomical")

    @property
    def sun_alt_max_deg(self) -> float:
        """Highest allowed Sun altitude [deg]."""
        return TWILIGHT_SUN_ALT_DEG[self.twilight]

    def ok(self, sky: SkyModel, i: int, x: FloatArray) -> BoolArray:
        return np.asarray(sky.sun_alt_deg(x) <= self.sun_alt_max_deg)

    def screen(self, sky: SkyModel, i: int, x: FloatArray, slack_s: float) -> Int8Array:
        return _certain(self.sun_alt_max_deg - sky.sun_alt_deg(x), ALT_RATE_DEG_S, slack_s)

    def describe(self) -> str:
        return f"{self.twilight} night (Sun altitude <= {self.sun_alt_max_deg:g} deg)"

    def reason(self) -> str:
        return f"not during {self.twilight} night"


@dataclass(frozen=True)
class AirmassConstraint(Constraint):
    """Airmass (sec z) at most ``max_airmass`` (target above the horizon).

    Parameters
    ----------
    max_airmass : float
        Largest airmass [1], in [1, :data:`MAX_AIRMASS`].

    Raises
    ------
    InputError
        ``max_airmass`` outside that range or not a number.
    """

    max_airmass: float = 2.0
    name: ClassVar[str] = "airmass"

    def __post_init__(self) -> None:
        object.__setattr__(self, "max_airmass", check_airmass(self.max_airmass, "max_airmass"))

    def ok(self, sky: SkyModel, i: int, x: FloatArray) -> BoolArray:
        return np.asarray(airmass_from_alt(sky.target_alt_deg(i, x)) <= self.max_airmass)

    def screen(self, sky: SkyModel, i: int, x: FloatArray, slack_s: float) -> Int8Array:
        alt_min = math.degrees(math.asin(1.0 / self.max_airmass))  # sec z = max_airmass
        return _certain(sky.target_alt_deg(i, x) - alt_min, ALT_RATE_DEG_S, slack_s)

    def describe(self) -> str:
        return f"airmass <= {self.max_airmass:g}"


@dataclass(frozen=True)
class AltitudeConstraint(Constraint):
    """Altitude at least ``min_deg``.

    Parameters
    ----------
    min_deg : float or Quantity
        Lowest altitude [deg] (or an angle ``Quantity``), in [−90, 90].

    Raises
    ------
    InputError
        ``min_deg`` outside that range or not an angle.
    """

    min_deg: float = 30.0
    name: ClassVar[str] = "altitude"

    def __post_init__(self) -> None:
        limit = check_range("min_deg", _degrees(self.min_deg), -90.0, 90.0, "deg", "an altitude")
        object.__setattr__(self, "min_deg", limit)

    def ok(self, sky: SkyModel, i: int, x: FloatArray) -> BoolArray:
        return np.asarray(sky.target_alt_deg(i, x) >= self.min_deg)

    def screen(self, sky: SkyModel, i: int, x: FloatArray, slack_s: float) -> Int8Array:
        return _certain(sky.target_alt_deg(i, x) - self.min_deg, ALT_RATE_DEG_S, slack_s)

    def describe(self) -> str:
        return f"altitude >= {self.min_deg:g} deg"


@dataclass(frozen=True)
class ZenithHoleConstraint(Constraint):
    """Target outside a cone of ``radius_deg`` around the zenith (alt-az mount keyhole).

    Parameters
    ----------
    radius_deg : float or Quantity
        The cone's radius [deg] (or an angle ``Quantity``), in [0,
        :data:`MAX_ZENITH_HOLE_DEG`]; 0: no hole.

    Raises
    ------
    InputError
        ``radius_deg`` outside that range or not an angle.
    """

    radius_deg: float = 4.0
    name: ClassVar[str] = "zenith-hole"

    def __post_init__(self) -> None:
        radius = check_zenith_hole(_degrees(self.radius_deg), "radius_deg")
        object.__setattr__(self, "radius_deg", radius)

    def ok(self, sky: SkyModel, i: int, x: FloatArray) -> BoolArray:
        return np.asarray(sky.target_alt_deg(i, x) <= 90.0 - self.radius_deg)

    def screen(self, sky: SkyModel, i: int, x: FloatArray, slack_s: float) -> Int8Array:
        margin = 90.0 - self.radius_deg - sky.target_alt_deg(i, x)
        return _certain(margin, ALT_RATE_DEG_S, slack_s)

    def describe(self) -> str:
        return f"outside the {self.radius_deg:g} deg zenith hole"

    def reason(self) -> str:
        return f"passes through the {self.radius_deg:g} deg zenith hole"


@dataclass(frozen=True)
class MoonSeparationConstraint(Constraint):
    """Target at least ``min_deg`` from the Moon; with ``moon_down_ok`` (the default) always
    satisfied while the Moon is below the horizon (astroplan's counts the Moon down too:
    ``moon_down_ok=False``).

    Parameters
    ----------
    min_deg : float or Quantity
        Smallest separation [deg] (or an angle ``Quantity``), in [0, 180]; 0: no limit.
    moon_down_ok : bool
        Count the constraint as met while the Moon is below the horizon.

    Raises
    ------
    InputError
        ``min_deg`` outside that range or not an angle.
    """

    min_deg: float = 30.0
    moon_down_ok: bool = True
    name: ClassVar[str] = "moon-sep"

    def __post_init__(self) -> None:
        object.__setattr__(self, "min_deg", check_moon_sep(_degrees(self.min_deg), "min_deg"))

    def ok(self, sky: SkyModel, i: int, x: FloatArray) -> BoolArray:
        far = sky.moon_sep_deg(i, x) >= self.min_deg
        if not self.moon_down_ok:
            return np.asarray(far)
        return np.asarray(far | (sky.moon_alt_deg(x) < 0.0))

    def screen(self, sky: SkyModel, i: int, x: FloatArray, slack_s: float) -> Int8Array:
        far = _certain(sky.moon_sep_deg(i, x) - self.min_deg, MOON_SEP_RATE_DEG_S, slack_s)
        if not self.moon_down_ok:
            return far
        return _either(far, _certain(-sky.moon_alt_deg(x), MOON_ALT_RATE_DEG_S, slack_s))

    def describe(self) -> str:
        down = " (or Moon down)" if self.moon_down_ok else ""
        return f"Moon separation >= {self.min_deg:g} deg{down}"

    def reason(self) -> str:
        return f"closer than {self.min_deg:g} deg to the Moon"


@dataclass(frozen=True)
class MoonIlluminationConstraint(Constraint):
    """Moon illuminated fraction at most ``max_fraction``, or Moon below the horizon.

    Parameters
    ----------
    max_fraction : float
        Largest illuminated fraction [1], in [0, 1] (0: new Moon, 1: full Moon, no limit).

    Raises
    ------
    InputError
        ``max_fraction`` outside that range or not a number.
    """

    max_fraction: float = 1.0
    name: ClassVar[str] = "moon-illum"

    def __post_init__(self) -> None:
        fraction = check_moon_illum(self.max_fraction, "max_fraction")
        object.__setattr__(self, "max_fraction", fraction)

    def ok(self, sky: SkyModel, i: int, x: FloatArray) -> BoolArray:
        return np.asarray((sky.moon_illum(x) <= self.max_fraction) | (sky.moon_alt_deg(x) < 0.0))

    def screen(self, sky: SkyModel, i: int, x: FloatArray, slack_s: float) -> Int8Array:
        dim = _certain(self.max_fraction - sky.moon_illum(x), MOON_ILLUM_RATE_S, slack_s)
        return _either(dim, _certain(-sky.moon_alt_deg(x), MOON_ALT_RATE_DEG_S, slack_s))

    def describe(self) -> str:
        return f"Moon illumination <= {self.max_fraction:g} (or Moon down)"

    def reason(self) -> str:
        return f"Moon up and more than {self.max_fraction:g} illuminated"


#: astroplan's name for the night constraint (same class).
AtNightConstraint = NightConstraint


def check_airmass(value: Any, parameter: str) -> float:
    """An airmass limit in [1, :data:`MAX_AIRMASS`] (error names ``parameter``)."""
    why = "sec z: 1 at the zenith, 100 at 0.6 deg altitude"
    return check_range(parameter, value, 1.0, MAX_AIRMASS, "", why)


def check_moon_sep(value: Any, parameter: str) -> float:
    """A Moon separation in [0, 180] deg."""
    return check_range(parameter, value, 0.0, 180.0, "deg", "an angle on the sky; 0 = no limit")


def check_moon_illum(value: Any, parameter: str) -> float:
    """A Moon illuminated fraction in [0, 1]."""
    why = "illuminated fraction: 0 new Moon, 1 full Moon"
    return check_range(parameter, value, 0.0, 1.0, "", why)


def check_zenith_hole(value: Any, parameter: str) -> float:
    """A zenith-hole radius in [0, :data:`MAX_ZENITH_HOLE_DEG`] deg."""
    why = "radius around the zenith; alt-az telescopes have a few degrees, 0 = none"
    return check_range(parameter, value, 0.0, MAX_ZENITH_HOLE_DEG, "deg", why)


#: Constraint classes by name; :func:`make_constraint` builds one from its name.
CONSTRAINTS: dict[str, type[Constraint]] = {
    cls.name: cls
    for cls in (
        NightConstraint,
        AirmassConstraint,
        AltitudeConstraint,
        ZenithHoleConstraint,
        MoonSeparationConstraint,
        MoonIlluminationConstraint,
    )
}


def make_constraint(name: str, **kwargs: Any) -> Constraint:
    """Build a registered constraint by name.

    Raises
    ------
    InputError
        For an unknown name (lists the known ones).
    """
    try:
        cls = CONSTRAINTS[name]
    except KeyError:
        raise InputError(
            f"unknown constraint {name!r}; known: {', '.join(sorted(CONSTRAINTS))}"
        ) from None
    return cls(**kwargs)


@dataclass(frozen=True)
class ConstraintSet:
    """The constraints of one run, each under its own name.

    Night and airmass always apply (the planner explains failures with them); the others are
    optional. Iterating yields the active constraints in a fixed order — night first (it explains
    most failures), then airmass, altitude, zenith hole, Moon separation, Moon illumination — and
    the ``first_failed`` indices of :func:`evaluate_window` refer to :attr:`active`.

    Attributes
    ----------
    night : NightConstraint
        Sun below the twilight limit.
    airmass : AirmassConstraint
        Largest airmass.
    altitude, zenith_hole, moon_sep, moon_illum : Constraint or None
        Optional constraints (None: not applied).
    extra : tuple of Constraint
        Further constraints (the user's own, astroplan's, a second one of a kind), after the
        named ones.
    """

    night: NightConstraint = field(default_factory=NightConstraint)
    airmass: AirmassConstraint = field(default_factory=AirmassConstraint)
    altitude: AltitudeConstraint | None = None
    zenith_hole: ZenithHoleConstraint | None = None
    moon_sep: MoonSeparationConstraint | None = None
    moon_illum: MoonIlluminationConstraint | None = None
    extra: tuple[Constraint, ...] = ()

    @property
    def active(self) -> tuple[Constraint, ...]:
        """The applied constraints, in evaluation order (the user's own last)."""
        named = (
            self.night,
            self.airmass,
            self.altitude,
            self.zenith_hole,
            self.moon_sep,
            self.moon_illum,
        )
        return tuple(c for c in named if c is not None) + tuple(self.extra)

    @property
    def pointing(self) -> tuple[Constraint, ...]:
        """The constraints an acquisition must meet too (the telescope points at the target
        while it acquires): night, airmass, altitude and the zenith hole; the Moon limits and
        the user's own concern the exposures."""
        named = (self.night, self.airmass, self.altitude, self.zenith_hole)
        return tuple(c for c in named if c is not None)

    def __iter__(self) -> Iterator[Constraint]:
        return iter(self.active)

    def __len__(self) -> int:
        return len(self.active)

    def describe(self) -> list[str]:
        """One line per active constraint (the table provenance ``constraints``)."""
        return [c.describe() for c in self.active]
