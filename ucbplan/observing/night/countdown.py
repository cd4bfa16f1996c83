"""At the telescope: every exposure of a plan in time order, and what is next at an instant.

:func:`plan_exposures` turns a blocks table into its exposures — one per exposure, not per
block: a block of ``n_exp`` exposures gives ``n_exp`` starts, ``exptime_s + readout_s`` apart
(the block layout of :class:`ucbplan.observing.blocks.block.ExposurePlan`) — with the visit each
belongs to and the visit's acquisition start. :func:`what_next` says, at an instant, which
exposure should be running, which starts next and in how many seconds, and which one after;
:func:`countdown_lines` writes that as the lines ``ucbplan now`` prints, and the night sheet's
clock does the same in the browser (:mod:`ucbplan.observing.night.sheet_html`).

All instants are UTC as a wall clock counts them (:class:`datetime.datetime`, POSIX seconds, no
leap second), as the telescope's clock and the browser's ``Date`` do; a leap second inside a
countdown makes it 1 s long.
"""

from __future__ import annotations

import math
import re
import textwrap
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from datetime import UTC, datetime, timedelta
from typing import Any

import numpy as np
from astropy.table import Table

from ucbplan.core.constants import HOUR_S_INT
from ucbplan.errors import InputError, shorten
from ucbplan.observing.night.chart import VisitRows, group_visits
from ucbplan.observing.observatory.sites import Site

#: Longest target name in a countdown line [characters] (longer names are cut with "…").
_NAME_CHARS = 40
#: Longest visit name in an exposure label [characters] (``V01`` from ``…-20400215-V01``).
_LABEL_CHARS = 12
#: An ISO UTC instant: date, ``T`` or a space, time; optional fraction, ``Z``/``+00:00``/``UTC``.
_ISO = re.compile(
    r"^\s*(\d{4}-\d{2}-\d{2})(?:[T ](\d{2}:\d{2}(?::\d{2}(?:\.\d+)?)?))?"
    r"\s*(Z|[+-]00:?00|UTC)?\s*$",
    re.IGNORECASE,
)


@dataclass(frozen=True, slots=True)
class TimedExposure:
    """One exposure of a plan: when it starts and ends (UTC), its visit and its anchor.

    Attributes
    ----------
    target : str
        Target name.
    visit_id : str
        The visit's identifier in the blocks table (``visit_id``, else ``session_id``, else
        ``block_id``).
    label : str
        ``V01/03``: the visit's short name and the block's number in it; ``V01/03.2`` for the
        second exposure of a block of several.
    number : int
        1, 2, … in the visit (one per exposure).
    block_id : str
        The block it belongs to.
    start, end : datetime
        Shutter opens and closes, UTC (timezone-aware).
    anchor : str
        The block's anchor name.
    u_star_rad : float
        The anchor's argument of latitude [rad].
    anchor_utc : datetime
        The anchor epoch (block centre), UTC.
    sigma_t_s : float
        1σ uncertainty of the anchor epoch [s].
    airmass, lambda_k : float
        Airmass and smearing attenuation Λ_K of the block (at its centre).
    exptime_s, readout_s : float
        Exposure time and dead time after it [s].
    acq_start : datetime or None
        The visit's acquisition start, UTC (None when the table does not say).
    """

    target: str
    visit_id: str
    label: str
    number: int
    block_id: str
    start: datetime
    end: datetime
    anchor: str
    u_star_rad: float
    anchor_utc: datetime
    sigma_t_s: float
    airmass: float
    lambda_k: float
    exptime_s: float
    readout_s: float
    acq_start: datetime | None

    @property
    def first_of_visit(self) -> bool:
        """The visit's first exposure (the acquisition comes before it)."""
        return self.number == 1


@dataclass(frozen=True, slots=True)
class Countdown:
    """What the plan asks for at ``now`` (:func:`what_next`).

    Attributes
    ----------
    now : datetime
        The instant, UTC.
    previous : Exposure or None
        The latest exposure that started before ``now`` (running if ``now`` < its end).
    next : Exposure or None
        The first exposure starting at or after ``now``; None when the plan is over.
    after : Exposure or None
        The exposure after ``next``.
    """

    now: datetime
    previous: TimedExposure | None
    next: TimedExposure | None
    after: TimedExposure | None

    @property
    def running(self) -> TimedExposure | None:
        """The exposure that should be running at ``now`` (None between exposures)."""
        p = self.previous
        return p if p is not None and p.end > self.now else None

    @property
    def seconds_to_next(self) -> float | None:
        """Seconds from ``now`` to the next start [s]; None when the plan is over."""
        return None if self.next is None else (self.next.start - self.now).total_seconds()


def parse_utc(text: str, name: str = "at") -> datetime:
    """An ISO UTC instant (``2027-06-15T08:20:00``, ``…Z``, ``… UTC``, a space for ``T``).

    Raises
    ------
    InputError
        Not an ISO date and time, or a time zone other than UTC.
    """
    match = _ISO.match(text)
    hint = f"{name}: expected an ISO UTC time like 2027-06-15T08:20:00Z, got {shorten(text, 60)}"
    if match is None:
        raise InputError(f"{hint}; give the date, T and the time (UTC)")
    day, clock = match.group(1), match.group(2) or "00:00"
    try:
        value = datetime.fromisoformat(f"{day}T{clock}")
    except ValueError as exc:
        raise InputError(f"{hint} ({exc}); check the date and the time") from None
    return value.replace(tzinfo=UTC)


def _utc(text: Any) -> datetime:
    """A blocks-table ISO UTC cell (already checked by the reader) as an aware datetime."""
    iso = str(text).strip().replace(" ", "T")[:26]
    if iso[17:19] == "60":  # inside a leap second: the wall clock shows 59.999
        iso = f"{iso[:17]}59.999"
    return datetime.fromisoformat(iso).replace(tzinfo=UTC)


def _float(row: Any, name: str, default: float = math.nan) -> float:
    if name not in row.colnames or np.ma.is_masked(row[name]):
        return default
    value = float(row[name])
    return value if math.isfinite(value) else default


def _acquisition(visit: VisitRows, meta: Mapping[str, Any]) -> datetime | None:
    """The visit's acquisition start: the ``acq_s`` column, the plan's visit record, or the
    plan's ``overhead_s`` before the first exposure; None when the table says none of these."""
    start = _utc(visit.start_utc)
    acq = _float(visit.rows[0], "acq_s")
    if math.isfinite(acq):
        return start - timedelta(seconds=acq)
    for entry in meta.get("visits") or ():
        if isinstance(entry, Mapping) and entry.get("visit_id") == visit.visit_id:
            if entry.get("target", visit.target) == visit.target and entry.get("acq_start_utc"):
                return _utc(entry["acq_start_utc"])
    overhead = meta.get("overhead_s")
    try:
        seconds = float(overhead) if overhead is not None else math.nan
    except (TypeError, ValueError):
        seconds = math.nan
    return start - timedelta(seconds=seconds) if math.isfinite(seconds) else None


def visit_exposures(visit: VisitRows, meta: Mapping[str, Any] | None = None) -> list[TimedExposure]:
    """The exposures of a visit in time order (``meta``: the table's, for the acquisition)."""
    acq = _acquisition(visit, meta or {})
    short = visit.visit_id.rsplit("-", 1)[-1][:_LABEL_CHARS]
    out: list[TimedExposure] = []
    for k, row in enumerate(visit.rows, start=1):
        start, n_exp = _utc(row["t_start_utc"]), int(row["n_exp"])
        exptime, readout = float(row["exptime_s"]), max(_float(row, "readout_s", 0.0), 0.0)
        for j in range(n_exp):
            t0 = start + timedelta(seconds=j * (exptime + readout))
            out.append(
                TimedExposure(
                    target=str(row["target"]),
                    visit_id=visit.visit_id,
                    label=f"{short}/{k:02d}" + (f".{j + 1}" if n_exp > 1 else ""),
                    number=len(out) + 1,
                    block_id=str(row["block_id"]),
                    start=t0,
                    end=t0 + timedelta(seconds=exptime),
                    anchor=str(row["anchor"]),
                    u_star_rad=float(row["u_star_rad"]),
                    anchor_utc=_utc(row["t_mid_utc"]),
                    sigma_t_s=float(row["sigma_t_s"]),
                    airmass=float(row["airmass"]),
                    lambda_k=float(row["lambda_k"]),
                    exptime_s=exptime,
                    readout_s=readout,
                    acq_start=acq,
                )
            )
    return out


def _site_of(table: Table) -> Site:
    """The plan's site from the table's ``meta['site']``; UTC when it has none (the nights then
    come from the ``night`` column, which the planner always writes)."""
    entry = table.meta.get("site")
    if isinstance(entry, Mapping):
        try:
            return Site(
                str(entry["name"]),
                float(entry["lon_deg"]),
                float(entry["lat_deg"]),
                float(entry["height_m"]),
                str(entry["timezone"]),
            )
        except (KeyError, TypeError, ValueError):
            pass
    return Site("UTC", 0.0, 0.0, 0.0, "UTC")


def plan_exposures(table: Table, site: Site | None = None) -> list[TimedExposure]:
    """Every exposure of a blocks table in time order (visits as the night sheet groups them).

    Parameters
    ----------
    table : astropy.table.Table
        A blocks table (:func:`ucbplan.observing.blocks.read.read_blocks`).
    site : Site, optional
        The plan's site (default: the table's ``meta['site']``).
    """
    site = site if site is not None else _site_of(table)
    out = [
        e
        for visits in group_visits(table, site).values()
        for v in visits
        for e in visit_exposures(v, table.meta)
    ]
    out.sort(key=lambda e: e.start)
    return out


def what_next(exposures: Sequence[TimedExposure], now: datetime) -> Countdown:
    """The exposure before ``now``, the next one at or after it and the one after that.

    Parameters
    ----------
    exposures : sequence of Exposure
        In time order (:func:`plan_exposures`).
    now : datetime
        The instant, UTC (a naive datetime is taken as UTC).
    """
    now = now if now.tzinfo is not None else now.replace(tzinfo=UTC)
    k = next((i for i, e in enumerate(exposures) if e.start >= now), len(exposures))
    return Countdown(
        now=now,
        previous=exposures[k - 1] if k > 0 else None,
        next=exposures[k] if k < len(exposures) else None,
        after=exposures[k + 1] if k + 1 < len(exposures) else None,
    )


def hms(t: datetime) -> str:
    """``HH:MM:SS`` of a UTC instant, rounded to the nearest second."""
    return (t + timedelta(microseconds=500_000)).strftime("%H:%M:%S")


def _when(t: datetime, now: datetime) -> str:
    """``HH:MM:SS UTC``, with the date when it is not ``now``'s UTC date."""
    day = (t + timedelta(microseconds=500_000)).date()
    return f"{'' if day == now.date() else f'{day.isoformat()} '}{hms(t)} UTC"


def wait_text(seconds: float) -> str:
    """A wait in words, rounded to the second: ``45 s``, ``2 min 13 s``, ``3 h 02 min 05 s``."""
    s = max(round(seconds), 0)
    h, m, x = s // HOUR_S_INT, s % HOUR_S_INT // 60, s % 60
    if h:
        return f"{h} h {m:02d} min {x:02d} s"
    return f"{m} min {x} s" if m else f"{x} s"


def seconds_text(seconds: float) -> str:
    """An exposure or readout time for people [s]: whole seconds when it is one (within 1 ms),
    else one decimal (``60``, ``45``, ``59.6``)."""
    whole = round(seconds)
    return f"{whole:d}" if abs(seconds - whole) < 1e-3 else f"{seconds:.1f}"


def _name(e: TimedExposure) -> str:
    name = e.target if len(e.target) <= _NAME_CHARS else f"{e.target[: _NAME_CHARS - 1]}…"
    return f"{name} {e.label}"


def _anchor(e: TimedExposure) -> str:
    return f"{e.anchor} (u★ = {e.u_star_rad:.3f} rad)"


def _entries(c: Countdown) -> list[tuple[str, str]]:
    """(tag, text) of each entry of a countdown frame (see :func:`countdown_lines`)."""
    now, run, nxt, prev = c.now, c.running, c.next, c.previous
    out = [("now", f"{now.strftime('%Y-%m-%d %H:%M:%S')} UTC")]
    if run is not None:
        out.append(
            ("exposing", f"{_name(run)} since {hms(run.start)} UTC, ends {hms(run.end)} UTC")
        )
    if nxt is None:
        if run is not None:
            out.append(("over", "no exposure after this one: the plan is over when it ends"))
        elif prev is not None:
            end = prev.end.strftime("%Y-%m-%d %H:%M:%S")
            out.append(
                ("over", f"the plan is over: its last exposure, {_name(prev)}, ended {end} UTC")
            )
        else:
            out.append(("over", "the plan has no exposures"))
        return out
    wait = wait_text((nxt.start - now).total_seconds())
    out.append(("next", f"{_name(nxt)}, anchor {_anchor(nxt)}"))
    out.append(
        (
            "",
            f"start {_when(nxt.start, now)} (±{nxt.sigma_t_s:.2g} s), in {wait}; "
            f"{seconds_text(nxt.exptime_s)} s exposure",
        )
    )
    if nxt.first_of_visit and nxt.acq_start is not None:
        verb = "started" if nxt.acq_start <= now else "starts"
        out.append(("", f"new visit: acquisition {verb} {_when(nxt.acq_start, now)}"))
    if c.after is not None:
        a = c.after
        wait_a = wait_text((a.start - now).total_seconds())
        out.append(("then", f"{_name(a)}, start {_when(a.start, now)}, in {wait_a}"))
    if prev is not None and (run is not None or prev.visit_id == nxt.visit_id):
        out.append(
            (
                "missed?",
                f"{prev.label} should have started at {hms(prev.start)} UTC; if it did not, skip "
                f"it (a late start is off its anchor) and start {nxt.label} at "
                f"{hms(nxt.start)} UTC",
            )
        )
    return out


def countdown_lines(c: Countdown, width: int = 100) -> list[str]:
    """What ``ucbplan now`` prints at ``c.now``: the clock, the exposure that should be running,
    the next start and the wait, the one after, and what to do if the previous start was
    missed; each entry wrapped to ``width`` columns under a 10-column tag."""
    lines: list[str] = []
    for tag, text in _entries(c):
        head = f"{tag:<10}"
        lines += textwrap.wrap(
            text, width, initial_indent=head, subsequent_indent=" " * 10, break_on_hyphens=False
        )
    return lines
