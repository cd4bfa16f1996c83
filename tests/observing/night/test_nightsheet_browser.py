"""The HTML night sheet's live clock, in a real browser (issue 24).

Debian's ``chromium`` renders the sheet headless from ``file://`` with ``?now=T`` and a virtual
time budget of :data:`BUDGET_MS` (the page's clock runs on from T by at most that much), then
dumps its DOM; html.parser reads it back. The expected next start is computed from the blocks
table with astropy (tests/support/night.py: ``expected``, ``instants``), independently of
the page's JavaScript and of ``ucbplan.observing.night.countdown``. The countdown must agree to the
rounding (0.5 s) with the page's own clock, which ran on < 1 s from T. The tests skip, saying
why, where chromium is not installed (``.ci/run`` installs it).
"""

from __future__ import annotations

import subprocess
from pathlib import Path
from urllib.parse import quote

import pytest
from astropy import units as u
from astropy.table import Table
from astropy.time import Time
from support.browser import BROWSER_MARKS, CHROMIUM
from support.night import INSTANT_NAMES, SheetReader, expected, instants, seconds_of, table_starts

from ucbplan.observing.blocks.read import read_blocks
from ucbplan.observing.night.sheet import write_night_sheet
from ucbplan.observing.night.sheet_html import EXPOSURE_COLUMNS
from ucbplan.observing.observatory.sites import get_site

pytestmark = BROWSER_MARKS


#: Virtual time the browser runs the page for before dumping it [ms] (the clock ticks 4×/s),
#: and the most its clock may have run on from ?now= by then (the budget is not exact: a tick
#: or two more) [ms].
BUDGET_MS, RAN_ON_MS = 300, 1000


@pytest.fixture(scope="module")
def table(telescope_plan: Path) -> Table:
    return read_blocks(telescope_plan)


@pytest.fixture(scope="module")
def sheet(table: Table, tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("sheet") / "night [draft].html"  # a name to escape in a URL
    write_night_sheet(table, get_site("paranal"), path)
    return path


def render(sheet: Path, now: str, profile: Path) -> SheetReader:
    """The sheet's DOM after the browser ran it for ``BUDGET_MS`` with ``?now=``."""
    assert CHROMIUM is not None
    url = f"{sheet.as_uri()}?now={quote(now)}"
    cmd = [
        CHROMIUM,
        "--headless",
        "--no-sandbox",  # root in CI containers
        "--disable-gpu",
        f"--user-data-dir={profile}",
        f"--virtual-time-budget={BUDGET_MS}",
        "--dump-dom",
        url,
    ]
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert out.returncode == 0 and "<html" in out.stdout, out.stderr[-600:]
    reader = SheetReader()
    reader.feed(out.stdout)
    return reader


def _rows(reader: SheetReader) -> list[dict[str, str]]:
    return [
        {**r["attrs"], "status": r["cells"][len(EXPOSURE_COLUMNS)]}  # then the log buttons
        for s in reader.sections
        for v in s["visits"]
        for r in v["rows"]
    ]


@pytest.mark.parametrize("name", INSTANT_NAMES)
def test_clock_countdown_and_highlighted_row(
    table: Table, sheet: Path, tmp_path: Path, name: str
) -> None:
    at = instants(table)[name]
    reader = render(sheet, at.isot + "Z", tmp_path)
    clock = reader.ids["clock"]["attrs"]
    at_ms = at.unix * 1000
    now_ms = float(clock["data-now"])
    assert at_ms - 1 <= now_ms <= at_ms + RAN_ON_MS  # started at ?now=, then ran on
    shown = Time(reader.ids["utc"]["text"], scale="utc")  # "YYYY-MM-DD HH:MM:SS", rounded
    assert abs(shown.unix * 1000 - now_ms) <= 500
    assert reader.ids["rehearsal"]["text"].startswith("REHEARSAL clock")
    rows = _rows(reader)
    want = expected(table, at)
    marked = [r for r in rows if r["class"] == "next"]
    if want is None:
        assert marked == [] and clock["data-next"] == ""
        assert reader.ids["advice"]["text"].startswith("The plan is over")
        return
    start, target = want
    (nxt,) = marked
    assert abs(int(nxt["data-start"]) - start.unix * 1000) <= 1  # the table's ms
    assert nxt["data-target"] == target and nxt["status"] == "NEXT"
    assert clock["data-next"] == nxt["data-label"]
    # the wait from the page's own clock, rounded to the second (±0.5 s); from T, ±1 s more
    # for the virtual time the page ran
    wait_s = (start.unix * 1000 - now_ms) / 1000
    assert abs(int(clock["data-seconds"]) - wait_s) <= 0.501
    assert abs(seconds_of(reader.ids["countdown"]["text"].strip()) - wait_s) <= 0.501
    assert abs(int(clock["data-seconds"]) - (start - at).to_value(u.s)) <= 0.5 + RAN_ON_MS / 1000
    for r in rows:  # ended rows are marked, the running one says so
        if float(r["data-end"]) <= now_ms:
            assert r["class"] == "done" and r["status"] == "ended"
        elif float(r["data-start"]) < now_ms:
            assert r["class"] == "running" and r["status"] == "exposing?"
    advice = reader.ids["advice"]["text"]
    if name == "during an exposure":
        assert "Start missed? Do not start it late: start " + nxt["data-label"] in advice
    else:
        assert "missed" not in advice


def test_every_exposure_start_is_its_own_row(table: Table, sheet: Path, tmp_path: Path) -> None:
    reader = render(sheet, "2040-02-16T00:00:00Z", tmp_path)
    starts = sorted(int(r["data-start"]) for r in _rows(reader))
    want = [round(s.unix * 1000) for s, _, _ in table_starts(table)]
    assert len(starts) == len(want) == 92
    assert all(abs(a - b) <= 1 for a, b in zip(starts, want, strict=True))


def test_a_now_it_cannot_read_falls_back_to_the_computer_clock(sheet: Path, tmp_path: Path) -> None:
    reader = render(sheet, "tonight", tmp_path)
    assert reader.ids["rehearsal"]["text"].startswith("?now= not understood")
    now_ms = float(reader.ids["clock"]["attrs"]["data-now"])
    assert abs(now_ms / 1000 - Time.now().unix) < 600  # the computer's clock (generous: CI)


def test_a_now_without_a_zone_is_utc(table: Table, sheet: Path, tmp_path: Path) -> None:
    at = instants(table)["between exposures"]
    reader = render(sheet, at.isot.replace("T", " "), tmp_path)  # no Z: still UTC
    now_ms = float(reader.ids["clock"]["attrs"]["data-now"])
    assert at.unix * 1000 - 1 <= now_ms <= at.unix * 1000 + RAN_ON_MS
