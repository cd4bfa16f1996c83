"""Hypothesis strategies shared by the property tests."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from astropy import units as u
from hypothesis import strategies as st
from hypothesis.strategies import SearchStrategy


def any_value(
    *,
    integers: int = 10**12,
    text: int = 12,
    more: Sequence[SearchStrategy[Any]] = (),
    units: Sequence[u.UnitBase] = (),
    magnitude: float = 1e3,
) -> SearchStrategy[Any]:
    """Any value a caller might pass to a public function: the API tests' "anything" argument.

    Parameters
    ----------
    integers : int
        Integers are drawn in [-integers, integers].
    text : int
        Longest drawn string [characters].
    more : sequence of SearchStrategy
        Further strategies, drawn after the plain values (lists, dictionaries, …).
    units : sequence of astropy units
        If given, quantities ``v * unit`` with |v| ≤ ``magnitude`` are drawn last.
    magnitude : float
        Largest |v| of a drawn quantity, in its unit.

    Returns
    -------
    SearchStrategy
        Floats (NaN and ±inf included), integers, text, None, booleans, ``more``, quantities.
    """
    parts: list[SearchStrategy[Any]] = [
        st.floats(allow_nan=True, allow_infinity=True),
        st.integers(-integers, integers),
        st.text(max_size=text),
        st.none(),
        st.booleans(),
        *more,
    ]
    if units:
        quantity = st.builds(
            lambda v, unit: v * unit, st.floats(-magnitude, magnitude), st.sampled_from(list(units))
        )
        parts.append(quantity)
    return st.one_of(*parts)
