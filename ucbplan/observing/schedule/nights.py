"""Nights: local evening dates and their UTC windows (local noon to local noon)."""

from __future__ import annotations

from collections.abc import Sequence
from datetime import date, datetime, time, timedelta
from typing import NamedTuple

from astropy.time import Time

from ucbplan.errors import UcbplanError
from ucbplan.observing.sites import Site
from ucbplan.observing.timeaxis import TimeAxis
from ucbplan.observing.timeconv import quiet_erfa

__all__ = ["NightSpan", "NightWindow", "night_dates", "night_spans", "night_windows"]


class NightWindow(NamedTuple):
    """One night: its label (the local evening date, ISO) and UTC start and end."""

    label: str
    start: Time
    end: Time


class NightSpan(NamedTuple):
    """One night on a plan's :class:`~ucbplan.observing.timeaxis.TimeAxis` [s]."""

    label: str
    x0: float
    x1: float


def night_dates(first: str | date, count: int = 1) -> list[date]:
    """``count`` consecutive local evening dates from ``first`` (a date or ``YYYY-MM-DD``).

    Raises
    ------
    UcbplanError
        For a malformed date or ``count`` < 1.
    """
    if isinstance(first, date):
        start = first
    else:
        try:
            start = date.fromisoformat(first)
        except ValueError:
            raise UcbplanError(
                f"--night: expected the local evening date YYYY-MM-DD, got {first!r}"
            ) from None
    if count < 1:
        raise UcbplanError(f"--nights must be >= 1, got {count}")
    return [start + timedelta(days=k) for k in range(count)]


def night_windows(site: Site, nights: Sequence[date]) -> list[NightWindow]:
    """UTC windows from local noon of each date to local noon the next day at ``site``."""
    zone = site.zone
    out = []
    for d in nights:
        start = datetime.combine(d, time(12, 0), tzinfo=zone)
        end = datetime.combine(d + timedelta(days=1), time(12, 0), tzinfo=zone)
        with quiet_erfa():
            out.append(NightWindow(d.isoformat(), Time(start, scale="utc"), Time(end, scale="utc")))
    return out


def night_spans(windows: Sequence[NightWindow], axis: TimeAxis) -> list[NightSpan]:
    """The night windows on ``axis``."""
    return [NightSpan(w.label, axis.x(w.start), axis.x(w.end)) for w in windows]
