"""The interpolations of the fast semester plan against full-precision astropy (issue 23, item 4).

Promised: epochs and UTC times within 1 µs, altitudes within 0.1″, accepted sets identical away
from 1 s of a constraint edge. Three shortcuts are pinned here, each against the exact chain:
the site's barycentric track between Earth-orientation nodes (:data:`ORIENTATION_STEP_S`), the
TDB − TT spline of :meth:`TimeAxis.utc`, and the daylight shortcut of
:func:`~ucbplan.observing.constraints.checks.evaluate_window` (exact: never skips a block that
touches the night). End to end, a plan is compared with the same plan through the exact conversions.
"""

from __future__ import annotations

from datetime import date, timedelta

import numpy as np
import pytest
from astropy import units as u
from astropy.coordinates import SkyCoord, solar_system_ephemeris
from astropy.time import Time, TimeDelta

from ucbplan.observing.blocks.block import ExposurePlan
from ucbplan.observing.constraints import NightConstraint
from ucbplan.observing.constraints.checks import DARK_STEP_S, NightScreens, _maybe_dark
from ucbplan.observing.observatory import barycentric as barycentric_time
from ucbplan.observing.observatory import time_axis as site_time_axis
from ucbplan.observing.observatory.barycentric import SiteTrack, site_icrs_frames
from ucbplan.observing.observatory.sites import get_site
from ucbplan.observing.observatory.sky import SkyModel
from ucbplan.observing.observatory.time_axis import TimeAxis
from ucbplan.observing.schedule import PlanSettings, plan_nights
from ucbplan.offline import offline
from ucbplan.targets import load_target

pytestmark = [
    pytest.mark.filterwarnings("ignore::erfa.ErfaWarning"),
    pytest.mark.filterwarnings("ignore::astropy.utils.exceptions.AstropyWarning"),
]

C_M_S = 299_792_458.0
#: 1 µs of light time [m].
ONE_US_M = C_M_S * 1e-6


def test_site_track_within_30_m_of_astropys_chain() -> None:
    # 120 days at Paranal: the interpolated track against astropy's ITRS → GCRS → ICRS chain at
    # every node. Measured ≤ 18 m (diurnal aberration of the geocentric vector, ∝ h⁴); 30 m is
    # 0.1 µs of light time, a tenth of the promise.
    loc = get_site("paranal").location
    with offline(), solar_system_ephemeris.set("builtin"):
        origin = Time("2040-03-01", scale="tdb", location=loc)
        track = SiteTrack.build(origin, (0.0, 120 * 86400.0), loc)
        exact = site_icrs_frames(loc, origin + TimeDelta(track.x_s * u.s))
    err = np.linalg.norm(track.r_m - exact, axis=1)
    assert err.max() < 30.0 < ONE_US_M / 9  # ~0.1 µs of light time
    assert err.max() > 0.01  # the track is interpolated (not the exact chain again)
    sky_dirs = SkyCoord([0.0, 121.6, 250.0] * u.deg, [-89.0, 15.5, 40.0] * u.deg)
    dirs = sky_dirs.cartesian.xyz.value.T
    assert np.abs((track.r_m - exact) @ dirs.T).max() / C_M_S < 1e-7  # light time [s]


def test_axis_utc_within_1_ns_of_astropy() -> None:
    loc = get_site("la silla").location
    with offline():
        axis = TimeAxis.starting_at(Time("2040-01-01T15:00", scale="utc"), loc)
        x = np.sort(np.random.default_rng(5).uniform(-3600.0, 183 * 86400.0, 5000))
        for shape in ((5000,), (1250, 4)):
            got = axis.utc(x.reshape(shape))
            ref = axis.tdb(x.reshape(shape)).utc  # astropy: erfa dtdb at every time
            assert got.shape == ref.shape and got.scale == "utc" and got.format == ref.format
            err_s = np.abs(((got.jd1 - ref.jd1) + (got.jd2 - ref.jd2)) * 86400.0)
            assert err_s.max() < 1e-9
        assert axis.utc(x[:10]).isot.tolist() == axis.tdb(x[:10]).utc.isot.tolist()  # exact


def test_daylight_shortcut_never_skips_a_block_that_touches_the_night() -> None:
    # Every block the shortcut skips is in daylight at every instant (Sun sampled every 10 s);
    # and it does skip the day (the point of it).
    loc = get_site("paranal").location
    night = NightConstraint("civil")
    with offline():
        sky = SkyModel.build(
            loc, Time("2040-06-01", scale="tdb"), (0.0, 20 * 86400.0), SkyCoord(0, 0, unit="deg")
        )
    rng = np.random.default_rng(7)
    xs = np.sort(rng.uniform(0.0, 20 * 86400.0 - 4000.0, 4000))
    xe = xs + rng.choice([1.0, 60.0, 900.0, 3600.0], xs.size)
    maybe = _maybe_dark(NightScreens(night, sky).dark, xs, xe)
    grid = np.arange(0.0, 20 * 86400.0, 10.0)
    dark = sky.sun_alt_deg(grid) <= night.sun_alt_max_deg
    touched = np.array(
        [dark[int(a // 10) : int(b // 10) + 2].any() for a, b in zip(xs, xe, strict=True)]
    )
    assert np.all(maybe[touched])
    assert (~maybe).sum() > xs.size / 4  # the day is skipped
    # and what is kept lies within a block and a node spacing (+ its slack) of the night
    near = np.array(
        [
            dark[max(int(a - 2 * DARK_STEP_S) // 10, 0) : int(b + 2 * DARK_STEP_S) // 10].any()
            for a, b in zip(xs[maybe], xe[maybe], strict=True)
        ]
    )
    assert near.all()


def _plan(nights: int, settings: PlanSettings) -> list:  # type: ignore[type-arg]
    hm = load_target("catalogs/hm-cnc-simulated.yaml")
    far = load_target("catalogs/fiducial-eccentric.yaml")
    days = [date(2040, 2, 15) + timedelta(days=k) for k in range(nights)]
    with offline():
        res = plan_nights([hm, far], get_site("paranal"), days, settings)
    return list(res.blocks)


def test_plan_matches_the_exact_conversions(monkeypatch: pytest.MonkeyPatch) -> None:
    # The same plan through the exact chain (site track at every node, dtdb at every time):
    # same blocks, UTC and TDB within 1 µs, altitudes within 0.1″.
    settings = PlanSettings(
        mode="u=0", exposure=ExposurePlan(60.0), sessions_per_night=1000, overhead_s=0.0
    )
    fast = _plan(6, settings)
    monkeypatch.setattr(
        barycentric_time, "_site_icrs_interpolated", lambda loc, origin, x, step_s=1.0: (
            barycentric_time._site_icrs_m(loc, origin + TimeDelta(x * u.s))
        )
    )  # fmt: skip
    monkeypatch.setattr(site_time_axis, "TDB_TT_MIN", 10**12)
    exact = _plan(6, settings)
    assert len(fast) > 200
    assert [b.block_id for b in fast] == [b.block_id for b in exact]

    def _s(a: Time, b: Time) -> float:
        return abs(float(((a.jd1 - b.jd1) + (a.jd2 - b.jd2)) * 86400.0))

    assert max(_s(f.t_mid_utc, e.t_mid_utc) for f, e in zip(fast, exact, strict=True)) > 0
    for f, e in zip(fast, exact, strict=True):
        for name in ("t_mid_utc", "t_start_utc", "t_end_utc", "t_mid_tdb_bary"):
            assert _s(getattr(f, name), getattr(e, name)) < 1e-6, name
        for name in ("alt_start_deg", "altitude_deg", "alt_end_deg"):
            assert abs(getattr(f, name) - getattr(e, name)) * 3600.0 < 0.1, name
