"""Observability: a fast sky model (Sun, Moon, targets) and small composable constraints.

:class:`SkyModel` evaluates geometric altitudes (no refraction, like astroplan with pressure 0)
and Moon separation/illumination at arbitrary times of a run. It calls astropy once on a coarse
grid (6 h) for the slowly moving apparent positions — targets, Sun and Moon in CIRS (which
includes precession, nutation, aberration and light deflection) and the Earth rotation angle from
UT1 — and then applies the Earth's rotation analytically: sin(alt) = û·ẑ_up with the site's
geodetic vertical rotated by the ERA. The Moon's topocentric parallax (≤ 1°) is exact (vector
difference with the site position). Polar motion (< 0.5″) and diurnal aberration (0.3″) are
neglected; the test suite compares against astropy ``AltAz`` (errors < 2″ for targets and the
Sun, < 10″ for the Moon).

Constraints are small classes registered by name in :data:`CONSTRAINTS`; each returns a boolean
mask and a short reason. :func:`evaluate_window` checks a block at start, middle, end and every
≤ 5 min in between.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from astropy import units as u
from astropy.coordinates import CIRS, EarthLocation, SkyCoord, get_body, get_sun
from astropy.time import Time, TimeDelta
from numpy.typing import NDArray
from scipy.interpolate import CubicSpline

from ucbplan.errors import UcbplanError
from ucbplan.observing.timeconv import quiet_erfa

__all__ = [
    "CONSTRAINTS",
    "TWILIGHT_SUN_ALT_DEG",
    "AirmassConstraint",
    "AltitudeConstraint",
    "Constraint",
    "MoonIlluminationConstraint",
    "MoonSeparationConstraint",
    "NightConstraint",
    "SkyModel",
    "ZenithHoleConstraint",
    "airmass_from_alt",
    "evaluate_window",
    "make_constraint",
]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

#: Sun altitude [deg] that ends each twilight.
TWILIGHT_SUN_ALT_DEG = {"civil": -6.0, "nautical": -12.0, "astronomical": -18.0}

#: Node spacing of the coarse astropy grid [s] (apparent places move < 3.5 deg per node).
SLOW_STEP_S = 6 * 3600.0

#: Largest spacing between constraint samples inside a block [s].
SAMPLE_STEP_S = 300.0


def airmass_from_alt(alt_deg: FloatArray) -> FloatArray:
    """Plane-parallel airmass sec z [1]; +inf at or below the horizon."""
    alt = np.asarray(alt_deg, dtype=np.float64)
    with np.errstate(divide="ignore"):
        out = np.where(alt > 0.0, 1.0 / np.sin(np.radians(np.maximum(alt, 1e-9))), np.inf)
    return np.asarray(out, dtype=np.float64)


def _unit(v: FloatArray) -> FloatArray:
    return np.asarray(v / np.linalg.norm(v, axis=-1, keepdims=True), dtype=np.float64)


@dataclass(frozen=True)
class SkyModel:
    """Sun, Moon and target geometry at one site over a span of time.

    Times are ``x`` = TDB seconds after ``origin`` (the site-arrival axis used by
    :class:`ucbplan.observing.timeconv.DelayInterpolator`).
    """

    origin: Time
    location: EarthLocation
    coords: SkyCoord
    era: CubicSpline
    sun: CubicSpline
    moon: CubicSpline
    targets: tuple[CubicSpline, ...]
    site_itrs_m: FloatArray
    up_itrs: FloatArray

    @classmethod
    def build(
        cls,
        location: EarthLocation,
        origin: Time,
        span_s: tuple[float, float],
        coords: SkyCoord,
        step_s: float = SLOW_STEP_S,
    ) -> SkyModel:
        """Sample apparent places on a coarse grid covering ``span_s`` (s after ``origin``).

        Parameters
        ----------
        location : EarthLocation
            Observatory.
        origin : Time
            Axis origin (any scale; used as TDB).
        span_s : (float, float)
            Times to cover [s after ``origin``]; padded by two nodes each side.
        coords : SkyCoord
            Targets (ICRS), scalar or 1-d.
        step_s : float
            Node spacing [s].
        """
        lo, hi = float(span_s[0]) - 2 * step_s, float(span_s[1]) + 2 * step_s
        n = max(math.ceil((hi - lo) / step_s) + 1, 5)
        x = np.linspace(lo, hi, n)
        coords = coords.reshape(-1) if not coords.isscalar else coords.reshape(1)
        origin = Time(origin, scale="tdb", location=location)
        with quiet_erfa():
            import erfa

            t = origin + TimeDelta(x * u.s)
            ut1 = t.ut1
            era = np.unwrap(erfa.era00(ut1.jd1, ut1.jd2))
            frame = CIRS(obstime=t)
            sun = get_sun(t).transform_to(frame).cartesian.xyz.to_value(u.m).T
            moon = get_body("moon", t).transform_to(frame).cartesian.xyz.to_value(u.m).T
            tgt = coords[:, None].transform_to(CIRS(obstime=t[None, :]))
            tvec = tgt.cartesian.xyz.value  # (3, n_targets, n_nodes), unit vectors
        tvec = np.moveaxis(tvec, 0, -1)  # (n_targets, n_nodes, 3)
        geo = location.geodetic
        lon, lat = float(geo.lon.to_value(u.rad)), float(geo.lat.to_value(u.rad))
        up = np.array([math.cos(lat) * math.cos(lon), math.cos(lat) * math.sin(lon), math.sin(lat)])
        site = np.array([c.to_value(u.m) for c in location.to_geocentric()], dtype=np.float64)
        return cls(
            origin=origin,
            location=location,
            coords=coords,
            era=CubicSpline(x, era),
            sun=CubicSpline(x, sun, axis=0),
            moon=CubicSpline(x, moon, axis=0),
            targets=tuple(CubicSpline(x, v, axis=0) for v in tvec),
            site_itrs_m=site,
            up_itrs=up,
        )

    @property
    def n_targets(self) -> int:
        """Number of targets in the model."""
        return int(self.coords.shape[0])

    def x_of(self, t: Time) -> FloatArray:
        """Axis coordinate [s after ``origin``] of times ``t``."""
        with quiet_erfa():
            return np.asarray((t - self.origin).to_value(u.s), dtype=np.float64)

    def _rotate(self, v_itrs: FloatArray, x: FloatArray) -> FloatArray:
        """ITRS (≈TIRS) vector → CIRS at times x: rotation by −ERA about z. Shape x.shape+(3,)."""
        era = self.era(x)
        c, s = np.cos(era), np.sin(era)
        return np.stack(
            [
                c * v_itrs[0] - s * v_itrs[1],
                s * v_itrs[0] + c * v_itrs[1],
                np.full_like(c, v_itrs[2]),
            ],
            axis=-1,
        )

    def up(self, x: FloatArray) -> FloatArray:
        """Local geodetic vertical in CIRS at times x."""
        return self._rotate(self.up_itrs, np.asarray(x, dtype=np.float64))

    def _alt(self, direction: FloatArray, x: FloatArray) -> FloatArray:
        s = np.einsum("...k,...k->...", _unit(direction), self.up(x))
        return np.asarray(np.degrees(np.arcsin(np.clip(s, -1.0, 1.0))), dtype=np.float64)

    def _topocentric(self, spline: CubicSpline, x: FloatArray) -> FloatArray:
        return np.asarray(spline(x) - self._rotate(self.site_itrs_m, x), dtype=np.float64)

    def sun_alt_deg(self, x: FloatArray) -> FloatArray:
        """Geometric altitude of the Sun's centre [deg]."""
        x = np.asarray(x, dtype=np.float64)
        return self._alt(self._topocentric(self.sun, x), x)

    def moon_alt_deg(self, x: FloatArray) -> FloatArray:
        """Geometric topocentric altitude of the Moon's centre [deg]."""
        x = np.asarray(x, dtype=np.float64)
        return self._alt(self._topocentric(self.moon, x), x)

    def target_dir(self, i: int, x: FloatArray) -> FloatArray:
        """Apparent (CIRS) unit vector of target ``i`` at times x."""
        return _unit(np.asarray(self.targets[i](np.asarray(x, dtype=np.float64)), dtype=np.float64))

    def target_alt_deg(self, i: int, x: FloatArray) -> FloatArray:
        """Geometric altitude of target ``i`` [deg]."""
        x = np.asarray(x, dtype=np.float64)
        return self._alt(self.target_dir(i, x), x)

    def moon_sep_deg(self, i: int, x: FloatArray) -> FloatArray:
        """Angle between target ``i`` and the topocentric Moon [deg]."""
        x = np.asarray(x, dtype=np.float64)
        m = _unit(self._topocentric(self.moon, x))
        cosang = np.einsum("...k,...k->...", m, self.target_dir(i, x))
        return np.asarray(np.degrees(np.arccos(np.clip(cosang, -1.0, 1.0))), dtype=np.float64)

    def moon_illum(self, x: FloatArray) -> FloatArray:
        """Illuminated fraction of the Moon (geocentric phase angle, as astroplan) [0–1]."""
        x = np.asarray(x, dtype=np.float64)
        s, m = self.sun(x), self.moon(x)
        rs, rm = np.linalg.norm(s, axis=-1), np.linalg.norm(m, axis=-1)
        cos_elong = np.einsum("...k,...k->...", s, m) / (rs * rm)
        elong = np.arccos(np.clip(cos_elong, -1.0, 1.0))
        phase = np.arctan2(rs * np.sin(elong), rm - rs * np.cos(elong))
        return np.asarray((1.0 + np.cos(phase)) / 2.0, dtype=np.float64)


class Constraint:
    """Base class: ``ok(sky, i, x)`` → boolean mask over times ``x`` for target ``i``."""

    name: ClassVar[str] = ""

    def ok(self, sky: SkyModel, i: int, x: FloatArray) -> BoolArray:
        """True where the constraint holds."""
        raise NotImplementedError

    def describe(self) -> str:
        """One-line human description (goes into the table provenance)."""
        raise NotImplementedError

    def reason(self) -> str:
        """Why a block fails this constraint (for the 'not placed' report)."""
        return f"violates {self.describe()}"


@dataclass(frozen=True)
class NightConstraint(Constraint):
    """Sun below the twilight limit (civil −6°, nautical −12°, astronomical −18°)."""

    twilight: str = "nautical"
    name: ClassVar[str] = "night"

    def __post_init__(self) -> None:
        if self.twilight not in TWILIGHT_SUN_ALT_DEG:
            raise UcbplanError(
                f"--twilight: expected one of {sorted(TWILIGHT_SUN_ALT_DEG)}, got {self.twilight!r}"
            )

    @property
    def sun_alt_max_deg(self) -> float:
        """Highest allowed Sun altitude [deg]."""
        return TWILIGHT_SUN_ALT_DEG[self.twilight]

    def ok(self, sky: SkyModel, i: int, x: FloatArray) -> BoolArray:
        return np.asarray(sky.sun_alt_deg(x) <= self.sun_alt_max_deg)

    def describe(self) -> str:
        return f"{self.twilight} night (Sun altitude <= {self.sun_alt_max_deg:g} deg)"

    def reason(self) -> str:
        return f"not during {self.twilight} night"


@dataclass(frozen=True)
class AirmassConstraint(Constraint):
    """Airmass (sec z) at most ``max_airmass`` (target above the horizon)."""

    max_airmass: float = 2.0
    name: ClassVar[str] = "airmass"

    def __post_init__(self) -> None:
        if not self.max_airmass >= 1.0:
            raise UcbplanError(f"--airmass-max must be >= 1, got {self.max_airmass}")

    def ok(self, sky: SkyModel, i: int, x: FloatArray) -> BoolArray:
        return np.asarray(airmass_from_alt(sky.target_alt_deg(i, x)) <= self.max_airmass)

    def describe(self) -> str:
        return f"airmass <= {self.max_airmass:g}"


@dataclass(frozen=True)
class AltitudeConstraint(Constraint):
    """Altitude at least ``min_deg``."""

    min_deg: float = 30.0
    name: ClassVar[str] = "altitude"

    def ok(self, sky: SkyModel, i: int, x: FloatArray) -> BoolArray:
        return np.asarray(sky.target_alt_deg(i, x) >= self.min_deg)

    def describe(self) -> str:
        return f"altitude >= {self.min_deg:g} deg"


@dataclass(frozen=True)
class ZenithHoleConstraint(Constraint):
    """Target outside a cone of ``radius_deg`` around the zenith (alt-az mount keyhole)."""

    radius_deg: float = 4.0
    name: ClassVar[str] = "zenith-hole"

    def ok(self, sky: SkyModel, i: int, x: FloatArray) -> BoolArray:
        return np.asarray(sky.target_alt_deg(i, x) <= 90.0 - self.radius_deg)

    def describe(self) -> str:
        return f"outside the {self.radius_deg:g} deg zenith hole"

    def reason(self) -> str:
        return f"passes through the {self.radius_deg:g} deg zenith hole"


@dataclass(frozen=True)
class MoonSeparationConstraint(Constraint):
    """Target at least ``min_deg`` from the Moon (always satisfied when the Moon is down)."""

    min_deg: float = 30.0
    name: ClassVar[str] = "moon-sep"

    def ok(self, sky: SkyModel, i: int, x: FloatArray) -> BoolArray:
        return np.asarray((sky.moon_sep_deg(i, x) >= self.min_deg) | (sky.moon_alt_deg(x) < 0.0))

    def describe(self) -> str:
        return f"Moon separation >= {self.min_deg:g} deg (or Moon down)"

    def reason(self) -> str:
        return f"closer than {self.min_deg:g} deg to the Moon"


@dataclass(frozen=True)
class MoonIlluminationConstraint(Constraint):
    """Moon illuminated fraction at most ``max_fraction``, or Moon below the horizon."""

    max_fraction: float = 1.0
    name: ClassVar[str] = "moon-illum"

    def ok(self, sky: SkyModel, i: int, x: FloatArray) -> BoolArray:
        return np.asarray((sky.moon_illum(x) <= self.max_fraction) | (sky.moon_alt_deg(x) < 0.0))

    def describe(self) -> str:
        return f"Moon illumination <= {self.max_fraction:g} (or Moon down)"

    def reason(self) -> str:
        return f"Moon up and more than {self.max_fraction:g} illuminated"


#: Constraint classes by name (STYLE.md §5).
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
    UcbplanError
        For an unknown name (lists the known ones).
    """
    try:
        cls = CONSTRAINTS[name]
    except KeyError:
        raise UcbplanError(
            f"unknown constraint {name!r}; known: {', '.join(sorted(CONSTRAINTS))}"
        ) from None
    return cls(**kwargs)


def evaluate_window(
    constraints: list[Constraint],
    sky: SkyModel,
    i: int,
    x_start: FloatArray,
    x_end: FloatArray,
) -> tuple[BoolArray, NDArray[np.int64]]:
    """Check every constraint over whole blocks [x_start, x_end].

    Samples start, middle, end and enough interior points that consecutive samples are at most
    :data:`SAMPLE_STEP_S` apart (altitude is monotonic between samples except near transit, where
    the zenith-hole constraint matters: 5-min sampling resolves a 4° hole for any declination).

    Returns
    -------
    ok : ndarray of bool
        True where all constraints hold at all samples.
    first_failed : ndarray of int
        Index in ``constraints`` of the first violated constraint, −1 where ``ok``.
    """
    xs = np.asarray(x_start, dtype=np.float64)
    xe = np.asarray(x_end, dtype=np.float64)
    width = float(np.max(xe - xs)) if xs.size else 0.0
    n = max(3, math.ceil(width / SAMPLE_STEP_S) + 1)
    if n % 2 == 0:
        n += 1  # keep the exact middle among the samples
    frac = np.linspace(0.0, 1.0, n)
    x = xs[:, None] + (xe - xs)[:, None] * frac[None, :]
    ok = np.ones(xs.shape, dtype=bool)
    first = np.full(xs.shape, -1, dtype=np.int64)
    for j, c in enumerate(constraints):
        good = np.all(c.ok(sky, i, x), axis=1)
        first[(~good) & ok] = j
        ok &= good
    return ok, first
