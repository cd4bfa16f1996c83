"""The planner never overlaps blocks (one target or several, any overhead, fixed-u pairs). The
`plan` options' bad values are refused in tests/cli/test_option_bad_input.py."""

from __future__ import annotations

import itertools
from datetime import date, timedelta
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from ucbplan.errors import UcbplanError
from ucbplan.observing.blocks.block import Block, ExposurePlan
from ucbplan.observing.constraints import ConstraintSet
from ucbplan.observing.constraints import checks as constraints_module
from ucbplan.observing.constraints.checks import evaluate_window
from ucbplan.observing.observatory.sites import get_site
from ucbplan.observing.schedule import PlanSettings, plan_nights
from ucbplan.targets import Target, load_target

pytestmark = [
    pytest.mark.filterwarnings("ignore::erfa.ErfaWarning"),
    pytest.mark.filterwarnings("ignore::astropy.utils.exceptions.AstropyWarning"),
]

REPO = Path(__file__).resolve().parents[3]
HM = REPO / "catalogs" / "hm-cnc-simulated.yaml"
ECC = REPO / "catalogs" / "fiducial-eccentric.yaml"
INJ = REPO / "catalogs" / "fiducial-injection.yaml"
NIGHT = date(2040, 2, 15)


def _one_line(exc: BaseException, *names: str) -> None:
    text = str(exc)
    assert "\n" not in text and len(text) < 400, text
    for name in names:
        assert name in text, text


def test_evaluate_window_in_chunks_is_exact(monkeypatch: pytest.MonkeyPatch) -> None:
    # The night pre-check at start/middle/end and the chunking must not change any answer.
    from ucbplan.observing.observatory.sky import SkyModel
    from ucbplan.observing.observatory.time_axis import TimeAxis

    site, target = get_site("paranal"), load_target(HM)
    from astropy.coordinates import SkyCoord
    from astropy.time import Time

    axis = TimeAxis.starting_at(Time("2040-02-15T16:00:00", scale="utc"), site.location)
    span = (0.0, 86400.0)
    coord = SkyCoord([target.ra_deg], [target.dec_deg], unit="deg")
    sky = SkyModel.build(site.location, axis.origin, span, coord)
    cs = ConstraintSet()
    xs = np.linspace(0.0, 80000.0, 997)
    xe = xs + 1900.0  # 7 samples per block
    whole = evaluate_window(cs, sky, 0, xs, xe)
    monkeypatch.setattr(constraints_module, "_MAX_SAMPLES", 20)
    chunked = evaluate_window(cs, sky, 0, xs, xe)
    assert np.array_equal(whole[0], chunked[0]) and np.array_equal(whole[1], chunked[1])
    assert 0 < whole[0].sum() < xs.size and {0, 1} <= set(whole[1].tolist())


def _assert_no_overlap(blocks: list[Block]) -> None:
    ordered = sorted(blocks, key=lambda b: b.t_start_utc.jd1 + b.t_start_utc.jd2)
    for a, b in itertools.pairwise(ordered):
        gap = (b.t_start_utc - a.t_end_utc).to_value("s")
        assert gap >= -1e-6, f"{a.block_id} and {b.block_id} overlap by {-gap:.3f} s"
    assert len({b.block_id for b in blocks}) == len(blocks), "duplicate block ids"


@pytest.fixture(scope="module")
def targets() -> list[Target]:
    return [load_target(p) for p in (HM, ECC, INJ)]


@pytest.mark.parametrize("mode", ["quadrature", "conjunction", "zero-crossing"])
def test_zero_overhead_never_overlaps(targets: list[Target], mode: str) -> None:
    # Issue 9: --overhead 0 must not give overlapping blocks (one target or several).
    s = PlanSettings(mode=mode, overhead_s=0.0, sessions_per_night=40)
    res = plan_nights(targets, get_site("paranal"), [NIGHT], s)
    assert len(res.blocks) > 40
    _assert_no_overlap(res.blocks)


def test_fixed_u_pairs_are_unique_and_never_overlap(targets: list[Target]) -> None:
    # Second epochs were planned alone on their night: several first blocks chose the same
    # second block (duplicate ids, identical rows) on top of other targets' blocks, and on
    # nights outside the plan. Now: only the nights given, unique ids, no overlaps.
    s = PlanSettings(mode="fixed-u-pairs", overhead_s=0.0, sessions_per_night=3)
    nights = [NIGHT + timedelta(days=i) for i in range(8)]
    res = plan_nights(targets[1:], get_site("paranal"), nights, s)
    seconds = [b for b in res.blocks if b.night != NIGHT.isoformat()]
    assert len(seconds) >= 4
    assert {b.night for b in res.blocks} <= {n.isoformat() for n in nights}
    _assert_no_overlap(res.blocks)
    assert len({b.block_id for b in res.blocks}) == len(res.blocks)
    assert len({b.session_id for b in seconds}) == len(seconds)


@settings(
    max_examples=8,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(
    overhead=st.sampled_from([0.0, 1.0, 60.0, 300.0]),
    exptime=st.sampled_from([10.0, 30.0, 60.0, 140.0]),
    n_exp=st.integers(1, 3),
    sessions=st.sampled_from([1, 5, 1000]),
    mode=st.sampled_from(["quadrature", "conjunction", "zero-crossing", "u=0.3"]),
)
def test_planner_never_overlaps(
    targets: list[Target], overhead: float, exptime: float, n_exp: int, sessions: int, mode: str
) -> None:
    s = PlanSettings(
        mode=mode,
        overhead_s=overhead,
        sessions_per_night=sessions,
        exposure=ExposurePlan(exptime, n_exp, 5.0),
    )
    try:
        res = plan_nights(targets, get_site("paranal"), [NIGHT], s)
    except UcbplanError as exc:  # a smearing budget, for example
        _one_line(exc)
        return
    _assert_no_overlap(res.blocks)
    # sessions keep the overhead clear of each other
    starts = {}
    for b in res.blocks:
        key = (b.target, b.session_id)
        t0, t1 = starts.get(key, (b.t_start_utc, b.t_end_utc))
        starts[key] = (min(t0, b.t_start_utc), max(t1, b.t_end_utc))
    spans = sorted(starts.values(), key=lambda p: p[0].jd1 + p[0].jd2)
    for (_, a1), (b0, _) in itertools.pairwise(spans):
        assert (b0 - a1).to_value("s") >= overhead - 1e-3


def test_failure_groups_nights(targets: list[Target]) -> None:
    # 60 nights without a block were 60 clauses (thousands of characters, cut by the CLI).
    from ucbplan.observing.schedule import plan_files

    run = plan_files(
        [HM],
        first_night="2040-02-15",
        n_nights=60,
        site="paranal",
        settings=PlanSettings(exposure=ExposurePlan(43200.0), allow_smeared=True),
    )
    text = run.failure()
    assert text is not None and len(text) < 400, text
    assert "HM Cnc (simulated) (60 nights 2040-02-15..2040-04-14): " in text
