"""Not-a-knot cubic splines: the one interpolant of the observing code (sky model, site track,
light-time delay, TDB − TT).

The planner interpolates slowly varying quantities (apparent places, the Earth's and the site's
positions, the light-time delay, TDB − TT) between exact evaluations at nodes; docs/method.md
states each node spacing and its interpolation error. The spline is the classic one: C²
through the nodes, with the "not-a-knot" condition at both ends (the third derivative is
continuous across the second and the second-to-last node), its node slopes from one tridiagonal
system solved by Gaussian elimination with partial pivoting, and each interval's cubic evaluated
in powers of the offset from its left node.

The arithmetic is written out operation by operation: the system and the coefficients as
``scipy.interpolate.CubicSpline`` forms them, the solve as LAPACK's ``dgtsv``, the evaluation
as scipy's piecewise-polynomial evaluation. With IEEE double arithmetic (no fused
multiply-add), it therefore gives scipy's numbers bit for bit (the test suite compares on
random data), so a plan's output is the same as when the planner called scipy; it is defined
by this module from now on, independently of a scipy version. Written here because
``scipy.interpolate`` costs ~0.3 CPU s to import, most of a planning command's start-up
(issue 34), for an algorithm of a page.

Several splines on one set of nodes share the elimination (:func:`splines`): its multipliers
depend on the nodes alone, and each right-hand side is eliminated with them exactly as on its
own.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]

#: Fewest nodes of the general (tridiagonal) construction; 2 or 3 nodes take scipy's special
#: cases (a line, a parabola), left to scipy itself.
MIN_NODES = 4

#: From this many points in ascending order, evaluation counts them per interval instead of
#: searching for each (a binary search per point costs more from here on).
SORTED_MIN = 2048


def _checked_nodes(x: ArrayLike) -> FloatArray:
    xs = np.asarray(x, dtype=np.float64)
    if xs.ndim != 1 or xs.size < 2:
        raise ValueError("spline nodes must be one-dimensional, at least two")
    if not np.all(np.isfinite(xs)):
        raise ValueError("spline nodes must be finite")
    if np.any(np.diff(xs) <= 0):
        raise ValueError("spline nodes must be strictly increasing")
    return xs


def _system(
    x: FloatArray, y: FloatArray
) -> tuple[list[float], list[float], list[float], FloatArray]:
    """The not-a-knot system for the node slopes: (sub-, main and super-diagonal, right-hand
    sides (n, k)), formed as scipy forms it."""
    dx = np.diff(x)
    dxr = dx[:, None]
    slope = np.diff(y, axis=0) / dxr
    n = x.size
    diag, upper, lower = np.zeros(n), np.zeros(n), np.zeros(n)
    diag[1:-1] = 2 * (dx[:-1] + dx[1:])
    upper[2:] = dx[:-1]
    lower[:-2] = dx[1:]
    b = np.empty_like(y)
    b[1:-1] = 3 * (dxr[1:] * slope[:-1] + dxr[:-1] * slope[1:])
    d = x[2] - x[0]
    diag[0], upper[1] = dx[1], d
    b[0] = ((dxr[0] + 2 * d) * dxr[1] * slope[0] + dxr[0] ** 2 * slope[1]) / d
    d = x[-1] - x[-3]
    diag[-1], lower[-2] = dx[-2], d
    b[-1] = (dxr[-1] ** 2 * slope[-2] + (2 * d + dxr[-1]) * dxr[-2] * slope[-1]) / d
    return lower[:-1].tolist(), diag.tolist(), upper[1:].tolist(), b


Steps = tuple[list[float], list[int]]


def _eliminate(dl: list[float], d: list[float], du: list[float]) -> Steps:
    """``dgtsv``'s forward elimination of the matrix, in place: (each row's multiplier, the
    rows interchanged with the next; the spline's matrix rarely needs any)."""
    n = len(d)
    facts, swapped = [0.0] * (n - 1), []
    di = d[0]
    for i in range(n - 1):
        li = dl[i]
        if abs(di) >= abs(li):
            if di == 0.0:
                raise ValueError("spline system is singular (repeated nodes?)")
            f = li / di
            di = d[i + 1] - f * du[i]
            dl[i] = 0.0
        else:
            f = di / li
            d[i] = li
            temp = d[i + 1]
            di = du[i] - f * temp
            if i < n - 2:
                dl[i] = du[i + 1]
                du[i + 1] = -f * dl[i]
            du[i] = temp
            swapped.append(i)
        d[i + 1] = di
        facts[i] = f
    if d[-1] == 0.0:
        raise ValueError("spline system is singular (repeated nodes?)")
    return facts, swapped


def _forward_column(steps: Steps, b: list[float]) -> list[float]:
    """One right-hand side through the elimination's row operations."""
    facts, swapped = steps
    if not swapped:
        prev = b[0]
        out = [prev]
        for f, bi in zip(facts, b[1:], strict=True):
            prev = bi - f * prev
            out.append(prev)
        return out
    swaps = set(swapped)
    for i, f in enumerate(facts):
        if i in swaps:
            b[i], b[i + 1] = b[i + 1], b[i] - f * b[i + 1]
        else:
            b[i + 1] = b[i + 1] - f * b[i]
    return b


def _solve_column(
    steps: Steps, dl: list[float], d: list[float], du: list[float], b: list[float]
) -> list[float]:
    """One right-hand side through ``dgtsv``'s elimination and back substitution."""
    b = _forward_column(steps, b)
    n = len(d)
    b1 = b[n - 1] / d[n - 1]
    b0 = (b[n - 2] - du[n - 2] * b1) / d[n - 2]
    b[n - 1], b[n - 2] = b1, b0
    for i in range(n - 3, -1, -1):
        b0, b1 = (b[i] - du[i] * b0 - dl[i] * b1) / d[i], b0
        b[i] = b0
    return b


def _node_slopes(x: FloatArray, y: FloatArray) -> FloatArray:
    """The not-a-knot slopes at the nodes, (n, k), for the columns of ``y`` (n, k)."""
    dl, d, du, b = _system(x, y)
    steps = _eliminate(dl, d, du)
    columns = [_solve_column(steps, dl, d, du, col) for col in b.T.tolist()]
    slopes = np.array(columns, dtype=np.float64).T
    if not np.all(np.isfinite(slopes)):
        raise ValueError("spline slopes are not finite")
    return slopes


class CubicSpline:
    """A not-a-knot cubic spline through ``(x, y)``, evaluated by calling it (extrapolating
    each end's cubic beyond the nodes).

    Parameters
    ----------
    x : array_like, shape (n,)
        Nodes, strictly increasing, finite.
    y : array_like, shape (n, ...)
        Values at the nodes (axis 0 runs along ``x``), finite.
    """

    _scipy: Callable[[ArrayLike], ArrayLike] | None = None  # 2 or 3 nodes

    def __init__(self, x: ArrayLike, y: ArrayLike) -> None:
        self.x = _checked_nodes(x)
        values = np.asarray(y, dtype=np.float64)
        if values.ndim == 0 or values.shape[0] != self.x.size:
            raise ValueError("spline values must run along the nodes (axis 0)")
        if not np.all(np.isfinite(values)):
            raise ValueError("spline values must be finite")
        self._shape = values.shape[1:]
        flat = values.reshape(self.x.size, -1)
        if self.x.size < MIN_NODES:
            self._scipy = _scipy_spline(self.x, values)
            return
        self._set(flat, _node_slopes(self.x, flat))

    @classmethod
    def _from_slopes(cls, x: FloatArray, y: FloatArray, slopes: FloatArray) -> CubicSpline:
        out = cls.__new__(cls)
        out.x, out._shape = x, y.shape[1:]
        out._set(y.reshape(x.size, -1), slopes)
        return out

    def __call__(self, x: ArrayLike) -> FloatArray:
        """Values at ``x`` (any shape), shape ``x.shape + y.shape[1:]``."""
        if self._scipy is not None:
            return np.asarray(self._scipy(x), dtype=np.float64)
        xs = np.asarray(x, dtype=np.float64)
        flat = xs.reshape(-1)
        i = self._intervals(flat)
        s = flat - self._left.take(i)
        if self._k > 1:
            s = s[:, None]
        c0, c1, c2, c3 = (c.take(i, axis=0) for c in self._c)
        # ((c0 + c1 s) + c2 s²) + c3 s³, with s³ = s² s: each sum and product as in scipy's
        # evaluation (a sum of two terms is the same either way round)
        c1 *= s
        c0 += c1
        s2 = s * s
        c2 *= s2
        c0 += c2
        s2 *= s
        c3 *= s2
        c0 += c3
        return np.asarray(c0.reshape(xs.shape + self._shape), dtype=np.float64)

    def _intervals(self, flat: FloatArray) -> NDArray[np.intp]:
        """Each point's interval i: x[i] <= x < x[i + 1], the end intervals extended (NaN: the
        last). Many points in order are counted per interval instead of each searched for."""
        if flat.size < SORTED_MIN or not np.all(flat[1:] >= flat[:-1]):  # NaN: not in order
            return self._inner.searchsorted(flat, side="right")
        before = flat.searchsorted(self._inner, side="left")  # points before each inner node
        counts = np.empty(self.x.size - 1, dtype=np.intp)
        counts[0], counts[-1] = before[0], flat.size - before[-1]
        np.subtract(before[1:], before[:-1], out=counts[1:-1])
        return np.repeat(self._interval_numbers, counts)

    def _set(self, y: FloatArray, slopes: FloatArray) -> None:
        """Keep each interval's left node and its cubic's coefficients, lowest power first (the
        constant as ``0.0 + y``: the sum the evaluation starts from), each (n − 1,) or
        (n − 1, k)."""
        c = _coefficients(self.x, y, slopes)  # (n - 1, 4, k), highest power first
        self._k = c.shape[2]
        lowest_first = (0.0 + c[:, 3], c[:, 2], c[:, 1], c[:, 0])
        self._c = tuple(np.ascontiguousarray(a[:, 0] if self._k == 1 else a) for a in lowest_first)
        self._left = self.x[:-1]
        self._inner = self.x[1:-1]
        self._interval_numbers = np.arange(self.x.size - 1)


def _coefficients(x: FloatArray, y: FloatArray, slopes: FloatArray) -> FloatArray:
    """Each interval's cubic in powers of the offset from its left node, highest first:
    (n − 1, 4, k), as scipy's cubic Hermite spline forms them."""
    dxr = np.diff(x)[:, None]
    slope = np.diff(y, axis=0) / dxr
    t = (slopes[:-1] + slopes[1:] - 2 * slope) / dxr
    return np.stack((t / dxr, (slope - slopes[:-1]) / dxr - t, slopes[:-1], y[:-1]), axis=1)


def _scipy_spline(x: FloatArray, y: FloatArray) -> Callable[[ArrayLike], ArrayLike]:
    from scipy.interpolate import CubicSpline as ScipySpline

    return ScipySpline(x, y)


def splines(x: ArrayLike, ys: Sequence[ArrayLike]) -> list[CubicSpline]:
    """:class:`CubicSpline` of each of ``ys`` on the nodes ``x``, the matrix eliminated once:
    each is what ``CubicSpline(x, y)`` gives, bit for bit."""
    xs = _checked_nodes(x)
    arrays = [np.asarray(y, dtype=np.float64) for y in ys]
    if xs.size < MIN_NODES or not arrays:
        return [CubicSpline(xs, y) for y in arrays]
    flats = [y.reshape(xs.size, -1) for y in arrays]
    if any(not np.all(np.isfinite(f)) for f in flats):
        raise ValueError("spline values must be finite")
    stacked = np.concatenate(flats, axis=1)
    slopes = _node_slopes(xs, stacked)
    out, start = [], 0
    for y, flat in zip(arrays, flats, strict=True):
        width = flat.shape[1]
        out.append(CubicSpline._from_slopes(xs, y, slopes[:, start : start + width]))
        start += width
    return out
