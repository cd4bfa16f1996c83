"""The planner's one inner time axis: conversions checked against plain astropy Time arithmetic."""

from __future__ import annotations

import numpy as np
import pytest
from astropy import units as u
from astropy.time import Time, TimeDelta

from ucbplan.observing.observatory.sites import get_site
from ucbplan.observing.observatory.time_axis import TimeAxis, elapsed
from ucbplan.offline import offline

pytestmark = pytest.mark.filterwarnings("ignore::erfa.ErfaWarning")


@pytest.fixture(scope="module")
def axis() -> TimeAxis:
    # Local noon at Paranal (UTC-3 in February) as the plan origin.
    with offline():
        start = Time("2040-02-15T15:00:00", scale="utc")
    return TimeAxis.starting_at(start, get_site("paranal").location)


def test_origin_is_the_start_as_tdb_at_the_site(axis: TimeAxis) -> None:
    assert axis.origin.scale == "tdb"
    assert axis.location is not None
    # The TDB clock reads 32.184 s + 37 leap seconds (+ < 2 ms periodic terms) ahead of UTC.
    with offline():
        tdb_reading_as_utc = Time(axis.origin.isot, scale="utc")
        start = Time("2040-02-15T15:00:00", scale="utc")
    assert elapsed(start, tdb_reading_as_utc) == pytest.approx(69.184, abs=2e-3)
    assert axis.utc(0.0).isot == "2040-02-15T15:00:00.000"


def test_x_and_times_round_trip(axis: TimeAxis) -> None:
    x = np.array([0.0, 1.5, 3600.0, 86400.0 * 3 + 0.123456])
    tdb = axis.tdb(x)
    back = np.array([axis.x(t) for t in tdb])
    np.testing.assert_allclose(back, x, rtol=0, atol=1e-9)  # Time keeps ~20 ps
    utc = axis.utc(x)
    assert utc.scale == "utc"
    assert [t.isot for t in utc] == [t.utc.isot for t in tdb]
    # A UTC time's x is measured in TAI seconds: it differs from TDB seconds by the rate of
    # TDB - TT (< 3.4e-10; 1.657 ms annual term), not by leap seconds or the 69.184 s offset.
    back_utc = np.array([axis.x(t) for t in utc])
    np.testing.assert_allclose(back_utc, x, rtol=3.4e-10, atol=1e-9)
    assert elapsed(tdb[0], tdb[3], u.d) == pytest.approx(3.0 + 0.123456 / 86400.0, abs=1e-14)


def test_epoch_axis_matches_time_arithmetic(axis: TimeAxis) -> None:
    with offline():
        t_ref = Time("2036-03-01T12:00:00", scale="tdb")
    ep = axis.epoch_axis(t_ref)
    rng = np.random.default_rng(3)
    whole = 1.2e8
    dt = rng.uniform(0.0, 5e6, 5)
    x = ep.to_x(whole, dt)
    with offline():
        direct = np.array([axis.x(t_ref + TimeDelta((whole + d) * u.s)) for d in dt])
    np.testing.assert_allclose(x, direct, rtol=0, atol=1e-6)
    assert ep.from_x(float(x[0])) == pytest.approx(whole + dt[0], abs=1e-6)
    t = ep.time(whole, dt)
    assert ep.tau(t[2]) == pytest.approx(whole + dt[2], abs=1e-6)
    np.testing.assert_allclose(np.array([axis.x(ti) for ti in t]), x, rtol=0, atol=1e-6)


def test_tdb_grid_converts_as_a_plain_grid_bit_for_bit(axis: TimeAxis) -> None:
    """A :meth:`TimeAxis.tdb_grid` (its TDB − TT term computed once and kept) converts to TT,
    TAI, UTC and UT1, itself and its slices, to the same bits as a plain :meth:`TimeAxis.tdb`;
    and its slices carry the term along (astropy's frames do not compute it again)."""
    x = np.linspace(-3.0e5, 2.0e7, 997)
    with offline():
        plain, grid = axis.tdb(x), axis.tdb_grid(x)
        for scale in ("tt", "tai", "utc", "ut1"):
            a, b = getattr(plain, scale), getattr(grid, scale)
            np.testing.assert_array_equal(a.jd1, b.jd1)
            np.testing.assert_array_equal(a.jd2, b.jd2)
        row = grid[None, :]
        assert "_delta_tdb_tt" in vars(row)  # carried along: no erfa dtdb for the slice
        np.testing.assert_array_equal(row.utc.jd2[0], plain.utc.jd2)
        assert "_delta_tdb_tt" not in vars(axis.tdb(x))  # a plain grid computes it per use
