"""Range checks for observing option values, site fields and blocks-table cells.

Each check refuses a value in one line that names the option (or field), the allowed range with
its unit, the reason, and the value found (shortened). They complement
:func:`ucbplan.inputs.check_number` (an open lower bound) with closed ranges, since many
observing values may be exactly 0 (``--readout 0``, ``--moon-sep 0``) or exactly the bound.
"""

from __future__ import annotations

import math
from typing import Any, TypeGuard

import numpy as np

from ucbplan.errors import InputError, shorten

__all__ = ["check_int", "check_range", "is_number"]


def is_number(value: Any) -> TypeGuard[int | float | np.integer[Any] | np.floating[Any]]:
    """A real number (``int`` or ``float``, numpy scalars included), not a bool."""
    if isinstance(value, bool | np.bool_):
        return False
    return isinstance(value, int | float | np.integer | np.floating)


def _suffix(unit: str, why: str) -> str:
    return (f" {unit}" if unit else "") + (f" ({why})" if why else "")


def check_range(
    name: str,
    value: Any,
    low: float,
    high: float,
    unit: str = "",
    why: str = "",
    *,
    low_open: bool = False,
    error: type[InputError] = InputError,
) -> float:
    """``value`` as a float if it is a finite number with ``low <= value <= high``
    (``low < value`` with ``low_open``).

    Raises
    ------
    InputError
        (or ``error``) One line: ``NAME: expected a number in [LOW, HIGH] UNIT (WHY), got V``.
    """
    ok = is_number(value) and math.isfinite(float(value))
    ok = ok and (low < float(value) if low_open else low <= float(value)) and float(value) <= high
    if not ok:
        bracket = "(" if low_open else "["
        raise error(
            f"{name}: expected a number in {bracket}{low:g}, {high:g}]{_suffix(unit, why)}, "
            f"got {shorten(value, 40)}"
        )
    return float(value)


def check_int(
    name: str,
    value: Any,
    low: int,
    high: int,
    why: str = "",
    *,
    error: type[InputError] = InputError,
) -> int:
    """``value`` as an int if it is a whole number with ``low <= value <= high``.

    Raises
    ------
    InputError
        (or ``error``) One line: ``NAME: expected a whole number in [LOW, HIGH] (WHY), got V``.
    """
    ok = is_number(value) and math.isfinite(float(value)) and float(value) == int(value)
    if not (ok and low <= int(value) <= high):
        raise error(
            f"{name}: expected a whole number in [{low}, {high}]{_suffix('', why)}, "
            f"got {shorten(value, 40)}"
        )
    return int(value)
