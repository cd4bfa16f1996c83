"""Timing epochs ("BJD_TDB 2458305.6827886"): full precision, and every refused form one line."""

from __future__ import annotations

import random
from decimal import Decimal

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ucbplan.core.timing_epochs import format_bjd_tdb, parse_timing_epoch

DAY = Decimal(86400)


def _error_s(text_number: str, t: object, mjd: bool = False) -> float:
    """|parsed − exact decimal| [s], exact sums of the two float64 parts."""
    exact = Decimal(text_number) + (Decimal("2400000.5") if mjd else 0)
    got = Decimal(float(t.jd1)) + Decimal(float(t.jd2))  # type: ignore[attr-defined]
    return float(abs(got - exact) * DAY)


def test_thirteen_decimals_of_a_jd_survive() -> None:
    """13 decimals of a JD (8.6 ns) are kept to < 10 µs (in fact < 1 ns), where one float64 of
    the JD is off by up to ~20 µs."""
    rng = random.Random(10)
    worst, worst_float = 0.0, 0.0
    for _ in range(300):
        number = f"{rng.randint(2440000, 2480000)}.{rng.randint(0, 10**13 - 1):013d}"
        t = parse_timing_epoch(f"BJD_TDB {number}")
        worst = max(worst, _error_s(number, t))
        worst_float = max(worst_float, float(abs(Decimal(float(number)) - Decimal(number)) * DAY))
    assert worst < 1e-9  # s; the requirement is < 10 µs
    assert worst_float > 5e-6  # s: the test would catch a float64 round trip


@pytest.mark.parametrize(
    ("text", "number", "mjd"),
    [
        ("BJD_TDB 2458305.6827886", "2458305.6827886", False),
        ("bjd_tdb 2458305.6827886", "2458305.6827886", False),
        ("BJD-TDB 2458305.6827886", "2458305.6827886", False),
        ("JD_TDB 2458305.6827886", "2458305.6827886", False),
        ("BMJD_TDB 58305.1827886", "58305.1827886", True),
        ("MJD_TDB 58305.1827886", "58305.1827886", True),
        ("MJD 58305.1827886 TDB", "58305.1827886", True),
        ("BJD 2458305.6827886 (TDB)", "2458305.6827886", False),
        ("  BJD_TDB   2458305.6827886  ", "2458305.6827886", False),
    ],
)
def test_accepted_forms(text: str, number: str, mjd: bool) -> None:
    t = parse_timing_epoch(text)
    assert t.scale == "tdb"
    assert _error_s(number, t, mjd) < 1e-9


def test_iso_labelled_tdb() -> None:
    t = parse_timing_epoch("2018-07-06T04:23:12.935 TDB")
    ref = parse_timing_epoch("BJD_TDB 2458305.6827886")
    assert abs(float((t - ref).to_value("s"))) < 5e-4  # the ISO text has 1 ms


def test_bmjd_and_bjd_agree() -> None:
    a = parse_timing_epoch("BJD_TDB 2458305.6827886")
    b = parse_timing_epoch("BMJD_TDB 58305.1827886")
    assert abs(float((a - b).to_value("s"))) < 1e-9


@given(st.integers(2440000, 2480000), st.integers(0, 10**13 - 1))
@settings(max_examples=200, deadline=None, derandomize=True)
def test_format_round_trip(day: int, frac: int) -> None:
    """format_bjd_tdb writes back exactly the 13 decimals it read."""
    text = f"BJD_TDB {day}.{frac:013d}"
    assert format_bjd_tdb(parse_timing_epoch(text)) == text


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("HJD 2458305.6827886", ["HJD", "BJD_TDB", "convert"]),
        ("HJD_UTC 2458305.6827886", ["HJD", "convert"]),
        ("HMJD 58305.18", ["HJD", "convert"]),
        ("BJD_UTC 2458305.6827886", ["BJD_UTC", "leap seconds", "convert"]),
        ("BJD_TT 2458305.6827886", ["BJD_TT", "convert"]),
        ("JD 2458305.6827886", ["bare JD", "convert"]),
        ("MJD 58305.1827886", ["bare MJD", "convert"]),
        ("BJD 2458305.6827886", ["ambiguous", "convert"]),
        ("MJD 58305.18 UTC", ["UTC", "convert"]),
        ("2018-07-06T04:23:12.935 UTC", ["UTC", "convert"]),
        ("2018-07-06T04:23:12.935", ["scale", "TDB"]),
        ("2458305.6827886", ["state the time scale", "BJD_TDB 2458305.6827886"]),
        ("BJD_XYZ 2458305.68", ["unknown time-scale word", "BJD_TDB"]),
        ("julian 2458305.68", ["unknown time-scale word"]),
        ("BJD_TDB 2458305.68 UTC", ["contradicts"]),
        ("BJD_TDB 2.4583e6", ["plain decimals"]),
        ("BJD_TDB -2458305.6", ["plain decimals"]),
        ("BJD_TDB nan", ["plain decimals"]),
        ("BJD_TDB 58305.18", ["year", "MJD"]),
        ("BMJD_TDB 2458305.68", ["year", "BMJD"]),
        ("BJD_TDB " + "9" * 80, ["expected an epoch"]),
        ("", ["expected an epoch"]),
    ],
)
def test_refused_forms_are_one_line(text: str, words: list[str]) -> None:
    with pytest.raises(ValueError) as exc:
        parse_timing_epoch(text)
    msg = str(exc.value)
    assert "\n" not in msg and len(msg) < 400
    for w in words:
        assert w in msg, (w, msg)


@pytest.mark.parametrize("value", [2458305.6827886, 58305, True, None, [1, 2], {"a": 1}])
def test_non_text_values(value: object) -> None:
    with pytest.raises(ValueError) as exc:
        parse_timing_epoch(value)
    msg = str(exc.value)
    assert "\n" not in msg and len(msg) < 400
    if isinstance(value, float):
        assert "quote it" in msg and "BJD_TDB" in msg


def test_unquoted_yaml_date() -> None:
    import datetime as dt

    with pytest.raises(ValueError, match="quote it"):
        parse_timing_epoch(dt.datetime(2018, 7, 6, 4, 23, 12))


@given(st.text(max_size=80))
@settings(max_examples=300, deadline=500, derandomize=True)
def test_arbitrary_text_is_an_epoch_or_one_line(text: str) -> None:
    try:
        parse_timing_epoch(text)
    except ValueError as exc:
        msg = str(exc)
        assert "\n" not in msg.replace(repr(text), "") and len(msg) < 400


def test_bjd_numbers_of_an_array_keep_full_precision() -> None:
    """bjd_tdb_numbers (the ephemeris table's t_star_bjd_tdb) from two-part JDs, 12 decimals."""
    from astropy.time import Time

    from ucbplan.core.timing_epochs import bjd_tdb_numbers

    rng = random.Random(3)
    texts = [
        f"{rng.randint(2440000, 2480000)}.{rng.randint(0, 10**12 - 1):012d}" for _ in range(200)
    ]
    texts += ["2458305.999999999999", "2458306.000000000000", "2458305.500000000000"]
    times = Time([parse_timing_epoch(f"BJD_TDB {x}") for x in texts])
    assert bjd_tdb_numbers(times) == texts
