"""The acceptance simulation of issue 32 (benchmarks/replan_acceptance.py): a goal plan loses
nights and its σ_v changes; the replan, observed with noise and fitted, reaches the goal within
5 % in at most 5 % more hours than the fewest possible, or states rightly (5 %) how far short
it falls. One case here; a handful in the slow test (the benchmark runs 30)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

import pytest

BENCH = Path(__file__).resolve().parents[3] / "benchmarks" / "replan_acceptance.py"


def _module() -> ModuleType:
    spec = importlib.util.spec_from_file_location("replan_acceptance", BENCH)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules.setdefault("replan_acceptance", module)  # its dataclass looks itself up
    spec.loader.exec_module(sys.modules["replan_acceptance"])
    return sys.modules["replan_acceptance"]


def test_one_replanned_run_reaches_its_goal_in_the_fewest_hours() -> None:
    """Seed 1: HM Cnc, 8 nights, 2 lost, σ_v × 1.10, replanned from the third night."""
    acc = _module()
    (case,) = acc.run_cases(range(1, 2))
    assert not case.short
    assert set(case.checks) == {"goal", "hours"}, case.line()
    assert all(case.checks.values()), case.line()


def test_a_check_can_fail() -> None:
    acc = _module()
    case = acc.Case(0, "t.yaml", 5, 2.0, ["2040-02-16"], "2040-02-16", 1.0)
    case.achieved, case.booked_h, case.fewest_h = 2.2, 1.0, 1.0
    assert case.checks == {"goal": False, "hours": True}
    case.short, case.stated = "short", 2.0
    assert case.checks == {"stated": False}
    case.achieved = case.stated = float("inf")  # nothing taken, no visit fits: stated so
    assert case.checks == {"stated": True}
    case.stated = 2.0
    assert case.checks == {"stated": False}


@pytest.mark.slow
def test_a_handful_of_replanned_runs() -> None:
    """Six seeded cases: every check that applies passes (goal, hours or the statement)."""
    acc = _module()
    rates = acc.pass_rates(acc.run_cases(range(8, 14)))
    assert all(got == n for got, n in rates.values()), rates


@pytest.mark.slow
def test_the_cases_that_booked_a_pattern_too_many_now_book_the_fewest_hours() -> None:
    """Seeds 6, 14 and 30 (HM Cnc) booked 7–14 % over the bound: the first night's best visit
    sat at σ_v ~0.5 % worse than the best anchors of a later night, one anchor pattern more at a
    threshold. Seed 73 (back-to-back exposures) was held to a bound no schedule of the plan's
    cadence reaches (3 exposures at |cos u| = 1). Every one now passes every check."""
    acc = _module()
    cases = acc.run_cases([6, 14, 30, 73])
    for case in cases:
        assert "hours" in case.checks and all(case.checks.values()), case.line()
