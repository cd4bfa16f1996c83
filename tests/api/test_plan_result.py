"""The ``Plan`` a notebook user gets: its repr, typed records, table, chart, files and round trip.

One small plan (HM Cnc at Paranal, one night of 1-h visits with X-shooter, the exposure time
chosen for information per visit) serves every test; it is built as ``ucbplan plan`` builds it
(:func:`~ucbplan.observing.schedule.run.plan_files`), so the files compared with the command
line's come from the same run.
"""

from __future__ import annotations

import contextlib
import tempfile
from dataclasses import replace
from datetime import date
from html.parser import HTMLParser
from pathlib import Path
from typing import Any

import astropy.units as u
import numpy as np
import pytest
from astropy.time import Time
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from ucbplan.api.plan_result import Plan
from ucbplan.errors import InputFileError, OutputExistsError, UcbplanError
from ucbplan.observing.blocks.block import ExposurePlan
from ucbplan.observing.schedule.run import planned_exposure

ROOT = Path(__file__).resolve().parents[2]
HM = ROOT / "catalogs" / "hm-cnc-simulated.yaml"
#: The plan of issue 30's report, as the command line spells it.
CLI_ARGS = [str(HM), "--site", "paranal", "--night", "2040-02-15", "--sigma-v", "30km/s@300s",
            "--visit", "1h", "--instrument", "xshooter-vis"]  # fmt: skip


@pytest.fixture(scope="module")
def plan() -> Plan:
    from ucbplan.api._convert import scope
    from ucbplan.observing.schedule import plan_settings
    from ucbplan.observing.schedule.run import plan_files

    with scope():
        settings = plan_settings(sigma_v_kms="30km/s@300s", visit="1h", instrument="xshooter-vis")
        run = plan_files([HM], first_night="2040-02-15", site="paranal", settings=settings)
    return Plan(run)


# ------------------------------------------------------------------ the meta says what was planned


def test_meta_exposure_is_the_planned_one_not_the_default(plan: Plan) -> None:
    # issue 30: the meta said 60 s (the default) while every exposure was 80 s
    text = plan.text_table
    planned = sorted(set(text["exptime_s"].tolist()))
    assert planned == [80.0]  # chosen for information per visit (not the 60-s default)
    assert text.meta["exposure"] == {"exptime_s": 80.0, "n_exp": 1, "readout_s": 45.0}
    assert text.meta["exposure"]["readout_s"] == float(text["readout_s"][0])


def test_planned_exposure_keeps_what_the_targets_share() -> None:
    a, b = ExposurePlan(80.0, 1, 45.0), ExposurePlan(59.576, 1, 45.0)
    requested = ExposurePlan(60.0, 1, 45.0)
    assert planned_exposure([a, a], requested) == {"exptime_s": 80.0, "n_exp": 1, "readout_s": 45.0}
    # targets that differ: no one exposure time describes the run (each target's is in planning)
    assert planned_exposure([a, b], requested) == {"exptime_s": None, "n_exp": 1, "readout_s": 45.0}
    assert planned_exposure([], requested) == {"exptime_s": 60.0, "n_exp": 1, "readout_s": 45.0}


# ------------------------------------------------------------------------------ the plan object


@pytest.fixture(scope="module")
def goal_plan() -> Plan:
    """Two nights of 1-h visits towards σ(K) ≤ 12 km/s: goals, strategies, two chart panels."""
    return _plan(GOAL_OPTIONS, 2)


GOAL_OPTIONS = {"sigma_v_kms": "30km/s@300s", "visit": "1h", "instrument": "xshooter-vis",
                "goal": "sigma_K=12km/s"}  # fmt: skip
GOAL_ARGS = ["--sigma-v", "30km/s@300s", "--visit", "1h", "--instrument", "xshooter-vis",
             "--goal", "sigma_K=12km/s"]  # fmt: skip


def _plan(options: dict[str, Any], nights: int) -> Plan:
    from ucbplan.api._convert import scope
    from ucbplan.observing.schedule import plan_settings
    from ucbplan.observing.schedule.run import plan_files

    with scope():
        settings = plan_settings(**options)
        run = plan_files([HM], first_night="2040-02-15", n_nights=nights, site="paranal",
                         settings=settings)  # fmt: skip
    return Plan(run)


def _cli(*args: str) -> Any:
    from typer.testing import CliRunner

    from ucbplan.cli.app import app

    result = CliRunner().invoke(app, list(args))
    assert result.exit_code == 0, result.output
    return result


def test_repr_is_one_short_line(goal_plan: Plan) -> None:
    text = repr(goal_plan)
    assert "\n" not in text and len(text) <= 100, text
    assert text == "<Plan at Paranal: 1 target, 2 nights, 2 visits, 32 exposures, 1.63 h>"


class _Cells(HTMLParser):
    """The text of every cell and the tags still open (an escaped text opens none)."""

    def __init__(self) -> None:
        super().__init__()
        self.open: list[str] = []
        self.cells: list[str] = []

    def handle_starttag(self, tag: str, attrs: Any) -> None:
        self.open.append(tag)

    def handle_endtag(self, tag: str) -> None:
        assert self.open.pop() == tag

    def handle_data(self, data: str) -> None:
        if self.open and self.open[-1] in ("td", "caption"):
            self.cells.append(data)


def _parsed(text: str) -> list[str]:
    parser = _Cells()
    parser.feed(text)
    parser.close()
    assert parser.open == []
    return parser.cells


def test_repr_html_is_the_summary(goal_plan: Plan) -> None:
    cells = _parsed(goal_plan._repr_html_())
    pairs = dict(zip(cells[1::2], cells[2::2], strict=True))
    total = goal_plan.accounting.total
    assert pairs["exposures"] == str(len(goal_plan)) == "32"
    assert pairs["visits"] == str(total.visits) and pairs["nights"] == "2"
    assert pairs["hours (shutter + overheads + idle)"] == f"{total.total_s / 3600:.2f}"
    goal = goal_plan.goals[0]
    assert pairs[f"goal σ(K) ≤ 12 km/s: {goal.target}"] == "11.9 km/s (32 spectra)"
    assert pairs[f"strategy targeted (planned): {goal.target}"] == "100% of best"


def test_repr_html_escapes_every_text(goal_plan: Plan) -> None:
    assert goal_plan.run is not None
    run = replace(goal_plan.run, site=replace(goal_plan.run.site, name="<b>Cerro & Co</b>"))
    cells = _parsed(Plan(run)._repr_html_())
    assert cells[0] == "Plan at <b>Cerro & Co</b>"  # text, not markup


def test_typed_records_are_the_meta(goal_plan: Plan) -> None:
    entry = goal_plan.meta["planning"]["targets"]["HM Cnc (simulated)"]
    facts = entry["strategy"]
    assert [s.strategy for s in goal_plan.strategies] == list(facts["strategies"])
    for s in goal_plan.strategies:
        row = facts["strategies"][s.strategy]
        assert s.chosen == (s.strategy == facts["chosen"])
        assert (None if s.exptime is None else s.exptime.to_value(u.s)) == row["exptime_s"]
        assert s.info_per_visit.to_value(u.km**-2 * u.s**2) == row["info_per_visit"]
        assert s.info_per_hour.to_value(u.km**-2 * u.s**2 / u.h) == row["info_per_hour"]
        assert s.fraction_of_best == row["fraction_of_best"]
        assert (None if s.goal_hours is None else s.goal_hours.to_value(u.h)) == row["goal_hours"]
    (goal,) = goal_plan.goals
    assert goal.expected.to_value(u.km / u.s) == entry["goal_expected"]
    assert goal.n_spectra == entry["goal_spectra"] and goal.goal == "sigma_K=12km/s"
    assert goal.expected < 12 * u.km / u.s  # the goal is met by the plan
    assert goal_plan.accounting.as_meta() == goal_plan.meta["time_accounting"]
    assert [v.as_dict() for v in goal_plan.visits] == goal_plan.meta["visits"]
    assert goal_plan.nights == [date(2040, 2, 15), date(2040, 2, 16)]
    assert goal_plan.warnings == goal_plan.meta["warnings"]


def test_len_is_the_number_of_exposures(goal_plan: Plan) -> None:
    n_exp = goal_plan.text_table["n_exp"]
    assert len(goal_plan) == int(sum(n_exp)) == goal_plan.accounting.total.exposures == 32


def test_table_has_times_and_quantities_and_the_file_stays_text(goal_plan: Plan) -> None:
    table, text = goal_plan.table, goal_plan.text_table
    assert isinstance(table["t_mid_utc"], Time) and table["t_mid_utc"].scale == "utc"
    assert isinstance(table["t_mid_tdb_bary"], Time) and table["t_mid_tdb_bary"].scale == "tdb"
    assert list(table["t_start_utc"].isot) == text["t_start_utc"].tolist()
    assert list(table["t_mid_tdb_bary"].isot) == text["t_mid_tdb_bary"].tolist()
    assert table["exptime_s"].unit == u.s and isinstance(table["exptime_s"], u.Quantity)
    assert table["smear_kms"].unit == u.km / u.s
    assert text["t_start_utc"].dtype.kind == "U"  # what the files hold is untouched
    assert table.meta == text.meta


def test_plot_returns_labelled_axes(goal_plan: Plan) -> None:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from ucbplan.plotting.layout import layout_problems

    ax = goal_plan.plot()
    try:
        assert isinstance(ax, Axes) and len(ax.figure.axes) == 2  # a panel per night
        assert ax.get_xlabel().startswith("UTC [hh:mm]") and ax.get_ylabel() == "altitude [deg]"
    finally:
        import matplotlib.pyplot as plt

        plt.close(ax.figure)
    mine = Figure(figsize=(11, 5.2), layout="constrained").subplots()
    assert goal_plan.plot(ax=mine, night="2040-02-16") is mine
    assert "night of 2040-02-16" in mine.get_title() and layout_problems(mine.figure) == []


def test_plot_draws_what_plot_writes(plan: Plan, tmp_path: Path) -> None:
    import matplotlib.pyplot as plt

    ax = plan.plot()
    try:  # what `plan --plot night.png` writes (whose layout test_nightsheet checks)
        ax.figure.savefig(tmp_path / "mine.png", format="png", dpi=110)
    finally:
        plt.close(ax.figure)
    assert plan.charts(tmp_path / "cli.png") == 1
    assert (tmp_path / "mine.png").read_bytes() == (tmp_path / "cli.png").read_bytes()


def test_to_dict_is_the_json_document(goal_plan: Plan) -> None:
    import json

    assert goal_plan.to_dict() == json.loads(goal_plan.to_text("json"))


def test_write_and_read_round_trip(goal_plan: Plan, tmp_path: Path) -> None:
    path = goal_plan.write(tmp_path / "plan.ecsv")
    back = Plan.read(path)
    assert back.run is None
    assert back.text_table.meta == goal_plan.text_table.meta
    assert back.text_table.colnames == goal_plan.text_table.colnames
    for name in back.text_table.colnames:
        x, y = np.asarray(back.text_table[name]), np.asarray(goal_plan.text_table[name])
        assert np.array_equal(x, y, equal_nan=x.dtype.kind == "f"), name
        assert back.text_table[name].unit == goal_plan.text_table[name].unit, name
    assert back.accounting == goal_plan.accounting and back.visits == goal_plan.visits
    assert back.strategies == goal_plan.strategies and back.goals == goal_plan.goals
    assert back.nights == goal_plan.nights and back.warnings == goal_plan.warnings
    assert back.not_planned == goal_plan.not_planned
    assert back.site.as_dict() == goal_plan.site.as_dict()  # (the aliases are not recorded)
    assert repr(back) == repr(goal_plan) and len(back) == len(goal_plan)
    assert back.to_text("ecsv") == path.read_text(encoding="utf-8")
    with pytest.raises(OutputExistsError):
        goal_plan.write(path)


@pytest.mark.parametrize(
    ("key", "value", "attribute"),
    [
        ("site", {"name": "x"}, "site"),
        ("nights", ["2040-13-45"], "nights"),
        ("visits", [{"visit_id": 3}], "visits"),
        ("not_planned", [1], "not_planned"),
        ("time_accounting", {"total": {"visits": -1}}, "accounting"),
        (
            "planning",
            {"targets": {"HM Cnc (simulated)": {"strategy": {"strategies": {"x": 1}}}}},
            "strategies",
        ),
        (
            "planning",
            {"goal": "sigma_K=5km/s", "targets": {"a": {"goal_spectra": "many"}}},
            "goals",
        ),
        ("planning", {"goal": "nonsense", "targets": {}}, "goals"),
    ],
)
def test_a_hand_edited_meta_is_named(goal_plan: Plan, key: str, value: Any, attribute: str) -> None:
    table = goal_plan.text_table.copy()
    table.meta[key] = value
    with pytest.raises(UcbplanError) as info:
        getattr(Plan(None, table), attribute)
    assert "\n" not in str(info.value)


def test_read_wants_the_ecsv_plan(goal_plan: Plan, tmp_path: Path) -> None:
    path = goal_plan.write(tmp_path / "plan.csv")
    with pytest.raises(InputFileError, match=r"write the plan as \.ecsv"):
        Plan.read(path)


def test_a_read_plan_charts_exports_and_sheets(goal_plan: Plan, tmp_path: Path) -> None:
    back = Plan.read(goal_plan.write(tmp_path / "plan.ecsv"))
    ax = back.plot(night="2040-02-15")
    import matplotlib.pyplot as plt

    plt.close(ax.figure)
    assert back.export("phase-table") == goal_plan.export("phase-table")
    assert back.to_astroplan() is not None


@pytest.mark.parametrize("to", ["ics", "phase-table"])
def test_export_is_what_the_cli_writes(tmp_path: Path, to: str) -> None:
    cli_plan = tmp_path / "plan.ecsv"
    _cli("plan", str(HM), "--site", "paranal", "--night", "2040-02-15", "--nights", "2",
         *GOAL_ARGS, "-o", str(cli_plan))  # fmt: skip
    plan = Plan.read(cli_plan)
    result = _cli("export", str(cli_plan), "--to", to)
    text = plan.export(to)
    assert isinstance(text, str) and text.encode("utf-8") == result.stdout_bytes
    written = plan.export(to, tmp_path / f"out.{to}")
    assert isinstance(written, Path) and written.read_bytes() == result.stdout_bytes


def test_sheet_writes_the_night_sheet(plan: Plan, tmp_path: Path) -> None:
    path = tmp_path / "night.html"
    assert plan.sheet(path) == 1  # nights
    text = path.read_text(encoding="utf-8")
    assert "night of 2040-02-15" in text and "V01" in text
    with pytest.raises(OutputExistsError):
        plan.sheet(path)


# ------------------------------------------------------------------------------------ bad input

_ANY = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-(10**6), 10**6),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=12),
    st.lists(st.integers(), max_size=3),
    st.just(object()),
    st.just(date(1999, 1, 1)),
)


@settings(max_examples=80, deadline=None)
@given(
    method=st.sampled_from(["plot", "charts", "sheet", "write", "read", "export", "to_text"]),
    parameter=st.sampled_from(["first", "ax", "night", "overwrite", "fmt", "semester", "to"]),
    value=_ANY,
)
def test_methods_take_any_value(goal_plan: Plan, method: str, parameter: str, value: Any) -> None:
    # anything at all: a ucbplan error in one line naming what is wrong, or a result
    import matplotlib.pyplot as plt

    # a good value draws a figure (seconds): the tests above cover those
    assume(not (method in ("plot", "charts", "sheet") and (value is None or value is False)))
    with tempfile.TemporaryDirectory() as folder, contextlib.chdir(folder):
        # any text is a path: a relative one is written into the folder, never the checkout
        call = _call(goal_plan, method, parameter, value, Path(folder))
        try:
            result = call()
        except UcbplanError as exc:
            text = str(exc)
            assert "\n" not in text and len(text) < 400, text
            result = None
        if hasattr(result, "figure"):
            plt.close(result.figure)


def _call(plan: Plan, method: str, parameter: str, value: Any, folder: Path) -> Any:
    """``plan.method`` with ``value`` as its first argument or as keyword ``parameter``."""
    first = {"plot": None, "charts": folder / "c.png", "sheet": folder / "s.html",
             "write": folder / "p.ecsv", "read": folder / "none.ecsv", "export": "ics",
             "to_text": "csv"}[method]  # fmt: skip
    keywords = {"plot": ("ax", "night"), "charts": ("overwrite",), "sheet": ("overwrite",),
                "write": ("fmt", "overwrite"), "export": ("overwrite", "semester", "to"),
                "read": (), "to_text": ()}[method]  # fmt: skip
    target = Plan.read if method == "read" else getattr(plan, method)
    if method == "plot":  # no positional argument but ax
        return lambda: target(**{parameter if parameter in keywords else "night": value})
    if parameter == "first" or parameter not in keywords:
        return lambda: target(value)
    if parameter == "to":  # export's first argument by name
        return lambda: target(to=value)
    return lambda: target(first, **{parameter: value})


# ------------------------------------------------------------------------ offline, no global state


def test_a_read_plan_works_offline_and_leaves_astropy_as_it_was(
    goal_plan: Plan, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import socket

    from astropy.utils import data, iers
    from matplotlib.figure import Figure
    from support.state import astropy_state

    path = goal_plan.write(tmp_path / "plan.ecsv")
    table_meta = repr(goal_plan.text_table.meta)

    def no_network(*args: Any, **kwargs: Any) -> None:
        raise OSError("network disabled by tests/api/test_plan_result.py")

    monkeypatch.setattr(socket.socket, "connect", no_network)
    # step out of the session's offline scope (conftest) to astropy's defaults
    monkeypatch.setattr(iers.earth_orientation_table, "_value", None)
    with iers.conf.set_temp("auto_download", True), data.conf.set_temp("allow_internet", True):
        before = astropy_state()
        back = Plan.read(path)
        assert isinstance(back.table["t_mid_utc"], Time) and back.goals and back.strategies
        assert back.plot(ax=Figure().subplots()) is not None
        assert back.export("ics", tmp_path / "plan.ics") == tmp_path / "plan.ics"
        assert len(back.to_astroplan().scheduled_blocks) == len(back)  # one block per exposure
        assert astropy_state() == before
    assert repr(goal_plan.text_table.meta) == table_meta  # the plan's own meta untouched
