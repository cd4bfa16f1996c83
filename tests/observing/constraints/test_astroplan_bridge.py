"""astroplan earns its place (issue 9, item 10): a plan as an astroplan Schedule, and our
visibility constraints agree with astroplan's on random sites, targets and times."""

from __future__ import annotations

from datetime import date
from pathlib import Path

import numpy as np
import pytest
from astropy import units as u
from astropy.coordinates import EarthLocation, SkyCoord
from astropy.table import Table
from astropy.time import Time
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from ucbplan.errors import InputError
from ucbplan.observing import constraints as ours
from ucbplan.observing.blocks.block import ExposurePlan
from ucbplan.observing.blocks.make import blocks_to_table
from ucbplan.observing.exports.astroplan_schedule import to_astroplan
from ucbplan.observing.observatory.sites import get_site
from ucbplan.observing.observatory.sky import SkyModel
from ucbplan.observing.schedule import PlanSettings, plan_nights
from ucbplan.targets import load_target

CATALOGS = Path(__file__).resolve().parents[3] / "catalogs"

pytestmark = [
    pytest.mark.filterwarnings("ignore::erfa.ErfaWarning"),
    pytest.mark.filterwarnings("ignore::astropy.utils.exceptions.AstropyWarning"),
]


@pytest.fixture(scope="module")
def plan_table() -> Table:
    hm = load_target(CATALOGS / "hm-cnc-simulated.yaml")
    settings = PlanSettings(exposure=ExposurePlan(60.0), sessions_per_night=2)
    res = plan_nights([hm], get_site("paranal"), [date(2040, 2, 15)], settings)
    return blocks_to_table(res.blocks, {})


def test_planner_visits_become_astroplan_blocks(plan_table: Table) -> None:
    """One astroplan block per exposure (here one per row), each naming its visit."""
    sched = to_astroplan(plan_table, get_site("paranal"))
    blocks = sched.observing_blocks
    assert [b.name for b in blocks] == list(plan_table["block_id"])
    assert [b.configuration["visit_id"] for b in blocks] == list(plan_table["visit_id"])


def test_schedule_holds_every_block(plan_table: Table) -> None:
    site = get_site("paranal")
    plan_table = plan_table.copy()
    plan_table.remove_column("visit_id")  # without visits: one astroplan block per row
    sched = to_astroplan(plan_table, site)
    blocks = sched.observing_blocks
    assert [b.name for b in blocks] == list(plan_table["block_id"])  # time order
    for b, row in zip(blocks, plan_table, strict=True):
        # astroplan fits blocks into its slots to within 1 s.
        assert abs((b.start_time - Time(row["t_start_utc"])).to_value(u.s)) < 1.0
        assert abs((b.end_time - Time(row["t_end_utc"])).to_value(u.s)) < 1.0
        assert b.target.coord.ra.deg == pytest.approx(row["ra_deg"])
    assert sched.observer.location == site.location


def test_visits_keep_every_exposure(plan_table: Table) -> None:
    t = plan_table.copy()
    t["visit_id"] = ["V1"] * len(t)  # one visit spanning every block
    blocks = to_astroplan(t, get_site("paranal")).observing_blocks
    assert {b.configuration["visit_id"] for b in blocks} == {"V1"}
    shutter = sum(b.duration.to_value(u.s) for b in blocks)
    assert shutter == pytest.approx(float(sum(t["n_exp"] * t["exptime_s"])), abs=1.0)


def test_schedule_table(plan_table: Table) -> None:
    plan_table = plan_table.copy()
    plan_table.remove_column("visit_id")
    table = to_astroplan(plan_table, get_site("paranal")).to_table()
    assert list(table["target"]) == list(plan_table["target"])


@pytest.mark.skipif(
    not hasattr(__import__("matplotlib.axes").axes.Axes, "plot_date"),
    reason="astroplan 0.10.1's plots call Axes.plot_date, removed in matplotlib 3.10",
)
def test_plot_schedule_airmass_runs(plan_table: Table) -> None:
    from astroplan.plots import plot_schedule_airmass

    from ucbplan.plotting import pyplot

    plt = pyplot()
    plot_schedule_airmass(to_astroplan(plan_table, get_site("paranal")))
    plt.close("all")


def test_missing_column_one_line(plan_table: Table) -> None:
    with pytest.raises(InputError, match=r"missing .?ra_deg") as err:
        to_astroplan(plan_table[["target", "t_start_utc", "t_end_utc"]], get_site("paranal"))
    assert "\n" not in str(err.value) and len(str(err.value)) < 400


def _edge_ok(mismatch: np.ndarray, theirs_at: object, times: Time, ours_mask: np.ndarray) -> bool:
    """Every disagreement lies within 1 s of an astroplan edge: astroplan gives our answer at
    t - 1 s or t + 1 s."""
    idx = np.flatnonzero(mismatch)
    if idx.size == 0:
        return True
    before = theirs_at(times[idx] - 1 * u.s)  # type: ignore[operator]
    after = theirs_at(times[idx] + 1 * u.s)  # type: ignore[operator]
    return bool(np.all((before == ours_mask[idx]) | (after == ours_mask[idx])))


def _our_edges(ok: object, x: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Our edges [s on the axis], bisected to 0.05 s between samples where the mask changes."""
    k = np.flatnonzero(mask[1:] != mask[:-1])
    lo, hi = x[k].copy(), x[k + 1].copy()
    while np.any(hi - lo > 0.05):
        mid = (lo + hi) / 2
        same = ok(mid) == mask[k]  # type: ignore[operator]
        lo, hi = np.where(same, mid, lo), np.where(same, hi, mid)
    return (lo + hi) / 2


def _edges_match(
    ok: object, theirs_at: object, x: np.ndarray, mask: np.ndarray, origin: Time
) -> bool:
    """astroplan is on our side of each of our edges 1 s before and 1 s after it."""
    k = np.flatnonzero(mask[1:] != mask[:-1])
    if k.size == 0:
        return True
    edges = origin + _our_edges(ok, x, mask) * u.s
    before = theirs_at(edges - 1 * u.s)  # type: ignore[operator]
    after = theirs_at(edges + 1 * u.s)  # type: ignore[operator]
    return bool(np.all((before == mask[k]) & (after == mask[k + 1])))


@pytest.mark.slow
@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    lat=st.floats(-70.0, 70.0),
    lon=st.floats(-180.0, 180.0),
    ra=st.floats(0.0, 360.0),
    dec=st.floats(-85.0, 85.0),
    day=st.integers(0, 5 * 365),
    limits=st.tuples(st.floats(1.1, 3.0), st.floats(0.0, 60.0), st.floats(5.0, 90.0)),
)
def test_visibility_agrees_with_astroplan(
    lat: float,
    lon: float,
    ra: float,
    dec: float,
    day: int,
    limits: tuple[float, float, float],
) -> None:
    """Ours vs astroplan's AltitudeConstraint, AirmassConstraint, AtNightConstraint and
    MoonSeparationConstraint at 241 instants over one day (inside the bundled IERS tables), and
    at each of our edges (bisected to 0.05 s): astroplan must agree 1 s before and 1 s after.

    Tolerance: masks may differ only within 1 s of an edge. One second moves the Sun, Moon and
    target by <= 15 arcsec in altitude, more than the < 2 arcsec between our spline sky model
    and astropy's full transformation (tests/observing/constraints/test_constraints.py), so a larger
    disagreement would be a real error.
    """
    from astroplan import FixedTarget, Observer
    from astroplan import constraints as ap

    airmass_max, alt_min, moon_sep = limits
    loc = EarthLocation.from_geodetic(lon * u.deg, lat * u.deg, 1000.0 * u.m)
    coord = SkyCoord(ra * u.deg, dec * u.deg)
    origin = Time("2020-01-01T00:00:00", scale="utc") + day * u.day
    x = np.linspace(0.0, 86400.0, 241)
    sky = SkyModel.build(loc, origin.tdb, (0.0, 86400.0), coord)
    times = Time(origin.tdb + x * u.s, location=loc)
    observer, target = Observer(location=loc), FixedTarget(coord)
    pairs = [
        (ours.AltitudeConstraint(alt_min), ap.AltitudeConstraint(min=alt_min * u.deg)),
        (ours.AirmassConstraint(airmass_max), ap.AirmassConstraint(max=airmass_max)),
        (ours.NightConstraint("nautical"), ap.AtNightConstraint.twilight_nautical()),
    ]
    for mine, theirs in pairs:
        mask = mine.ok(sky, 0, x)

        def at(t: Time, c: object = theirs) -> np.ndarray:
            return np.asarray(c(observer, target, times=t)).ravel()  # type: ignore[operator]

        assert _edge_ok(mask != at(times), at, times, mask), type(mine).__name__
        ok = lambda xs, c=mine: c.ok(sky, 0, xs)  # noqa: E731
        assert _edges_match(ok, at, x, mask, times[0]), type(mine).__name__
    # Ours passes the Moon separation while the Moon is down; astroplan's does not look.
    sep = ap.MoonSeparationConstraint(min=moon_sep * u.deg)

    def moon_at(t: Time) -> np.ndarray:
        down = np.asarray(observer.moon_altaz(t).alt.deg < 0.0).ravel()
        return np.asarray(sep(observer, target, times=t)).ravel() | down

    mask = ours.MoonSeparationConstraint(moon_sep).ok(sky, 0, x)
    assert _edge_ok(mask != moon_at(times), moon_at, times, mask), "moon separation"
    moon_ok = ours.MoonSeparationConstraint(moon_sep)
    assert _edges_match(lambda xs: moon_ok.ok(sky, 0, xs), moon_at, x, mask, times[0])
