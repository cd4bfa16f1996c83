"""``ucbplan replan`` / :func:`ucbplan.replan` (issue 32, item 2).

Base case: HM Cnc (simulated) at Paranal, ``sigma_v=30km/s@300s``, 1-h visits, X-shooter VIS,
goal σ_K ≤ 15 km/s over the three nights from 2040-02-15 (the goal needs the first two).
"""

from __future__ import annotations

import math
import shutil
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from astropy.table import Table, vstack
from astropy.time import Time
from support.cli import run_main
from support.observed import brute_force_info

import ucbplan
from ucbplan.api.replanning import plan_changes
from ucbplan.errors import InputError, InputFileError
from ucbplan.observing.schedule.goalplan import REPLAN_INFO_SLACK
from ucbplan.targets import load_target

TARGET = Path(__file__).resolve().parents[3] / "catalogs" / "hm-cnc-simulated.yaml"
BASE: dict[str, Any] = {
    "site": "paranal",
    "sigma_v": "30km/s@300s",
    "visit": "1h",
    "instrument": "xshooter-vis",
    "goal": "sigma_K=15km/s",
}
#: An instant (UTC) before the first block of the second night (15:00 local).
SECOND = "2040-02-16T18:00"


def _quiet(func: Any, *args: Any, **kw: Any) -> Any:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return func(*args, **kw)


def _data_lines(path: Path) -> list[str]:
    return [line for line in path.read_text().splitlines() if not line.startswith("#")]


def _data_lines_of(plan: Any, folder: Path) -> list[str]:
    plan.write(folder / "out.ecsv", overwrite=True)
    return _data_lines(folder / "out.ecsv")


@pytest.fixture(scope="module")
def original(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("replan") / "plan.ecsv"
    _quiet(ucbplan.plan, str(TARGET), night="2040-02-15", nights=3, **BASE).write(out)
    return out


def test_replan_from_the_start_without_losses_is_the_original_plan(
    original: Path, tmp_path: Path
) -> None:
    new = _quiet(ucbplan.replan, original, "2040-02-15T12:00")
    new.write(tmp_path / "new.ecsv")
    assert _data_lines(tmp_path / "new.ecsv") == _data_lines(original)
    assert len(_data_lines(original)) > 10
    assert plan_changes(ucbplan.Plan.read(original), new).line() == (
        "replan: 2 visit(s) kept, 0 moved, 0 added, 0 dropped"
    )


def test_a_replan_later_in_the_run_without_losses_keeps_every_visit(
    original: Path, tmp_path: Path
) -> None:
    """From the second night, nothing lost and the first night's spectra taken as planned: the
    plan stands (the observer's schedule does not move)."""
    new = _quiet(ucbplan.replan, original, SECOND)
    new.write(tmp_path / "new.ecsv")
    assert _data_lines(tmp_path / "new.ecsv") == _data_lines(original)
    assert plan_changes(ucbplan.Plan.read(original), new).line() == (
        "replan: 2 visit(s) kept, 0 moved, 0 added, 0 dropped"
    )


def test_a_lost_night_gets_nothing_and_the_history_is_kept(original: Path, tmp_path: Path) -> None:
    new = _quiet(ucbplan.replan, ucbplan.Plan.read(original), SECOND, lost=["2040-02-16"])
    new.write(tmp_path / "new.ecsv")
    old_lines, new_lines = _data_lines(original), _data_lines(tmp_path / "new.ecsv")
    old = Table.read(original, format="ascii.ecsv")
    n_first = int(np.sum(old["night"] == "2040-02-15"))
    assert new_lines[: n_first + 1] == old_lines[: n_first + 1]  # header line + night 1
    nights = list(new.text_table["night"])
    assert "2040-02-16" not in nights and "2040-02-17" in nights
    changes = plan_changes(ucbplan.Plan.read(original), new)
    assert (len(changes.added), len(changes.dropped)) == (1, 1)


def test_a_replan_file_names_its_kept_nights_not_a_temporary_file(
    original: Path, tmp_path: Path
) -> None:
    """The replan's meta said ``observed: [/tmp/tmpXXXX/history.ecsv]``: a file that no longer
    exists, and another name on every run (two replans of one plan differed byte for byte)."""
    texts = []
    for k in range(2):
        new = _quiet(ucbplan.replan, original, SECOND, lost=["2040-02-16"])
        new.write(tmp_path / f"new{k}.ecsv")
        texts.append((tmp_path / f"new{k}.ecsv").read_text())
    assert "/tmp" not in texts[0] and "history.ecsv" not in texts[0]
    assert new.meta["planning"]["observed"] == ["the plan's nights before 2040-02-16"]
    strip = [[ln for ln in t.splitlines() if "created_utc" not in ln] for t in texts]
    assert strip[0] == strip[1]


def test_observed_may_be_a_table_in_memory(original: Path, tmp_path: Path) -> None:
    """``plan(observed=Table)`` counts the same spectra as the same table written to a file."""
    rows = Table.read(original, format="ascii.ecsv")
    rows = rows[rows["night"] == "2040-02-15"]
    rows["status"] = ["taken"] * len(rows)
    rows.write(tmp_path / "obs.ecsv", format="ascii.ecsv")
    kw: dict[str, Any] = {**BASE, "night": "2040-02-16", "nights": 2}
    from_file = _quiet(ucbplan.plan, str(TARGET), observed=tmp_path / "obs.ecsv", **kw)
    from_table = _quiet(ucbplan.plan, str(TARGET), observed=rows, **kw)
    assert len(from_table) > 0 and from_table.goals[0].expected == from_file.goals[0].expected
    assert _data_lines_of(from_table, tmp_path) == _data_lines_of(from_file, tmp_path)
    assert from_table.meta["planning"]["observed"] == ["a table in memory"]


@pytest.mark.parametrize("alternate", [False, True])
def test_promised_sigma_k_with_half_observed_matches_a_fisher_sum(
    original: Path, tmp_path: Path, alternate: bool
) -> None:
    """The goal's promise after a replan counting half of night 1 taken (the first half, or
    every other row: all at one anchor, which alone gives no information on K but with the
    planned rows fixing γ does: one γ for all) equals 1/√(F_KK) of the taken + planned rows, F
    from the design matrix (test_observed); 2 %: the planner's promise assumes balanced planned
    visits (Σ Λ cos u/σ_v² = 0), which their airmasses break by a little."""
    old = Table.read(original, format="ascii.ecsv")
    first = old[old["night"] == "2040-02-15"]
    n = len(first)
    half = np.arange(n) % 2 == 0 if alternate else np.arange(n) < n // 2
    first["status"] = np.where(half, "taken", "missed")
    first.write(tmp_path / "log.ecsv", format="ascii.ecsv")
    new = _quiet(ucbplan.replan, original, SECOND, observed=tmp_path / "log.ecsv")
    planned = new.text_table[new.text_table["night"] != "2040-02-15"]
    rows = vstack([first[first["status"] == "taken"], planned], metadata_conflicts="silent")
    tau = (Time(list(rows["t_mid_tdb_bary"]), scale="tdb") - load_target(TARGET).t_ref).to("s")
    info = brute_force_info(
        tau.value, np.asarray(rows["exptime_s"], float), np.asarray(rows["sigma_v_kms"], float)
    )
    (goal,) = new.goals
    assert goal.expected.to_value("km/s") == pytest.approx(info**-0.5, rel=0.02)
    # a changed replan may leave REPLAN_INFO_SLACK of the information: σ ≤ goal/√(1 − slack)
    assert goal.expected.to_value("km/s") <= 15.0 / math.sqrt(1.0 - REPLAN_INFO_SLACK)


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"from_": "2040-03-01T00:00"}, "before the plan's end"),
        ({"from_": SECOND, "lost": ["2040-02-20"]}, "lost: expected a night of the plan"),
        ({"from_": "2040-02-16T06:00"}, "before the first block of night"),
        ({"from_": "yesterday"}, "ISO UTC instant"),
    ],
)
def test_bad_input_is_one_line(original: Path, kw: dict[str, Any], match: str) -> None:
    with pytest.raises(InputError, match=match) as info:
        _quiet(ucbplan.replan, original, **kw)
    assert "\n" not in str(info.value)


def test_a_bad_status_is_refused(original: Path, tmp_path: Path) -> None:
    log = Table.read(original, format="ascii.ecsv")[:3]
    log["status"] = np.array(["taken", "cloudy", "taken"])
    log.write(tmp_path / "log.ecsv", format="ascii.ecsv")
    with pytest.raises(InputError, match="status"):
        _quiet(ucbplan.replan, original, SECOND, observed=tmp_path / "log.ecsv")


def test_a_changed_target_file_or_a_plan_without_options_is_refused(tmp_path: Path) -> None:
    target = shutil.copy(TARGET, tmp_path / "t.yaml")
    plan = _quiet(ucbplan.plan, target, night="2040-02-15", nights=2, **BASE)
    plan.write(tmp_path / "p.ecsv")
    Path(target).write_text(Path(target).read_text() + "\n# edited\n")
    with pytest.raises(InputFileError, match="target file changed"):
        ucbplan.replan(tmp_path / "p.ecsv", "2040-02-15T12:00")
    table = Table.read(tmp_path / "p.ecsv", format="ascii.ecsv")
    del table.meta["plan_options"]
    table.write(tmp_path / "bare.ecsv", format="ascii.ecsv")
    with pytest.raises(InputFileError, match="plan_options"):
        ucbplan.replan(tmp_path / "bare.ecsv", "2040-02-15T12:00")


def test_cli_exit_codes_and_nothing_written_on_bad_input(original: Path, tmp_path: Path) -> None:
    out = tmp_path / "new.ecsv"
    args = ["replan", str(original), "-o", str(out)]
    code, _, err = run_main([*args, "--from", SECOND, "--lost", "2040-02-16"])
    assert code == 0, err
    assert "replan: 0 visit(s) kept, 0 moved, 1 added, 1 dropped" in err
    assert "expected" in err and out.is_file()
    for bad in (["--from", "2040-03-01T00:00"], ["--from", SECOND, "--lost", "2040-02-20"]):
        code, _, err = run_main(["replan", str(original), "-o", str(tmp_path / "x.ecsv"), *bad])
        assert code == 2 and len(err.strip().splitlines()) == 1, err
        assert not (tmp_path / "x.ecsv").exists()


def test_a_goal_out_of_reach_is_planned_as_far_as_it_goes_and_stated(
    original: Path, tmp_path: Path
) -> None:
    """Night 1 missed and night 2 lost: night 3 alone cannot reach σ_K ≤ 15 km/s. The replan
    plans it anyway, in one visit as full as the 1-h visit holds (not the half of an even split
    that assumed two nights), and states in one line of ≤ 100 columns the σ_K reached, which
    equals 1/√(F_KK) of the planned rows from the design matrix within 2 % (the planner counts
    the planned visits as balanced), and the hours more: the missing information at the
    information per hour of the visits planned."""
    old = Table.read(original, format="ascii.ecsv")
    first = old[old["night"] == "2040-02-15"]
    first["status"] = "missed"
    first.write(tmp_path / "log.ecsv", format="ascii.ecsv")
    new = _quiet(
        ucbplan.replan, original, SECOND, observed=tmp_path / "log.ecsv", lost=["2040-02-16"]
    )
    assert new.run is not None
    (line,) = new.run.shortfall_lines()
    assert "not reached" in line and "h (~1 night(s)) more" in line and len(line) <= 100
    (short,) = new.run.result.shortfalls
    rows = new.text_table[new.text_table["night"] != "2040-02-15"]  # the history goes
    tau = (Time(list(rows["t_mid_tdb_bary"]), scale="tdb") - load_target(TARGET).t_ref).to("s")
    info = brute_force_info(
        tau.value, np.asarray(rows["exptime_s"], float), np.asarray(rows["sigma_v_kms"], float)
    )
    assert short.reachable == pytest.approx(info**-0.5, rel=0.02)
    assert 15.0 < short.reachable < 16.0  # 19.6 km/s in half a visit
    (goal,) = new.goals
    assert goal.expected.to_value("km/s") == pytest.approx(short.reachable)
    hours = new.run.time_account.targets[short.target].total_s / 3600
    assert f"needs {(short.needed / short.got - 1) * hours:.2g} h" in line


def test_cli_one_anchor_spectra_taken_say_they_fix_nothing_alone(
    original: Path, tmp_path: Path
) -> None:
    """Every other row of night 1 taken (one anchor): alone they give no σ_K (the report said
    so by dividing by zero before); with the plan's spectra they count."""
    old = Table.read(original, format="ascii.ecsv")
    first = old[old["night"] == "2040-02-15"]
    first["status"] = np.where(np.arange(len(first)) % 2 == 0, "taken", "missed")
    first.write(tmp_path / "log.ecsv", format="ascii.ecsv")
    code, _, err = run_main(
        ["replan", str(original), "--from", SECOND, "--observed", str(tmp_path / "log.ecsv")]
    )
    assert code == 0, err
    assert "no σ_K alone (γ and K not separated)" in err


def test_an_observing_log_of_another_plan_is_refused_in_one_line(
    original: Path, tmp_path: Path
) -> None:
    """A ``now --log`` file of this plan counts; the same log of another plan (one block start
    moved: another plan_id) is refused in one line, by the API and the CLI (exit 2, nothing
    written)."""
    from ucbplan.observing.blocks.read import read_blocks
    from ucbplan.observing.night.observing_log import ObservingLog

    ours = ObservingLog.open(read_blocks(original), tmp_path / "ours.csv")
    other_table = read_blocks(original)
    other_table["t_start_utc"][0] = "2040-02-15T23:59:59.000"
    theirs = ObservingLog.open(other_table, tmp_path / "theirs.csv")
    for log in (ours, theirs):
        for e in log.exposures[:4]:
            log.mark(e, "taken")
    assert _quiet(ucbplan.replan, original, SECOND, observed=ours.path).goals
    with pytest.raises(InputError, match=r"^observed .*: a log of another plan \(plan_id ") as e:
        _quiet(ucbplan.replan, original, SECOND, observed=theirs.path)
    assert "\n" not in str(e.value)
    out = tmp_path / "new.ecsv"
    args = ["replan", str(original), "--from", SECOND, "--observed", str(theirs.path)]
    code, _, err = run_main([*args, "-o", str(out)])
    assert code == 2 and len(err.strip().splitlines()) == 1 and not out.exists(), err


def test_a_replan_after_one_lost_night_keeps_the_other_nights_visits(tmp_path: Path) -> None:
    """σ_K ≤ 9 km/s over five nights books three visits (2040-02-15 to 17); 02-16 lost, the
    replan keeps the visits of 02-15 and 02-17 (same start, every exposure) and adds one visit
    for what the lost night held; the goal is still reached (within the replan's slack)."""
    plan = _quiet(
        ucbplan.plan, str(TARGET), night="2040-02-15", nights=5, **{**BASE, "goal": "sigma_K=9km/s"}
    )
    plan.write(tmp_path / "p.ecsv")
    old = ucbplan.Plan.read(tmp_path / "p.ecsv")
    new = _quiet(ucbplan.replan, tmp_path / "p.ecsv", "2040-02-15T12:00", lost=["2040-02-16"])
    changes = plan_changes(old, new)
    survivors = old.text_table[old.text_table["night"] != "2040-02-16"]
    assert len(set(survivors["visit_id"])) == 2
    assert sorted(changes.kept) == sorted(set(survivors["visit_id"]))
    assert (len(changes.moved), len(changes.added)) == (0, 1)
    starts = {str(s) for s in new.text_table["t_start_utc"]}
    assert {str(s) for s in survivors["t_start_utc"]} <= starts  # every exposure kept
    (goal,) = new.goals
    assert goal.expected.to_value("km/s") <= 9.0 / math.sqrt(1.0 - REPLAN_INFO_SLACK)


def test_kept_visits_are_dropped_only_when_the_goal_is_over_reached_without_them() -> None:
    """Three kept visits of information 4, 2 and 3 (per hour: 4, 1, 3): with 5 still needed the
    least information per hour goes first (2: 7 ≥ 5 without it), then none can go (4 or 3
    alone < 5); with 10 needed every one stays; with no goal nothing is judged."""
    from types import SimpleNamespace

    from ucbplan.observing.schedule.pinning import _needed
    from ucbplan.observing.schedule.placement import Allowance, Session

    run: Any = SimpleNamespace(weight=np.array([2.0, 2.0, 1.0, 1.0, 1.5, 1.5]))
    visits = [
        Session(0, 0, (0, 1), 0.0, 1.0),
        Session(0, 1, (2, 3), 10.0, 12.0),
        Session(0, 2, (4, 5), 20.0, 21.0),
    ]
    assert _needed(run, visits, Allowance(info=5.0)) == [visits[0], visits[2]]
    assert _needed(run, visits, Allowance(info=10.0)) == visits
    assert _needed(run, visits, Allowance()) == visits
