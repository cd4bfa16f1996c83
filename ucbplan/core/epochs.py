"""Epochs and their time scales: TDB at the barycentre unless the user states otherwise.

Epoch text is read in linear time: the optional scale label is split off by scanning from the
end (no backtracking regex), and text longer than :data:`MAX_EPOCH_CHARS` is refused before any
parsing. Timing-ephemeris epochs ("BJD_TDB 2458305.6827886", full precision) are read and
written by :mod:`ucbplan.core.timing_epochs`.
"""

from __future__ import annotations

import math
from typing import Any

from astropy.time import Time

from ucbplan.errors import EpochRangeError, InputError, shorten

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


def years_of(jd1: Any, jd2: Any) -> Any:
    """Julian year (J2000.0 = 2000.0) of two-part Julian dates ``jd1 + jd2``: floats or arrays,
    the same operations either way (:func:`year_of` of one Time, many at once)."""
    return 2000.0 + (jd1 - 2451545.0 + jd2) / 365.25


def year_of(t: Time) -> float:
    return float(years_of(float(t.jd1), float(t.jd2)))


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
        year = year_of(t)
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
