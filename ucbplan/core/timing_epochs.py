"""Timing-ephemeris epochs as text, at full precision: ``"BJD_TDB 2458305.6827886"``.

Two readings of the same strings: as an astropy ``Time`` whose two-part JD holds the decimal
value (:func:`parse_timing_epoch`, target files' ``t0``), and as an exact ``Decimal`` JD
(:func:`parse_epoch_label`, eclipse-time tables and initial ephemerides, whose arithmetic is done
in decimals: :func:`jd_to_seconds`, :func:`seconds_to_jd`). Written back by
:func:`format_bjd_tdb` (a ``Time``), :func:`format_bjd` (a ``Decimal``) and
:func:`bjd_tdb_numbers` (arrays of ``Time``). HJD, UTC-, TT- or TCB-based epochs and unlabelled
numbers are refused with a message saying how to convert.
"""

from __future__ import annotations

import datetime as _dt
import decimal
import re
from decimal import Decimal

from astropy.time import Time

from ucbplan.core.constants import DAY_S_INT
from ucbplan.core.epochs import YEAR_RANGE, split_scale_label, year_of
from ucbplan.errors import InputError, shorten

#: Scale words of a timing epoch → astropy format of the number that follows (all TDB at the
#: solar-system barycentre).
TIMING_EPOCH_WORDS: dict[str, str] = {
    "BJD_TDB": "jd",
    "BMJD_TDB": "mjd",
    "MJD_TDB": "mjd",
    "JD_TDB": "jd",
}
#: Words of other time scales or reference points, with how to convert them to BJD_TDB.
_REFUSED_WORDS: dict[str, str] = {
    "HJD": "a heliocentric JD (HJD, usually UTC-based) differs from BJD_TDB by up to ~4 s "
    "(plus 32.184 s and the leap seconds when UTC-based)",
    "BJD_UTC": "BJD_UTC lacks the leap seconds: BJD_TDB = BJD_UTC + (32.184 s + leap seconds + "
    "TDB − TT)",
    "JD_UTC": "a UTC epoch is not barycentric",
    "MJD_UTC": "a UTC epoch is not barycentric",
    "BJD_TT": "BJD_TT differs from BJD_TDB by up to ~1.7 ms",
    "BJD_TCB": "TCB runs faster than TDB (~20 s apart in 2020)",
    "JD": "a bare JD does not say its time scale or reference point",
    "MJD": "a bare MJD does not say its time scale or reference point",
    "BJD": "BJD without a scale is ambiguous (BJD_UTC or BJD_TDB)",
    "BMJD": "BMJD without a scale is ambiguous (BMJD_UTC or BMJD_TDB)",
}
#: Day-number words that are TDB only with a trailing ``TDB`` label ("MJD 58305.18 TDB").
_BARE_WORDS: dict[str, str] = {"JD": "jd", "BJD": "jd", "MJD": "mjd", "BMJD": "mjd"}
_HOW_TO_CONVERT = (
    "convert it to BJD_TDB first (e.g. Eastman et al. 2010's converter, or astropy: "
    "t.tdb + t.light_travel_time(coord, 'barycentric'))"
)
_DECIMAL_DIGITS = frozenset("0123456789")
#: Longest timing-epoch text [characters] ("BMJD_TDB 58305.18278860000000000000" is 35).
MAX_TIMING_EPOCH_CHARS = 64
TIMING_EPOCH_EXAMPLE = '"BJD_TDB 2458305.6827886"'


def _split_decimal(number: str) -> tuple[float, float] | None:
    """``"2458305.6827886"`` → (2458305.0, 0.6827886) exactly split; None if not a plain decimal.

    The integer part is exact in float64 (< 2**53) and the fraction is rounded once, so the
    epoch keeps ~1e-16 d (10 ps): never one float64 of the whole JD (~40 µs steps at 2.4e6 d).
    """
    whole, dot, frac = number.partition(".")
    if not whole or not set(whole) <= _DECIMAL_DIGITS or len(whole) > 9:
        return None
    if dot and frac and not set(frac) <= _DECIMAL_DIGITS:
        return None
    return float(int(whole)), float(f"0.{frac}") if frac else 0.0


def parse_timing_epoch(text: object) -> Time:
    """A timing-ephemeris epoch (barycentric TDB) with full two-part precision.

    Accepted: ``"BJD_TDB 2458305.6827886"``, ``"BMJD_TDB 58305.1827886"``, ``"MJD_TDB …"``,
    ``"JD_TDB …"`` (the word first, then a plain decimal number), or an ISO epoch labelled TDB
    (``"2018-07-06T04:23:12.93 TDB"``). HJD, UTC-, TT- or TCB-based epochs and unlabelled
    numbers are refused with a message saying how to convert; the text is read in linear time.

    Parameters
    ----------
    text : str
        The epoch as written.

    Returns
    -------
    Time
        TDB, ``jd1`` + ``jd2`` holding the decimal value to ~1e-16 d.

    Raises
    ------
    ValueError
        One line (without the file name): what is wrong and how to fix it.
    """
    expect = f"expected an epoch like {TIMING_EPOCH_EXAMPLE} (or an ISO epoch labelled TDB)"
    raw = _epoch_text(text, expect)
    body, label = split_scale_label(raw)
    head, _, number = body.partition(" ")
    word = head.upper().replace("-", "_")
    if word in TIMING_EPOCH_WORDS:
        if label not in (None, "tdb"):
            raise ValueError(f"{shorten(raw)}: the label {label.upper()} contradicts {word}")
        return _word_epoch(TIMING_EPOCH_WORDS[word], number.strip(), raw, expect)
    if word in _BARE_WORDS and label == "tdb":
        return _word_epoch(_BARE_WORDS[word], number.strip(), raw, expect)
    if word.startswith(("HJD", "HMJD")) or word in _REFUSED_WORDS or word in _BARE_WORDS:
        key = "HJD" if word.startswith(("HJD", "HMJD")) else word
        why = _REFUSED_WORDS.get(key, "")
        if label is not None and key in _BARE_WORDS:
            why = f"a {label.upper()} epoch is not TDB"
        raise ValueError(
            f"{shorten(raw)}: only BJD_TDB epochs are accepted; {why}; {_HOW_TO_CONVERT}"
        )
    if head[:1].isalpha():
        known = ", ".join(TIMING_EPOCH_WORDS)
        raise ValueError(
            f"unknown time-scale word {shorten(head, 40)}; expected one of {known} before the "
            f"number, e.g. {TIMING_EPOCH_EXAMPLE}"
        )
    return _iso_epoch(raw, body, label, expect)


def _epoch_text(text: object, expect: str) -> str:
    """The epoch's text, stripped; bare numbers, YAML dates and over-long text refused."""
    if isinstance(text, bool) or isinstance(text, int | float):
        raise ValueError(
            f"{expect}, got the bare number {shorten(text)}; quote it and state the scale, e.g. "
            f'"BJD_TDB {text}" (one float64 of a JD loses up to ~20 µs)'
        )
    if isinstance(text, _dt.date):
        raise ValueError(
            f"{expect}, got the unquoted date {shorten(str(text))}; quote it and label the "
            'scale, e.g. "2018-07-06T04:23:12.93 TDB"'
        )
    if not isinstance(text, str) or len(text) > MAX_TIMING_EPOCH_CHARS:
        raise ValueError(f"{expect}, got {shorten(text)}")
    return text.strip()


def _word_epoch(fmt: str, number: str, raw: str, expect: str) -> Time:
    parts = _split_decimal(number)
    if parts is None:
        raise ValueError(f"{expect}, got {shorten(raw)} (write the number as plain decimals)")
    t = Time(parts[0], parts[1], format=fmt, scale="tdb")
    _check_year(t, raw)
    return t


def _iso_epoch(raw: str, body: str, label: str | None, expect: str) -> Time:
    if label is None:
        if body[:1].isdigit() and _split_decimal(body) is not None:
            raise ValueError(
                f'{expect}, got {shorten(raw)}: state the time scale, e.g. "BJD_TDB {body}"'
            )
        raise ValueError(
            f"{expect}, got {shorten(raw)}: an ISO epoch needs its scale, e.g. "
            '"2018-07-06T04:23:12.93 TDB"'
        )
    if label != "tdb":
        raise ValueError(
            f"{shorten(raw)}: only TDB (barycentric) epochs are accepted, got {label.upper()}; "
            f"{_HOW_TO_CONVERT}"
        )
    try:
        t = Time(body, scale="tdb", format="isot" if "T" in body else "iso")
    except (ValueError, TypeError, OverflowError, KeyError, IndexError, UnicodeError):
        raise ValueError(f"{expect}, got {shorten(raw)}") from None
    _check_year(t, raw)
    return t


def _check_year(t: Time, raw: str) -> None:
    year = year_of(t)
    if not YEAR_RANGE[0] <= year <= YEAR_RANGE[1]:
        raise ValueError(
            f"{shorten(raw)} lies in the year {year:.6g}; expected an epoch in the years "
            f"{YEAR_RANGE[0]:.0f}–{YEAR_RANGE[1]:.0f} (a JD given as an MJD, or BMJD as BJD?)"
        )


def format_bjd_tdb(t: Time, decimals: int = 13) -> str:
    """``"BJD_TDB 2458305.6827886000000"``: a TDB epoch as text, exact to ``10**-decimals`` d.

    The exact sum of the two-part JD is rounded once, so no digit is lost to a float64 of the
    whole JD (1e-13 d = 8.6 ns). :func:`parse_timing_epoch` reads it back.
    """
    from decimal import Decimal

    tdb = t.tdb
    total = Decimal(float(tdb.jd1)) + Decimal(float(tdb.jd2))
    q = Decimal(1).scaleb(-decimals)
    return f"BJD_TDB {total.quantize(q)}"


def bjd_tdb_numbers(t: Time, decimals: int = 12) -> list[str]:
    """BJD_TDB day numbers of (an array of) TDB epochs as text, from the two-part JD.

    ``decimals=12`` is 86 ns; unlike one float64 of the JD (~40 µs steps) nothing is lost.
    Vectorised: the whole day and the fraction are split before formatting.
    """
    import numpy as np

    tdb = t.tdb
    jd1 = np.atleast_1d(np.asarray(tdb.jd1, dtype=np.float64))
    jd2 = np.atleast_1d(np.asarray(tdb.jd2, dtype=np.float64))
    i1 = np.floor(jd1)
    rest = (jd1 - i1) + jd2  # to ~1e-16 d: jd1 − floor(jd1) is 0 or 0.5, |jd2| ≤ 1
    i2 = np.floor(rest)
    zero = f"{0.0:.{decimals}f}"
    out = []
    for whole, frac in zip(i1 + i2, rest - i2, strict=True):
        text = f"{frac:.{decimals}f}"
        day = int(whole)
        if text.startswith("1."):
            day, text = day + 1, zero
        out.append(f"{day}{text[1:]}")
    return out


# exact decimals (eclipse-time tables, initial ephemerides)

#: JD − MJD (exact).
MJD_OFFSET = Decimal("2400000.5")
#: Decimal context wide enough for every epoch arithmetic here (JDs with 20+ digits, times 86400).
DECIMAL_CONTEXT = decimal.Context(prec=60)

#: Plausible JD range of an eclipse time (1758 … 2501); outside it the column is misread.
JD_RANGE = (Decimal(2_363_000), Decimal(2_635_000))

_NUMBER = re.compile(r"^[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d{1,4})?$")
_LABELLED = re.compile(r"^\s*([A-Za-z_]+)\s+(\S+)\s*$")
_LABEL_OFFSETS = {
    "BJD_TDB": Decimal(0),
    "JD_TDB": Decimal(0),
    "BMJD_TDB": MJD_OFFSET,
    "MJD_TDB": MJD_OFFSET,
}


def parse_decimal(text: str) -> Decimal:
    """An exact decimal from a plain number text (``ValueError`` for anything else)."""
    s = text.strip()
    if len(s) > 60 or not _NUMBER.match(s):
        raise ValueError(f"not a plain number: {text!r}")
    return DECIMAL_CONTEXT.create_decimal(s)


def parse_epoch_label(text: str, what: str) -> Decimal:
    """A labelled TDB epoch as an exact JD: ``BJD_TDB x``, ``BMJD_TDB x``, ``JD_TDB x``,
    ``MJD_TDB x`` or an ISO date ending in ``TDB``.

    Raises
    ------
    InputError
        Unlabelled, another time scale (HJD, UTC: convert to BJD_TDB first) or not a number.
    """
    s = str(text).strip()
    m = _LABELLED.match(s)
    if m and m.group(1).upper() in _LABEL_OFFSETS:
        try:
            jd = parse_decimal(m.group(2)) + _LABEL_OFFSETS[m.group(1).upper()]
        except ValueError:
            raise InputError(
                f'{what}: expected "BJD_TDB 2458305.6827886", got {shorten(text, 80)}'
            ) from None
        return _check_jd(jd, what, text)
    upper = s.upper()
    if "HJD" in upper or "UTC" in upper:
        raise InputError(
            f"{what}: {shorten(text, 80)} is not a barycentric TDB epoch; convert it to BJD_TDB "
            "first (e.g. astropy Time(...).tdb with the light-travel time to the barycentre) and "
            'write "BJD_TDB …"'
        )
    if upper.endswith("TDB") and re.match(r"^\d{4}-\d\d-\d\d[T ]", s):
        from astropy.time import Time

        try:
            t = Time(re.sub(r"\s*\(?TDB\)?$", "", s, flags=re.IGNORECASE), scale="tdb")
        except ValueError:
            raise InputError(
                f'{what}: expected an ISO epoch like "2018-07-03T04:23:12.93 TDB", got '
                f"{shorten(text, 80)}"
            ) from None
        jd = DECIMAL_CONTEXT.add(Decimal(float(t.jd1)), Decimal(float(t.jd2)))
        return _check_jd(jd, what, text)
    raise InputError(
        f'{what}: expected a labelled TDB epoch like "BJD_TDB 2458305.6827886" (or BMJD_TDB, '
        f"MJD_TDB, ISO … TDB), got {shorten(text, 80)}"
    )


def _check_jd(jd: Decimal, what: str, text: object) -> Decimal:
    if not (JD_RANGE[0] <= jd <= JD_RANGE[1]):
        raise InputError(
            f"{what}: expected an epoch between JD {JD_RANGE[0]} and {JD_RANGE[1]}, got "
            f"{shorten(text, 80)}"
        )
    return jd


def format_bjd(jd: Decimal, decimals: int = 12) -> str:
    """``"BJD_TDB 2458305.682788600000"``: ``decimals`` = 12 resolves 0.1 µs."""
    q = Decimal(1).scaleb(-decimals)
    return f"BJD_TDB {jd.quantize(q, rounding=decimal.ROUND_HALF_EVEN, context=DECIMAL_CONTEXT)}"


def jd_to_seconds(jd: Decimal, ref: Decimal) -> float:
    """``(jd − ref)`` in seconds as float64, the subtraction exact."""
    return float(DECIMAL_CONTEXT.multiply(DECIMAL_CONTEXT.subtract(jd, ref), Decimal(DAY_S_INT)))


def seconds_to_jd(t_s: float, ref: Decimal) -> Decimal:
    """``ref + t_s`` (seconds, float64 taken exactly) as an exact JD."""
    return DECIMAL_CONTEXT.add(ref, DECIMAL_CONTEXT.divide(Decimal(t_s), Decimal(DAY_S_INT)))
