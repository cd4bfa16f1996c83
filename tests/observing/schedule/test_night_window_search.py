"""Anchor epochs searched only inside the night windows (issue 23, item 4).

Promised: epochs and UTC times within 1 µs, altitudes within 0.1″, accepted sets identical away
from 1 s of a constraint edge. Pinned here against the whole-span search (every epoch of the
run solved, as before): the windowed solver gives the same epochs (same orbit counts, offsets
within a few ulp), the night intervals hold every dark instant (Sun sampled every 10 s), and
whole plans — blocks, reason counts and explanations — come out the same.
"""

from __future__ import annotations

from datetime import date, timedelta

import numpy as np
import pytest
from astropy.coordinates import SkyCoord
from astropy.time import Time

from ucbplan.core.ephemeris import find_epochs
from ucbplan.observing.blocks.block import ExposurePlan
from ucbplan.observing.constraints import ALT_RATE_DEG_S, NightConstraint
from ucbplan.observing.constraints.checks import DARK_STEP_S
from ucbplan.observing.observatory.sites import get_site, site_from_lonlat
from ucbplan.observing.observatory.sky import SkyModel
from ucbplan.observing.schedule import PlanSettings, candidates, plan_nights
from ucbplan.offline import offline
from ucbplan.targets import load_target

pytestmark = [
    pytest.mark.filterwarnings("ignore::erfa.ErfaWarning"),
    pytest.mark.filterwarnings("ignore::astropy.utils.exceptions.AstropyWarning"),
]

HM = "catalogs/hm-cnc-simulated.yaml"
ECC = "catalogs/fiducial-eccentric.yaml"


@pytest.mark.parametrize("path", [HM, ECC])
@pytest.mark.parametrize("anchor", ["quadrature", "zero-crossing", "conjunction", 1.0])
def test_windowed_epochs_are_the_whole_span_epochs_inside_the_windows(
    path: str, anchor: str | float
) -> None:
    # 20 days from 10⁸ s after the reference; windows of 2-9 h a day, one beyond each end.
    # Same orbit counts, same u★; offsets within 4 ulp of the offset (Newton's last step may
    # round differently when fewer epochs iterate together): ≤ 7 ns here, far below 1 µs.
    target = load_target(path)
    lo, hi = 1e8, 1e8 + 20 * 86400.0
    rng = np.random.default_rng(11)
    starts = lo - 3600.0 + 86400.0 * np.arange(22) + rng.uniform(0, 3600.0, 22)
    windows = np.stack([starts, starts + rng.uniform(2, 9, 22) * 3600.0], axis=1)
    whole = find_epochs(target, lo, hi, anchor, details=False)
    part = find_epochs(target, lo, hi, anchor, details=False, windows=windows)
    assert part.origin_s == whole.origin_s
    tau = whole.origin_s + whole.dt_s
    j = np.searchsorted(windows[:, 0], tau, side="right") - 1
    inside = (j >= 0) & (tau <= windows[np.maximum(j, 0), 1])
    assert 0 < inside.sum() < 0.5 * inside.size  # the day is skipped
    assert np.array_equal(part.k, whole.k[inside])
    assert np.array_equal(part.u_star_rad, whole.u_star_rad[inside])
    err = np.abs(part.dt_s - whole.dt_s[inside])
    assert np.all(err <= 4 * np.spacing(whole.dt_s[inside]))
    assert err.max() < 1e-8


def test_no_window_no_epoch() -> None:
    target = load_target(HM)
    none = find_epochs(target, 0.0, 86400.0, "quadrature", windows=np.zeros((0, 2)))
    assert len(none) == 0
    outside = find_epochs(target, 0.0, 86400.0, "quadrature", windows=np.array([[9e5, 1e6]]))
    assert len(outside) == 0


@pytest.mark.parametrize(
    ("site", "first", "twilight"),
    [
        (get_site("paranal"), "2040-06-01", "nautical"),
        (get_site("paranal"), "2040-12-01", "astronomical"),
        (site_from_lonlat("18.9,69.6,0", "Europe/Oslo"), "2040-04-25", "civil"),  # night ends
    ],
)
def test_night_intervals_hold_every_dark_instant(site: object, first: str, twilight: str) -> None:
    # The Sun sampled every 10 s over 20 days: every instant at or below the limit lies in an
    # interval; the intervals hold nothing else than twilight within the reach of the screen
    # (two node spacings at the altitude rate bound, 5.4 deg above the limit).
    loc = site.location  # type: ignore[attr-defined]
    night = NightConstraint(twilight)
    span = (0.0, 20 * 86400.0)
    with offline():
        sky = SkyModel.build(loc, Time(first, scale="tdb"), span, SkyCoord(0, 0, unit="deg"))
    w = candidates.night_search_x(night, sky, span)
    x = np.arange(0.0, span[1], 10.0)
    sun = sky.sun_alt_deg(x)
    dark = sun <= night.sun_alt_max_deg
    j = np.searchsorted(w[:, 0], x, side="right") - 1
    held = (j >= 0) & (x <= w[np.maximum(j, 0), 1])
    assert np.all(held[dark])
    assert np.all(w[1:, 0] > w[:-1, 1])  # sorted, disjoint
    reach = 2 * DARK_STEP_S * ALT_RATE_DEG_S + 1e-6
    assert np.all(sun[held] <= night.sun_alt_max_deg + reach)
    assert held.sum() < 0.8 * held.size  # the day is skipped


def _plan(site_name: str, first: date, nights: int, settings: PlanSettings) -> object:
    targets = [load_target(HM), load_target(ECC)]
    site = site_from_lonlat(site_name, "UTC") if "," in site_name else get_site(site_name)
    days = [first + timedelta(days=k) for k in range(nights)]
    with offline():
        return plan_nights(targets, site, days, settings)


def _seconds(a: Time, b: Time) -> float:
    return abs(float(((a.jd1 - b.jd1) + (a.jd2 - b.jd2)) * 86400.0))


@pytest.mark.parametrize(
    ("site", "first", "settings", "least"),
    [
        ("paranal", date(2040, 2, 15), PlanSettings(), 10),  # quadrature pairs, the defaults
        (
            "paranal",
            date(2040, 5, 1),
            PlanSettings(
                mode="u=0", exposure=ExposurePlan(60.0), sessions_per_night=1000, overhead_s=0
            ),
            500,
        ),
        ("paranal", date(2040, 3, 1), PlanSettings(mode="quadrature+conjunction"), 10),
        ("paranal", date(2040, 3, 1), PlanSettings(mode="zero-crossing"), 10),
        ("18.9,69.6,0", date(2040, 4, 10), PlanSettings(twilight="civil"), 5),  # short nights
        ("18.9,69.6,0", date(2040, 5, 10), PlanSettings(twilight="civil"), 0),  # no night
    ],
)
def test_plan_is_the_whole_span_plan(
    monkeypatch: pytest.MonkeyPatch, site: str, first: date, settings: PlanSettings, least: int
) -> None:
    # Same blocks (ids), times within 1 µs, altitudes within 0.1″; reason counts and the
    # explanations of unplaced nights identical (they read only blocks that touch the night).
    fast = _plan(site, first, 12, settings)
    monkeypatch.setattr(candidates, "night_search_x", lambda night, sky, span: None)
    whole = _plan(site, first, 12, settings)
    f_blocks, w_blocks = list(fast.blocks), list(whole.blocks)  # type: ignore[attr-defined]
    assert len(w_blocks) >= least
    assert fast.unplaced or least  # type: ignore[attr-defined]
    assert [b.block_id for b in f_blocks] == [b.block_id for b in w_blocks]
    for f, e in zip(f_blocks, w_blocks, strict=True):
        for name in ("t_mid_utc", "t_start_utc", "t_end_utc", "t_mid_tdb_bary"):
            assert _seconds(getattr(f, name), getattr(e, name)) < 1e-6, name
        for name in ("alt_start_deg", "altitude_deg", "alt_end_deg"):
            assert abs(getattr(f, name) - getattr(e, name)) * 3600.0 < 0.1, name
    assert fast.reasons == whole.reasons  # type: ignore[attr-defined]
    assert fast.unplaced == whole.unplaced  # type: ignore[attr-defined]


def test_night_windows_are_the_one_by_one_conversions() -> None:
    # One vectorised Time for all edges gives the same UTC instants, bit for bit, as one Time
    # per edge (the conversion of each datetime is element-wise), across a DST change.
    from datetime import datetime, time

    from ucbplan.observing.schedule import night_windows

    site = site_from_lonlat("-3.7,40.4,650", "Europe/Madrid")
    nights = [date(2040, 3, 20) + timedelta(days=k) for k in range(20)]
    got = night_windows(site, nights)
    assert [w.label for w in got] == [d.isoformat() for d in nights]
    for w, d in zip(got, nights, strict=True):
        for t, day in ((w.start, d), (w.end, d + timedelta(days=1))):
            one = Time(datetime.combine(day, time(12, 0), tzinfo=site.zone), scale="utc")
            assert (t.jd1, t.jd2, t.scale, t.format) == (one.jd1, one.jd2, "utc", one.format)
    assert night_windows(site, []) == []
