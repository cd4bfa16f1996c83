"""At the telescope (issue 24): every exposure of a plan, what is next at an instant, and
``ucbplan now``.

The plan is the issue's: two targets, two nights of 1-h visits at Paranal. The expected next
start at an instant T is computed independently from the blocks table with astropy's own time
arithmetic (every start is ``t_start_utc + k (exptime_s + readout_s)``, k < ``n_exp``; the next is
the first at or after T), for instants before, during, between exposures, between visits,
between nights and after the last one, plus seeded random instants. ``now --once`` rounds
times to the second, so it must agree within 1 s; the library to 1 ms (the table's ISO
precision). Live mode is tested with an injected clock, never by timing.
"""

from __future__ import annotations

import dataclasses
import io
import re
import sys
from datetime import UTC, datetime, timedelta
from pathlib import Path

import numpy as np
import pytest
from astropy import units as u
from astropy.table import Table
from astropy.time import Time
from hypothesis import given, settings
from hypothesis import strategies as st
from rich.cells import cell_len
from support.cli import run_cli
from support.night import INSTANT_NAMES, expected, instants, seconds_of, table_starts
from typer.testing import CliRunner

from ucbplan.cli import now as now_cli
from ucbplan.cli.app import app, main
from ucbplan.errors import InputError
from ucbplan.observing.blocks.read import read_blocks
from ucbplan.observing.night.countdown import (
    countdown_lines,
    parse_utc,
    plan_exposures,
    wait_text,
    what_next,
)

pytestmark = [
    pytest.mark.filterwarnings("ignore::erfa.ErfaWarning"),
    pytest.mark.filterwarnings("ignore::astropy.utils.exceptions.AstropyWarning"),
]


@pytest.fixture(scope="module")
def table(telescope_plan: Path) -> Table:
    return read_blocks(telescope_plan)


def _dt(t: Time) -> datetime:
    return t.to_datetime(timezone=UTC)


def test_every_exposure_once_in_time_order(table: Table) -> None:
    exposures = plan_exposures(table)
    starts = table_starts(table)
    assert len(exposures) == int(np.sum(table["n_exp"])) == len(starts) == 92
    for e, (start, end, target) in zip(exposures, starts, strict=True):
        assert abs((e.start - _dt(start)).total_seconds()) < 1e-3  # ISO ms precision
        assert abs((e.end - _dt(end)).total_seconds()) < 1e-3
        assert e.target == target
    assert [e.number for e in exposures[:3]] == [1, 2, 3] and exposures[0].label.endswith("/01")
    # the planner's visit record: acquisition 409 s (X-shooter overheads) before the first start
    first = exposures[0]
    assert first.acq_start is not None
    assert (first.start - first.acq_start).total_seconds() == pytest.approx(409.0, abs=1.0)


def test_a_block_of_several_exposures_gives_one_start_each(table: Table) -> None:
    several = table.copy()
    several["n_exp"][0] = 3
    exposures = plan_exposures(several)
    assert len(exposures) == 92 + 2
    mine = [e for e in exposures if e.block_id == several["block_id"][0]]
    assert [e.label[-2:] for e in mine] == [".1", ".2", ".3"]
    t0 = Time(str(several["t_start_utc"][0]), scale="utc")
    step = float(several["exptime_s"][0]) + float(several["readout_s"][0])
    for k, e in enumerate(mine):
        assert abs((e.start - _dt(t0 + k * step * u.s)).total_seconds()) < 1e-3


def _random_instants(table: Table, n: int) -> list[Time]:
    rng = np.random.default_rng(24)
    starts = table_starts(table)
    lo, hi = starts[0][0] - 1 * u.h, starts[-1][1] + 1 * u.h
    return [lo + x * (hi - lo) for x in rng.uniform(0.0, 1.0, n)]


def test_what_next_against_the_table(table: Table) -> None:
    exposures = plan_exposures(table)
    named = list(instants(table).values())
    for at in [*named, *_random_instants(table, 40)]:
        c = what_next(exposures, _dt(at))
        want = expected(table, at)
        if want is None:
            assert c.next is None and c.seconds_to_next is None
            continue
        assert c.next is not None and c.seconds_to_next is not None
        assert c.next.target == want[1]
        assert c.seconds_to_next == pytest.approx((want[0] - at).to_value(u.s), abs=1e-3)
        if c.previous is not None:
            assert c.previous.start < c.now <= c.next.start


def _once(plan: Path, at: Time) -> list[str]:
    result = CliRunner().invoke(app, ["now", str(plan), "--at", at.isot + "Z", "--once"])
    assert result.exit_code == 0, result.output
    return result.stdout.splitlines()


@pytest.mark.parametrize("name", INSTANT_NAMES)
def test_now_once_shows_the_next_start_and_the_wait(
    table: Table, telescope_plan: Path, name: str
) -> None:
    at = instants(table)[name]
    lines = _once(telescope_plan, at)
    assert lines[0] == f"now       {at.iso[:19]} UTC"
    assert all(cell_len(line) <= 100 for line in lines)
    want = expected(table, at)
    text = "\n".join(lines)
    if want is None:
        assert "the plan is over" in text
        return
    start, target = want
    m = re.search(
        r"start (?:(\d{4}-\d\d-\d\d) )?(\d\d:\d\d:\d\d) UTC \(±[\d.]+ s\), in ([^;]+);", text
    )
    assert m is not None, text
    rounded = (start + 0.5 * u.s).isot  # HH:MM:SS rounded to the nearest second
    assert m.group(2) == rounded[11:19]
    assert (m.group(1) or at.isot[:10]) == rounded[:10]  # the date is shown when it changes
    assert abs(seconds_of(m.group(3)) - (start - at).to_value(u.s)) <= 1.0
    assert f"next      {target}" in text
    running = "during an exposure" == name
    assert ("exposing" in text) == running
    assert ("missed?" in text) == (name in ("during an exposure", "between exposures"))


def test_missed_start_says_skip_it_and_when_the_next_one_starts(table: Table) -> None:
    exposures = plan_exposures(table)
    during = exposures[2].start + timedelta(seconds=5)
    text = " ".join(line.strip() for line in countdown_lines(what_next(exposures, during)))
    e2, e3 = exposures[2], exposures[3]
    assert f"exposing  {e2.target} {e2.label} since" in text
    assert f"missed?   {e2.label} should have started at" in text
    assert f"skip it (a late start is off its anchor) and start {e3.label} at" in text


def test_lines_fit_100_columns_with_long_names(table: Table) -> None:
    exposures = [
        dataclasses.replace(e, target="A very long target name " * 4, anchor="zero-crossing")
        for e in plan_exposures(table)
    ]
    for at in _random_instants(table, 20):
        for line in countdown_lines(what_next(exposures, _dt(at))):
            assert cell_len(line) <= 100, line


def test_wait_text() -> None:
    assert [wait_text(s) for s in (0.4, 45, 133, 3725.4, 90000)] == [
        "0 s",
        "45 s",
        "2 min 13 s",
        "1 h 02 min 05 s",
        "25 h 00 min 00 s",
    ]


@settings(max_examples=60, deadline=None)
@given(st.datetimes(min_value=datetime(1900, 1, 1), max_value=datetime(2100, 12, 31)))
def test_parse_utc_round_trip(t: datetime) -> None:
    t = t.replace(microsecond=t.microsecond - t.microsecond % 1000, tzinfo=UTC)
    text = t.isoformat(timespec="milliseconds").replace("+00:00", "")
    for form in (text, text + "Z", text.replace("T", " ") + " UTC", text + "+00:00"):
        assert parse_utc(form) == t


@settings(max_examples=80, deadline=None)
@given(st.text(max_size=40))
def test_parse_utc_takes_an_iso_time_or_says_what_it_expected(text: str) -> None:
    try:
        value = parse_utc(text, "--at")
    except InputError as exc:
        assert str(exc).startswith("--at: expected an ISO UTC time like ")
    else:
        assert value.tzinfo is UTC


@pytest.mark.parametrize("bad", ["tonight", "2040-02-30T01:00", "2040-02-16T01:00+02:00", ""])
def test_now_bad_at_is_one_line_exit_2(telescope_plan: Path, bad: str) -> None:
    code, err = run_cli(["now", str(telescope_plan), "--at", bad, "--once"])
    assert code == 2
    (line,) = err.splitlines()
    assert line.startswith("error: --at: expected an ISO UTC time like 2027-06-15T08:20:00Z")


def test_now_unreadable_plan_is_exit_2(tmp_path: Path) -> None:
    bad = tmp_path / "plan[1].ecsv"
    bad.write_text("not a table\n", encoding="utf-8")
    code, err = run_cli(["now", str(bad), "--once"])
    assert code == 2
    (line,) = err.splitlines()
    assert line.startswith(f"error: {bad}") and "ucbplan plan" in line


class _FakeClock:
    """A monotonic clock that moves only when ``sleep`` is called (no real waiting)."""

    def __init__(self, limit: int) -> None:
        self.t, self.calls, self.limit = 1000.0, 0, limit

    def monotonic(self) -> float:
        return self.t

    def sleep(self, seconds: float) -> None:
        assert 0.0 < seconds <= 1.0
        self.calls += 1
        if self.calls > self.limit:
            raise AssertionError("live mode did not stop after the plan was over")
        self.t += seconds


def test_live_prints_a_frame_per_next_exposure_and_stops_when_over(table: Table) -> None:
    exposures = plan_exposures(table)
    last = exposures[-1]
    origin = last.start - timedelta(seconds=150)  # two starts before the end
    clock, out = _FakeClock(limit=400), io.StringIO()
    now_cli.live(exposures, origin, out, monotonic=clock.monotonic, sleep=clock.sleep)
    frames = [f for f in out.getvalue().split("\n\n") if f.strip()]
    assert 2 <= len(frames) <= 4  # a new frame when the next start changes, none in between
    assert "the plan is over" in frames[-1] or "the plan is over" in out.getvalue()
    assert clock.calls >= 150 + last.exptime_s - 2  # it ran on until the last exposure ended


def test_ctrl_c_in_live_mode_exits_130_without_a_traceback(
    telescope_plan: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    def interrupt(seconds: float) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr("time.sleep", interrupt)
    monkeypatch.setattr(sys, "argv", ["ucbplan", "now", str(telescope_plan), "--at", "2040-02-16"])
    with pytest.raises(SystemExit) as exit_info:
        main()
    assert exit_info.value.code == 130
    out, err = capsys.readouterr()
    assert out.startswith("now       2040-02-16 00:00:00 UTC")  # one frame, then Ctrl-C
    assert "Traceback" not in err and "KeyboardInterrupt" not in err
