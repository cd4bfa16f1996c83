"""The same epochs with the same constraints give identical accepted sets (issue 14): the plan
kernel's accept/reject decision (``candidate_blocks``' ``ok``) against astroplan's
``is_event_observable`` on the same blocks, 3 targets × 20 nights at Paranal.

Constraints on both sides: nautical night (Sun altitude ≤ −12°), airmass ≤ 2 and Moon separation
≥ 30° (the benchmark's), or airmass ≤ 5 and Moon ≥ 60° (slow; there the Moon rule below
decides blocks); pressure 0 (astroplan's ``AtNightConstraint`` forces it; an ``Observer``'s
pressure defaults to 0, so its ``AirmassConstraint`` is geometric too); no zenith hole
(astroplan is not given one). Convention difference: ours accepts any separation while the Moon
is below the horizon, astroplan's ``MoonSeparationConstraint`` does not look at the Moon's
altitude; the comparison applies our rule to astroplan's Moon altitude. With airmass ≤ 2 and a
30° limit it cannot change a decision: a target ≥ 30° up and a Moon below the horizon are ≥ 30°
apart.

Tolerance: decisions may differ only where, at the block's start, middle or end, a decisive
quantity (astropy's value) lies within the stated accuracy of our sky model of its limit — 2″ for
the target and Sun altitudes, 10″ for the Moon (ucbplan/observing/observatory/sky.py).
"""

from __future__ import annotations

import sys
from dataclasses import replace
from datetime import date, timedelta
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from ucbplan.observing.blocks.block import ExposurePlan
from ucbplan.observing.observatory.sites import get_site
from ucbplan.observing.schedule import PlanSettings

pytest.importorskip("astroplan")
sys.path.insert(0, str(Path(__file__).resolve().parents[3] / "benchmarks"))

import bench_plan
import plan_peers

pytestmark = [
    pytest.mark.filterwarnings("ignore::erfa.ErfaWarning"),
    pytest.mark.filterwarnings("ignore::astropy.utils.exceptions.AstropyWarning"),
]


#: (airmass_max, moon_sep_deg) of the two cases.
BENCHMARK_LIMITS, LOOSE_LIMITS = (2.0, 30.0), (5.0, 60.0)


@pytest.fixture(
    scope="module",
    params=[BENCHMARK_LIMITS, pytest.param(LOOSE_LIMITS, marks=pytest.mark.slow)],
    ids=["airmass2-moon30", "airmass5-moon60"],
)
def run(request: pytest.FixtureRequest) -> dict[str, Any]:
    """Candidates of 3 targets over 20 nights with astroplan's constraints (no zenith hole);
    the Moon decides changes of the decision (at 30°: target UCB05 on 2040-01-31)."""
    airmass_max, moon_sep = request.param
    settings = PlanSettings(
        exposure=ExposurePlan(60.0), airmass_max=airmass_max, moon_sep_deg=moon_sep
    )
    cs = settings.constraints(None)
    targets = bench_plan.make_targets(10)[5:8]
    nights = [date(2040, 1, 20) + timedelta(days=k) for k in range(20)]
    return {
        "cands": bench_plan.ours(targets, nights, cs)[2],
        "coords": [t.coord for t in targets],
        "cs": cs,
        "location": get_site("paranal").location,
        "loose": request.param == LOOSE_LIMITS,
    }


def test_accepted_sets_agree_with_astroplan(run: dict[str, Any]) -> None:
    """Every block next to a change of our decision (night, airmass or Moon limit) and a
    random sample: no disagreement outside the sky model's accuracy."""
    cands, coords, cs = run["cands"], run["coords"], run["cs"]
    edges = plan_peers.edge_picks(cands, 10**6, seed=0)
    rand = plan_peers.random_picks([c.x_mid.size for c, _ in cands], 60, seed=0)
    samples = plan_peers.make_samples(coords, cands, edges)
    samples += plan_peers.make_samples(coords, cands, rand)
    a = plan_peers.agreement(run["location"], samples, cs)
    assert a.n == sum(e.size for e in edges) + sum(r.size for r in rand)
    assert 0 < a.accepted < a.n
    assert min(e.size for e in edges) > 0  # every target crosses a limit
    moon = [np.any(c.first_failed[e] == 2) for (c, _), e in zip(cands, edges, strict=True)]
    assert any(moon)  # and the Moon limit is among them
    assert a.outside == 0, a
    assert a.naive_outside == 0, a
    if run["loose"]:
        assert a.moon_down > 0, a  # the Moon rule decides blocks (17 here)
    else:
        assert a.moon_down == 0, a  # airmass <= 2: the Moon rule cannot matter (see above)
    assert a.inside <= 1, a  # blocks come within seconds of arc of a limit only by chance


def test_a_changed_decision_is_caught(run: dict[str, Any]) -> None:
    """The comparison is not blind: flipping our decision on blocks next to a limit makes each
    one a disagreement, outside the accuracy unless a quantity is within it of a limit."""
    c, axis = run["cands"][1]
    pick = plan_peers.edge_picks([(c, axis)], 4, seed=1)[0]
    (s,) = plan_peers.make_samples(run["coords"][1:2], [(c, axis)], [pick])
    flipped = replace(s, ok=~s.ok)
    a = plan_peers.agreement(run["location"], [s, flipped], run["cs"])
    assert a.outside + a.inside == pick.size and a.outside > a.inside, a


def test_near_limit_uses_the_stated_accuracy() -> None:
    """2″ for the target and Sun altitudes, 10″ for the Moon; any of start, middle, end."""
    cs = PlanSettings().constraints(None)
    far = {"sun_alt": -20.0, "alt": 60.0, "moon_alt": -30.0, "moon_sep": 90.0}
    q = {k: np.full((3, 4), v) for k, v in far.items()}
    q["sun_alt"][1, 0] = -12.0 + 1.9 / 3600  # middle of block 0: Sun within 2″
    q["alt"][2, 1] = 30.0 - 2.1 / 3600  # end of block 1: target 2.1″ from airmass 2
    q["moon_sep"][0, 2] = 30.0 + 9.0 / 3600  # start of block 2: Moon within 10″
    near = plan_peers.near_limit(plan_peers.limit_margins(q, cs))
    assert near.tolist() == [True, False, True, False]
