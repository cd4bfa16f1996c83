"""Column readers of :mod:`~ucbplan.targets.columnwise`: one field of many target documents
read at once, each value as the one-file readers (:mod:`~ucbplan.targets.values`) read it and
each check run once over the column; a value they do not take is None and fails, and its
document then goes the one-file way, which gives the message.
"""

from __future__ import annotations

from collections.abc import Hashable
from typing import Any

import numpy as np
from astropy.time import Time
from numpy.typing import NDArray

from ucbplan.errors import TargetFileError
from ucbplan.targets.fastvalues import quantity_in
from ucbplan.targets.fieldtypes import Field
from ucbplan.targets.schema import field
from ucbplan.targets.values import (
    MALFORMED,
    MAX_VALUE_CHARS,
    Ctx,
    fast_angle_deg,
    parse_epoch,
    to_float,
)

BoolArray = NDArray[np.bool_]
#: A column: each document's value (None: not read) and which documents pass its checks.
Column = tuple[list[Any], BoolArray]
#: A field absent from its mapping.
ABSENT = object()


def quantities(sections: list[dict[str, Any]], f: Field) -> Column:
    """Field ``f`` of each section as ``parse_quantity`` reads it and ``check_range`` checks it
    (absent: its default)."""
    unit = f.unit
    assert unit is not None, f.path
    raws = [s.get(f.name, ABSENT) for s in sections]
    values = [f.default if raw is ABSENT else quantity(raw, unit, f.unit_required) for raw in raws]
    return values, in_range(values, [raw is not ABSENT for raw in raws], f)


def quantity(raw: Any, unit: str, unit_required: bool) -> float | None:
    """``parse_quantity``'s value where it takes the common spellings (a number with a unit, a
    YAML number); None: the one-file path reads it."""
    kind = type(raw)
    if kind is str:
        return quantity_in(raw, unit) if len(raw) <= MAX_VALUE_CHARS else None
    if unit_required or (kind is not float and kind is not int):
        return None
    try:
        return float(raw)
    except OverflowError:
        return None


def in_range(values: list[Any], given: list[bool], f: Field) -> BoolArray:
    """Which values pass: absent, or finite and inside ``f.bounds`` (None fails)."""
    x = np.array([np.nan if v is None else v for v in values], dtype=np.float64)
    ok = np.isfinite(x)
    b = f.bounds
    if b is not None:
        with np.errstate(invalid="ignore"):
            ok &= (x > b.low) if b.low_open else (x >= b.low)
            ok &= (x < b.high) if b.high_open else (x <= b.high)
    return ok | ~np.array(given, dtype=bool)


def angles(sky: list[dict[str, Any]], f: Field, hours: bool) -> Column:
    """``sky.ra`` (``hours``) or ``sky.dec`` in degrees, as ``parse_angle`` reads them."""
    values = [_angle(s[f.name], hours) for s in sky]
    return values, in_range(values, [True] * len(values), f)


def _angle(raw: Any, hours: bool) -> float | None:
    if type(raw) is str and len(raw) > MAX_VALUE_CHARS:
        return None
    try:
        return fast_angle_deg(raw, hours)
    except ValueError:
        return None


def numbers(docs: list[dict[str, Any]], f: Field) -> Column:
    """A plain number at the top level (absent: its default), as ``number`` reads it."""
    raws = [doc.get(f.name, ABSENT) for doc in docs]
    values = [f.default if raw is ABSENT else _number(raw) for raw in raws]
    return values, in_range(values, [raw is not ABSENT for raw in raws], f)


def _number(raw: Any) -> float | None:
    try:
        return to_float(raw)
    except ValueError:
        return None


def choices(sections: list[dict[str, Any]], f: Field, only: str | None = None) -> Column:
    """A choice (absent: its default) as the schema spells it, as ``parse_choice`` reads it;
    ``only``: the one choice the columns take."""
    values = [_choice(s.get(f.name, f.default), f.choices) for s in sections]
    good = [v is not None and (only is None or v == only) for v in values]
    return values, np.array(good, dtype=bool)


def _choice(raw: Any, choices: tuple[str, ...]) -> str | None:
    if type(raw) is not str or len(raw) > MAX_VALUE_CHARS:
        return None
    text = raw.strip().lower()
    for choice in choices:
        if choice.lower() == text:
            return choice
    return None


def epochs(raws: list[Any]) -> Column:
    """``lisa.t_ref`` as TDB, read once per distinct value (each target takes a copy, as
    ``parse_epoch`` hands it out); None: not a TDB epoch (the one-file path reads or refuses
    it)."""
    f = field("lisa.t_ref")
    read: dict[tuple[type, Hashable], Time | None] = {}
    values: list[Time | None] = []
    for raw in raws:
        if not isinstance(raw, Hashable):
            values.append(None)
            continue
        key = (type(raw), raw)
        if key not in read:
            read[key] = _epoch(f, raw)
        values.append(read[key])
    return values, np.array([v is not None for v in values], dtype=bool)


def _epoch(f: Field, raw: Any) -> Time | None:
    try:
        tdb, converted = parse_epoch(Ctx(None), f, raw, None)
    except (TargetFileError, *MALFORMED):
        return None
    return tdb if converted is None else None
