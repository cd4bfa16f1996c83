"""Time-scale guards: epochs are TDB at the barycentre unless the user states otherwise.

Epoch text is read in linear time: the optional scale label is split off by scanning from the
end (no backtracking regex, which was quadratic on padded strings), and text longer than
:data:`MAX_EPOCH_CHARS` is refused before any parsing.
"""

from __future__ import annotations

import datetime as _dt
import math

from astropy.time import Time

from ucbplan.errors import EpochRangeError, InputError, shorten

__all__ = [
    "MAX_EPOCH_CHARS",
    "SCALES",
    "TIMING_EPOCH_WORDS",
    "EpochRangeError",
    "bjd_tdb_numbers",
    "epoch_in_scale",
    "format_bjd_tdb",
    "parse_tdb",
    "parse_timing_epoch",
    "split_scale_label",
]

#: Time scales an epoch may be labelled with (lower case).
SCALES: tuple[str, ...] = ("tdb", "tcb", "tt", "utc", "tai")
#: Longest epoch text [characters]: "MJD 65059.123456789012345 (TDB)" is 31.
MAX_EPOCH_CHARS = 64
#: Epochs must lie in these years (catches a JD given as an MJD, and garbage numbers).
YEAR_RANGE = (1000.0, 3000.0)

_LETTERS = frozenset("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz")


def split_scale_label(text: str) -> tuple[str, str | None]:
    """``(epoch text, scale)`` of ``text`` with an optional trailing scale label removed.

    Accepted labels: ``"… UTC"``, ``"… (UTC)"``, ``"…(UTC)"`` (any case, any of :data:`SCALES`);
    the label must be a separate word. Without a label the scale is None. Linear in
    ``len(text)``.
    """
    t = text.strip()
    core = t[:-1] if t.endswith(")") else t
    i = len(core)
    while i > 0 and core[i - 1] in _LETTERS:
        i -= 1
    word = core[i:].lower()
    if word not in SCALES:
        return t, None
    before = core[:i]
    if before.endswith("("):
        before = before[:-1]
    elif before and (before[-1].isalnum() or before[-1] == "_"):
        return t, None  # "…00UTC": not a separate word
    return before.strip(), word


def _year(t: Time) -> float:
    return 2000.0 + (float(t.jd1) - 2451545.0 + float(t.jd2)) / 365.25


def epoch_in_scale(text: str, scale: str, isot_if_t: bool = False) -> Time:
    """Unlabelled epoch text (ISO, ``"MJD x"`` or ``"JD x"``) in ``scale``, converted to TDB.

    ``isot_if_t`` reads text containing ``T`` strictly as ISO ``YYYY-MM-DDThh:mm:ss``.

    Raises
    ------
    ValueError
        Not an epoch, not finite, or outside the years of :data:`YEAR_RANGE` (the message says
        which).
    """
    raw = text.strip()
    if not raw or len(raw) > MAX_EPOCH_CHARS:
        raise ValueError("not an epoch")
    upper = raw.upper()
    # future UTC: leap seconds after the bundled table are unknown (TDB − UTC kept at the
    # last value); the user stated the scale, so convert with that caveat
    try:
        if upper.startswith(("MJD", "JD")):
            fmt = "mjd" if upper.startswith("MJD") else "jd"
            number = float(raw[len(fmt) :])
            if not math.isfinite(number):
                raise ValueError("not finite")
            t = Time(number, format=fmt, scale=scale)
        else:
            t = Time(raw, scale=scale, format="isot" if isot_if_t and "T" in raw else None)
        year = _year(t)
        tdb = t.tdb if YEAR_RANGE[0] <= year <= YEAR_RANGE[1] else None
    except (ValueError, TypeError, OverflowError, KeyError, IndexError, UnicodeError):
        raise ValueError("not an epoch") from None
    if tdb is None:
        raise EpochRangeError(
            f"lies in the year {year:.6g}; expected an epoch in the years "
            f"{YEAR_RANGE[0]:.0f}–{YEAR_RANGE[1]:.0f} (a JD given as an MJD?)"
        )
    return tdb


def parse_tdb(text: str, what: str = "epoch") -> Time:
    """Parse an ISO epoch (or ``MJD x`` / ``JD x``) as TDB.

    A trailing scale label (``UTC``, ``TT``, ``TCB``, ``TAI``) is an explicit statement of the
    scale, and the epoch is converted to TDB; an unlabelled epoch is taken as TDB.

    Raises
    ------
    InputError
        If the text is not an epoch (one line, the value cut to 200 characters).
    """
    expected = (
        f'{what}: expected an ISO epoch like "2040-01-15T00:00:00" (TDB; append UTC to give '
        f"UTC), got {shorten(text)}"
    )
    if not isinstance(text, str) or len(text.strip()) > MAX_EPOCH_CHARS + 8:
        raise InputError(expected)
    raw, label = split_scale_label(text)
    try:
        return epoch_in_scale(raw, label or "tdb")
    except EpochRangeError as exc:
        raise InputError(f"{what}: {shorten(text)} {exc}") from None
    except ValueError:
        raise InputError(expected) from None


# ---------------------------------------------------------------------------------------------
# timing epochs: "BJD_TDB 2458305.6827886" with full precision
# ---------------------------------------------------------------------------------------------

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
    year = _year(t)
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
