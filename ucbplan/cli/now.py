"""``ucbplan now``: at the telescope, the next exposure start and the wait, refreshed live.

A thin shell over the countdown of :mod:`ucbplan.api.terminal`: read the blocks table
(:func:`ucbplan.api.exporting.read_blocks`), list its exposures, and print the countdown for
the current UTC
(or ``--at``, a rehearsal clock that runs on from that instant). The frame goes to stdout: on a
terminal it is redrawn every second; in a pipe a new frame is printed only when the next
exposure changes. ``--once`` prints one frame and exits. Ctrl-C exits with code 130.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable, Sequence
from datetime import UTC, datetime, timedelta
from pathlib import Path
from typing import Any, TextIO

import typer

from ucbplan.api import terminal
from ucbplan.api.exporting import NOW_FLAGS, countdown, read_blocks
from ucbplan.cli._derive import argument, flag

__all__ = ["live", "register"]

#: Clears a terminal and puts the cursor top left (ANSI).
_CLEAR = "\x1b[H\x1b[2J"
#: Exit code of Ctrl-C (as :data:`ucbplan.cli.app.EXIT_INTERRUPTED`).
_INTERRUPTED = 130


def live(
    exposures: Sequence[Any],  # ucbplan.api.terminal.plan_exposures(table)
    origin: datetime | None,
    out: TextIO,
    *,
    monotonic: Callable[[], float] | None = None,
    sleep: Callable[[float], None] | None = None,
    wall: Callable[[], datetime] | None = None,
) -> None:
    """Print countdown frames until the plan is over (the clock and sleep are injectable).

    ``origin`` starts a rehearsal clock at that UTC instant, running on by ``monotonic``; None
    uses ``wall`` (default: the computer's UTC). A terminal ``out`` is redrawn every second;
    another stream gets a frame when the next exposure changes. ``monotonic`` and ``sleep``
    default to :mod:`time`'s, looked up at call time (tests replace them).
    """
    what_next, countdown_lines = terminal.what_next, terminal.countdown_lines
    monotonic = monotonic or time.monotonic
    sleep = sleep or time.sleep
    wall = wall or (lambda: datetime.now(UTC))
    tty = out.isatty()
    t0, shown = monotonic(), object()
    while True:
        now = origin + timedelta(seconds=monotonic() - t0) if origin is not None else wall()
        c = what_next(exposures, now)
        key = None if c.next is None else (c.next.target, c.next.label, c.next.start)
        if tty or key != shown:
            out.write((_CLEAR if tty else "") + "\n".join(countdown_lines(c)) + "\n")
            out.write("" if tty else "\n")
            out.flush()
            shown = key
        if c.next is None and c.running is None:
            return
        sleep(1.0 - (now.timestamp() % 1.0))  # redraw on the next whole second


def now(
    plan: Path = argument(NOW_FLAGS, "plan"),
    at: str | None = flag(NOW_FLAGS, "at"),
    once: bool = typer.Option(False, "--once", help="Print one frame and exit (for scripts)."),
) -> None:
    """At the telescope: the next exposure start (UTC) and the wait, refreshed every second.

    Shows the current UTC, the exposure that should be running, the next one (target,
    visit/exposure, anchor, start HH:MM:SS UTC and "in 2 min 13 s"), the one after, and what
    to do if the previous start was missed. After the last exposure it says the plan is over.
    """
    # loaded here: `ucbplan --help` must not load astropy (tests/test_cli_help_units.py)
    origin = terminal.parse_utc(at, "--at") if at is not None else None
    if once:
        typer.echo("\n".join(countdown(plan, origin)))
        return
    exposures = terminal.plan_exposures(read_blocks(plan))
    try:
        live(exposures, origin, sys.stdout)
    except KeyboardInterrupt:
        sys.stdout.write("\n")
        raise typer.Exit(_INTERRUPTED) from None


def register(app: typer.Typer) -> None:
    """Add ``now`` to the ucbplan app."""
    app.command("now")(now)
