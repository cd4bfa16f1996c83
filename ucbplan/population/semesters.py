"""Observatory semesters and ESO periods: the rule lives in :mod:`ucbplan.observing.semesters`
(shared with the proposal export); re-exported here for ``population --semester``."""

from __future__ import annotations

from ucbplan.observing.semesters import semester_dates

__all__ = ["semester_dates"]
