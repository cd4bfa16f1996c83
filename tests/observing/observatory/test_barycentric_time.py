"""Barycentric TDB <-> site UTC: fixed-point inversion, fast path, round trip, table coverage."""

from __future__ import annotations

import numpy as np
import pytest
from astropy import units as u
from astropy.coordinates import SkyCoord
from astropy.time import Time, TimeDelta
from hypothesis import given, settings
from hypothesis import strategies as st

from ucbplan.observing.observatory.barycentric import (
    DelayInterpolator,
    bary_tdb_to_site_utc,
    coverage_warnings,
    light_time_s,
    site_utc_to_bary_tdb,
)
from ucbplan.observing.observatory.sites import get_site
from ucbplan.offline import offline

HM_CNC = SkyCoord(121.5967 * u.deg, 15.4583 * u.deg)

# Dates past the leap-second table are intended (2040 nights); the planner warns once itself.
pytestmark = pytest.mark.filterwarnings("ignore::erfa.ErfaWarning")


def _epochs(n: int, start: str, span_d: float, seed: int) -> Time:
    rng = np.random.default_rng(seed)
    return Time(start, scale="tdb") + TimeDelta(np.sort(rng.uniform(0, span_d, n)) * u.d)


def test_exact_round_trip_below_1us() -> None:
    site = get_site("paranal")
    with offline():
        t_star = _epochs(50, "2040-01-01", 365.0, seed=1)
    t_utc = bary_tdb_to_site_utc(t_star, HM_CNC, site.location, fast=False)
    back = site_utc_to_bary_tdb(t_utc, HM_CNC, site.location)
    err_s = np.abs((back - t_star).to_value(u.s))
    # Requirement: < 1 us; three fixed-point iterations leave < 1 ns (dDelta/dt <= 1e-4).
    assert err_s.max() < 1e-6
    # Independent magnitude check: |Delta| <= 1.017 AU/c + R_earth/c = 507.5 s (astropy's Time
    # difference is elapsed time, so the 69.184 s UTC-TDB label offset does not enter).
    delay = (t_star - t_utc).to_value(u.s)
    assert np.abs(delay).max() < 507.6
    assert np.abs(delay).max() > 100.0  # HM Cnc is 5 deg from the ecliptic: large annual swing


def test_fast_path_interpolation_error_below_1us() -> None:
    # 60 days of epochs off the spline nodes, compared with the exact inversion at the same epochs.
    site = get_site("mauna kea")
    t_star = _epochs(400, "2040-02-01", 60.0, seed=2)
    t0 = t_star[0]
    tau = (t_star - t0).to_value(u.s)
    interp = DelayInterpolator.build(t0, (tau.min(), tau.max()), HM_CNC, site.location)
    with offline():
        exact = t_star - bary_tdb_to_site_utc(t_star, HM_CNC, site.location, fast=False).tdb
    exact_delay = exact.to_value(u.s)
    err_s = np.abs(interp.delay_s(tau) - exact_delay)
    # Requirement: < 1 us. Expected ~5/384 (omega h)^4 * 21 ms ~ 0.1 us at h = 30 min.
    assert err_s.max() < 1e-6
    fast = bary_tdb_to_site_utc(t_star, HM_CNC, site.location, fast=True)
    back = site_utc_to_bary_tdb(fast, HM_CNC, site.location)
    assert np.abs((back - t_star).to_value(u.s)).max() < 1e-6


def test_light_time_sign_convention() -> None:
    # astropy: t_bary = t.tdb + Delta. At the March equinox the Sun is at RA 0h, so the Earth
    # lies towards RA 12h, 60 deg from HM Cnc (RA 8h, ~0 ecliptic latitude): photons reach the
    # Earth first, Delta = +cos(60 deg) * 499 s ~ 250 s (ecliptic vs equator geometry: +-10 s).
    site = get_site("paranal")
    with offline():
        t = Time("2040-03-20T00:00:00", scale="utc", location=site.location)
    assert 235.0 < light_time_s(t, HM_CNC, site.location) < 265.0


def test_rejects_non_tdb() -> None:
    with pytest.raises(ValueError, match="must be TDB"):
        bary_tdb_to_site_utc(Time("2040-01-01", scale="utc"), HM_CNC, get_site("paranal").location)


def test_coverage_warnings_for_2040_and_none_for_2026() -> None:
    with offline():
        first, last = Time("2040-02-15", scale="utc"), Time("2040-02-16", scale="utc")
    warns = coverage_warnings(first, last)
    assert len(warns) == 2
    assert "IERS-A" in warns[0] and "arcsec" in warns[0]
    assert "leap-second" in warns[1] and "1 s" in warns[1]
    # One line each that fits a 100-column terminal after "warning: " (issue 15: they were ~700
    # characters; issue 24: 206 columns).
    assert all("\n" not in w and len(f"warning: {w}") <= 100 and "pip install" in w for w in warns)
    assert coverage_warnings(Time("2026-01-01"), Time("2026-01-02")) == []


@settings(max_examples=12, deadline=None)
@given(
    day=st.floats(0.0, 15 * 365.25),
    ra=st.floats(0.0, 360.0),
    dec=st.floats(-89.0, 89.0),
    site_name=st.sampled_from(["paranal", "mauna kea", "sutherland", "calar alto"]),
)
def test_round_trip_property(day: float, ra: float, dec: float, site_name: str) -> None:
    # Any epoch 2030-2045, any sky position, several sites: TDB -> site UTC -> TDB within 1 us.
    loc = get_site(site_name).location
    coord = SkyCoord(ra * u.deg, dec * u.deg)
    with offline():
        t_star = Time("2030-01-01", scale="tdb") + TimeDelta(day * u.d)
    back = site_utc_to_bary_tdb(bary_tdb_to_site_utc(t_star, coord, loc), coord, loc)
    assert abs((back - t_star).to_value(u.s)) < 1e-6


@pytest.mark.parametrize("site_name", ["paranal", "calar alto"])
def test_site_and_earth_from_one_epv00_equal_astropys(
    site_name: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The site track's nodes: the site through astropy's GCRS → ICRS steps applied with its
    astrometry context, and the Earth from that context, equal astropy's frame chain and erfa's
    ``epv00`` bit for bit; so does the fallback when a future astropy moves its helpers."""
    import erfa
    from astropy.constants import au

    from ucbplan.observing.observatory import barycentric

    location = get_site(site_name).location
    with offline():
        t = Time("2031-06-01", scale="tdb", location=location) + TimeDelta(
            np.linspace(0.0, 731.0, 500) * u.d
        )
        chain = barycentric.site_icrs_frames(location, t)
        earth = erfa.epv00(t.jd1, t.jd2)[1]["p"] * au.to_value(u.m)
        got = [barycentric._site_and_earth_m(location, t)]
        monkeypatch.setattr(barycentric, "astropy_astrometry", lambda: None)
        got.append(barycentric._site_and_earth_m(location, t))
    for site, geocentre in got:
        np.testing.assert_array_equal(site, chain)
        np.testing.assert_array_equal(geocentre, earth)


def test_site_and_earth_under_a_users_interpolated_astrometry() -> None:
    """With astropy's astrometry interpolated (a user's ``erfa_astrom.set``), the site follows
    astropy's chain under it and the Earth stays erfa's ``epv00``, bit for bit."""
    import erfa
    from astropy.constants import au
    from astropy.coordinates.erfa_astrom import ErfaAstromInterpolator, erfa_astrom

    from ucbplan.observing.observatory import barycentric

    location = get_site("paranal").location
    with offline(), erfa_astrom.set(ErfaAstromInterpolator(300 * u.s)):
        t = Time("2031-06-01", scale="tdb", location=location) + TimeDelta(
            np.linspace(0.0, 30.0, 300) * u.d
        )
        assert not barycentric.exact_astrometry()
        site, geocentre = barycentric._site_and_earth_m(location, t)
        np.testing.assert_array_equal(site, barycentric.site_icrs_frames(location, t))
    np.testing.assert_array_equal(geocentre, erfa.epv00(t.jd1, t.jd2)[1]["p"] * au.to_value(u.m))


def test_site_track_positions_equal_astropys_frame_chain() -> None:
    """The site track's direct rotations give astropy's ITRS → GCRS → ICRS chain (the one
    ``Time.light_travel_time`` uses) bit for bit, and that chain's light time is astropy's."""
    from ucbplan.observing.observatory.barycentric import _site_icrs_m, site_icrs_frames

    site = get_site("paranal")
    with offline():
        t = Time("2040-01-01", scale="tdb", location=site.location) + TimeDelta(
            np.linspace(0.0, 366.0, 400) * u.d
        )
        fast = _site_icrs_m(site.location, t)
        np.testing.assert_array_equal(fast, site_icrs_frames(site.location, t))
        n_hat = HM_CNC.cartesian.xyz.value
        ltt = fast @ n_hat / 299792458.0
    np.testing.assert_allclose(ltt, light_time_s(t, HM_CNC, site.location), rtol=0, atol=1e-12)
