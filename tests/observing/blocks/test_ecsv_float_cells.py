"""Float cells of the blocks table's ECSV/CSV data lines (issue 34): a column whose values
repeat (a target's coordinates, period and Λ_K on each of its blocks) is formatted once per
distinct value, bit for bit (0.0 and -0.0, NaNs of other payloads apart), and written byte for
byte as astropy's own writer writes it."""

from __future__ import annotations

import io

import numpy as np
from astropy.table import Table
from hypothesis import given
from hypothesis import strategies as st

from ucbplan.observing.blocks.write import _float_texts, write_table

#: Values whose texts differ though they compare equal (0.0, -0.0) or are all "nan", the
#: extremes, and ordinary numbers of several lengths.
POOL = [0.0, -0.0, np.nan, np.inf, -np.inf, 5e-324, 1e16, 1e-5, 0.1, 238.68750448469524, -38.3]


def _payload_nan() -> float:
    """A NaN of another bit pattern than ``np.nan``."""
    return float(np.array([0x7FF8000000000123], dtype=np.uint64).view(np.float64)[0])


@given(
    picks=st.lists(st.integers(0, len(POOL)), min_size=0, max_size=300),
    single=st.booleans(),
)
def test_float_cells_as_str_of_each(picks: list[int], single: bool) -> None:
    """Each cell's text is ``str`` of its value, whether the column repeats (formatted once
    per bit pattern) or not; float32 cells as their Python floats."""
    values = [POOL[k] if k < len(POOL) else _payload_nan() for k in picks]
    data = np.array(values, dtype=np.float32 if single else np.float64)
    table = Table({"x": data})
    assert _float_texts(table["x"]) == list(map(str, data.tolist()))


@given(picks=st.lists(st.integers(0, len(POOL) - 1), min_size=0, max_size=120))
def test_ecsv_of_repeating_floats_as_astropy_writes_it(picks: list[int]) -> None:
    repeated = np.array([POOL[k] for k in picks], dtype=np.float64)
    distinct = np.arange(len(picks), dtype=np.float64) / 7.0  # every value its own
    table = Table({"r": repeated, "d": distinct, "n": np.arange(len(picks))})
    ours, theirs = io.StringIO(), io.StringIO()
    write_table(table, ours, "ecsv")
    table.write(theirs, format="ascii.ecsv")
    assert ours.getvalue() == theirs.getvalue()


def test_zero_and_minus_zero_keep_their_signs() -> None:
    """Half the cells 0.0, half -0.0 (equal as numbers, two texts)."""
    table = Table({"z": np.array([0.0, -0.0] * 50)})
    assert _float_texts(table["z"]) == ["0.0", "-0.0"] * 50
