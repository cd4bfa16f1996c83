"""`plan` option values: each is checked against its physical range before any work, in one line;
and the planner never overlaps blocks (one target or several, any overhead, fixed-u pairs)."""

from __future__ import annotations

import itertools
import math
from datetime import date, timedelta
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from support.cli import check_outcome, run_cli

from ucbplan.cli._flags import FLAGS, cli_message
from ucbplan.errors import InputError, UcbplanError
from ucbplan.observing.blocks.block import Block, ExposurePlan
from ucbplan.observing.constraints import ConstraintSet
from ucbplan.observing.constraints import checks as constraints_module
from ucbplan.observing.constraints.checks import evaluate_window
from ucbplan.observing.observatory.sites import get_site, site_from_lonlat
from ucbplan.observing.schedule import PlanSettings, night_dates, plan_nights
from ucbplan.observing.schedule.run import parse_priorities
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
BAD = [math.nan, math.inf, -math.inf, 3.8e239, -1e300]


def _one_line(exc: BaseException, *names: str) -> None:
    text = str(exc)
    assert "\n" not in text and len(text) < 400, text
    for name in names:
        assert name in text, text


# (flag of the CLI, keyword of the library object, values to refuse, values to keep): the library
# names the keyword, the CLI the flag (ucbplan.cli._flags)
SETTINGS_CASES = [
    ("--airmass-max", "airmass_max", [0.5, 0.999, 101.0], [1.0, 2.0, 100.0]),
    ("--moon-sep", "moon_sep_deg", [-1.0, 180.5], [0.0, 30.0, 180.0]),
    ("--moon-illum", "moon_illum_max", [-0.1, 1.01], [0.0, 0.5, 1.0]),
    ("--zenith-hole", "zenith_hole_deg", [-3.0, 46.0, 100.0], [0.0, 4.0, 45.0]),
    ("--alpha", "alpha", [0.0, -1.0, 11.0], [0.01, 1.0, 10.0]),
    ("--sigma-v", "sigma_v_kms", [0.0, -1.0, 1.1e4], [0.5, 1e4]),
    ("--k-eff", "k_eff_kms", [0.0, -5.0, 1e5], [1.0, 390.0]),
    ("--max-bin-fraction", "max_bin_fraction", [0.0, -1.0, 1.5], [0.1, 1.0]),
    ("--overhead", "overhead_s", [-5.0, 43201.0], [0.0, 300.0, 43200.0]),
]


@pytest.mark.parametrize(("option", "key", "bad", "good"), SETTINGS_CASES)
def test_plan_settings_ranges(option: str, key: str, bad: list[float], good: list[float]) -> None:
    for value in [*bad, *BAD]:
        with pytest.raises(InputError) as info:
            PlanSettings(**{key: value})
        _one_line(info.value, key, "expected a number in")
        assert cli_message(str(info.value)).startswith(option)
    for value in good:
        PlanSettings(**{key: value})


@pytest.mark.parametrize(
    ("option", "kwargs"),
    [
        ("--exptime", {"exptime_s": 0.0}),
        ("--exptime", {"exptime_s": 43201.0}),
        ("--exptime", {"exptime_s": 3.8e239}),  # was "Maximum allowed size exceeded"
        ("--exptime", {"exptime_s": math.nan}),
        ("--readout", {"readout_s": -1.0}),
        ("--readout", {"readout_s": 1e300}),
        ("--readout", {"readout_s": math.nan}),
        ("--n-exp", {"n_exp": 0}),
        ("--n-exp", {"n_exp": 100_000_000}),  # was a 80 GiB allocation
        ("--n-exp", {"n_exp": 2.5}),
        ("--n-exp/--exptime/--readout", {"exptime_s": 40.0, "n_exp": 2000}),
    ],
)
def test_exposure_plan_ranges(option: str, kwargs: dict[str, float]) -> None:
    with pytest.raises(InputError) as info:
        ExposurePlan(**kwargs)  # type: ignore[arg-type]
    _one_line(cli_message(str(info.value)), option)  # the keyword, printed as the flag by the CLI


def test_other_plan_options_fail_in_one_line() -> None:
    cases: list[tuple[str, object]] = [
        ("sessions_per_night", lambda: PlanSettings(sessions_per_night=0)),
        ("sessions_per_night", lambda: PlanSettings(sessions_per_night=10**9)),
        ("twilight", lambda: PlanSettings(twilight="foo")),
        ("twilight", lambda: PlanSettings(twilight="x" * 5000)),
        ("--mode", lambda: PlanSettings(mode="x" * 5000)),
        ("--mode u=VALUE", lambda: PlanSettings(mode="u=1e300")),
        ("max_smear", lambda: PlanSettings(max_smear="..*sigma_v")),  # was a bare ValueError
        ("max_smear", lambda: PlanSettings(max_smear="-1")),
        ("max_smear", lambda: PlanSettings(max_smear="1e300 km/s")),
        ("max_smear", lambda: PlanSettings(max_smear="x" * 5000)),
        ("--nights", lambda: night_dates(NIGHT, 0)),
        ("--nights", lambda: night_dates(NIGHT, 100_000)),
        ("--night", lambda: night_dates("15/02/2040")),
        ("--night", lambda: night_dates("2040-02-15" * 500)),
        ("--night", lambda: night_dates("9999-12-31")),  # was OverflowError: date out of range
        ("--night", lambda: night_dates("0001-01-01")),
        ("--night", lambda: night_dates("2100-12-01", 60)),
        ("--priority", lambda: parse_priorities(["HM Cnc=nan"])),
        ("--priority", lambda: parse_priorities(["=3"])),
        ("--priority", lambda: parse_priorities(["HM Cnc"])),
        ("--priority", lambda: parse_priorities(["HM Cnc=1e400"])),
        ("--priority", lambda: parse_priorities(["HM Cnc=" + "9" * 5000])),
        ("--site-lonlat", lambda: site_from_lonlat("nan,0,0")),  # was "cannot convert NaN"
        ("--site-lonlat", lambda: site_from_lonlat("0,95,0")),
        ("--site-lonlat", lambda: site_from_lonlat("0,0,1e300")),
        ("--site-lonlat", lambda: site_from_lonlat("1," * 3000)),
    ]
    for option, make in cases:
        with pytest.raises(UcbplanError) as info:
            make()  # type: ignore[operator]
        _one_line(cli_message(str(info.value)), FLAGS.get(option, option))
    assert night_dates("2100-12-30") == [date(2100, 12, 30)]
    assert parse_priorities(["HM Cnc=2", "a=b=-1.5"]) == {"hm cnc": 2.0, "a=b": -1.5}


@pytest.mark.parametrize(
    "args",
    [
        ["--exptime", "3.8e239"],
        ["--exptime", "1e9"],
        ["--n-exp", "100000000"],
        ["--overhead", "nan"],
        ["--moon-sep", "200"],
        ["--night", "9999-12-31"],
        ["--site-lonlat", "nan,0,0"],
        ["--k-eff", "0"],  # was silently replaced by the target file's K
    ],
)
def test_plan_cli_refuses_before_any_work(tmp_path: Path, args: list[str]) -> None:
    out = tmp_path / "plan.ecsv"
    base = ["plan", str(HM), "--night", "2040-02-15"]
    if "--site-lonlat" not in args:
        base += ["--site", "paranal"]
    code, err = run_cli([*base, *args, "-o", str(out)])
    check_outcome(code, err)
    assert code == 2 and not out.exists()
    assert args[0] in err.strip().splitlines()[-1]


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
