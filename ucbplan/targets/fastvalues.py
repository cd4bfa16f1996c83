"""The common spellings of quantities, angles and epochs, read without astropy's parsers.

A target file's values are almost always written the same few ways: ``"6.2e-3 Hz"``,
``"08h06m23.2s"``, ``"+15d27m30s"``, ``"2037-01-01T00:00:00"``. astropy reads each through its
general parsers (a yacc grammar per unit string and per angle), which cost most of the time a
target takes to load. The readers here give the very same float for those spellings:

- a unit string is parsed by astropy once per distinct string, and its scale to the field's unit
  kept (:func:`quantity_in`), so a number with a unit is then one multiplication, as astropy's
  ``Quantity(text).to_value(unit)`` does it;
- sexagesimal ``12h34m56.7s``, ``-12d34m56.7s`` and ``12:34:56.7`` are summed with astropy's
  operations in astropy's order (:func:`sexagesimal_deg`);
- an epoch text is converted by astropy once per distinct text and scale, and a copy of that
  :class:`~astropy.time.Time` handed out (:func:`cached_epoch`).

Each returns None for anything else (and for values astropy would warn about or refuse), and the
caller then goes astropy's way, which gives every message.
``tests/targets/test_target_fastvalues.py`` checks the results bit for bit against astropy.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable

from astropy import units as u
from astropy.time import Time
from astropy.units.utils import is_effectively_unity

#: Most distinct entries each cache keeps (a catalog uses a handful of unit strings).
CACHE_SIZE = 1024

#: A decimal number (astropy's number pattern without nan, inf and vectors), then its unit: the
#: lookahead refuses a split where astropy's greedy pattern would take more characters.
_QUANTITY = re.compile(
    r"\s*([+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)(?![.+\-\d]|[eE][+-]?\d)\s*(.*?)\s*"
)
#: The number of :data:`_QUANTITY` alone.
_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")
#: ``12h34m56.7s`` / ``-12d34m56.7s`` / ``12:34:56.7`` (no spaces, no exponent).
_SEXAGESIMAL = re.compile(r"([+-]?)(\d+)([hd:])(\d+)([m:])(\d+(?:\.\d*)?|\.\d+)(s?)")

#: Degrees per hour of angle as astropy converts them (14.999999999999998, not 15).
_HOURANGLE_DEG: float = u.hourangle._to(u.deg)

_scales: dict[tuple[str, str], float] = {}
_epochs: dict[tuple[str, str, bool], Time] = {}


def _scale(unit_text: str, unit: str) -> float | None:
    """Factor from ``unit_text`` to ``unit`` (astropy's; 1.0 where astropy takes the value as
    is), None if astropy must decide."""
    key = (unit_text, unit)
    scale = _scales.get(key)
    if scale is None:
        try:
            given = u.Unit(unit_text)
            found = given._to(u.Unit(unit))  # the scale Quantity.to_value multiplies by
        except Exception:  # astropy's own path reports it
            return None
        if not isinstance(found, float) or not math.isfinite(found):
            return None
        scale = 1.0 if is_effectively_unity(found) else float(found)
        if len(_scales) < CACHE_SIZE:
            _scales[key] = scale
    return scale


def quantity_in(text: str, unit: str) -> float | None:
    """``Quantity(text).to_value(unit)`` for ``"<decimal number> <unit string>"``, or None.

    None: not that spelling (a bare number included), or a unit astropy does not convert to
    ``unit`` directly.
    """
    split = _split_quantity(text)
    if split is None or not split[1] or "[" in text:
        return None  # a bare number (the caller reads it), or not astropy's split
    scale = _scale(split[1], unit)
    if scale is None:
        return None
    x = float(split[0])
    return x if scale == 1.0 else x * scale


def _split_quantity(text: str) -> tuple[str, str] | None:
    """``(number, unit)`` as :data:`_QUANTITY` splits ``text`` (None: no match): the usual
    ``"<number> <unit>"``, one space between and none around, without the regular expression
    (the number is all before the space, so the greedy pattern takes the same split)."""
    number, space, rest = text.partition(" ")
    if space and rest and _NUMBER.fullmatch(number) and rest == rest.strip() and "\n" not in rest:
        return number, rest
    m = _QUANTITY.fullmatch(text)
    return None if m is None else (m.group(1), m.group(2))


def sexagesimal_deg(text: str, hours: bool) -> float | None:
    """Degrees of ``12h34m56.7s`` (hours), ``-12d34m56.7s`` (degrees) or ``12:34:56.7`` (hours
    if ``hours``), summed as :class:`astropy.coordinates.Angle` does; None for other text or
    fields astropy warns about (minutes or seconds ≥ 60, hours ≥ 24)."""
    m = _SEXAGESIMAL.fullmatch(text)
    if m is None:
        return None
    sign, first, sep1, minutes, sep2, seconds, sec_mark = m.groups()
    if (sep1 == ":") != (sep2 == ":") or (sep1 == ":") == bool(sec_mark):
        return None
    in_hours = sep1 == "h" or (sep1 == ":" and hours)
    lead = (-1.0 if sign == "-" else 1.0) * int(first)
    mins = int(minutes)
    secs = float(seconds) if "." in seconds else int(seconds)
    if mins >= 60 or secs >= 60 or (in_hours and abs(lead) >= 24):
        return None
    value = math.copysign(abs(lead) + mins / 60.0 + secs / 3600.0, lead)
    return value * _HOURANGLE_DEG if in_hours else value


def cached_epoch(text: str, scale: str, isot_if_t: bool, read: Callable[[], Time]) -> Time:
    """A copy of ``read()`` (the epoch ``text`` in ``scale`` as TDB), read once per distinct
    (text, scale) of a run; ``read`` raises for a bad epoch, which is then not kept."""
    key = (text, scale, isot_if_t)
    found = _epochs.get(key)
    if found is None:
        found = read()
        if len(_epochs) < CACHE_SIZE:
            _epochs[key] = found
    return found.copy()
