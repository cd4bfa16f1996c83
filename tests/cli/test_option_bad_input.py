"""CLI options: every case of the bad-input corpus (tests/support/bad_options.py) is refused before
any work, in one line naming the flag; exit 2 and nothing written."""

from __future__ import annotations

from collections.abc import Callable
from datetime import date
from pathlib import Path

import pytest
from support.bad_eclipse_times import GOOD, times_table
from support.bad_options import (
    EXPOSURE_PLANS,
    NON_FINITE,
    OPTICAL_SIGMA_OPTIONS,
    OPTICAL_SIGMA_VALUES,
    OTHER_PLAN_OPTIONS,
    PLAN_ARGS,
    PLOT_NAMES,
    RANK_OPTIONS,
    SETTINGS_RANGES,
    SIMULATE_OPTIONS,
)
from support.cli import check_outcome, run_cli, run_main
from support.paths import CATALOGS

from ucbplan.cli._flags import FLAGS, cli_message
from ucbplan.errors import InputError, UcbplanError
from ucbplan.observing.blocks.block import ExposurePlan
from ucbplan.observing.schedule import PlanSettings, night_dates
from ucbplan.observing.schedule.run import parse_priorities

pytestmark = [
    pytest.mark.filterwarnings("ignore::erfa.ErfaWarning"),
    pytest.mark.filterwarnings("ignore::astropy.utils.exceptions.AstropyWarning"),
]

HM = CATALOGS / "hm-cnc-simulated.yaml"
ECC = CATALOGS / "fiducial-eccentric.yaml"
POP = CATALOGS / "population" / "ldc-200.ecsv"


def refused(*args: str) -> str:
    """Run ``ucbplan ARGS``, check it failed with exit 2 and one error line; return the line."""
    code, _, err = run_main(list(args))
    assert code == 2, err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    return lines[0]


def _one_line(exc: BaseException | str, *names: str) -> None:
    text = str(exc)
    assert "\n" not in text and len(text) < 400, text
    for name in names:
        assert name in text, text


@pytest.fixture
def times_csv(tmp_path: Path) -> Path:
    path = tmp_path / "times.csv"
    path.write_text(times_table(GOOD), encoding="utf-8")
    return path


def _plot_cases(times_csv: Path) -> list[list[str]]:
    return [
        ["ephemeris", "fit", str(times_csv), "--terms", "2"],
        ["feasibility", str(ECC)],
        ["horizon", str(HM)],
    ]


@pytest.mark.parametrize("name", PLOT_NAMES)
@pytest.mark.parametrize("which", [0, 1, 2])
def test_plot_to_an_unknown_format_is_refused_before_the_run(
    tmp_path: Path, times_csv: Path, name: str, which: int
) -> None:
    out = tmp_path / "out"
    out.mkdir()
    args = [*_plot_cases(times_csv)[which], "--plot", str(out / name), "-o", str(out / "r.json")]
    line = refused(*args)
    assert "--plot: expected a .png, .pdf or .svg file name" in line
    assert list(out.iterdir()) == []


@pytest.mark.parametrize(("extra", "blame"), RANK_OPTIONS)
def test_population_rank_checks_everything_before_making_its_folder(
    tmp_path: Path, extra: list[str], blame: str
) -> None:
    out = tmp_path / "r" / "deeper"
    source = str(POP) if blame != "nosuch.ecsv" else str(tmp_path / "nosuch.ecsv")
    line = refused("population", "rank", source, "--out-dir", str(out), *extra)
    assert blame in line
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(("extra", "blame"), SIMULATE_OPTIONS)
def test_population_simulate_option_errors_come_before_the_run(
    tmp_path: Path, extra: list[str], blame: str
) -> None:
    args = ["population", "simulate", str(POP), "-o", str(tmp_path / "s.ecsv")]
    line = refused(*args, "--out-dir", str(tmp_path / "sd"), *extra)
    assert blame in line
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("option", OPTICAL_SIGMA_OPTIONS)
@pytest.mark.parametrize("value", OPTICAL_SIGMA_VALUES)
def test_feasibility_refuses_negative_or_meaningless_optical_sigmas(
    option: str, value: str
) -> None:
    line = refused("feasibility", str(ECC), f"--optical-sigma-{option}", value)
    assert f"--optical-sigma-{option}: expected a number in [0, " in line


@pytest.mark.parametrize(("option", "key", "bad", "good"), SETTINGS_RANGES)
def test_plan_settings_ranges(option: str, key: str, bad: list[float], good: list[float]) -> None:
    for value in [*bad, *NON_FINITE]:
        with pytest.raises(InputError) as info:
            PlanSettings(**{key: value})
        _one_line(info.value, key, "expected a number in")
        assert cli_message(str(info.value)).startswith(option)
    for value in good:
        PlanSettings(**{key: value})


@pytest.mark.parametrize(("option", "kwargs"), EXPOSURE_PLANS)
def test_exposure_plan_ranges(option: str, kwargs: dict[str, float]) -> None:
    with pytest.raises(InputError) as info:
        ExposurePlan(**kwargs)  # type: ignore[arg-type]
    _one_line(cli_message(str(info.value)), option)  # the keyword, printed as the flag by the CLI


def test_other_plan_options_fail_in_one_line() -> None:
    cases: list[tuple[str, Callable[[], object]]] = OTHER_PLAN_OPTIONS
    for option, make in cases:
        with pytest.raises(UcbplanError) as info:
            make()
        _one_line(cli_message(str(info.value)), FLAGS.get(option, option))
    assert night_dates("2100-12-30") == [date(2100, 12, 30)]
    assert parse_priorities(["HM Cnc=2", "a=b=-1.5"]) == {"hm cnc": 2.0, "a=b": -1.5}


@pytest.mark.parametrize("args", PLAN_ARGS)
def test_plan_cli_refuses_before_any_work(tmp_path: Path, args: list[str]) -> None:
    out = tmp_path / "plan.ecsv"
    base = ["plan", str(HM), "--night", "2040-02-15"]
    if "--site-lonlat" not in args:
        base += ["--site", "paranal"]
    code, err = run_cli([*base, *args, "-o", str(out)])
    check_outcome(code, err)
    assert code == 2 and not out.exists()
    assert args[0] in err.strip().splitlines()[-1]
