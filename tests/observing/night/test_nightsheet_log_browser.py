"""The night sheet's observing log, as a person uses it, in a real browser (issue 32 item 4).

Debian's ``chromium`` runs headless and is driven over the DevTools protocol through a pipe
(``--remote-debugging-pipe``: JSON messages, NUL-terminated, on file descriptors 3 and 4; no
network, no extra package). The test opens the sheet from ``file://``, clicks status buttons
with real mouse events at their place on the page (one row clicked twice: unmarked again),
clicks "save log", and reads the downloaded file with Python's csv module: its rows are the
marked exposures in time order with their statuses, byte for byte what ``now --log`` writes for
the same marks (:func:`ucbplan.observing.night.observing_log.log_text`); fed to ``plan --observed``
it counts the independent Fisher sum of its taken rows (tests/observing/night/test_obslog.py).
Skips, saying why, where chromium is not installed (``.ci/run`` installs it).
"""

from __future__ import annotations

import csv
import fcntl
import json
import os
import subprocess
import time
import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from support.browser import BROWSER_MARKS, CHROMIUM
from support.observed import BASE, NAME, TARGET, fisher_of_taken

import ucbplan
from ucbplan.observing.blocks.read import read_blocks
from ucbplan.observing.night.observing_log import log_cells, log_text
from ucbplan.observing.night.sheet import write_night_sheet
from ucbplan.observing.observatory.sites import get_site

#: As the night sheet's other browser tests: skipped, saying why, without chromium.
pytestmark = [pytest.mark.slow, *BROWSER_MARKS]

#: Longest wait for the browser to answer or to finish the download [s].
TIMEOUT_S = 60.0


class Browser:
    """Headless chromium over the DevTools pipe: commands and their replies, events kept."""

    def __init__(self, profile: Path) -> None:
        assert CHROMIUM is not None
        to_child, self._out = os.pipe()
        self._in, from_child = os.pipe()
        # above 4, so that placing them at 3 and 4 in the child cannot overwrite one another
        high = [fcntl.fcntl(fd, fcntl.F_DUPFD_CLOEXEC, 10) for fd in (to_child, from_child)]
        for fd in (to_child, from_child):
            os.close(fd)

        def plumb() -> None:  # in the child: its fd 3 reads our commands, fd 4 answers
            os.dup2(high[0], 3)  # inheritable, unlike every other descriptor of ours
            os.dup2(high[1], 4)

        args = ["--headless", "--no-sandbox", "--disable-gpu", "--remote-debugging-pipe"]
        self.proc = subprocess.Popen(
            [CHROMIUM, *args, f"--user-data-dir={profile}", "about:blank"],
            preexec_fn=plumb,
            close_fds=False,  # 3 and 4 stay; the others close on exec (O_CLOEXEC)
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        for fd in high:
            os.close(fd)
        self._buf, self._next = b"", 0
        self.events: list[dict[str, Any]] = []

    def _message(self) -> dict[str, Any]:
        while b"\0" not in self._buf:
            chunk = os.read(self._in, 1 << 16)
            assert chunk, "chromium closed the DevTools pipe"
            self._buf += chunk
        text, self._buf = self._buf.split(b"\0", 1)
        return dict(json.loads(text))

    def send(self, method: str, session: str | None = None, **params: Any) -> dict[str, Any]:
        self._next += 1
        msg: dict[str, Any] = {"id": self._next, "method": method, "params": params}
        if session:
            msg["sessionId"] = session
        os.write(self._out, json.dumps(msg).encode() + b"\0")
        while True:
            reply = self._message()
            if reply.get("id") == self._next:
                assert "error" not in reply, reply
                return dict(reply.get("result", {}))
            self.events.append(reply)

    def wait_event(self, method: str, **match: Any) -> dict[str, Any]:
        """The first event ``method`` whose params include ``match`` (kept or to come)."""
        deadline = time.monotonic() + TIMEOUT_S
        while time.monotonic() < deadline:
            for e in self.events:
                params = e.get("params", {})
                if e.get("method") == method and all(params.get(k) == v for k, v in match.items()):
                    return dict(params)
            self.events.append(self._message())
        raise AssertionError(f"no {method} {match} within {TIMEOUT_S} s")

    def close(self) -> None:
        try:
            self.send("Browser.close")
        finally:
            self.proc.wait(timeout=TIMEOUT_S)
            os.close(self._in)
            os.close(self._out)


@pytest.fixture
def browser(tmp_path: Path) -> Iterator[Browser]:
    b = Browser(tmp_path / "profile")
    try:
        yield b
    finally:
        b.close()


def _page(b: Browser, url: str, downloads: Path) -> str:
    """A new tab at ``url``, loaded, downloads going to ``downloads``: its session id."""
    b.send("Browser.setDownloadBehavior", behavior="allow", downloadPath=str(downloads),
           eventsEnabled=True)  # fmt: skip
    target = b.send("Target.createTarget", url="about:blank")["targetId"]
    session = b.send("Target.attachToTarget", targetId=target, flatten=True)["sessionId"]
    b.send("Page.enable", session)
    b.send("Page.navigate", session, url=url)
    b.wait_event("Page.loadEventFired")
    return str(session)


def _click(b: Browser, session: str, element: str) -> None:
    """A left click, as a mouse makes it, at the middle of ``element`` (JavaScript)."""
    js = (
        f"(function(){{var e={element};"
        "e.scrollIntoView({block:'center'});var r=e.getBoundingClientRect();"
        "return JSON.stringify([r.left+r.width/2,r.top+r.height/2]);})()"
    )
    value = b.send("Runtime.evaluate", session, expression=js, returnByValue=True)
    x, y = json.loads(value["result"]["value"])
    for kind in ("mousePressed", "mouseReleased"):
        b.send("Input.dispatchMouseEvent", session, type=kind, x=x, y=y, button="left",
               clickCount=1)  # fmt: skip


def _button(row: int, status: str) -> str:
    """The ``status`` button of the exposure row ``row`` (0, 1, … down the page)."""
    rows = "document.querySelectorAll('tr[data-log]')"
    return f"{rows}[{row}].querySelector('button[data-status={status}]')"


def test_click_statuses_save_the_log_and_plan_with_it(browser: Browser, tmp_path: Path) -> None:
    plan_file = tmp_path / "goal.ecsv"
    with warnings.catch_warnings():  # the plan's IERS and smearing warnings
        warnings.simplefilter("ignore")
        plan = ucbplan.plan(str(TARGET), night="2040-02-15", nights=3, **BASE,
                            goal="sigma_K=13km/s")  # fmt: skip
    plan.write(plan_file)
    table = read_blocks(plan_file)
    sheet = tmp_path / "night [1].html"
    write_night_sheet(table, get_site("paranal"), sheet)
    downloads = tmp_path / "downloads"
    downloads.mkdir()
    session = _page(browser, f"{sheet.as_uri()}?now=2040-02-16T02:00:00Z", downloads)
    cells = [c for _, c in log_cells(table)]
    clicks = {0: "taken", 1: "missed", 2: "taken", 3: "skipped", 5: "taken", 16: "taken"}
    for k, status in clicks.items():
        _click(browser, session, _button(k, status))
    row4 = _button(4, "taken")
    _click(browser, session, row4)
    _click(browser, session, row4)  # clicked again: unmarked
    _click(browser, session, "document.getElementById('save-log')")
    done = browser.wait_event("Browser.downloadProgress", state="completed")
    (saved,) = downloads.iterdir()
    assert saved.name.startswith("observing-log-") and saved.suffix == ".csv", done
    with saved.open(newline="", encoding="utf-8") as handle:
        rows = list(csv.DictReader(handle))
    assert [(r["exposure"], r["status"]) for r in rows] == [
        (cells[k][3], s) for k, s in sorted(clicks.items())
    ]
    statuses = [clicks.get(k, "") for k in range(len(cells))]
    assert saved.read_text(encoding="utf-8") == log_text(cells, statuses)  # as `now --log`
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        p = ucbplan.plan(str(TARGET), night="2040-02-16", nights=2, **BASE,
                         goal="sigma_K=13km/s", observed=str(saved))  # fmt: skip
    goal = p.run.result.goals[NAME]
    assert goal.collected_spectra == 4
    assert goal.collected_info == pytest.approx(fisher_of_taken(plan_file, saved), rel=1e-9)
