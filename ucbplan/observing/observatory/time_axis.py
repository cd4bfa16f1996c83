"""The one time representation inside the observing code: float TDB seconds after one epoch.

astropy ``Time`` appears only at the edges — night windows come in, block times go out. Inside,
the sky model, the site track, candidate blocks and night windows all use ``x`` = TDB seconds
after the origin of a :class:`TimeAxis`: the start of the first night window (local noon), as
TDB at the site. The barycentric epochs of :func:`ucbplan.core.ephemeris.find_epochs` come on
each target's own axis, TDB seconds after its ``t_ref`` (kept as a whole part plus a remainder
for precision); an :class:`EpochAxis` is that axis seen from the plan's :class:`TimeAxis`. Every
conversion between the two axes, and between either axis and ``Time``, happens in this module.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from astropy import units as u
from astropy.coordinates import EarthLocation
from astropy.time import Time, TimeDelta
from numpy.typing import ArrayLike, NDArray

from ucbplan.core.constants import HOUR_S
from ucbplan.core.spline import CubicSpline

FloatArray = NDArray[np.float64]


#: Node spacing of the TDB − TT spline of :meth:`TimeAxis.utc` [s]. The fastest term is the
#: diurnal topocentric one (amplitude ~2 µs): a cubic spline errs by ≈ 5/384·(ωh)⁴·2 µs
#: = 0.1 ns at 1 h (tests compare with astropy's exact conversion: < 1 ns).
TDB_TT_STEP_S = HOUR_S

#: Fewest times :meth:`TimeAxis.utc` converts through the spline.
TDB_TT_MIN = 64


def _n_nodes(lo: float, hi: float) -> int:
    return int(np.ceil((hi - lo) / TDB_TT_STEP_S)) + 3


def elapsed(start: Time, end: Time, unit: u.UnitBase = u.s) -> float:
    """Time from ``start`` to ``end`` in ``unit`` (negative if ``end`` is earlier)."""
    return float((end - start).to_value(unit))


@dataclass(frozen=True)
class TimeAxis:
    """A plan's time axis: ``x`` = TDB seconds after ``origin``.

    Attributes
    ----------
    origin : Time
        The axis epoch: TDB, with the site's location (the topocentric TDB − TT term is the
        site's).
    """

    origin: Time

    @classmethod
    def starting_at(cls, start: Time, location: EarthLocation) -> TimeAxis:
        """The axis whose origin is the instant ``start`` (any scale), as TDB at ``location``."""
        at_site = Time(start, location=location)
        return cls(Time(at_site.tdb, location=location))

    @property
    def location(self) -> EarthLocation:
        """The site of the axis."""
        location: EarthLocation = self.origin.location
        return location

    def x(self, t: Time) -> float:
        """Axis coordinate [s after ``origin``] of the scalar time ``t``.

        Exact for a TDB ``t``. For a UTC ``t`` astropy measures the interval in TAI seconds,
        which run at the TDB rate to within 3.4e-10 (≤ 30 µs per day of span): used only for
        night-window edges, where it is immaterial.
        """
        return elapsed(self.origin, t)

    def tdb(self, x: ArrayLike) -> Time:
        """``Time`` (TDB, with location) of axis coordinates ``x`` [s]."""
        return self.origin + TimeDelta(np.asarray(x, dtype=np.float64) * u.s)

    def tdb_grid(self, x: ArrayLike) -> Time:
        """:meth:`tdb`, with the TDB − TT term (erfa ``dtdb``) computed once, now, and kept.

        For a grid that astropy converts many times (frames read its TT, UTC and UT1): astropy
        carries the term to the grid's slices and copies and reuses it in every later scale
        conversion of them, so ``dtdb`` runs once instead of once per conversion. It is astropy's
        own value for these times, so every conversion gives the same bits.
        """
        t = self.tdb(x)
        _ = t.delta_tdb_tt  # the property computes and keeps it (t is TDB)
        return t

    def utc(self, x: ArrayLike) -> Time:
        """``Time`` (UTC, with location) of axis coordinates ``x`` [s].

        TDB → TT needs the TDB − TT series (erfa ``dtdb``, ~20 µs a time): for many times it is
        evaluated every :data:`TDB_TT_STEP_S` and splined (module notes); a few times, exactly.
        """
        x = np.asarray(x, dtype=np.float64)
        tdb = self.tdb(x)
        if x.size < TDB_TT_MIN:
            return tdb.utc
        flat = x.ravel()
        lo, hi = float(np.min(flat)), float(np.max(flat))
        nodes = np.linspace(lo - TDB_TT_STEP_S, hi + TDB_TT_STEP_S, _n_nodes(lo, hi))
        if 4 * nodes.size > flat.size:
            return tdb.utc
        exact = self.tdb(nodes)
        tt = exact.tt
        lag_d = (exact.jd1 - tt.jd1) + (exact.jd2 - tt.jd2)  # TDB − TT [d], < 2 ms
        lag = CubicSpline(nodes, lag_d)(flat).reshape(x.shape)
        out = Time(tdb.jd1, tdb.jd2 - lag, format="jd", scale="tt", location=self.location)
        out.format = tdb.format
        return out.utc

    def epoch_axis(self, epoch: Time) -> EpochAxis:
        """The axis of seconds after ``epoch`` (e.g. a target's ``t_ref``), tied to this one."""
        return EpochAxis(epoch=epoch, lag_s=elapsed(epoch, self.origin))


@dataclass(frozen=True)
class EpochAxis:
    """Seconds after ``epoch`` (``tau``), the axis of the ephemeris, tied to a :class:`TimeAxis`.

    ``tau = x + lag_s``: the same instant on both axes (both count TDB seconds).

    Attributes
    ----------
    epoch : Time
        The axis epoch (a target's ``t_ref``, TDB).
    lag_s : float
        Seconds from ``epoch`` to the :class:`TimeAxis` origin.
    """

    epoch: Time
    lag_s: float

    def to_x(self, tau_s: ArrayLike, dt_s: ArrayLike | None = None) -> FloatArray:
        """Plan-axis ``x`` [s] of epochs ``tau_s`` (+ ``dt_s``: a whole part and a remainder are
        kept apart until after the shift, which keeps the remainder's precision)."""
        x = np.asarray(tau_s, dtype=np.float64) - self.lag_s
        if dt_s is not None:
            x = x + np.asarray(dt_s, dtype=np.float64)
        return np.asarray(x, dtype=np.float64)

    def from_x(self, x: float) -> float:
        """``tau`` [s after ``epoch``] of the plan-axis coordinate ``x``."""
        return x + self.lag_s

    def tau(self, t: Time) -> float:
        """``tau`` [s after ``epoch``] of the scalar time ``t``."""
        return elapsed(self.epoch, t)

    def time(self, whole_s: float, dt_s: ArrayLike) -> Time:
        """``Time`` (TDB) of epochs ``whole_s + dt_s`` [s after ``epoch``]."""
        dt = np.asarray(dt_s, dtype=np.float64)
        return self.epoch + TimeDelta(whole_s * u.s) + TimeDelta(dt * u.s)
