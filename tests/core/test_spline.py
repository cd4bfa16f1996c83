"""The observing code's cubic spline (issue 34): scipy's ``CubicSpline`` numbers bit for bit
(the plans it interpolates for stay byte-identical), an exact cubic reproduced, bad input
refused."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.interpolate import CubicSpline as ScipySpline

from ucbplan.core import spline as spline_module
from ucbplan.core.spline import CubicSpline, splines


def _evaluation_points(x: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Random points inside and beyond the nodes, the nodes themselves, and a NaN."""
    span = x[-1] - x[0]
    inside = rng.uniform(x[0] - 0.2 * span, x[-1] + 0.2 * span, 64)
    return np.concatenate([inside, x, [np.nan]])


@settings(max_examples=150, deadline=None)
@given(
    n=st.integers(min_value=2, max_value=40),
    k=st.integers(min_value=0, max_value=6),
    spread=st.floats(min_value=0.0, max_value=4.0),
    scale=st.floats(min_value=-6.0, max_value=12.0),
    seed=st.integers(min_value=0, max_value=2**32 - 1),
)
def test_equals_scipys_cubic_spline_bit_for_bit(
    n: int, k: int, spread: float, scale: float, seed: int
) -> None:
    """Nodes spaced evenly or up to 10⁴× unevenly (row interchanges in the elimination),
    values of any magnitude, one-dimensional (k = 0) or k columns; evaluated inside, at and
    beyond the nodes and at NaN."""
    rng = np.random.default_rng(seed)
    x = rng.normal() * 1e3 + np.cumsum(10 ** rng.uniform(0.0, spread, n))
    y = rng.normal(size=(n, k) if k else n) * 10**scale
    at = _evaluation_points(x, rng)
    np.testing.assert_array_equal(CubicSpline(x, y)(at), ScipySpline(x, y)(at))


def test_row_interchanges_are_exercised_and_give_scipys_numbers() -> None:
    """A node spacing that jumps ×100 makes the elimination interchange rows (the not-a-knot
    end rows are not diagonally dominant there)."""
    x = np.array([0.0, 1.0, 2.0, 200.0, 201.0, 202.0, 400.0, 401.0])
    y = np.sin(x)[:, None] * [1.0, -3.0]
    dl, d, du, _ = spline_module._system(x, y)
    assert spline_module._eliminate(dl, d, du)[1]  # rows interchanged
    at = _evaluation_points(x, np.random.default_rng(1))
    np.testing.assert_array_equal(CubicSpline(x, y)(at), ScipySpline(x, y, axis=0)(at))


@pytest.mark.parametrize("n", [4, 5, 37, 2201])
def test_splines_on_shared_nodes_equal_each_alone(n: int) -> None:
    """:func:`splines` eliminates once for several value arrays (up to 31 columns, as the
    sky model's): each equals its own spline and scipy's."""
    rng = np.random.default_rng(n)
    x = np.sort(rng.uniform(0.0, 1e6, n))
    ys = [rng.normal(size=n), rng.normal(size=(n, 3)), rng.normal(size=(n, 3)) * 1e11]
    if n < 100:  # many columns, as the sky model's (ten targets)
        ys += [rng.normal(size=(n, 3)) for _ in range(8)]
    at = _evaluation_points(x, rng)
    for shared, y in zip(splines(x, ys), ys, strict=True):
        np.testing.assert_array_equal(shared(at), CubicSpline(x, y)(at))
        np.testing.assert_array_equal(shared(at), ScipySpline(x, y)(at))


def test_an_exact_cubic_is_reproduced() -> None:
    """The not-a-knot spline of a cubic is that cubic (independent of scipy): within 1e-12 of
    its largest value, the rounding of the elimination over 50 nodes."""
    x = np.linspace(-3.0, 5.0, 50) ** 3 / 10.0
    cubic = np.polynomial.Polynomial([2.0, -1.5, 0.25, 0.125])
    at = np.linspace(-4.0, 14.0, 997)
    got = CubicSpline(x, cubic(x))(at)
    np.testing.assert_allclose(got, cubic(at), rtol=0, atol=1e-12 * np.abs(cubic(at)).max())


def test_output_shapes_follow_the_points_and_the_values() -> None:
    x = np.arange(6.0)
    assert CubicSpline(x, np.ones(6))(2.5).shape == ()
    assert CubicSpline(x, np.ones((6, 3)))(np.ones((2, 4))).shape == (2, 4, 3)
    assert CubicSpline(x, np.ones((6, 2, 3)))(np.ones(5)).shape == (5, 2, 3)


@pytest.mark.parametrize(
    ("x", "y", "match"),
    [
        ([0.0, 1.0, 1.0, 2.0], [0.0, 1.0, 2.0, 3.0], "strictly increasing"),
        ([0.0, 2.0, 1.0, 3.0], [0.0, 1.0, 2.0, 3.0], "strictly increasing"),
        ([0.0, 1.0, np.inf, 3.0], [0.0, 1.0, 2.0, 3.0], "finite"),
        ([0.0, 1.0, 2.0, 3.0], [0.0, np.nan, 2.0, 3.0], "finite"),
        ([0.0, 1.0, 2.0, 3.0], [0.0, 1.0, 2.0], "along the nodes"),
        ([0.0], [1.0], "at least two"),
    ],
)
def test_bad_nodes_or_values_are_refused(x: list[float], y: list[float], match: str) -> None:
    with pytest.raises(ValueError, match=match):
        CubicSpline(x, y)


def test_many_points_in_order_are_located_as_one_by_one() -> None:
    """Thousands of ascending points (counted per interval, not searched one by one),
    including repeated points, the nodes themselves and points beyond both ends."""
    rng = np.random.default_rng(7)
    x = np.sort(rng.uniform(0.0, 100.0, 300))
    y = rng.normal(size=(300, 3))
    at = np.sort(np.concatenate([rng.uniform(-10.0, 110.0, 6000), x, x[:50], [x[0] - 1e-9]]))
    assert at.size >= spline_module.SORTED_MIN
    np.testing.assert_array_equal(CubicSpline(x, y)(at), ScipySpline(x, y)(at))
    np.testing.assert_array_equal(CubicSpline(x, y[:, 0])(at), ScipySpline(x, y[:, 0])(at))
