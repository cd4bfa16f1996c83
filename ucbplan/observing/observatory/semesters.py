"""Observatory semesters and ESO periods as date ranges (the observatory's own definitions).

- ``2041A`` / ``2041B`` (Gemini, NOIRLab, Keck, …): A = 1 Feb – 31 Jul, B = 1 Aug – 31 Jan of the
  next year.
- ``P147`` (ESO): six-month periods starting 1 April (odd numbers) and 1 October (even); P110 is
  2022-10-01 … 2023-03-31, so period n starts 6 (n − 110) months after 2022-10-01.

Ranges are half-open in dates: ``[first, end)``, the nights starting on those local dates.

Declared here, below both users: :mod:`ucbplan.population` (``--semester`` of ``population``)
and the proposal export.
"""

from __future__ import annotations

import datetime as dt
import re

from ucbplan.errors import InputError, shorten

_SEMESTER = re.compile(r"^(\d{4})([AB])$")
_ESO = re.compile(r"^P(\d{1,3})$")
#: P110 starts here (ESO).
_P110 = (2022, 10)


def _add_months(year: int, month: int, n: int) -> dt.date:
    k = year * 12 + (month - 1) + n
    return dt.date(k // 12, k % 12 + 1, 1)


def semester_dates(text: str) -> tuple[dt.date, dt.date]:
    """First date and end date (exclusive) of a semester ``2041A|2041B`` or ESO period ``P147``.

    Raises
    ------
    InputError
        Anything else (one line naming --semester).
    """
    key = text.strip().upper()
    m = _SEMESTER.match(key)
    if m:
        year = int(m.group(1))
        if m.group(2) == "A":
            return dt.date(year, 2, 1), dt.date(year, 8, 1)
        return dt.date(year, 8, 1), dt.date(year + 1, 2, 1)
    m = _ESO.match(key)
    if m and int(m.group(1)) >= 1:
        start = _add_months(*_P110, 6 * (int(m.group(1)) - 110))
        return start, _add_months(start.year, start.month, 6)
    raise InputError(
        f"semester: expected YYYYA, YYYYB (A = Feb-Jul, B = Aug-Jan) or an ESO period like P147, "
        f"got {shorten(text)}"
    )


def semester_label(night: dt.date, eso: bool) -> str:
    """The semester (``2041A``/``2041B``) or, with ``eso``, the ESO period (``P147``) that
    contains the night starting on the local date ``night``.

    Inverse of :func:`semester_dates`: ``semester_dates(semester_label(d, e))`` contains ``d``.
    """
    if eso:
        months = (night.year - _P110[0]) * 12 + night.month - _P110[1]
        return f"P{110 + months // 6}"
    if night.month == 1:
        return f"{night.year - 1}B"
    return f"{night.year}{'A' if night.month < 8 else 'B'}"
