"""Sky model vs astropy AltAz/astroplan, and the constraint classes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from astropy import units as u
from astropy.coordinates import AltAz, SkyCoord, get_body, get_sun
from astropy.time import Time, TimeDelta

from ucbplan.errors import UcbplanError
from ucbplan.observing.constraints import (
    CONSTRAINTS,
    AirmassConstraint,
    Constraint,
    MoonIlluminationConstraint,
    MoonSeparationConstraint,
    NightConstraint,
    ZenithHoleConstraint,
    make_constraint,
)
from ucbplan.observing.constraints.checks import evaluate_window
from ucbplan.observing.observatory.sites import get_site
from ucbplan.observing.observatory.sky import SkyModel, airmass_from_alt
from ucbplan.offline import offline

pytestmark = [
    pytest.mark.filterwarnings("ignore::erfa.ErfaWarning"),
    pytest.mark.filterwarnings("ignore::astropy.utils.exceptions.AstropyWarning"),
]

# HM Cnc, the fiducial source, a zenith-passing star at Paranal, a south-polar star.
COORDS = SkyCoord([121.5967, 108.318, 0.0, 250.0] * u.deg, [15.4583, -55.652, -24.7, -89.0] * u.deg)
ORIGIN = "2040-02-01T00:00:00"
HM = str(Path(__file__).resolve().parents[3] / "catalogs" / "hm-cnc-simulated.yaml")


@pytest.fixture(scope="module")
def sky() -> SkyModel:
    site = get_site("paranal")
    with offline():
        return SkyModel.build(site.location, Time(ORIGIN, scale="tdb"), (0, 20 * 86400), COORDS)


@pytest.fixture(scope="module")
def reference(sky: SkyModel) -> dict:
    """astropy AltAz (pressure 0, like the model) at 120 random times over 20 days."""
    rng = np.random.default_rng(7)
    x = np.sort(rng.uniform(0, 20 * 86400, 120))
    with offline():
        t = Time(ORIGIN, scale="tdb", location=sky.location) + TimeDelta(x * u.s)
        frame = AltAz(obstime=t, location=sky.location)
        moon = get_body("moon", t, location=sky.location)
        return {
            "x": x,
            "t": t,
            "sun": get_sun(t).transform_to(frame).alt.deg,
            "moon": moon.transform_to(frame).alt.deg,
            "targets": [COORDS[i].transform_to(frame).alt.deg for i in range(len(COORDS))],
            "sep": [moon.separation(COORDS[i]).deg for i in range(len(COORDS))],
        }


def test_altitudes_match_astropy(sky: SkyModel, reference: dict) -> None:
    x = reference["x"]
    # Tolerances: 2 arcsec for Sun and targets (measured ~0.4"; polar motion + diurnal aberration
    # bound the model at ~0.8"), 5 arcsec for the topocentric Moon (measured ~0.6").
    assert np.abs(sky.sun_alt_deg(x) - reference["sun"]).max() * 3600 < 2.0
    assert np.abs(sky.moon_alt_deg(x) - reference["moon"]).max() * 3600 < 5.0
    for i in range(len(COORDS)):
        err = np.abs(sky.target_alt_deg(i, x) - reference["targets"][i]).max() * 3600
        assert err < 2.0, (i, err)
        sep = np.abs(sky.moon_sep_deg(i, x) - reference["sep"][i]).max() * 3600
        assert sep < 5.0, (i, sep)


def test_moon_illumination_matches_astroplan(sky: SkyModel, reference: dict) -> None:
    from astroplan import moon_illumination

    with offline():
        ref = moon_illumination(reference["t"])
    # Same geocentric phase-angle formula; 1e-3 absorbs the spline (measured 2e-5).
    assert np.abs(sky.moon_illum(reference["x"]) - ref).max() < 1e-3


def test_airmass() -> None:
    assert airmass_from_alt(np.array([90.0, 30.0, -1.0])) == pytest.approx([1.0, 2.0, np.inf])


def test_constraints_against_reference_values(sky: SkyModel, reference: dict) -> None:
    x = reference["x"]
    night = NightConstraint("astronomical").ok(sky, 0, x)
    np.testing.assert_array_equal(night, reference["sun"] <= -18.0 + 0.0)
    am = AirmassConstraint(1.5).ok(sky, 0, x)
    alt0 = reference["targets"][0]
    decided = np.abs(alt0 - np.degrees(np.arcsin(1 / 1.5))) > 1e-3  # skip knife-edge cases
    np.testing.assert_array_equal(am[decided], (alt0 >= np.degrees(np.arcsin(1 / 1.5)))[decided])
    hole = ZenithHoleConstraint(4.0).ok(sky, 2, x)
    np.testing.assert_array_equal(hole, reference["targets"][2] <= 86.0)
    sep = MoonSeparationConstraint(60.0).ok(sky, 0, x)
    expect = (reference["sep"][0] >= 60.0) | (reference["moon"] < 0)
    np.testing.assert_array_equal(sep, expect)
    # Moon illumination limit 0 is satisfied only when the Moon is down.
    dark = MoonIlluminationConstraint(0.0).ok(sky, 0, x)
    np.testing.assert_array_equal(dark, reference["moon"] < 0)


def test_zenith_hole_caught_inside_long_block(sky: SkyModel) -> None:
    # Target 2 transits ~0.1 deg from the zenith at Paranal. A 40-min block centred on transit
    # has start/end below 86 deg altitude but passes through the hole: interior sampling catches it.
    x = np.arange(0, 2 * 86400, 60.0)
    alt = sky.target_alt_deg(2, x)
    x_transit = x[np.argmax(alt)]
    ok, first = evaluate_window(
        [ZenithHoleConstraint(4.0)],
        sky,
        2,
        np.array([x_transit - 1200]),
        np.array([x_transit + 1200]),
    )
    assert sky.target_alt_deg(2, np.array([x_transit - 1200]))[0] < 86.0
    assert not ok[0] and first[0] == 0


def test_registry_and_errors() -> None:
    assert set(CONSTRAINTS) == {
        "night",
        "airmass",
        "altitude",
        "zenith-hole",
        "moon-sep",
        "moon-illum",
    }
    assert make_constraint("airmass", max_airmass=1.8).describe() == "airmass <= 1.8"
    with pytest.raises(UcbplanError, match="unknown constraint 'seeing'"):
        make_constraint("seeing")
    with pytest.raises(UcbplanError, match=r"^twilight: "):
        NightConstraint("dusk")
    with pytest.raises(UcbplanError, match=r"^max_airmass: "):  # the keyword of the class
        AirmassConstraint(0.5)


def test_constraint_set_by_name_in_fixed_order() -> None:
    from ucbplan.observing.constraints import ConstraintSet

    full = ConstraintSet(
        night=NightConstraint(twilight="astronomical"),
        airmass=AirmassConstraint(max_airmass=1.5),
        moon_illum=MoonIlluminationConstraint(max_fraction=0.3),
        zenith_hole=ZenithHoleConstraint(radius_deg=5.0),
        moon_sep=MoonSeparationConstraint(min_deg=45.0),
    )
    assert [c.name for c in full] == ["night", "airmass", "zenith-hole", "moon-sep", "moon-illum"]
    assert len(full) == 5 and full.active[2] is full.zenith_hole
    assert full.describe()[0] == "astronomical night (Sun altitude <= -18 deg)"
    assert [c.name for c in ConstraintSet()] == ["night", "airmass"]


def test_plan_settings_constraints_follow_site_and_options() -> None:
    from ucbplan.observing.schedule import PlanSettings

    paranal = get_site("paranal")  # alt-az mounts: 4 deg zenith hole in the site table
    default = PlanSettings().constraints(paranal)
    assert default.zenith_hole == ZenithHoleConstraint(radius_deg=4.0)
    assert default.moon_sep == MoonSeparationConstraint(min_deg=30.0)
    assert default.moon_illum is None
    off = PlanSettings(zenith_hole_deg=0.0, moon_sep_deg=0.0, moon_illum_max=0.5)
    got = off.constraints(paranal)
    assert got.zenith_hole is None and got.moon_sep is None
    assert got.moon_illum == MoonIlluminationConstraint(max_fraction=0.5)
    with pytest.raises(UcbplanError, match="twilight"):
        PlanSettings(twilight="dusk").constraints(paranal)


@pytest.mark.parametrize("site_name", ["paranal", "la palma", "mauna kea"])
def test_sky_nodes_from_one_matrix_equal_astropys_frames(
    site_name: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The sky model's nodes: the targets through the astrometry context of astropy's ICRS →
    CIRS, whose GCRS → CIRS matrix is astropy's own and then rotates the Sun and the Moon, give
    the frame transformations' vectors bit for bit; so do the fallbacks (astropy's rotation
    functions alone, or none) when a future astropy moves its helpers."""
    from astropy.coordinates.builtin_frames.intermediate_rotation_transforms import (
        gcrs_to_cirs_mat,
    )

    from ucbplan.observing.observatory import sky as sky_module

    location = get_site(site_name).location
    with offline():
        t = Time(ORIGIN, scale="tdb", location=location) + TimeDelta(
            np.linspace(-400.0, 400.0, 300) * u.d
        )
        frames = (
            sky_module.targets_cirs_frames(COORDS, t),
            sky_module.sun_cirs_frames(t),
            sky_module.moon_cirs_frames(t),
        )
        tvec, c2i = sky_module._targets_cirs(COORDS, t)
        assert c2i is not None
        np.testing.assert_array_equal(c2i, gcrs_to_cirs_mat(t))
        got = [(tvec, *sky_module._sun_moon_cirs_m(t, c2i))]
        monkeypatch.setattr(sky_module, "astropy_astrometry", lambda: None)
        tvec, c2i = sky_module._targets_cirs(COORDS, t)
        assert c2i is None
        got.append((tvec, *sky_module._sun_moon_cirs_m(t, c2i)))
        monkeypatch.setattr(sky_module, "astropy_rotations", lambda: None)
        got.append((sky_module._targets_cirs(COORDS, t)[0], *sky_module._sun_moon_cirs_m(t, None)))
    for way in got:
        for mine, theirs in zip(way, frames, strict=True):
            np.testing.assert_array_equal(mine, theirs)


def test_sky_nodes_under_a_users_interpolated_astrometry_equal_astropys_frames() -> None:
    """With astropy's astrometry interpolated (a user's ``erfa_astrom.set``), the targets take
    the interpolated contexts as astropy's frames do, and the Sun and the Moon the exact
    matrix as there (not the interpolated one): the frames' vectors bit for bit."""
    from astropy.coordinates.erfa_astrom import ErfaAstromInterpolator, erfa_astrom

    from ucbplan.observing.observatory import sky as sky_module

    location = get_site("paranal").location
    with offline(), erfa_astrom.set(ErfaAstromInterpolator(300 * u.s)):
        t = Time(ORIGIN, scale="tdb", location=location) + TimeDelta(
            np.linspace(0.0, 100.0, 200) * u.d
        )
        tvec, c2i = sky_module._targets_cirs(COORDS, t)
        assert c2i is None
        got = (tvec, *sky_module._sun_moon_cirs_m(t, c2i))
        frames = (
            sky_module.targets_cirs_frames(COORDS, t),
            sky_module.sun_cirs_frames(t),
            sky_module.moon_cirs_frames(t),
        )
    for mine, theirs in zip(got, frames, strict=True):
        np.testing.assert_array_equal(mine, theirs)


@pytest.mark.parametrize(
    "shape", [(3,), (1, 3), (2, 3), (7, 3), (8, 3), (9, 3), (1000, 3), (5, 9, 3), (3, 1000, 3)]
)
def test_sky_unit_vectors_equal_numpys_norm(shape: tuple[int, ...]) -> None:
    """The sky model's norm over the last axis is np.linalg.norm's bit for bit (vectors of
    every size the model normalises: metres of the Moon and Sun, unit directions)."""
    from ucbplan.observing.observatory.sky import _unit

    rng = np.random.default_rng(11)
    for _ in range(20):
        v = rng.standard_normal(shape) * 10.0 ** rng.uniform(-3.0, 12.0, shape)
        np.testing.assert_array_equal(_unit(v), v / np.linalg.norm(v, axis=-1, keepdims=True))


class _Scalar(Constraint):
    def ok(self, sky, i, x):  # type: ignore[no-untyped-def]
        return True


class _Nothing(Constraint):
    def ok(self, sky, i, x):  # type: ignore[no-untyped-def]
        return None


class _WrongShape(Constraint):
    def ok(self, sky, i, x):  # type: ignore[no-untyped-def]
        return np.ones(3, dtype=bool)


class _Floats(Constraint):
    def ok(self, sky, i, x):  # type: ignore[no-untyped-def]
        return np.full(np.shape(x), 0.5)


class _NoOk(Constraint):
    pass


@pytest.mark.parametrize(
    ("constraint", "needle"),
    [
        (_Scalar(), "_Scalar.ok(sky, i, x) returned a scalar"),
        (_Nothing(), "_Nothing.ok(sky, i, x) returned None"),
        (_WrongShape(), "_WrongShape.ok(sky, i, x) returned shape (3,)"),
        (_Floats(), "_Floats.ok(sky, i, x) returned float64"),
        (_NoOk(), "_NoOk defines no ok(sky, i, x)"),
    ],
)
def test_a_broken_custom_constraint_is_one_line(constraint: Constraint, needle: str) -> None:
    """Issue 33: numpy's AxisError, a bare NotImplementedError (empty message), now one
    InputError naming the constraint and what ok() must return."""
    import ucbplan
    from ucbplan.errors import InputError

    with pytest.raises(InputError) as exc:
        ucbplan.plan(HM, site="paranal", night="2040-02-15", constraints=[constraint])
    text = str(exc.value)
    assert needle in text and "boolean array of x's shape" in text and "\n" not in text, text
    assert exc.value.parameter == "constraints"


def test_an_astroplan_limit_in_the_wrong_unit_is_one_line() -> None:
    """Issue 33: astroplan's AltitudeConstraint(min=30*u.m) raised UnitConversionError."""
    import astroplan

    import ucbplan
    from ucbplan.errors import InputError

    with pytest.raises(InputError, match=r"AltitudeConstraint: min: expected an angle") as exc:
        ucbplan.plan(
            HM,
            site="paranal",
            night="2040-02-15",
            constraints=[astroplan.AltitudeConstraint(min=30 * u.m)],
        )
    assert "30.0 m" in str(exc.value) and exc.value.parameter == "constraints"


def test_astroplan_local_time_is_the_sites_local_time(sky: SkyModel) -> None:
    """Issue 33: astroplan 0.10.1's LocalTimeConstraint compares UTC clock times (it finds the
    time zone, then never uses it), so "22:00-01:30 local" was 22:00-01:30 UTC (19:00-22:30 in
    Chile in February: blocks at 21:50 local). ucbplan evaluates it in the site's zone (or the
    zone of the limits, as astroplan documents): 2000 random instants over 20 days against
    zoneinfo's local clock."""
    import datetime as dt
    from zoneinfo import ZoneInfo

    import astroplan

    from ucbplan.observing.constraints import holds
    from ucbplan.observing.constraints.objects import as_constraint

    window = astroplan.LocalTimeConstraint(min=dt.time(22, 0), max=dt.time(1, 30))
    native = as_constraint(window, get_site("paranal"))
    x = np.sort(np.random.default_rng(3).uniform(0, 20 * 86400, 2000))
    got = holds(native, sky, 0, x)
    zone = ZoneInfo("America/Santiago")
    with offline():
        utc = sky.time(x).utc.to_datetime(timezone=dt.UTC)
    local = [t.astimezone(zone).time() for t in utc]
    want = np.array([t >= dt.time(22, 0) or t <= dt.time(1, 30) for t in local])
    assert np.array_equal(got, want)
    assert 0.1 < got.mean() < 0.2  # 3.5 h of 24
    assert "local time 22:00:00-01:30:00 (America/Santiago)" in native.describe()
    hawaii = astroplan.LocalTimeConstraint(min=dt.time(22, 0, tzinfo=ZoneInfo("US/Hawaii")))
    assert "US/Hawaii" in as_constraint(hawaii, get_site("paranal")).describe()


def test_a_plan_applies_local_time_in_the_sites_zone() -> None:
    """The API translates astroplan's constraint before it knows the site; the run's set then
    gives it the site's zone (the blocks, checked with zoneinfo, lie in local 22:00-01:30)."""
    import datetime as dt
    from zoneinfo import ZoneInfo

    import astroplan

    import ucbplan

    window = astroplan.LocalTimeConstraint(min=dt.time(22, 0), max=dt.time(1, 30))
    res = ucbplan.plan(HM, site="paranal", night="2040-02-15", constraints=[window])
    assert "local time 22:00:00-01:30:00 (America/Santiago)" in res.run.result.constraints
    zone = ZoneInfo("America/Santiago")
    assert res.run.result.blocks
    for b in res.run.result.blocks:
        for t in (b.t_start_utc, b.t_end_utc):
            local = t.to_datetime(timezone=dt.UTC).astimezone(zone).time()
            assert local >= dt.time(22, 0) or local <= dt.time(1, 30), (t.iso, local)
