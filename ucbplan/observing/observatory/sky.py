"""A fast sky model of one site: Sun, Moon and targets at arbitrary times of a run.

:class:`SkyModel` evaluates geometric altitudes (no refraction, like astroplan with pressure 0)
and Moon separation/illumination at arbitrary times of a run. It calls astropy once on a coarse
grid (6 h) for the slowly moving apparent positions — targets, Sun and Moon in CIRS (which
includes precession, nutation, aberration and light deflection) and the Earth rotation angle from
UT1 — and then applies the Earth's rotation analytically: sin(alt) = û·ẑ_up with the site's
geodetic vertical rotated by the ERA. The Moon's topocentric parallax (≤ 1°) is exact (vector
difference with the site position). Polar motion (< 0.5″) and diurnal aberration (0.3″) are
neglected; the test suite compares against astropy ``AltAz`` (errors < 2″ for targets and the
Sun, < 10″ for the Moon).

Times are ``x`` = TDB seconds after the model's origin (see
:class:`ucbplan.observing.observatory.barycentric.TimeAxis`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from astropy import units as u
from astropy.coordinates import (
    CIRS,
    GCRS,
    EarthLocation,
    SkyCoord,
    SphericalRepresentation,
    UnitSphericalRepresentation,
    get_body,
    get_sun,
)
from astropy.coordinates.erfa_astrom import erfa_astrom
from astropy.time import Time
from numpy.typing import NDArray

from ucbplan.core.constants import HOUR_S
from ucbplan.core.spline import CubicSpline, splines
from ucbplan.observing.observatory.barycentric import (
    astropy_astrometry,
    astropy_rotations,
    exact_astrometry,
)
from ucbplan.observing.observatory.sun_moon import sun_moon_cirs_m
from ucbplan.observing.observatory.time_axis import TimeAxis

FloatArray = NDArray[np.float64]

#: Node spacing of the coarse astropy grid [s] (apparent places move < 3.5 deg per node).
SLOW_STEP_S = 6 * HOUR_S


def airmass_from_alt(alt_deg: FloatArray) -> FloatArray:
    """Plane-parallel airmass sec z [1]; +inf at or below the horizon."""
    alt = np.asarray(alt_deg, dtype=np.float64)
    with np.errstate(divide="ignore"):
        out = np.where(alt > 0.0, 1.0 / np.sin(np.radians(np.maximum(alt, 1e-9))), np.inf)
    return np.asarray(out, dtype=np.float64)


def _norm3(v: FloatArray) -> FloatArray:
    """|v| over the last axis (length 3), kept as a length-1 axis: √((x² + y²) + z²), the sum
    ``np.linalg.norm`` forms there, in its order, without its generic reduction over a short
    axis (~4× faster; tests compare bit for bit)."""
    x, y, z = v[..., 0], v[..., 1], v[..., 2]
    return np.sqrt((x * x + y * y) + z * z)[..., None]


def _unit(v: FloatArray) -> FloatArray:
    return np.asarray(v / _norm3(v), dtype=np.float64)


def sun_cirs_frames(t: Time) -> FloatArray:
    """Geocentric CIRS position of the Sun at ``t`` [m], (n, 3), through astropy's frames."""
    sun = get_sun(t).transform_to(CIRS(obstime=t)).cartesian.xyz.to_value(u.m).T
    return np.asarray(sun, dtype=np.float64)


def moon_cirs_frames(t: Time) -> FloatArray:
    """Geocentric CIRS position [m], (n, 3), of the Moon as seen from ``t.location`` (its
    light time from the site), through astropy's frames."""
    moon = get_body("moon", t).transform_to(CIRS(obstime=t))
    return np.asarray(moon.cartesian.xyz.to_value(u.m).T, dtype=np.float64)


def targets_cirs_frames(coords: SkyCoord, t: Time) -> FloatArray:
    """Apparent (CIRS) unit vectors of the 1-d ``coords`` at ``t``, (n_targets, n, 3), through
    astropy's frames."""
    tgt = coords[:, None].transform_to(CIRS(obstime=t[None, :]))
    return np.moveaxis(tgt.cartesian.xyz.value, 0, -1)


def _targets_cirs(coords: SkyCoord, t: Time) -> tuple[FloatArray, FloatArray | None]:
    """(:func:`targets_cirs_frames`, astropy's GCRS → CIRS matrix at ``t`` or None).

    astropy's ICRS → CIRS builds an astrometry context (``erfa_astrom``'s ``apco``, public)
    whose ``bpn`` is the GCRS → CIRS matrix, from the same precession-nutation (erfa ``c2ixys``
    of ``pnm06a``'s pole, as ``c2i06a``); applying its direction function
    (:func:`~ucbplan.observing.observatory.barycentric.astropy_astrometry`) with that context
    gives the transformation's vectors, and the Sun and the Moon reuse the matrix, bit for bit
    (tests compare). The matrix is None where astropy's contexts are interpolated
    (:func:`~ucbplan.observing.observatory.barycentric.exact_astrometry`), and the frames give
    the vectors where a future astropy moved the function.
    """
    astrometry = astropy_astrometry()
    if astrometry is None:
        return targets_cirs_frames(coords, t), None
    astrom = erfa_astrom.get().apco(CIRS(obstime=t))
    sph = coords[:, None].spherical.without_differentials()
    ra, dec = astrometry[1](sph, astrom)
    cirs = UnitSphericalRepresentation(ra * u.rad, dec * u.rad, copy=False).to_cartesian()
    c2i = np.asarray(astrom["bpn"], dtype=np.float64) if exact_astrometry() else None
    return np.moveaxis(cirs.xyz.value, 0, -1), c2i


def _sun_moon_cirs_m(t: Time, c2i: FloatArray | None) -> tuple[FloatArray, FloatArray]:
    """(:func:`sun_cirs_frames`, :func:`moon_cirs_frames`) with astropy's GCRS → CIRS matrix
    ``c2i`` (None: :func:`astropy_rotations`'s) applied directly, bit for bit (tests compare).
    The Moon's frame transformation moves it to the geocentre first (GCRS → GCRS, as astropy's
    GCRS → CIRS does) and keeps spherical data, so the rotated vector goes through spherical
    coordinates as there."""
    if c2i is not None:
        shared = sun_moon_cirs_m(t, c2i)  # one Earth ephemeris per distinct time
        if shared is not None:
            return shared
    if c2i is None:
        rotations = astropy_rotations()
        if rotations is None:
            return sun_cirs_frames(t), moon_cirs_frames(t)
        c2i = rotations[1](t)
    sun = get_sun(t).cartesian.transform(c2i).xyz.to_value(u.m).T
    zero = [0.0, 0.0, 0.0]
    at_geocentre = GCRS(obstime=t, obsgeoloc=zero * u.m, obsgeovel=zero * u.m / u.s)
    moon = get_body("moon", t).frame.transform_to(at_geocentre).cartesian.transform(c2i)
    moon = moon.represent_as(SphericalRepresentation).to_cartesian().xyz.to_value(u.m).T
    return np.asarray(sun, dtype=np.float64), np.asarray(moon, dtype=np.float64)


@dataclass(frozen=True)
class SkyModel:
    """Sun, Moon and target geometry at one site over a span of time.

    Times are ``x`` = TDB seconds after ``origin`` (the site-arrival axis used by
    :class:`ucbplan.observing.observatory.barycentric.DelayInterpolator`).
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
        import erfa

        t = TimeAxis(origin).tdb_grid(x)  # one dtdb for every frame below
        ut1 = t.ut1
        era = np.unwrap(erfa.era00(ut1.jd1, ut1.jd2))
        tvec, c2i = _targets_cirs(coords, t)  # (n_targets, n_nodes, 3), unit vectors
        # the Moon seen from the site (t has its location), then geocentric CIRS
        sun, moon = _sun_moon_cirs_m(t, c2i)
        geo = location.geodetic
        lon, lat = float(geo.lon.to_value(u.rad)), float(geo.lat.to_value(u.rad))
        up = np.array([math.cos(lat) * math.cos(lon), math.cos(lat) * math.sin(lon), math.sin(lat)])
        site = np.array([c.to_value(u.m) for c in location.to_geocentric()], dtype=np.float64)
        era_s, sun_s, moon_s, *targets = splines(x, [era, sun, moon, *tvec])
        return cls(
            origin=origin,
            location=location,
            coords=coords,
            era=era_s,
            sun=sun_s,
            moon=moon_s,
            targets=tuple(targets),
            site_itrs_m=site,
            up_itrs=up,
        )

    def time(self, x: FloatArray) -> Time:
        """The instants ``x`` [s after the origin] as astropy ``Time`` (TDB at the site)."""
        return TimeAxis(self.origin).tdb(np.asarray(x, dtype=np.float64))

    @property
    def n_targets(self) -> int:
        """Number of targets in the model."""
        return int(self.coords.shape[0])

    def _spin(self, x: FloatArray) -> tuple[FloatArray, FloatArray]:
        """(cos, sin) of the Earth rotation angle at times x."""
        era = self.era(x)
        return np.cos(era), np.sin(era)

    @staticmethod
    def _rotate(v_itrs: FloatArray, spin: tuple[FloatArray, FloatArray]) -> FloatArray:
        """ITRS (≈TIRS) vector → CIRS: rotation by −ERA about z (``spin``: its cos and sin at
        the times wanted). Shape x.shape+(3,)."""
        c, s = spin
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
        return self._rotate(self.up_itrs, self._spin(np.asarray(x, dtype=np.float64)))

    def _alt(self, direction: FloatArray, spin: tuple[FloatArray, FloatArray]) -> FloatArray:
        s = np.einsum("...k,...k->...", _unit(direction), self._rotate(self.up_itrs, spin))
        return np.asarray(np.degrees(np.arcsin(np.clip(s, -1.0, 1.0))), dtype=np.float64)

    def _topocentric(
        self, spline: CubicSpline, x: FloatArray, spin: tuple[FloatArray, FloatArray]
    ) -> FloatArray:
        return np.asarray(spline(x) - self._rotate(self.site_itrs_m, spin), dtype=np.float64)

    def sun_alt_deg(self, x: FloatArray) -> FloatArray:
        """Geometric altitude of the Sun's centre [deg]."""
        x = np.asarray(x, dtype=np.float64)
        spin = self._spin(x)  # one Earth rotation angle for the site and its vertical
        return self._alt(self._topocentric(self.sun, x, spin), spin)

    def moon_alt_deg(self, x: FloatArray) -> FloatArray:
        """Geometric topocentric altitude of the Moon's centre [deg]."""
        x = np.asarray(x, dtype=np.float64)
        spin = self._spin(x)
        return self._alt(self._topocentric(self.moon, x, spin), spin)

    def target_dir(self, i: int, x: FloatArray) -> FloatArray:
        """Apparent (CIRS) unit vector of target ``i`` at times x."""
        return _unit(np.asarray(self.targets[i](np.asarray(x, dtype=np.float64)), dtype=np.float64))

    def target_alt_deg(self, i: int, x: FloatArray) -> FloatArray:
        """Geometric altitude of target ``i`` [deg]."""
        x = np.asarray(x, dtype=np.float64)
        return self._alt(self.target_dir(i, x), self._spin(x))

    def moon_sep_deg(self, i: int, x: FloatArray) -> FloatArray:
        """Angle between target ``i`` and the topocentric Moon [deg]."""
        x = np.asarray(x, dtype=np.float64)
        m = _unit(self._topocentric(self.moon, x, self._spin(x)))
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
