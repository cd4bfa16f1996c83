"""The Sun and the Moon on the sky model's nodes from one Earth ephemeris per distinct time.

astropy's ``get_sun`` and ``get_body("moon")`` (builtin ephemeris) followed by the frame
transformations to geocentric CIRS evaluate the Earth's ephemeris (erfa ``epv00``, a long
series: ~25 µs a time) eleven times on the same nodes: once for the Sun, once for the Earth and
once per pass of the Moon's light-time loop, and once in each of the three astrometry contexts
(``apcs``) of ICRS → GCRS (site) → ICRS → GCRS (geocentre). Here the same steps run in the same
order on the same numbers, but each distinct time's ephemeris is evaluated once: the nodes' own
(shared by the Sun, the Earth, the loop's first pass and the three contexts), and on each later
pass of the loop only where the emitted time moved (it stops moving, to the bit, as the loop
converges). The site's GCRS position reuses the GCRS → CIRS matrix the caller already holds.
The result is astropy's, bit for bit (tests compare with its frames at several sites).

It uses two of astropy's helpers that are not public API (its ``aticq``/``atciqz`` and its
CIRS → ITRS matrix function), each the one astropy's own transformations apply, as the site
track does; :func:`sun_moon_cirs_m` returns None when either moved, or when a user chose another
ephemeris or astrometry provider, and the caller then takes the frames. Every other step is
written here from public pieces (erfa, representations, ``Time``), so a later astropy that
changes its own steps changes no plan silently: the tests, comparing with its frames, say so.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import erfa
import numpy as np
from astropy import units as u
from astropy.constants import c as speed_of_light
from astropy.coordinates import (
    GCRS,
    CartesianRepresentation,
    EarthLocation,
    SphericalRepresentation,
    solar_system_ephemeris,
)
from astropy.coordinates.matrix_utilities import matrix_transpose
from astropy.time import Time
from numpy.typing import NDArray

from ucbplan.observing.observatory.barycentric import (
    Direction,
    astropy_astrometry,
    astropy_rotations,
    exact_astrometry,
    gcrs_to_icrs,
)

FloatArray = NDArray[np.float64]


class _Ephemeris:
    """erfa ``epv00`` (and ``moon98``) at TDB times, each distinct time evaluated once.

    It keeps the last times asked and their values, and on the next call evaluates only the
    elements whose (jd1, jd2) changed: erfa evaluates element by element, so the reused
    values are the ones a full call would give, to the bit.
    """

    def __init__(self, fn: Callable[..., Any]) -> None:
        self._fn = fn
        self._jd: tuple[np.ndarray, np.ndarray] | None = None
        self._out: Any = None

    def __call__(self, jd1: np.ndarray, jd2: np.ndarray) -> Any:
        if self._jd is None or self._jd[0].shape != np.shape(jd1):
            out = self._fn(jd1, jd2)
        else:
            moved = (jd1 != self._jd[0]) | (jd2 != self._jd[1])
            out = tuple(np.copy(a) for a in self._out) if self._pair else np.copy(self._out)
            if np.any(moved):
                fresh = self._fn(jd1[moved], jd2[moved])
                for old, new in zip(self._as_tuple(out), self._as_tuple(fresh), strict=True):
                    old[moved] = new
        self._jd, self._out = (np.copy(jd1), np.copy(jd2)), out
        return tuple(np.copy(a) for a in out) if self._pair else np.copy(out)

    @property
    def _pair(self) -> bool:
        return isinstance(self._out, tuple)

    @staticmethod
    def _as_tuple(value: Any) -> tuple[Any, ...]:
        return value if isinstance(value, tuple) else (value,)


def _tdb_jd(t: Time) -> tuple[np.ndarray, np.ndarray]:
    """(jd1, jd2) of a TDB ``t``: what astropy's ``get_jd12(t, "tdb")`` returns for it."""
    return np.asarray(t.jd1), np.asarray(t.jd2)


def _sun_gcrs(earth_helio: Any, earth_bary: Any) -> SphericalRepresentation:
    """astropy's ``get_sun`` from the Earth's ``epv00``: the Sun's GCRS position [AU], the
    aberration applied as there (the velocity divided into a new array, the inputs kept), held
    in spherical coordinates as its ``SkyCoord`` holds it."""
    earth_p = earth_helio["p"]
    earth_v = earth_bary["v"] / speed_of_light.to_value(u.au / u.d)
    dsun = np.sqrt(np.sum(earth_p**2, axis=-1))
    invlorentz = (1 - np.sum(earth_v**2, axis=-1)) ** 0.5
    properdir = erfa.ab(earth_p / dsun[..., None], -earth_v, dsun, invlorentz)
    return CartesianRepresentation(
        x=-dsun * properdir[..., 0] * u.AU,
        y=-dsun * properdir[..., 1] * u.AU,
        z=-dsun * properdir[..., 2] * u.AU,
    ).represent_as(SphericalRepresentation)


def _moon_barycentric(t: Time, epv00: _Ephemeris, moon98: _Ephemeris) -> CartesianRepresentation:
    """astropy's ``get_body_barycentric("moon", t)`` under the builtin ephemeris [AU]."""
    jd1, jd2 = _tdb_jd(t)
    earth_bary = epv00(jd1, jd2)[1]
    body = erfa.pvppv(moon98(jd1, jd2), earth_bary)
    return CartesianRepresentation(body["p"], unit=u.au, xyz_axis=-1, copy=None)


def _moon_icrs(
    t: Time, earth_bary: Any, obsgeoloc: CartesianRepresentation, epv00: _Ephemeris
) -> CartesianRepresentation:
    """The Moon's barycentric position at the time its light left it to reach the site at
    ``t``: astropy's light-time loop (``_get_apparent_body_position``), step for step."""
    moon98 = _Ephemeris(erfa.moon98)
    delta_light_travel_time = 20.0 * u.s
    emitted_time = t
    light_travel_time = 0.0 * u.s
    earth_loc = CartesianRepresentation(earth_bary["p"], unit=u.au, xyz_axis=-1, copy=None)
    earth_loc = earth_loc + obsgeoloc
    while np.any(np.fabs(delta_light_travel_time) > 1.0e-8 * u.s):
        body_loc = _moon_barycentric(emitted_time, epv00, moon98)
        earth_distance = (body_loc - earth_loc).norm()
        delta_light_travel_time = light_travel_time - earth_distance / speed_of_light
        light_travel_time = earth_distance / speed_of_light
        emitted_time = t - light_travel_time
    return _moon_barycentric(emitted_time, epv00, moon98)


def _apcs(frame: GCRS, earth: tuple[Any, Any]) -> Any:
    """astropy's ``ErfaAstrom.apcs(frame)`` with the Earth's ``epv00`` given."""
    tt = frame.obstime.tt
    obs_pv = np.empty(frame.obsgeoloc.shape, erfa.dt_pv)
    obs_pv["p"] = frame.obsgeoloc.get_xyz(xyz_axis=-1).value
    obs_pv["v"] = frame.obsgeovel.get_xyz(xyz_axis=-1).value
    return erfa.apcs(tt.jd1, tt.jd2, obs_pv, earth[1], earth[0]["p"])


def _to_gcrs(cart: CartesianRepresentation, astrom: Any, atciqz: Direction) -> Any:
    """astropy's ICRS → GCRS of a position with a distance (its ``icrs_to_gcrs``)."""
    eb = CartesianRepresentation(astrom["eb"], unit=u.au, xyz_axis=-1, copy=None)
    srepr = (cart - eb).represent_as(SphericalRepresentation)
    ra, dec = atciqz(srepr.without_differentials(), astrom)
    return SphericalRepresentation(
        lat=u.Quantity(dec, u.radian, copy=None),
        lon=u.Quantity(ra, u.radian, copy=None),
        distance=srepr.distance,
        copy=False,
    )


#: The Earth's rotation rate [rad/s] as astropy's ``EarthLocation`` states it.
OMEGA_EARTH = (1.002_737_811_911_354_48 * u.cycle / u.day).to(1 / u.s, u.dimensionless_angles())


def _site_gcrs_posvel(
    location: EarthLocation, cirs_to_itrs: FloatArray, c2i: FloatArray
) -> tuple[CartesianRepresentation, CartesianRepresentation]:
    """The site's GCRS position and velocity as ``location.get_gcrs_posvel(t)`` forms them
    (one rotation ITRS → GCRS through CIRS, the velocity the Earth's spin crossed with the
    position), from the two matrices at ``t``."""
    cirs_to_gcrs = matrix_transpose(c2i)
    itrs_to_gcrs = cirs_to_gcrs @ matrix_transpose(cirs_to_itrs)
    spin = CartesianRepresentation(cirs_to_gcrs[..., 2] * OMEGA_EARTH, xyz_axis=-1, copy=False)
    itrs = CartesianRepresentation(location.x, location.y, location.z, copy=False)
    position = itrs.transform(itrs_to_gcrs)
    return position, spin.cross(position)


def _usable(t: Time) -> bool:
    return (
        t.scale == "tdb"
        and t.location is not None
        and exact_astrometry()
        and solar_system_ephemeris.get() == "builtin"
    )


def sun_moon_cirs_m(t: Time, c2i: FloatArray) -> tuple[FloatArray, FloatArray] | None:
    """The Sun's and the Moon's geocentric CIRS positions [m], (n, 3), at the TDB times ``t``
    (with the site as location; ``c2i`` astropy's GCRS → CIRS matrix at ``t``), as
    ``get_sun(t)`` and ``get_body("moon", t)`` moved to the geocentre and rotated by ``c2i``
    give them, bit for bit; None where the helpers or the defaults it relies on are not
    there (module notes)."""
    astrometry, rotations = astropy_astrometry(), astropy_rotations()
    if astrometry is None or rotations is None or not _usable(t):
        return None
    aticq, atciqz = astrometry
    epv00 = _Ephemeris(erfa.epv00)
    earth = epv00(*_tdb_jd(t))
    sun = _sun_gcrs(*earth).to_cartesian().transform(c2i).xyz.to_value(u.m).T
    obsgeoloc, obsgeovel = _site_gcrs_posvel(t.location, rotations[0](t), c2i)
    at_site = GCRS(obstime=t, obsgeoloc=obsgeoloc, obsgeovel=obsgeovel)
    zero = [0.0, 0.0, 0.0]
    at_geocentre = GCRS(obstime=t, obsgeoloc=zero * u.m, obsgeovel=zero * u.m / u.s)
    site_astrom = _apcs(at_site, earth)
    moon = _to_gcrs(_moon_icrs(t, earth[1], obsgeoloc, epv00), site_astrom, atciqz)
    moon = _to_gcrs(gcrs_to_icrs(moon, site_astrom, aticq), _apcs(at_geocentre, earth), atciqz)
    moon = moon.to_cartesian().transform(c2i)
    moon = moon.represent_as(SphericalRepresentation).to_cartesian().xyz.to_value(u.m).T
    return np.asarray(sun, dtype=np.float64), np.asarray(moon, dtype=np.float64)
