"""The semester rule (observing.semesters): labels and date ranges are inverse of each other."""

from __future__ import annotations

import datetime as dt

import pytest
from hypothesis import given
from hypothesis import strategies as st

from ucbplan.observing.observatory.semesters import semester_dates, semester_label


@given(st.dates(dt.date(1990, 1, 1), dt.date(2200, 12, 31)), st.booleans())
def test_the_semester_of_a_night_contains_it(night: dt.date, eso: bool) -> None:
    first, end = semester_dates(semester_label(night, eso))
    assert first <= night < end
    assert (end - first).days in range(181, 185)  # six months


@pytest.mark.parametrize(
    ("night", "eso", "label"),
    [
        (dt.date(2041, 1, 31), False, "2040B"),
        (dt.date(2041, 2, 1), False, "2041A"),
        (dt.date(2041, 7, 31), False, "2041A"),
        (dt.date(2041, 8, 1), False, "2041B"),
        (dt.date(2023, 3, 31), True, "P110"),  # ESO: P110 = 2022-10-01 .. 2023-03-31
        (dt.date(2023, 4, 1), True, "P111"),
        (dt.date(2040, 10, 1), True, "P146"),
        (dt.date(2041, 4, 1), True, "P147"),
    ],
)
def test_semester_boundaries(night: dt.date, eso: bool, label: str) -> None:
    assert semester_label(night, eso) == label
