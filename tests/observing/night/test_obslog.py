"""The observing log (issue 32 item 4): ``ucbplan now --log`` and the night sheet write it,
``plan --observed`` / ``replan --observed`` read it.

Base case: the goal plan of HM Cnc (simulated) at Paranal for 2040-02-15 to 17 (σ_K = 13 km/s,
``--sigma-v 30km/s@300s --visit 1h --instrument xshooter-vis``: 14 spectra a night, one exposure
per block, on the first two nights). The information the reader collects from a log is checked
against an independent Fisher sum over the taken rows (tests/observing/precision/test_observed.py:
``brute_force_info``, the design matrix built row by row from the blocks table's epochs,
exposure times and σ_v, inverted with numpy), to 1e-9 relative (the log carries the table's
numbers in full and the same ISO µs epochs; only the summation order differs). Live mode is
driven by an injected clock and key source, never by timing.
"""

from __future__ import annotations

import csv
import dataclasses
import io
import subprocess
import sys
import warnings
from datetime import timedelta
from pathlib import Path
from typing import Any

import pytest
from astropy import units as u
from astropy.table import Table
from astropy.time import Time
from support.cli import run_main
from support.observed import BASE, CLI_BASE, NAME, TARGET, fisher_of_taken
from typer.testing import CliRunner

import ucbplan
from ucbplan.cli import now as now_cli
from ucbplan.cli.app import app
from ucbplan.errors import InputError
from ucbplan.observing.blocks.read import read_blocks
from ucbplan.observing.night.observing_log import (
    LOG_COLUMNS,
    LOG_KEYS,
    ObservingLog,
    check_log_plan,
    log_cells,
    log_lines,
    log_text,
    plan_id,
    read_log,
)

pytestmark = [
    pytest.mark.filterwarnings("ignore::erfa.ErfaWarning"),
    pytest.mark.filterwarnings("ignore::astropy.utils.exceptions.AstropyWarning"),
]

#: The statuses given to the first night's exposures, in time order (the rest: not marked).
MARKS = ["taken", "taken", "missed", "taken", "skipped", "taken", "taken", "missed", "taken"]


def _replan(plan: Path, log: Path) -> Any:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return ucbplan.replan(str(plan), "2040-02-16T20:00:00", observed=str(log))


class _Keys:
    """A rehearsal: a clock that moves only while waiting for a key, and a key pressed 20 s
    after each of the first exposures starts (``marks``), then ``q``."""

    def __init__(self, starts: list[Any], marks: list[str], log_path: Path) -> None:
        keys = {s: k for k, s in LOG_KEYS.items()}
        self.t, self.origin = 0.0, starts[0] - timedelta(seconds=30)
        self.script = [
            ((s - self.origin).total_seconds() + 20.0, keys[m])
            for s, m in zip(starts, marks, strict=False)
        ]
        self.script.append((self.script[-1][0] + 1.0, "q"))
        self.pressed: list[str] = []
        self.files: list[str] = []
        self.log_path = log_path

    def monotonic(self) -> float:
        return self.t

    def keys(self, timeout: float) -> str | None:
        assert 0.0 < timeout <= 1.0
        self.files.append(self.log_path.read_text(encoding="utf-8"))  # as the last key left it
        self.t += timeout
        if self.script and self.t >= self.script[0][0]:
            self.pressed.append(self.script[0][1])
            return self.script.pop(0)[1]
        return None


@pytest.fixture(scope="module")
def now_log(goal_plan: Path, tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, _Keys, str]:
    """A rehearsal of ``now --log`` over the first night: the log, the keys and the frames."""
    path = tmp_path_factory.mktemp("now") / "now.csv"
    log = ObservingLog.open(read_blocks(goal_plan), path)
    assert path.read_text(encoding="utf-8") == ",".join(LOG_COLUMNS) + "\n"  # written at once
    keys = _Keys([e.start for e in log.exposures], MARKS, path)
    out = io.StringIO()
    now_cli.live(log.exposures, keys.origin, out, monotonic=keys.monotonic, log=log, keys=keys.keys)
    return path, keys, out.getvalue()


def test_now_log_marks_the_exposure_just_started_and_writes_after_each_key(
    goal_plan: Path, now_log: tuple[Path, _Keys, str]
) -> None:
    path, keys, frames = now_log
    table = read_blocks(goal_plan)
    assert keys.script == [] and keys.pressed[-1] == "q"
    with path.open(newline="", encoding="utf-8") as handle:
        rows = list(csv.DictReader(handle))
    assert [r["status"] for r in rows] == MARKS
    cells = [c for _, c in log_cells(table)]
    assert [r["exposure"] for r in rows] == [c[3] for c in cells[: len(MARKS)]]
    assert {r["plan_id"] for r in rows} == {plan_id(table)} and {r["site"] for r in rows} == {
        "Paranal"
    }
    # the file after each key holds every mark so far: a crash loses none
    written = [f.count("\n") - 1 for f in dict.fromkeys(keys.files)]
    assert written == list(range(len(MARKS) + 1))
    assert "log       V01/09 taken; 9 marked, 0 earlier not" in frames


def test_the_log_entry_fits_100_columns(goal_plan: Path, tmp_path: Path) -> None:
    log = ObservingLog.open(read_blocks(goal_plan), tmp_path / "now.csv")
    log.exposures[0] = dataclasses.replace(log.exposures[0], label="VERYLONGVISIT/01.12")
    log.statuses[1:] = ["taken"] * (len(log.statuses) - 1)
    lines = log_lines(log, log.exposures[0])
    assert len(lines) == 2 and all(len(ln) <= 100 for ln in lines)
    assert lines[0].startswith("log       VERYLONGVISIT/01.12 not marked; 27 marked")
    assert lines[1].startswith(" " * 10) and lines[1].endswith("q quit")


def test_now_log_round_trip_counts_the_fisher_sum_of_the_taken_rows(
    goal_plan: Path, now_log: tuple[Path, _Keys, str]
) -> None:
    path = now_log[0]
    want = fisher_of_taken(goal_plan, path)
    goal = _replan(goal_plan, path).run.result.goals[NAME]
    assert goal.collected_spectra == MARKS.count("taken") == 6
    assert goal.collected_info == pytest.approx(want, rel=1e-9)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        kw = {**BASE, "goal": "sigma_K=13km/s", "observed": str(path)}
        p = ucbplan.plan(str(TARGET), night="2040-02-16", nights=2, **kw)
    assert p.run.result.goals[NAME].collected_info == pytest.approx(want, rel=1e-9)
    args = [*CLI_BASE, "--night", "2040-02-16", "--nights", "2", "--goal", "sigma_K=13km/s"]
    result = CliRunner().invoke(app, [*args, "--observed", str(path)])
    assert result.exit_code == 0, result.output
    assert (
        "collected so far σ_K = " in result.output and "from the 6 spectra taken" in result.output
    )
    assert "6 spectra taken" in result.output


def test_an_existing_log_of_the_same_plan_is_continued(goal_plan: Path, tmp_path: Path) -> None:
    table = read_blocks(goal_plan)
    path = tmp_path / "now.csv"
    first = ObservingLog.open(table, path)
    first.mark(first.exposures[0], "taken")
    again = ObservingLog.open(table, path)  # `now` restarted after a crash
    assert again.statuses[:2] == ["taken", ""]
    again.mark(again.exposures[1], "missed")
    assert [r["status"] for r in read_log(path)] == ["taken", "missed"]
    fresh = ObservingLog.open(table, path, overwrite=True)
    assert fresh.statuses == [""] * len(fresh.exposures)
    assert len(read_log(path)) == 0


def test_now_log_refuses_another_plans_log_or_another_file(
    goal_plan: Path, telescope_plan: Path, tmp_path: Path
) -> None:
    other = tmp_path / "other.csv"
    log = ObservingLog.open(read_blocks(telescope_plan), other)
    log.mark(log.exposures[0], "taken")
    before = other.read_bytes()
    for path, says in ((other, "a log of another plan"), (goal_plan, "is not an observing log")):
        code, _, err = run_main(["now", str(goal_plan), "--log", str(path)])
        assert code == 2
        (line,) = err.strip().splitlines()
        assert line.startswith("error: --log ") and says in line and "--overwrite" in line
    assert other.read_bytes() == before
    code, _, err = run_main(["now", str(goal_plan), "--once", "--log", str(other)])
    assert code == 2 and "drop --once" in err


def test_now_log_reads_keys_from_stdin(goal_plan: Path, tmp_path: Path) -> None:
    """The command itself, keys piped in: after the plan is over, t marks its last exposure."""
    path = tmp_path / "now.csv"
    cmd = [sys.executable, "-m", "ucbplan", "now", str(goal_plan), "--at", "2040-02-20T00:00:00Z"]
    run = subprocess.run(
        [*cmd, "--log", str(path)], input="t", capture_output=True, text=True, timeout=120
    )
    assert run.returncode == 0, run.stderr
    (row,) = read_log(path)
    table = read_blocks(goal_plan)
    assert row["status"] == "taken" and row["block_id"] == table["block_id"][-1]
    assert "V01/14 taken; 1 marked, 27 earlier not" in run.stdout


def test_plan_id_is_the_same_in_memory_and_in_every_file_format(tmp_path: Path) -> None:
    """The sheet of a plan just made and ``now`` on its ECSV, CSV or JSON name one plan."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        p = ucbplan.plan(str(TARGET), night="2040-02-15", nights=1, **BASE, goal="sigma_K=20km/s")
    ids = {
        plan_id(read_blocks(p.write(tmp_path / f"plan.{fmt}"))) for fmt in ("ecsv", "csv", "json")
    }
    assert ids == {plan_id(p.table)}
    shifted = p.table.copy()
    shifted["t_start_utc"][0] = "2040-02-16T03:00:00.000"  # another plan
    assert plan_id(shifted) not in ids


def test_a_log_of_a_csv_plan_names_no_site_and_counts_the_same(
    goal_plan: Path, now_log: tuple[Path, _Keys, str], tmp_path: Path
) -> None:
    """A CSV plan has no meta: its log's site is blank, and the reader checks no site."""
    plan_csv = tmp_path / "goal.csv"
    Table.read(goal_plan, format="ascii.ecsv").write(plan_csv, format="ascii.csv")
    log = ObservingLog.open(read_blocks(plan_csv), tmp_path / "now.csv")
    for e, status in zip(log.exposures, MARKS, strict=False):
        log.mark(e, status)
    rows = read_log(log.path)
    assert set(rows["site"]) == {""} and "site" not in rows.meta
    assert list(rows["t_mid_tdb_bary"]) == list(read_log(now_log[0])["t_mid_tdb_bary"])
    goal = _replan(goal_plan, log.path).run.result.goals[NAME]
    assert goal.collected_info == pytest.approx(fisher_of_taken(goal_plan, log.path), rel=1e-9)


def test_a_log_of_another_plan_is_refused_by_check_log_plan(
    goal_plan: Path, telescope_plan: Path, now_log: tuple[Path, _Keys, str]
) -> None:
    check_log_plan(now_log[0], read_blocks(goal_plan))  # its own plan: fine
    with pytest.raises(InputError, match=r"^observed .*: a log of another plan \(plan_id "):
        check_log_plan(now_log[0], read_blocks(telescope_plan))


def test_a_formula_name_is_written_safe_and_read_back(telescope_plan: Path, tmp_path: Path) -> None:
    """Issue 33 for the log: a target named like a formula is no formula in a spreadsheet."""
    table = read_blocks(telescope_plan)[:2]
    table["target"] = ["=cmd|' /C calc'!A0", "@SUM(1+1)*cmd"]
    path = tmp_path / "log.csv"
    path.write_text(log_text([c for _, c in log_cells(table)], ["taken", "missed"]), "utf-8")
    with path.open(newline="", encoding="utf-8") as handle:
        cells = [r["target"] for r in csv.DictReader(handle)]
    assert cells == ["'=cmd|' /C calc'!A0", "'@SUM(1+1)*cmd"]
    assert list(read_log(path)["target"]) == list(table["target"])


def test_log_of_a_block_of_several_exposures_gives_each_its_own_epoch(
    telescope_plan: Path,
) -> None:
    """A block of 3 exposures (T s each, 10 s readout): three rows whose TDB mid-times are the
    block's anchor epoch −(T + 10) s, +0 and +(T + 10) s (astropy's TDB arithmetic, to 1 µs)."""
    table = read_blocks(telescope_plan)[:1]
    table["n_exp"], table["readout_s"] = [3], [10.0]
    step = float(table["exptime_s"][0]) + 10.0
    table["t_end_utc"] = [(Time(str(table["t_start_utc"][0]), scale="utc") + 200 * u.s).isot]
    cells = [c for _, c in log_cells(table)]
    assert [c[3] for c in cells] == ["V01/01.1", "V01/01.2", "V01/01.3"]
    mid = Time(str(table["t_mid_tdb_bary"][0]), scale="tdb")
    for k, c in enumerate(cells):
        got = Time(c[6], scale="tdb")
        assert abs((got - mid).to_value("s") - (k - 1) * step) < 1e-6
    log = Table.read(log_text(cells, ["taken"] * 3), format="ascii.csv")
    assert list(log.colnames) == list(LOG_COLUMNS) and len(log) == 3
