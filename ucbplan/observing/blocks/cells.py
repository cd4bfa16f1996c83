"""Text of the blocks table's cells: ISO times (UTC and TDB), local civil times and sexagesimal
right ascension and declination — :func:`sexagesimal` is the one coordinate formatter, of the
table and of every export.

Each is made for a whole column at once (one ``erfa.d2dtf`` over the Julian dates as stored, a
coordinate's text once per distinct value), text for text what astropy makes time by time.
"""

from __future__ import annotations

import math
import operator
from collections.abc import Callable, Sequence
from datetime import UTC, datetime, timedelta, timezone
from typing import Literal
from zoneinfo import ZoneInfo

import erfa
import numpy as np
from astropy import units as u
from astropy.time import Time

from ucbplan.core.constants import DAY_S_INT, HOUR_S_INT
from ucbplan.observing.blocks.arrays import isot_array, time_array


def iso_column(times: Time, has: np.ndarray | None, precision: int) -> np.ndarray:
    """ISO strings of an array Time (its Julian dates as stored) with ``precision`` decimals of
    the second; empty where ``has`` is False."""
    if not len(times):
        return np.array([], dtype="U1")
    if has is None or bool(np.all(has)):
        return isot_array(times, precision)
    out = np.full(len(times), "", dtype=object)
    if np.any(has):
        out[has] = isot_array(times[has], precision)
    return out.astype(str)


def local_datetimes(times: Sequence[Time], zones: Sequence[str]) -> list[datetime]:
    """Scalar UTC Times as aware local datetimes (µs), each in its IANA zone.

    One calendar conversion (erfa ``d2dtf``, as astropy's ``to_datetime`` makes it) for all
    times, then each is moved into its zone by :mod:`zoneinfo`, so DST changes are exact. A
    time inside a leap second takes astropy's own path (which refuses it)."""
    if not len(times):
        return []
    return _local_of(time_array(times, "utc"), zones)


def _local_of(utc: Time, zones: Sequence[str]) -> list[datetime]:
    """:func:`local_datetimes` of an array UTC Time (the Julian dates as stored)."""
    year, month, day, hmsf = erfa.d2dtf(b"UTC", 6, utc.jd1, utc.jd2)
    if np.any(hmsf["s"] >= 60):  # datetime has no leap second: astropy raises, as it always did
        return [
            t.utc.to_datetime(timezone=UTC).astimezone(ZoneInfo(z))
            for t, z in zip(utc, zones, strict=True)
        ]
    tz = {z: ZoneInfo(z) for z in dict.fromkeys(zones)}
    fields = zip(
        year.tolist(),
        month.tolist(),
        day.tolist(),
        hmsf["h"].tolist(),
        hmsf["m"].tolist(),
        hmsf["s"].tolist(),
        hmsf["f"].tolist(),
        zones,
        strict=True,
    )
    return [
        datetime(y, mo, d, h, mi, sec, us, tzinfo=UTC).astimezone(tz[z])
        for y, mo, d, h, mi, sec, us, z in fields
    ]


def local_iso(times: Time | Sequence[Time], zones: Sequence[str]) -> np.ndarray:
    """Local civil time strings with UTC offset, second precision (of an array UTC Time or
    of scalar Times)."""
    if not len(times):
        return np.array([], dtype="U1")
    utc = times if isinstance(times, Time) else time_array(times, "utc")
    year, month, day, hmsf = erfa.d2dtf(b"UTC", 6, utc.jd1, utc.jd2)
    if np.any(hmsf["s"] >= 60) or np.any(year < 1970):  # a leap second (astropy's path refuses
        # it, as it always did) or a time before 1970 (not a POSIX time everywhere): time by time
        return np.array([dt.isoformat(timespec="seconds") for dt in _local_of(utc, zones)])
    # whole POSIX seconds: the seconds' fraction is cut by the format, and zones change their
    # offsets at whole seconds, so the zone's offset is that of the instant itself
    months = (year - 1970) * 12 + (month - 1)
    days = months.astype("datetime64[M]").astype("datetime64[D]").astype(np.int64) + (day - 1)
    posix = days * DAY_S_INT + hmsf["h"] * HOUR_S_INT + hmsf["m"] * 60 + hmsf["s"]
    tz = {z: ZoneInfo(z) for z in dict.fromkeys(zones)}
    if len(zones) != len(posix):
        raise ValueError(f"local_iso: {len(posix)} times but {len(zones)} zones")
    instants = map(datetime.fromtimestamp, posix.tolist(), map(tz.__getitem__, zones))
    offsets = list(map(datetime.utcoffset, instants))  # each instant's own, in its zone
    found = {off: _offset_text(off) for off in dict.fromkeys(offsets)}
    text = {off: got for off, got in found.items() if got is not None}
    if len(text) < len(found):
        return np.array([dt.isoformat(timespec="seconds") for dt in _local_of(utc, zones)])
    shift = np.array([text[off][0] for off in offsets], dtype=np.int64)
    wall = np.datetime_as_string((posix + shift).astype("datetime64[s]"), unit="s").tolist()
    local = list(map(operator.add, wall, (text[off][1] for off in offsets)))
    return np.array(local, dtype=str)


def _offset_text(offset: timedelta | None) -> tuple[int, str] | None:
    """(seconds, ``+HH:MM`` as ``isoformat`` writes it) of a UTC offset of whole seconds."""
    if offset is None or offset.microseconds:
        return None
    zone = timezone(offset)
    return offset.days * DAY_S_INT + offset.seconds, datetime(2000, 1, 1, tzinfo=zone).isoformat()[
        19:
    ]


def _per_distinct(values: np.ndarray, fmt: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
    """``fmt(values)``, formatting each distinct value (bit for bit: -0.0 is not 0.0) once: a
    target's coordinates repeat on every one of its blocks."""
    if len(values) == 0:
        return np.array([], dtype="U1")
    bits = np.ascontiguousarray(values, dtype=np.float64).view(np.int64)
    _, first, inverse = np.unique(bits, return_index=True, return_inverse=True)
    return fmt(values[first])[inverse.ravel()]


def ra_hms_column(ra_deg: np.ndarray) -> np.ndarray:
    """The ``ra_hms`` column: ``HH:MM:SS.sss`` of each right ascension [deg] (astropy's fields,
    see :func:`sexagesimal`)."""
    return _per_distinct(ra_deg, _hms)


def dec_dms_column(dec_deg: np.ndarray) -> np.ndarray:
    """The ``dec_dms`` column: ``+DD:MM:SS.ss`` of each declination [deg] (astropy's fields)."""
    return _per_distinct(dec_deg, _dms)


#: Hours per degree as astropy converts an ``Angle`` in degrees to hour angle (its unit scale,
#: 0.06666666666666668, not 1/15): the table's ``ra_hms`` has always been made this way.
_HOURS_PER_DEG = float(u.deg.to(u.hourangle))


def _hms(ra_deg: np.ndarray) -> np.ndarray:
    hours = np.asarray(ra_deg, dtype=float) * _HOURS_PER_DEG
    return np.array([sexagesimal(h, 3, ":", False, rounding="astropy") for h in hours.tolist()])


def _dms(dec_deg: np.ndarray) -> np.ndarray:
    dec = np.asarray(dec_deg, dtype=float).tolist()
    return np.array([sexagesimal(d, 2, ":", True, rounding="astropy") for d in dec])


def sexagesimal(
    value: float,
    decimals: int,
    sep: str,
    signed: bool,
    width: int = 2,
    *,
    rounding: Literal["once", "astropy"] = "once",
) -> str:
    """``value`` in hours (RA) or degrees (Dec) as sexagesimal text: the one coordinate formatter
    of the blocks table and the exports.

    Parameters
    ----------
    value : float
        Hours (RA) or degrees (Dec).
    decimals : int
        Decimals of the seconds.
    sep : str
        Separator of the fields (``:`` or a space).
    signed : bool
        Always write the sign (Dec). Unsigned (RA): see ``rounding``.
    width : int
        Digits of the first field (zero-padded).
    rounding : {"once", "astropy"}
        ``once`` (the exports): the value is rounded once, in whole units of the last decimal,
        so the seconds never read 60; unsigned, it wraps at 24 h (23:59:59.9999 → 00:00:00.000)
        and drops a sign; signed, a negative that rounds to zero is ``+00``.
        ``astropy`` (the blocks table's ``ra_hms``/``dec_dms``): the fields astropy's
        ``Angle.to_string`` makes — degrees, minutes and seconds split in floating point, the
        seconds rounded as text with a carry, no 24 h wrap (``24:00:00.000``), the sign that of
        the value (``-00:00:00.00`` for -0.0 and tiny negatives), ``nan`` for NaN. The two
        agree but at those edges and within a few ulps of a rounding tie of the last decimal
        (one unit apart there): never on random values nor on a catalogue's 1 ms / 0.01" grid.

    Returns
    -------
    str
        ``[sign]HH<sep>MM<sep>SS.s…``.

    Raises
    ------
    ValueError
        An unknown ``rounding``; a NaN with ``rounding="once"``.
    """
    if rounding == "astropy":
        if math.isnan(value):
            return "nan"
        negative, head, minutes, seconds = _astropy_fields(value, decimals, width)
    elif rounding == "once":
        negative, head, minutes, seconds = _rounded_once(value, decimals, signed, width)
    else:
        raise ValueError(f"rounding must be 'once' or 'astropy', got {rounding!r}")
    sign = "-" if negative else "+" if signed else ""
    return sign + sep.join([head, f"{minutes:02d}", seconds])


def _rounded_once(
    value: float, decimals: int, signed: bool, width: int
) -> tuple[bool, str, int, str]:
    """(negative, first field, minutes, seconds) of ``value`` rounded once (see
    :func:`sexagesimal`)."""
    scale = 10**decimals
    total = round(abs(value) * 3600.0 * scale)
    if not signed:
        total %= 24 * 3600 * scale  # RA: 23 59 59.999 rounds to 00 00 00.00, not 24
    whole, frac = divmod(total, scale)
    minutes_total, seconds = divmod(whole, 60)
    units, minutes = divmod(minutes_total, 60)
    sec = f"{seconds:02d}" + (f".{frac:0{decimals}d}" if decimals else "")
    return signed and value < 0 and total > 0, f"{units:0{width}d}", minutes, sec


def _astropy_fields(value: float, decimals: int, width: int) -> tuple[bool, str, int, str]:
    """(negative, first field, minutes, seconds) of a finite ``value`` as astropy's
    ``Angle.to_string(precision=decimals, pad=True)`` makes them (its
    ``_decimal_to_sexagesimal_string``, astropy 8; the tests compare with the installed one)."""
    frac, whole = math.modf(abs(value))
    frac_min, minutes = math.modf(frac * 60.0)
    seconds = frac_min * 60.0
    if round(seconds, decimals) >= 60.0:  # Python's round, as astropy's: ties as the text rounds
        seconds, minutes = 0.0, minutes + 1.0
    if minutes >= 60.0:
        minutes, whole = 0.0, whole + 1.0
    sec = f"{seconds:0{decimals + 3 if decimals else 2}.{decimals}f}"
    return math.copysign(1.0, value) < 0, f"{whole:0{width}.0f}", int(minutes), sec
