"""The one time-accounting module: the typed accounts, their meta form and its reader.

The meta form is what the blocks table (ECSV meta, ``--format json``) records and what the proposal
export reads back; these tests pin its keys, order, rounding and types against values written out
by hand, and the reader's validation against the messages the export has always given.
"""

from __future__ import annotations

import json
import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from ucbplan.errors import InputFileError
from ucbplan.observing.blocks.accounting import (
    ACCOUNT_KEYS,
    PlanAccount,
    TimeAccount,
    VisitColumns,
    VisitSummary,
    time_accounting,
)


def _visit(target: str, shutter: float, overhead: float, idle: float, n: int) -> VisitSummary:
    t = "2040-02-15T01:00:00"
    return VisitSummary("", target, "2040-02-14", t, t, t, n, shutter, overhead, idle)


def test_meta_entry_keys_order_and_rounding_by_hand() -> None:
    # shutter 600 s + 0.1234 s, overhead 300.0006 s, idle 99.9996 s: 1 ms rounding by hand
    a = TimeAccount(2, 10, 600.1234, 300.0006, 99.9996)
    meta = a.as_meta()
    assert tuple(meta) == ACCOUNT_KEYS
    assert meta == {
        "visits": 2,
        "exposures": 10,
        "shutter_s": 600.123,
        "overhead_s": 300.001,
        "idle_s": 100.0,
        # efficiency from the unrounded times: 600.1234 / 1000.1236, to 1e-6
        "efficiency": 0.600049,
    }


def test_empty_account_writes_integers_as_the_planner_always_did() -> None:
    # an empty sum is the integer 0: JSON "0", not "0.0" (byte-identical tables)
    plan = time_accounting([])
    assert json.dumps(plan.as_meta()) == (
        '{"total": {"visits": 0, "exposures": 0, "shutter_s": 0, "overhead_s": 0, '
        '"idle_s": 0, "efficiency": 0.0}, "targets": {}}'
    )


def test_plan_account_sums_visits_per_target_in_order_of_first_visit() -> None:
    visits = [
        _visit("B", 100.0, 50.0, 10.0, 2),
        _visit("A", 60.0, 30.0, 0.0, 1),
        _visit("B", 200.0, 50.0, 5.0, 4),
    ]
    plan = time_accounting(visits)
    assert list(plan.targets) == ["B", "A"]
    assert plan.targets["B"] == TimeAccount(2, 6, 300.0, 100.0, 15.0)
    assert plan.targets["A"] == TimeAccount(1, 1, 60.0, 30.0, 0.0)
    assert plan.total == plan.targets["B"] + plan.targets["A"]
    # efficiency = shutter / (shutter + overhead + idle), by hand: 360 / 505
    assert plan.as_meta()["total"]["efficiency"] == round(360 / 505, 6)


@given(
    st.integers(0, 10_000),
    st.integers(0, 10_000),
    st.floats(0, 1e7),
    st.floats(0, 1e7),
    st.floats(0, 1e7),
)
def test_meta_round_trip_keeps_the_recorded_figures(
    visits: int, exposures: int, shutter: float, overhead: float, idle: float
) -> None:
    written = TimeAccount(visits, exposures, shutter, overhead, idle).as_meta()
    back = TimeAccount.from_meta("total", json.loads(json.dumps(written)))
    assert back.as_meta() | {"efficiency": 0} == written | {"efficiency": 0}
    # the reader recomputes the efficiency from the recorded times: each moved by <= 0.5 ms,
    # so |s_r/t_r - s/t| <= (0.5 ms t + 1.5 ms s) / (t t_r) <= 2 ms / t_r, plus the 1e-6 rounding
    if back.total_s >= 1.0:
        assert back.efficiency == pytest.approx(
            written["efficiency"], abs=1e-6 + 2e-3 / back.total_s
        )


@pytest.mark.parametrize(
    ("entry", "message"),
    [
        ([], r"targets\.X: expected a mapping with visits, exposures, shutter_s"),
        ({"visits": 1, "exposures": 1, "shutter_s": -1, "overhead_s": 0, "idle_s": 0},
         r"targets\.X\.shutter_s: expected a number >= 0, got -1"),
        ({"visits": 1.5, "exposures": 1, "shutter_s": 1, "overhead_s": 0, "idle_s": 0},
         r"targets\.X\.visits: expected a whole number, got 1\.5"),
        ({"visits": 1, "exposures": 1, "shutter_s": math.nan, "overhead_s": 0, "idle_s": 0},
         r"targets\.X\.shutter_s: expected a number >= 0, got nan"),
        ({"visits": 1, "exposures": 1, "shutter_s": 1, "overhead_s": 0},
         r"targets\.X\.idle_s: expected a number >= 0, got None"),
    ],
)  # fmt: skip
def test_meta_reader_names_the_field_and_the_fix(entry: object, message: str) -> None:
    with pytest.raises(InputFileError, match=message) as info:
        TimeAccount.from_meta("targets.X", entry)
    assert str(info.value).startswith("blocks table meta time_accounting: ")
    assert str(info.value).endswith("regenerate the table with `ucbplan plan`")


def test_plan_account_meta_is_a_new_dict_each_time() -> None:
    plan = PlanAccount(TimeAccount(1, 1, 1.0, 1.0, 1.0), {"A": TimeAccount(1, 1, 1.0, 1.0, 1.0)})
    first = plan.as_meta()
    first["targets"]["A"]["visits"] = 99
    assert plan.as_meta()["targets"]["A"]["visits"] == 1


# -- the visits as columns (issue 34): records, walls and accounts read from the columns agree,
# bit for bit, with the same figures made one VisitSummary at a time.

_SECONDS = st.one_of(
    st.sampled_from([0.0, -0.0, 0.0005, 0.0015, 2.675, 1e-300, math.nan, math.inf, 60.0]),
    st.floats(-1e7, 1e7),
)
_VISITS = st.lists(
    st.builds(
        _visit, st.sampled_from(["A", "B Cnc", "c"]), _SECONDS, _SECONDS, _SECONDS, st.integers()
    ),
    max_size=30,
)


def _bits(value: object) -> object:
    """A value compared bit for bit (repr tells -0.0 from 0.0 and matches NaN with NaN)."""
    if isinstance(value, dict):
        return [(k, type(v), repr(v)) for k, v in value.items()]
    return (type(value), repr(value))


@given(_VISITS)
def test_visit_columns_give_each_summary_and_its_meta_record(visits: list[VisitSummary]) -> None:
    cols = VisitColumns.of(visits)
    assert len(cols) == len(visits)
    assert cols.summaries() == visits
    assert list(map(_bits, cols.records())) == [_bits(v.as_dict()) for v in visits]
    assert list(map(_bits, cols.wall_s())) == [_bits(v.wall_s) for v in visits]


def _account_one_by_one(visits: list[VisitSummary]) -> TimeAccount:
    return TimeAccount(
        len(visits),
        sum(v.exposures for v in visits),
        sum(v.shutter_s for v in visits),
        sum(v.overhead_s for v in visits),
        sum(v.idle_s for v in visits),
    )


@given(_VISITS)
def test_accounts_from_columns_are_the_sums_visit_by_visit(visits: list[VisitSummary]) -> None:
    plan = time_accounting(visits)
    names = list(dict.fromkeys(v.target for v in visits))
    assert list(plan.targets) == names
    want = [_account_one_by_one(visits)]
    want += [_account_one_by_one([v for v in visits if v.target == n]) for n in names]
    got = [plan.total, *plan.targets.values()]
    assert [list(map(_bits, vars_of(a))) for a in got] == [
        list(map(_bits, vars_of(a))) for a in want
    ]


def vars_of(account: TimeAccount) -> list[object]:
    return [getattr(account, k) for k in ACCOUNT_KEYS[:5]]
