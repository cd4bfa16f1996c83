"""``ucbplan now``: at the telescope, the next exposure start and the wait, refreshed live.

A thin shell over the countdown of :mod:`ucbplan.api.terminal`: read the blocks table
(:func:`ucbplan.api.exporting.read_blocks`), list its exposures, and print the countdown for
the current UTC
(or ``--at``, a rehearsal clock that runs on from that instant). The frame goes to stdout: on a
terminal it is redrawn every second; in a pipe a new frame is printed only when the next
exposure changes. ``--once`` prints one frame and exits. Ctrl-C exits with code 130.

``--log FILE`` writes the observing log (:mod:`ucbplan.observing.night.observing_log`): a key marks
the exposure just started (t taken, m missed, s skipped; again: a new mark replaces it), read from
stdin without Enter on a terminal, and the whole file is rewritten atomically at each key; q quits.
After the plan is over the countdown waits for the last exposure's mark (or q).
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from datetime import UTC, datetime, timedelta
from pathlib import Path
from typing import Any, TextIO

import typer

from ucbplan.api import terminal
from ucbplan.api.exporting import NOW_FLAGS, countdown, read_blocks
from ucbplan.cli._derive import argument, flag
from ucbplan.errors import InputError

#: Clears a terminal and puts the cursor top left (ANSI).
_CLEAR = "\x1b[H\x1b[2J"
#: What the key source returns when no key will come (the end of a piped stdin).
_END = "\x04"
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
    log: Any = None,  # ucbplan.api.terminal.ObservingLog
    keys: Callable[[float], str | None] | None = None,
) -> None:
    """Print countdown frames until the plan is over (the clock, sleep and keys injectable).

    ``origin`` starts a rehearsal clock at that UTC instant, running on by ``monotonic``; None
    uses ``wall`` (default: the computer's UTC). A terminal ``out`` is redrawn every second;
    another stream gets a frame when the next exposure (or a mark) changes. ``monotonic`` and
    ``sleep`` default to :mod:`time`'s, looked up at call time (tests replace them). With a
    ``log``, ``keys(timeout)`` waits up to ``timeout`` seconds for a key (None: none came) in
    place of ``sleep``: ``t``/``m``/``s`` mark the exposure just started, ``q`` quits, :data:`_END`
    says no key will come; the countdown ends when the plan is over and its last exposure is
    marked (or no key will come).
    """
    what_next = terminal.what_next
    monotonic = monotonic or time.monotonic
    sleep = sleep or time.sleep
    wall = wall or (lambda: datetime.now(UTC))
    tty = out.isatty()
    t0, shown = monotonic(), object()
    keys = keys if log is not None else None

    def clock() -> datetime:
        return origin + timedelta(seconds=monotonic() - t0) if origin is not None else wall()

    while True:
        now = clock()
        c = what_next(exposures, now)
        nxt = None if c.next is None else (c.next.target, c.next.label, c.next.start)
        key: Any = nxt if log is None else (nxt, tuple(log.statuses), c.previous)
        if tty or key != shown:
            _draw(out, c, log, tty)
            shown = key
        if c.next is None and c.running is None and (keys is None or _all_passed(log)):
            return
        wait = 1.0 - (now.timestamp() % 1.0)  # redraw on the next whole second
        if keys is None:
            sleep(wait)
            continue
        pressed = keys(wait)
        if pressed == "q":
            return
        if pressed == _END:  # no more keys: count down to the end of the plan
            keys = None
        status = terminal.LOG_KEYS.get(pressed or "")
        previous = what_next(exposures, clock()).previous
        if status is not None and previous is not None:
            log.mark(previous, status)


def _draw(out: TextIO, c: Any, log: Any, tty: bool) -> None:
    """One frame: the countdown, and with a log its line."""
    lines = terminal.countdown_lines(c)
    if log is not None:
        lines += terminal.log_lines(log, c.previous)
    out.write((_CLEAR if tty else "") + "\n".join(lines) + "\n")
    out.write("" if tty else "\n")
    out.flush()


def _all_passed(log: Any) -> bool:
    """The log's last exposure is marked (or the plan has none)."""
    return not log.statuses or bool(log.statuses[-1])


@contextmanager
def _keyboard(stream: TextIO) -> Iterator[Callable[[float], str | None]]:
    """``keys(timeout)`` reading single keys from ``stream`` (a terminal: without Enter, its
    mode restored after); at the end of the stream, :data:`_END`."""
    import select

    fd = stream.fileno()
    saved = None
    if stream.isatty():
        import termios
        import tty

        saved = termios.tcgetattr(fd)
        tty.setcbreak(fd)

    def keys(timeout: float) -> str | None:
        if not select.select([fd], [], [], timeout)[0]:
            return None
        return os.read(fd, 1).decode("utf-8", "replace").lower() or _END

    try:
        yield keys
    finally:
        if saved is not None:
            import termios

            termios.tcsetattr(fd, termios.TCSADRAIN, saved)


def now(
    plan: Path = argument(NOW_FLAGS, "plan"),
    at: str | None = flag(NOW_FLAGS, "at"),
    once: bool = typer.Option(False, "--once", help="Print one frame and exit (for scripts)."),
    log: Path | None = flag(NOW_FLAGS, "log"),
    overwrite: bool = flag(NOW_FLAGS, "overwrite", False),
) -> None:
    """At the telescope: the next exposure start (UTC) and the wait, refreshed every second.

    Shows the current UTC, the exposure that should be running, the next one (target,
    visit/exposure, anchor, start HH:MM:SS UTC and "in 2 min 13 s"), the one after, and what
    to do if the previous start was missed. After the last exposure it says the plan is over.
    """
    # loaded here: `ucbplan --help` must not load astropy (tests/cli/test_cli_help_units.py)
    origin = terminal.parse_utc(at, "--at") if at is not None else None
    if once and log is not None:
        raise InputError(
            "--log: the log is written by the live countdown, --once has none; drop --once"
        )
    if once:
        typer.echo("\n".join(countdown(plan, origin)))
        return
    table = read_blocks(plan)
    exposures = terminal.plan_exposures(table)
    try:
        if log is None:
            live(exposures, origin, sys.stdout)
            return
        book = terminal.ObservingLog.open(table, log, overwrite=overwrite)
        with _keyboard(sys.stdin) as keys:
            live(book.exposures, origin, sys.stdout, log=book, keys=keys)
    except KeyboardInterrupt:
        sys.stdout.write("\n")
        raise typer.Exit(_INTERRUPTED) from None


def register(app: typer.Typer) -> None:
    """Add ``now`` to the ucbplan app."""
    app.command("now")(now)
