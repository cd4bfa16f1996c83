"""Hypothesis strategies shared by the property tests."""

from __future__ import annotations

from astropy import units as u
from hypothesis import strategies as st

_ANY = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(-(10**12), 10**12),
    st.text(max_size=12),
    st.none(),
    st.booleans(),
    st.builds(
        lambda v, unit: v * unit,
        st.floats(-1e3, 1e3),
        st.sampled_from([u.deg, u.rad, u.m, u.s, u.one]),
    ),
)
