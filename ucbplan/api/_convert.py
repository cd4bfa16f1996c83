"""Units at the edge of the public API: astropy objects or the CLI's strings → SI floats."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from datetime import date, datetime
from typing import Any

from ucbplan.errors import InputError, shorten


@contextmanager
def scope() -> Iterator[None]:
    """Where every public function works: the offline astropy scope (:func:`~ucbplan.offline`),
    which also silences ERFA's "dubious year" and astropy's IERS-range warnings for future
    dates (ucbplan says the same once, in words a user can act on:
    :class:`ucbplan.EarthOrientationWarning`)."""
    from ucbplan.offline import offline

    with offline():
        yield


def as_float(value: Any, unit: str, parameter: str) -> Any:
    """A ``Quantity`` in ``unit`` as a float; anything else unchanged (range checks follow).

    Raises
    ------
    InputError
        For a ``Quantity`` whose unit cannot be converted to ``unit`` (naming ``parameter``).
    """
    to_value = getattr(value, "to_value", None)
    if to_value is None or not hasattr(value, "unit"):
        return value
    from astropy import units as u

    try:
        return float(to_value(u.Unit(unit)))
    except (u.UnitsError, TypeError, ValueError):
        raise InputError(
            f"{parameter}: expected a quantity in {unit} (or a number of {unit}), got "
            f"{shorten(value, 40)}",
            parameter=parameter,
        ) from None


def as_tdb(value: Any, parameter: str) -> Any:
    """An epoch as astropy ``Time`` in TDB: a ``Time`` (any scale) or the CLI's text
    (ISO, ``MJD x``, a trailing scale label; unlabelled text is TDB).

    Raises
    ------
    InputError
        For anything else (naming ``parameter``).
    """
    from astropy.time import Time

    from ucbplan.core.epochs import parse_tdb

    if isinstance(value, Time):
        if not value.isscalar:
            raise InputError(f"{parameter}: expected one epoch, got {value.size}", parameter)
        with scope():
            return value.tdb
    return parse_tdb(value, parameter)


def as_date(value: Any, parameter: str) -> Any:
    """A local evening date: a ``datetime.date``, a ``datetime`` (its date, in its own zone),
    ``YYYY-MM-DD`` text, or an astropy ``Time`` (its calendar date in its own scale)."""
    from astropy.time import Time

    if isinstance(value, datetime):
        return value.date()

    if isinstance(value, Time):
        if not value.isscalar:
            raise InputError(f"{parameter}: expected one date, got {value.size}", parameter)
        with scope():
            return date.fromisoformat(value.isot[:10])
    return value
