"""The Sun and the Moon from one Earth ephemeris per distinct time (issue 34): astropy's
frames' numbers bit for bit, and the frames wherever the shortcut's assumptions do not hold."""

from __future__ import annotations

from types import SimpleNamespace

import erfa
import numpy as np
import pytest
from astropy import units as u
from astropy.coordinates.builtin_frames.intermediate_rotation_transforms import gcrs_to_cirs_mat
from astropy.time import Time, TimeDelta
from hypothesis import given, settings
from hypothesis import strategies as st

from ucbplan.observing.observatory import sun_moon
from ucbplan.observing.observatory.sites import get_site
from ucbplan.observing.observatory.sky import moon_cirs_frames, sun_cirs_frames
from ucbplan.offline import offline


def _grid(site: str, start: str, days: float, n: int) -> Time:
    location = get_site(site).location
    t0 = Time(start, scale="tdb", location=location)
    return t0 + TimeDelta(np.linspace(0.0, days, n) * u.d)


@pytest.mark.parametrize(
    ("site", "start", "days", "n"),
    [
        ("paranal", "2040-01-01T12:00:00", 183.0, 733),  # a semester's 6-h nodes
        ("la silla", "2027-03-01T00:00:00", 2.0, 9),  # a night's
        ("mauna kea", "2031-07-15T06:00:00", 3650.0, 500),  # ten years, a node a week
        ("la palma", "2026-12-01T00:00:00", 0.0, 1),  # one node
    ],
)
def test_sun_and_moon_equal_astropys_frames_bit_for_bit(
    site: str, start: str, days: float, n: int
) -> None:
    """Against ``get_sun``/``get_body`` moved to geocentric CIRS by astropy's frames."""
    with offline():
        t = _grid(site, start, days, n)
        got = sun_moon.sun_moon_cirs_m(t, gcrs_to_cirs_mat(t))
        assert got is not None
        np.testing.assert_array_equal(got[0], sun_cirs_frames(t))
        np.testing.assert_array_equal(got[1], moon_cirs_frames(t))


def test_the_frames_are_used_where_the_shortcut_does_not_hold(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Another ephemeris, a time scale other than TDB, no site, or a moved helper: None (the
    caller takes astropy's frames)."""
    with offline():
        t = _grid("paranal", "2040-01-01T12:00:00", 1.0, 5)
        c2i = gcrs_to_cirs_mat(t)
        assert sun_moon.sun_moon_cirs_m(t, c2i) is not None
        assert sun_moon.sun_moon_cirs_m(t.tt, c2i) is None
        assert sun_moon.sun_moon_cirs_m(Time(t.jd1, t.jd2, format="jd", scale="tdb"), c2i) is None
        with monkeypatch.context() as m:  # a JPL kernel chosen (jplephem is not installed)
            m.setattr(sun_moon, "solar_system_ephemeris", SimpleNamespace(get=lambda: "de432s"))
            assert sun_moon.sun_moon_cirs_m(t, c2i) is None
        monkeypatch.setattr(sun_moon, "astropy_astrometry", lambda: None)
        assert sun_moon.sun_moon_cirs_m(t, c2i) is None


@settings(max_examples=40, deadline=None)
@given(
    st.lists(
        st.lists(st.integers(min_value=0, max_value=3), min_size=6, max_size=6),
        min_size=1,
        max_size=5,
    )
)
def test_the_ephemeris_memo_gives_each_call_what_erfa_gives(steps: list[list[int]]) -> None:
    """Successive calls in which any subset of the times moves (or none, or all): every call
    returns exactly erfa's values for its own times, and mutating what it returned does not
    change a later call's values."""
    memo = sun_moon._Ephemeris(erfa.epv00)
    jd1 = np.full(6, 2466000.5)
    for offsets in steps:
        jd2 = np.array(offsets, dtype=np.float64) * 0.01 - 1e-9 * np.arange(6)
        helio, bary = memo(jd1, jd2)
        want = erfa.epv00(jd1, jd2)
        np.testing.assert_array_equal(helio, want[0])
        np.testing.assert_array_equal(bary, want[1])
        bary["p"] = 0.0  # the caller's copy only
