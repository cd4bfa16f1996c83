"""The reduce report's JSON writer: the text of ucbplan.io.dumps_json byte for byte.

The reference is the library's one JSON rule (json.dumps(indent=2) after json_plain), so every
test compares the two texts exactly: any difference, a space, a digit or a ``null``, fails.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ucbplan.io import dumps_json
from ucbplan.reduce.jsontext import dumps_report

_scalars = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(min_value=-(2**70), max_value=2**70),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=8),  # unicode, quotes, control characters: escaped to ASCII
    st.floats(allow_nan=True, allow_infinity=True).map(np.float64),
    st.integers(min_value=-(2**62), max_value=2**62).map(np.int64),
    st.booleans().map(np.bool_),
)
_keys = st.one_of(st.text(max_size=6), st.integers(-5, 5), st.floats(allow_nan=False))
_docs = st.recursive(
    _scalars,
    lambda inner: st.one_of(
        st.lists(inner, max_size=4),
        st.lists(inner, max_size=4).map(tuple),
        st.dictionaries(_keys, inner, max_size=4),
    ),
    max_leaves=30,
)


@settings(max_examples=300, deadline=None)
@given(_docs)
def test_same_text_as_dumps_json(doc: object) -> None:
    assert dumps_report(doc) == dumps_json(doc)


def test_keys_equal_as_text_merge_as_json_plain_merges_them() -> None:
    """A key and another whose text is the same ("0" and 0) are one JSON key, the last value
    kept at the first one's place, as io.json_plain makes them (hypothesis found it)."""
    doc = {"0": None, 0: 1.5, "a": {1: "x", "1": "y"}}
    assert dumps_report(doc) == dumps_json(doc) == '{\n  "0": 1.5,\n  "a": {\n    "1": "y"\n  }\n}'


def test_non_text_key_after_nested_values() -> None:
    """A mapping whose first non-text key comes after nested values is written again from its
    start with text keys (the pieces already written for it are dropped)."""
    doc = {"x": [{"a": {"b": 1.0}, "c": [1, 2], 3: "x", "3": np.nan}], "y": {2.5: 0}}
    assert dumps_report(doc) == dumps_json(doc)
    assert json.loads(dumps_report(doc)) == {"x": [{"a": {"b": 1.0}, "c": [1, 2], "3": None}],
                                             "y": {"2.5": 0}}  # fmt: skip


def test_numpy_arrays_and_non_finite_values() -> None:
    doc = {
        "a": np.array([1.5, np.nan, -np.inf]),
        "b": np.arange(3),
        "c": {"d": [], "e": {}, "f": (math.inf, np.float32(0.1))},
        1: np.array([[1.0, 2.0], [3.0, 4.0]]),
    }
    text = dumps_report(doc)
    assert text == dumps_json(doc)
    assert json.loads(text)["a"] == [1.5, None, None]


def test_unsupported_value_is_the_reference_error() -> None:
    """A value json_default refuses: the same error as the reference, nothing written."""
    with pytest.raises(TypeError, match="not JSON serialisable: PosixPath"):
        dumps_report({"path": Path("x")})


_leaves = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.none(),
    st.text(max_size=6),
    st.integers(-3, 3),  # not a pair's value: the item goes to the general writer
    st.floats(allow_nan=False).map(np.float64),
)


def _q(draw: st.DrawFn, keys: tuple[str, ...]) -> dict[str, object]:
    return {k: draw(_leaves) for k in keys}


@st.composite
def _pair_docs(draw: st.DrawFn) -> dict[str, object]:
    """Fixed-u pair documents of the report's shape (1 or 2 components), sometimes bent."""
    q = ("value", "sigma", "unit")
    doc = {
        "alpha": draw(_leaves),
        "beta": draw(_leaves),
        "u_star_rad": draw(_leaves),
        "dT": _q(draw, q),
        "dv": [_q(draw, q) for _ in range(draw(st.integers(1, 2)))],
        "dkappa_spec": _q(draw, q),
        "dkappa_lisa": _q(draw, q),
        "dkappa_significance": draw(_leaves),
        "dv_cm": _q(draw, (*q, "upper_limit")),
    }
    bend = draw(st.integers(0, 5))
    if bend == 1:
        doc["extra"] = 1.0  # another key: not the template's shape
    elif bend == 2:
        doc["dT"] = {"sigma": 0.0, "value": 1.0, "unit": "d"}  # the keys in another order
    elif bend == 3:
        doc["dv"] = tuple(doc["dv"])  # type: ignore[arg-type]
    return doc


@settings(max_examples=300, deadline=None)
@given(st.lists(_pair_docs(), max_size=6), st.integers(0, 3))
def test_pairs_from_their_template_are_the_general_text(pairs: list, depth: int) -> None:
    """Pair documents written from the report's template (report._PairText, one per nesting
    level and component count) give dumps_json's text, whatever their values; documents of
    another shape or with other values fall back to the general writer."""
    from ucbplan.reduce.report import _PairText

    doc: dict[str, object] = {"drifts": {"n_groups": 3, "pairs": pairs}}
    for _ in range(depth):
        doc = {"x": [doc]}
    assert dumps_report(doc, {"pairs": _PairText()}) == dumps_json(doc)


def test_a_report_with_pairs_is_the_general_text() -> None:
    """The bundled example's report (fixed-u pairs of two components) through write_json: the
    text of dumps_json, byte for byte."""
    import io

    from ucbplan.api.reduction import reduce
    from ucbplan.reduce.report import write_json

    root = Path(__file__).resolve().parents[2] / "catalogs"
    rep = reduce(
        root / "fiducial-eccentric.yaml",
        root / "fiducial-eccentric-velocities.csv",
        1,
        samples=2000,
        warn=False,
    )
    doc = rep._doc
    assert doc["drifts"]["pairs"]
    out = io.StringIO()
    write_json(doc, out)
    assert out.getvalue() == dumps_json(doc) + "\n"
