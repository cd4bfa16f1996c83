"""Nights: local evening dates and their UTC windows (local noon to local noon)."""

from __future__ import annotations

from collections.abc import Sequence
from datetime import date, datetime, time, timedelta
from typing import NamedTuple

import numpy as np
from astropy import units as u
from astropy.time import Time

from ucbplan.errors import InputError, shorten
from ucbplan.inputs import check_int
from ucbplan.observing.observatory.sites import Site
from ucbplan.observing.observatory.time_axis import TimeAxis

#: Most nights in one plan (a year).
MAX_NIGHTS = 366
#: First and last night that can be planned (the built-in Earth ephemeris, ERFA epv00, used for
#: the light time, is valid 1900-2100).
NIGHT_RANGE = (date(1900, 1, 1), date(2100, 12, 30))


class NightWindow(NamedTuple):
    """One night: its label (the local evening date, ISO) and UTC start and end."""

    label: str
    start: Time
    end: Time


class NightSpan(NamedTuple):
    """One night on a plan's :class:`~ucbplan.observing.observatory.time_axis.TimeAxis` [s]."""

    label: str
    x0: float
    x1: float


def _parse_night(text: object) -> date:
    """``YYYY-MM-DD`` as a date."""
    t = text.strip() if isinstance(text, str) and len(text) <= 40 else ""
    try:
        if len(t) == 10:
            return date.fromisoformat(t)
    except ValueError:
        pass
    raise InputError(f"night: expected the local evening date YYYY-MM-DD, got {shorten(text, 40)}")


def night_dates(first: str | date, count: int = 1) -> list[date]:
    """``count`` consecutive local evening dates from ``first`` (a date or ``YYYY-MM-DD``).

    Raises
    ------
    InputError
        For a malformed date, ``count`` outside 1..:data:`MAX_NIGHTS`, or nights outside
        :data:`NIGHT_RANGE`.
    """
    check_int("nights", count, 1, MAX_NIGHTS, "a year at most; plan longer runs in parts")
    start = first if isinstance(first, date) else _parse_night(first)
    lo, hi = NIGHT_RANGE
    if not (lo <= start <= hi and (hi - start).days >= count - 1):
        span = str(start) if count == 1 else f"{count} nights from {start}"
        raise InputError(
            f"night/nights: expected nights from {lo} to {hi} (the built-in Earth ephemeris "
            f"of the light time is valid 1900-2100), got {span}"
        )
    return [start + timedelta(days=k) for k in range(count)]


def night_windows(site: Site, nights: Sequence[date]) -> list[NightWindow]:
    """UTC windows from local noon of each date to local noon the next day at ``site``.

    All edges are converted in one vectorised ``Time`` (the same values as one by one).
    """
    if not nights:
        return []
    zone = site.zone
    edges = [
        datetime.combine(d + timedelta(days=j), time(12, 0), tzinfo=zone)
        for d in nights
        for j in (0, 1)
    ]
    t = Time(edges, scale="utc")
    return [NightWindow(d.isoformat(), t[2 * k], t[2 * k + 1]) for k, d in enumerate(nights)]


def night_spans(windows: Sequence[NightWindow], axis: TimeAxis) -> list[NightSpan]:
    """The night windows on ``axis``."""
    if not windows:
        return []
    n = len(windows)
    edges = Time([w.start for w in windows] + [w.end for w in windows])
    x = np.atleast_1d((edges - axis.origin).to_value(u.s))
    return [NightSpan(w.label, float(x[k]), float(x[n + k])) for k, w in enumerate(windows)]
