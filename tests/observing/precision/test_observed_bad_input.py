"""Observed files (``plan --observed``): every case of the bad-input corpus
(tests/support/bad_observed.py), a blocks table with a status column, a velocity file or an
observing log, is refused in one line naming the row and column; exit 2, nothing written. The
base plans are the session fixtures ``first_night`` and ``goal_plan`` (tests/conftest.py)."""

from __future__ import annotations

from pathlib import Path

import pytest
from support.bad_observed import LOG_CELLS, OBSERVED_FILES, bad_observed_file, edited_log
from support.cli import run_main
from support.observed import CLI_BASE, plan_base

from ucbplan.errors import InputError, UcbplanError
from ucbplan.observing.blocks.read import read_blocks
from ucbplan.observing.night.observing_log import ObservingLog, log_cells, log_text

pytestmark = [
    pytest.mark.filterwarnings("ignore::erfa.ErfaWarning"),
    pytest.mark.filterwarnings("ignore::astropy.utils.exceptions.AstropyWarning"),
]


@pytest.mark.parametrize(("kind", "words"), OBSERVED_FILES)
def test_bad_observed_file_is_one_line_exit_2_nothing_written(
    first_night: Path, tmp_path: Path, kind: str, words: str
) -> None:
    obs = bad_observed_file(first_night, tmp_path, kind)
    with pytest.raises(UcbplanError, match=words):
        plan_base("2040-02-16", goal="sigma_K=13km/s", observed=obs)
    out = tmp_path / "out.ecsv"
    args = [*CLI_BASE, "--night", "2040-02-16", "--goal", "sigma_K=13km/s"]
    code, _, err = run_main([*args, "--observed", str(obs), "-o", str(out)])
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert code == 2 and "Traceback" not in err
    assert lines[-1].startswith("error: ") and words in lines[-1]
    assert not out.exists()


def test_observed_without_a_goal_or_with_a_bad_scale_is_refused(first_night: Path) -> None:
    with pytest.raises(InputError, match="count toward a goal"):
        plan_base("2040-02-16", observed=first_night)
    with pytest.raises(InputError, match="sigma_v_scale"):
        plan_base("2040-02-16", goal="sigma_K=13km/s", sigma_v_scale=-1.0)
    code, _, err = run_main([*CLI_BASE, "--night", "2040-02-16", "--sigma-v-scale", "0"])
    assert code == 2 and "--sigma-v-scale: expected a number in (0, 100]" in err


@pytest.mark.parametrize(("column", "value", "says"), LOG_CELLS)
def test_bad_log_is_one_line_exit_2_nothing_written(
    goal_plan: Path, tmp_path: Path, column: str, value: str, says: str
) -> None:
    table = read_blocks(goal_plan)
    cells = [c for _, c in log_cells(table)]
    good = tmp_path / "log.csv"
    good.write_text(log_text(cells, ["taken"] * len(cells)), encoding="utf-8")
    rows = len(cells) if column == "site" else 1
    bad = good
    for k in range(rows):  # a log of another site: every row says so
        bad = edited_log(bad, tmp_path / "bad.csv", column, value, k)
    out = tmp_path / "rest.ecsv"
    args = [*CLI_BASE, "--night", "2040-02-17", "--goal", "sigma_K=13km/s"]
    code, _, err = run_main([*args, "--observed", str(bad), "-o", str(out)])
    assert code == 2 and "Traceback" not in err
    (line,) = err.strip().splitlines()
    assert line.startswith("error: ") and says in line, line
    assert not out.exists()


def test_a_missing_observed_file_names_the_option(tmp_path: Path) -> None:
    args = [*CLI_BASE, "--night", "2040-02-17", "--goal", "sigma_K=13km/s"]
    code, _, err = run_main([*args, "--observed", str(tmp_path / "none.csv")])
    assert code == 2 and err.startswith("error: --observed: ") and "file not found" in err


def test_a_bad_status_through_the_library_is_refused(goal_plan: Path) -> None:
    log = ObservingLog.open(read_blocks(goal_plan), goal_plan.with_name("lib.csv"), overwrite=True)
    with pytest.raises(InputError, match="expected a status taken, missed, skipped, got 'lost'"):
        log.mark(log.exposures[0], "lost")
