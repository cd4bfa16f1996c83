"""The screened constraint check is the exact one, and its rate bounds hold (issue 14).

:func:`evaluate_window` decides most blocks from a 5-min grid, using the declared bounds on how
fast each screened quantity of the sky model changes. Two independent checks:

* the bounds themselves, against the largest rate found by finite differences of the model over
  a whole year at 20-s steps (targets from the pole to the equator, a zenith-passing one);
* the decisions, against :func:`evaluate_window_exact` (every constraint at every sample) on
  random blocks of several widths, many placed within minutes of a limit, with all six
  constraints active: ``ok`` and ``first_failed`` must be identical.
"""

from __future__ import annotations

import numpy as np
import pytest
from astropy import units as u
from astropy.coordinates import SkyCoord
from astropy.time import Time

from ucbplan.observing.constraints import (
    ALT_RATE_DEG_S,
    MOON_ALT_RATE_DEG_S,
    MOON_ILLUM_RATE_S,
    MOON_SEP_RATE_DEG_S,
    AirmassConstraint,
    AltitudeConstraint,
    ConstraintSet,
    MoonIlluminationConstraint,
    MoonSeparationConstraint,
    NightConstraint,
    ZenithHoleConstraint,
)
from ucbplan.observing.constraints.checks import (
    NightScreens,
    evaluate_window,
    evaluate_window_exact,
)
from ucbplan.observing.observatory.sites import get_site
from ucbplan.observing.observatory.sky import SkyModel
from ucbplan.offline import offline

pytestmark = [
    pytest.mark.filterwarnings("ignore::erfa.ErfaWarning"),
    pytest.mark.filterwarnings("ignore::astropy.utils.exceptions.AstropyWarning"),
]

# equatorial, Paranal-zenith (dec = site latitude), mid-south, near the south pole, far north
COORDS = SkyCoord(
    [10.0, 95.0, 200.0, 250.0, 300.0] * u.deg, [0.0, -24.63, -50.0, -88.0, 30.0] * u.deg
)
YEAR_S = 365.25 * 86400


@pytest.fixture(scope="module")
def sky() -> SkyModel:
    site = get_site("paranal")
    with offline():
        return SkyModel.build(site.location, Time("2041-03-01", scale="tdb"), (0, YEAR_S), COORDS)


def _max_rate(values: np.ndarray, step_s: float) -> float:
    return float(np.max(np.abs(np.diff(values))) / step_s)


def test_rate_bounds_hold_over_a_year(sky: SkyModel) -> None:
    """Largest finite-difference rate over a year (20-s steps) below each declared bound; a
    finite difference over 20 s underestimates a peak rate by < 1e-6 relative, far inside the
    ≥ 5 % the bounds keep to spare."""
    step = 20.0
    x = np.arange(0.0, YEAR_S, step)
    alt = max(_max_rate(sky.target_alt_deg(i, x), step) for i in range(sky.n_targets))
    assert alt < ALT_RATE_DEG_S
    assert _max_rate(sky.sun_alt_deg(x), step) < ALT_RATE_DEG_S
    assert _max_rate(sky.moon_alt_deg(x), step) < MOON_ALT_RATE_DEG_S
    sep = max(_max_rate(sky.moon_sep_deg(i, x), step) for i in range(sky.n_targets))
    assert sep < MOON_SEP_RATE_DEG_S
    assert _max_rate(sky.moon_illum(x), step) < MOON_ILLUM_RATE_S
    # and the bounds are not vacuous: within a factor 2 of what the sky does
    assert alt > ALT_RATE_DEG_S / 2 and sep > MOON_SEP_RATE_DEG_S / 10


def _all_six() -> ConstraintSet:
    return ConstraintSet(
        night=NightConstraint("astronomical"),
        airmass=AirmassConstraint(1.8),
        altitude=AltitudeConstraint(35.0),
        zenith_hole=ZenithHoleConstraint(6.0),
        moon_sep=MoonSeparationConstraint(40.0),
        moon_illum=MoonIlluminationConstraint(0.6),
    )


def _near_limits(sky: SkyModel, i: int, rng: np.random.Generator, n: int) -> np.ndarray:
    """Block centres: half uniform over the year, half within ±10 min of a limit crossing."""
    grid = np.arange(0.0, YEAR_S, 120.0)
    signals = [
        sky.sun_alt_deg(grid) + 18.0,
        sky.target_alt_deg(i, grid) - 35.0,
        sky.target_alt_deg(i, grid) - 84.0,
        sky.moon_sep_deg(i, grid) - 40.0,
        sky.moon_alt_deg(grid),
    ]
    crossings = np.concatenate([grid[np.flatnonzero(np.diff(np.sign(s)))] for s in signals])
    near = rng.choice(crossings, n // 2) + rng.uniform(-720.0, 720.0, n // 2)
    return np.concatenate([rng.uniform(0.0, YEAR_S, n - n // 2), near])


@pytest.mark.parametrize("width_s", [0.0, 60.0, 900.0, 3600.0])  # 0: instants, one sample
def test_screened_equals_exact(sky: SkyModel, width_s: float) -> None:
    rng = np.random.default_rng(int(width_s))
    cs = _all_six()
    decided: set[int] = set()
    for i in range(sky.n_targets):
        mid = _near_limits(sky, i, rng, 1500)
        xs, xe = mid - width_s / 2, mid + width_s / 2
        ok, first = evaluate_window(cs, sky, i, xs, xe)
        ok_ref, first_ref = evaluate_window_exact(cs, sky, i, xs, xe)
        np.testing.assert_array_equal(ok, ok_ref)
        np.testing.assert_array_equal(first, first_ref)
        decided |= set(first_ref.tolist())
    assert decided >= {-1, 0, 1, 2, 3, 4}  # every kind of answer is exercised


def test_few_blocks_over_a_long_span_use_the_exact_check(sky: SkyModel) -> None:
    cs = _all_six()
    xs = np.array([1000.0, YEAR_S - 5000.0])
    ok, first = evaluate_window(cs, sky, 0, xs, xs + 120.0)
    ok_ref, first_ref = evaluate_window_exact(cs, sky, 0, xs, xs + 120.0)
    np.testing.assert_array_equal(ok, ok_ref)
    np.testing.assert_array_equal(first, first_ref)


def test_night_screens_shared_by_targets_give_the_exact_answer(sky: SkyModel) -> None:
    """One :class:`NightScreens` for every target (as a plan shares it): each target's answer
    is the exact one, and a later target reuses the night's nodes instead of screening them
    again (the Sun is the same for all)."""
    rng = np.random.default_rng(11)
    cs = _all_six()
    shared = NightScreens(cs.night, sky)
    mid = np.sort(rng.uniform(0.0, YEAR_S / 4, 3000))
    for i in range(sky.n_targets):
        xs, xe = mid - 450.0, mid + 450.0
        ok, first = evaluate_window(cs, sky, i, xs, xe, shared)
        ok_ref, first_ref = evaluate_window_exact(cs, sky, i, xs, xe)
        np.testing.assert_array_equal(ok, ok_ref)
        np.testing.assert_array_equal(first, first_ref)
        if i == 0:
            computed = int(np.sum(shared.screen.codes != 2) + np.sum(shared.dark.codes != 2))
            assert computed > 0
    # the same blocks for the other targets: no node of the night screened twice
    after = int(np.sum(shared.screen.codes != 2) + np.sum(shared.dark.codes != 2))
    assert after == computed
    # a NightScreens of another sky model is not used (the answer stays the exact one)
    other = NightScreens(cs.night, SkyModel.build(*_other_sky_args()))
    ok, first = evaluate_window(cs, sky, 0, mid - 450.0, mid + 450.0, other)
    np.testing.assert_array_equal(
        first, evaluate_window_exact(cs, sky, 0, mid - 450.0, mid + 450.0)[1]
    )
    assert np.all(other.screen.codes == 2) and np.all(other.dark.codes == 2)


def _other_sky_args() -> tuple[object, ...]:
    with offline():
        t0 = Time("2041-09-01", scale="tdb")
    return get_site("paranal").location, t0, (0.0, 86400.0), COORDS
