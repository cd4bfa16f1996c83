"""Barycentric TDB <-> UTC at an observatory, and the coverage of astropy's time tables.

An ephemeris epoch t★ is TDB at the solar-system barycentre. The photons of that event reach the
site at t with t + Δ(t) = t★, Δ the barycentric light travel time (up to ±500 s; astropy
``Time.light_travel_time`` with the builtin ephemeris, within ~12 µs of DE421). The inversion
iterates t ← t★ − Δ(t) three times (residual < 1 ns; docs/method.md, "Barycentric and site time").
For long spans the delay Δ is evaluated exactly on a coarse grid of t★ and interpolated with a
cubic spline; the interpolation error is < 0.1 µs at the default 40-min node spacing (the fastest
term is the diurnal one, amplitude R⊕/c = 21 ms: error ≈ 5/384·(ωh)⁴·21 ms). The site's
barycentric position is sampled once (:class:`SiteTrack`) and shared by all targets; the spline
is built on nodes t★_k = t_k + Δ(t_k), exact at every node without iteration.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import erfa
import numpy as np
from astropy import units as u
from astropy.coordinates import CartesianRepresentation, EarthLocation, SkyCoord
from astropy.time import Time, TimeDelta

from ucbplan.core.constants import HOUR_S
from ucbplan.core.spline import CubicSpline, splines
from ucbplan.errors import InputError
from ucbplan.observing.observatory.time_axis import TimeAxis

#: Number of fixed-point iterations t ← t★ − Δ(t); Δ changes by ≤ 1e-4 s/s, so each iteration
#: shrinks the error by ≥ 1e4: 500 s → 0.05 s → 5 µs → 0.5 ns.
N_ITER = 3

#: Above this many epochs, :func:`bary_tdb_to_site_utc` uses the interpolated fast path.
FAST_PATH_MIN = 2000

#: Default node spacing of the delay interpolator [s].
DEFAULT_STEP_S = 2400.0

#: Node spacing of the exact astropy chain under :class:`SiteTrack` [s]. Between these nodes the
#: site's barycentric position is the Earth's (cubic spline) plus the site's geocentric vector,
#: splined in a frame turning with the Earth rotation angle (ERA, from UT1 − TDB splined): that
#: vector changes slowly (precession-nutation, polar motion) but for the aberration of the
#: 6400 km vector, which turns with the Earth relative to the orbital velocity (~640 m, diurnal;
#: a spline errs by ∝ h⁴). Measured against the exact chain over a year: ≤ 18 m at 2 h (95 m at
#: 3 h, 0.8 m at 1 h), i.e. ≤ 0.06 µs of light time; tests pin ≤ 30 m.
ORIENTATION_STEP_S = 2 * HOUR_S


def light_time_s(t: Time, coord: SkyCoord, location: EarthLocation) -> np.ndarray:
    """Barycentric light travel time Δ(t) [s] for photons from ``coord`` arriving at ``location``.

    ``t_bary = t.tdb + Δ`` (astropy convention, builtin ephemeris).
    """
    ltt = t.light_travel_time(coord, "barycentric", location=location, ephemeris="builtin")
    return np.asarray(ltt.to_value(u.s), dtype=float)


def _invert_exact(t_star: Time, coord: SkyCoord, location: EarthLocation) -> np.ndarray:
    """Delay Δ [s] with t_site + Δ(t_site) = t★ (fixed-point iteration, N_ITER times)."""
    t_star = Time(t_star, scale="tdb", location=location)
    delay = np.zeros(np.shape(t_star.jd1))
    for _ in range(N_ITER):
        t_site = t_star - TimeDelta(delay * u.s)
        delay = light_time_s(t_site, coord, location)
    return delay


def site_icrs_frames(location: EarthLocation, t: Time) -> np.ndarray:
    """Barycentric (ICRS) position of ``location`` at times ``t`` [m], shape (n, 3): the chain
    of :meth:`Time.light_travel_time`, ITRS → GCRS → ICRS through astropy's frames."""
    from astropy.coordinates import GCRS, ICRS

    itrs = location.get_itrs(obstime=t)
    bary = itrs.transform_to(GCRS(obstime=t)).transform_to(ICRS())
    return np.asarray(bary.cartesian.xyz.to_value(u.m).T, dtype=np.float64)


def astropy_rotations() -> tuple[Callable[[Time], np.ndarray], Callable[[Time], np.ndarray]] | None:
    """astropy's own (CIRS → ITRS, GCRS → CIRS) rotation-matrix functions, the ones its frame
    transformations apply, or None if a future astropy moved them (callers then take the public
    frame chain, which gives the same numbers). Applying them directly skips the frame
    machinery, which compares every per-time observer position one by one."""
    try:
        from astropy.coordinates.builtin_frames.intermediate_rotation_transforms import (
            cirs_to_itrs_mat,
            gcrs_to_cirs_mat,
        )
    except ImportError:
        return None
    return cirs_to_itrs_mat, gcrs_to_cirs_mat


#: A direction function of astropy's: (spherical representation, astrometry context) → (RA,
#: Dec) [rad].
Direction = Callable[..., tuple[np.ndarray, np.ndarray]]


def astropy_astrometry() -> tuple[Direction, Direction] | None:
    """astropy's own (GCRS or CIRS → ICRS, ICRS → GCRS or CIRS) direction functions (its
    ``aticq`` and ``atciqz``, the ones its frame transformations apply with an astrometry
    context from ``erfa_astrom``), or None if a future astropy moved them (callers then take
    the public frame chain)."""
    try:
        from astropy.coordinates.builtin_frames.utils import atciqz, aticq
    except ImportError:
        return None
    return aticq, atciqz


def gcrs_to_icrs(srepr: Any, astrom: Any, aticq: Direction) -> Any:
    """astropy's GCRS → ICRS of a position with a distance (its ``gcrs_to_icrs``), with the
    astrometry context ``astrom`` and :func:`astropy_astrometry`'s ``aticq``: the direction
    moved, then the observer's barycentric position ``eb`` added."""
    from astropy.coordinates import SphericalRepresentation

    ra, dec = aticq(srepr.without_differentials(), astrom)
    intermediate = SphericalRepresentation(
        lat=u.Quantity(dec, u.radian, copy=None),
        lon=u.Quantity(ra, u.radian, copy=None),
        distance=srepr.distance,
        copy=False,
    )
    return intermediate + CartesianRepresentation(astrom["eb"], unit=u.au, xyz_axis=-1, copy=None)


def exact_astrometry() -> bool:
    """Whether astropy builds its astrometry contexts exactly (its default ``ErfaAstrom``:
    ``apco``'s ``bpn`` is then ``c2i06a``'s matrix and ``apcs``'s ``eb`` the Earth's ``epv00``
    position), not through an interpolator a user chose (``erfa_astrom.set``)."""
    from astropy.coordinates.erfa_astrom import ErfaAstrom, erfa_astrom

    return type(erfa_astrom.get()) is ErfaAstrom


def _site_gcrs(location: EarthLocation, t: Time) -> CartesianRepresentation | None:
    """The site's GCRS position at ``t`` through the rotations of :func:`astropy_rotations`
    applied directly (None if astropy moved them)."""
    from astropy.coordinates.matrix_utilities import matrix_transpose

    rotations = astropy_rotations()
    if rotations is None:
        return None
    cirs_to_itrs_mat, gcrs_to_cirs_mat = rotations
    itrs = location.get_itrs(obstime=t).cartesian
    cirs = itrs.transform(matrix_transpose(cirs_to_itrs_mat(t)))
    return cirs.transform(matrix_transpose(gcrs_to_cirs_mat(t)))


def _site_icrs_m(location: EarthLocation, t: Time) -> np.ndarray:
    """:func:`site_icrs_frames` with the two rotations of :func:`astropy_rotations` applied
    directly: the same matrices in the same order, bit for bit (tests compare)."""
    from astropy.coordinates import GCRS, ICRS

    gcrs = _site_gcrs(location, t)
    if gcrs is None:
        return site_icrs_frames(location, t)
    bary = GCRS(gcrs, obstime=t).transform_to(ICRS())
    return np.asarray(bary.cartesian.xyz.to_value(u.m).T, dtype=np.float64)


def _site_and_earth_m(location: EarthLocation, t: Time) -> tuple[np.ndarray, np.ndarray]:
    """(:func:`_site_icrs_m`, the Earth's barycentric position, erfa ``epv00``) at ``t`` [m],
    from one ``epv00``: the astrometry context of astropy's GCRS → ICRS (``apcs``, public)
    holds the Earth's position as its observer's (``eb``: the geocentre's, exactly the
    Earth's under :func:`exact_astrometry` and the builtin ephemeris), and the
    transformation's two steps (:func:`astropy_astrometry`'s ``aticq``, then the shift by
    ``eb``) are applied to the site as astropy applies them, bit for bit (tests compare)."""
    from astropy.constants import au
    from astropy.coordinates import GCRS, SphericalRepresentation, solar_system_ephemeris
    from astropy.coordinates.erfa_astrom import erfa_astrom

    gcrs, astrometry = _site_gcrs(location, t), astropy_astrometry()
    builtin = solar_system_ephemeris.get() == "builtin"  # eb from epv00, as the Earth here
    if gcrs is None or astrometry is None or not (exact_astrometry() and builtin):
        earth = erfa.epv00(t.tdb.jd1, t.tdb.jd2)[1]["p"]
        return _site_icrs_m(location, t), earth * au.to_value(u.m)
    astrom = erfa_astrom.get().apcs(GCRS(obstime=t))
    sph = gcrs.represent_as(SphericalRepresentation)
    bary = gcrs_to_icrs(sph, astrom, astrometry[0])
    site = np.asarray(bary.to_cartesian().xyz.to_value(u.m).T, dtype=np.float64)
    return site, np.asarray(astrom["eb"] * au.to_value(u.m), dtype=np.float64)


def _turn(era: np.ndarray, v: np.ndarray, sign: float) -> np.ndarray:
    """Vectors ``v`` (n, 3) rotated about z by erfa's R3(era) (sign +1) or its inverse (−1)."""
    c, s = np.cos(era), sign * np.sin(era)
    return np.stack([c * v[:, 0] + s * v[:, 1], c * v[:, 1] - s * v[:, 0], v[:, 2]], axis=-1)


def _site_icrs_interpolated(
    location: EarthLocation, origin: Time, x: np.ndarray, step_s: float = ORIENTATION_STEP_S
) -> np.ndarray:
    """:func:`_site_icrs_m` at TDB ``origin + x`` [s] from the exact chain every ``step_s``
    (see :data:`ORIENTATION_STEP_S`); the exact chain itself where that is not fewer nodes."""
    n = int(np.ceil((x[-1] - x[0]) / step_s)) + 3
    if n + 2 >= x.size:
        return _site_icrs_m(location, origin + TimeDelta(x * u.s))
    xc = np.linspace(x[0] - step_s, x[0] + step_s * (n - 2), n)
    tc = TimeAxis(origin).tdb_grid(xc)  # TDB − TT once, kept for every conversion below
    r, earth = _site_and_earth_m(location, tc)
    ut1 = tc.ut1
    lag = (ut1.jd1 - tc.jd1) + (ut1.jd2 - tc.jd2)  # UT1 − TDB [d]: smooth (leap seconds cancel)
    spin = _turn(erfa.era00(ut1.jd1, ut1.jd2), r - earth, 1.0)  # the site in the turning frame
    td = origin + TimeDelta(x * u.s)
    lag_s, earth_s, spin_s = splines(xc, [lag, earth, spin])  # one elimination for the three
    era = erfa.era00(td.jd1, td.jd2 + lag_s(x))
    return np.asarray(earth_s(x) + _turn(era, spin_s(x), -1.0), dtype=np.float64)


@dataclass(frozen=True)
class SiteTrack:
    """Barycentric position of a site sampled on a grid of site TDB times (shared by targets).

    Attributes
    ----------
    origin : Time
        Grid origin (TDB, with ``location``); abscissae are TDB seconds after it.
    x_s : ndarray
        Node times [s after ``origin``], site-arrival axis.
    r_m : ndarray, shape (n, 3)
        ICRS-aligned barycentric position of the site at the nodes [m] (builtin ephemeris): the
        same vector astropy's ``light_travel_time`` dots with the target direction.
    """

    origin: Time
    x_s: np.ndarray
    r_m: np.ndarray
    location: EarthLocation

    @classmethod
    def build(
        cls,
        origin: Time,
        span_s: tuple[float, float],
        location: EarthLocation,
        step_s: float = DEFAULT_STEP_S,
    ) -> SiteTrack:
        """Sample the site's barycentric position every ``step_s`` over ``span_s`` (s after
        ``origin``), padded by the maximum light time plus one step on both sides."""
        from astropy.coordinates import solar_system_ephemeris

        pad = 520.0 + step_s
        lo, hi = float(span_s[0]) - pad, float(span_s[1]) + pad
        n = max(int(np.ceil((hi - lo) / step_s)) + 1, 4)
        x = np.linspace(lo, hi, n)
        origin = Time(origin, scale="tdb", location=location)
        with solar_system_ephemeris.set("builtin"):
            r = _site_icrs_interpolated(location, origin, x)
        return cls(origin=origin, x_s=x, r_m=np.ascontiguousarray(r), location=location)

    def delay_interpolator(self, coord: SkyCoord) -> DelayInterpolator:
        """Δ(t★) spline for one target: exact at nodes t★_k = x_k + Δ(x_k), no iteration."""
        from astropy import constants as const

        sph = coord.icrs.represent_as("unitspherical").to_cartesian()
        n_hat = sph.xyz.value.reshape(3)
        delay = self.r_m @ n_hat / const.c.to_value(u.m / u.s)
        return DelayInterpolator(
            t0=self.origin, spline=CubicSpline(self.x_s + delay, delay), location=self.location
        )


@dataclass(frozen=True)
class DelayInterpolator:
    """Cubic-spline model of the delay Δ(t★) over a span of barycentric TDB.

    Attributes
    ----------
    t0 : Time
        Reference epoch (TDB); abscissae are seconds after it, on the barycentric axis for t★
        and on the site-arrival axis for t = t★ − Δ.
    spline : CubicSpline
        Δ [s] as a function of t★ − t0 [s].
    """

    t0: Time
    spline: CubicSpline
    location: EarthLocation

    @classmethod
    def build(
        cls,
        t0: Time,
        span_s: tuple[float, float],
        coord: SkyCoord,
        location: EarthLocation,
        step_s: float = DEFAULT_STEP_S,
    ) -> DelayInterpolator:
        """Delay spline for one target over ``span_s`` (barycentric seconds after ``t0``)."""
        return SiteTrack.build(t0, span_s, location, step_s).delay_interpolator(coord)

    def delay_s(self, tau_s: np.ndarray) -> np.ndarray:
        """Δ [s] at barycentric epochs ``t0 + tau_s``."""
        return np.asarray(self.spline(np.asarray(tau_s, dtype=float)), dtype=float)

    def site_x(self, tau_s: np.ndarray) -> np.ndarray:
        """Arrival times at the site [TDB s after ``t0``] of barycentric epochs ``t0 + tau_s``."""
        tau = np.asarray(tau_s, dtype=float)
        return tau - self.delay_s(tau)

    def site_utc(self, tau_s: np.ndarray) -> Time:
        """UTC at the site (Time with ``location``) of barycentric TDB epochs ``t0 + tau_s``."""
        t_site = Time(self.t0, location=self.location) + TimeDelta(self.site_x(tau_s) * u.s)
        return t_site.utc


def bary_tdb_to_site_utc(
    t_star: Time,
    coord: SkyCoord,
    location: EarthLocation,
    *,
    fast: bool | None = None,
    step_s: float = DEFAULT_STEP_S,
) -> Time:
    """UTC at the site at which the light of barycentric TDB event(s) ``t_star`` arrives.

    Parameters
    ----------
    t_star : Time
        Barycentric epochs, TDB (any other scale is rejected: a TCB or UTC label would be off by
        24.5 s or 69.184 s).
    coord : SkyCoord
        Target position (ICRS).
    location : EarthLocation
        Observatory.
    fast : bool, optional
        Use the interpolated delay (default: when more than ``FAST_PATH_MIN`` epochs).
    step_s : float
        Node spacing of the fast path [s].

    Returns
    -------
    Time
        UTC, with ``location`` set (round trip through :func:`site_utc_to_bary_tdb` < 1 µs).

    Raises
    ------
    InputError
        If ``t_star`` is not in the TDB scale.

    Notes
    -----
    Inverts the light time as in docs/method.md, "Barycentric and site time"; the barycentric
    epochs come from Eq. u_precessing_app (Appendix A2).
    """
    if t_star.scale != "tdb":
        raise InputError(
            f"t_star: barycentric epochs must be TDB, got scale {t_star.scale!r}; pass t.tdb"
        )
    scalar = t_star.isscalar
    ts = t_star.reshape(-1) if not scalar else t_star.reshape(1)
    use_fast = fast if fast is not None else len(ts) > FAST_PATH_MIN
    if use_fast:
        t0 = ts[0]
        tau = (ts - t0).to_value(u.s)
        interp = DelayInterpolator.build(
            t0, (float(np.min(tau)), float(np.max(tau))), coord, location, step_s
        )
        out = interp.site_utc(tau)
    else:
        delay = _invert_exact(ts, coord, location)
        t_site = Time(ts, location=location) - TimeDelta(delay * u.s)
        out = t_site.utc
    return out[0] if scalar else out.reshape(t_star.shape)


def site_utc_to_bary_tdb(t_utc: Time, coord: SkyCoord, location: EarthLocation) -> Time:
    """Barycentric TDB of photons from ``coord`` arriving at ``location`` at UTC ``t_utc``.

    Notes
    -----
    ``t_bary = t.tdb + Δ(t)`` with astropy's builtin ephemeris; the inverse of
    :func:`bary_tdb_to_site_utc`.
    """
    t = Time(t_utc, location=location)
    return t.tdb + TimeDelta(light_time_s(t, coord, location) * u.s)


def _table_ends() -> tuple[Time, Time]:
    """(end of IERS-A UT1/polar-motion predictions, leap-second table expiry), offline."""
    from astropy.utils import iers

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        eop = iers.earth_orientation_table.get()
        iers_end = Time(float(np.max(eop["MJD"].to_value(u.d))), format="mjd", scale="utc")
        leap = iers.LeapSeconds.auto_open()
        expires = Time(leap.expires.iso[:10], scale="utc")  # a date; stored as TAI
    return iers_end, expires


def coverage_warnings(t_first: Time, t_last: Time) -> list[str]:
    """Warnings for planned times past the bundled IERS-A predictions or leap-second expiry.

    Parameters
    ----------
    t_first, t_last : Time
        First and last planned UTC.

    Returns
    -------
    list of str
        Zero, one or two one-line warnings (at most 91 characters each, so that a terminal line
        ``warning: …`` fits 100 columns) telling the user the impact and what to do;
        docs/method.md ("Barycentric and site time") explains them in full (block times are
        not affected by IERS-A; re-plan after updating the leap-second table).
    """
    iers_end, expires = _table_ends()
    out: list[str] = []
    # each fits one 100-column line after "warning: "
    if t_last > iers_end:
        out.append(
            f"IERS-A ends {iers_end.iso[:10]}: altitudes after it ~15 arcsec off; "
            "pip install -U astropy-iers-data"
        )
    if t_last > expires:
        out.append(
            f"leap-second table ends {expires.iso[:10]}: UTC may be 1 s off; "
            "pip install -U astropy-iers-data"
        )
    return out
