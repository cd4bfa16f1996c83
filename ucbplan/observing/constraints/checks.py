"""Whether whole blocks satisfy a constraint set: screened on a grid, exact where uncertain.

:func:`evaluate_window` checks a block at start, middle, end and every ≤ 5 min in between;
most samples are decided by each constraint's screen (:meth:`Constraint.screen`, from bounds on
how fast the sky changes), the rest exactly (:func:`evaluate_window_exact`, which tests compare).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ucbplan.observing.constraints import Constraint, NightConstraint, holds
from ucbplan.observing.observatory.sky import SkyModel

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
Int8Array = NDArray[np.int8]

#: Largest spacing between constraint samples inside a block [s].
SAMPLE_STEP_S = 300.0


#: Most samples :func:`evaluate_window` holds in memory at once (blocks x samples per block).
_MAX_SAMPLES = 1_000_000


#: Node spacing of the screening grid of :func:`evaluate_window` [s].
SCREEN_STEP_S = 300.0


def evaluate_window(
    constraints: Iterable[Constraint],
    sky: SkyModel,
    i: int,
    x_start: FloatArray,
    x_end: FloatArray,
) -> tuple[BoolArray, NDArray[np.int64]]:
    """Check every constraint over whole blocks [x_start, x_end].

    Samples start, middle, end and enough interior points that consecutive samples are at most
    :data:`SAMPLE_STEP_S` apart (altitude is monotonic between samples except near transit, where
    the zenith-hole constraint matters: 5-min sampling resolves a 4° hole for any declination).
    A block fails the first constraint (in iteration order) that fails at one of its samples.

    Many blocks are first screened on a grid of :data:`SCREEN_STEP_S` (:meth:`Constraint.screen`):
    a sample far enough from every limit, given how fast the sky changes, has a certain answer;
    only the others are checked exactly. The result is the exact one
    (:func:`evaluate_window_exact`; tests compare the two).

    Returns
    -------
    ok : ndarray of bool
        True where all constraints hold at all samples.
    first_failed : ndarray of int
        Index (in iteration order of ``constraints``) of the first violated constraint, −1
        where ``ok``.
    """
    active = list(constraints)
    xs = np.asarray(x_start, dtype=np.float64)
    xe = np.asarray(x_end, dtype=np.float64)
    if not active or xs.size == 0:
        return np.ones(xs.shape, dtype=bool), np.full(xs.shape, -1, dtype=np.int64)
    if isinstance(active[0], NightConstraint) and xs.ndim == 1:
        maybe = _maybe_dark(active[0], sky, xs, xe)
        if not maybe.all():  # the others certainly fail the night, the first constraint
            ok, first = np.zeros(xs.shape, dtype=bool), np.zeros(xs.shape, dtype=np.int64)
            if maybe.any():
                ok[maybe], first[maybe] = _evaluate_screened(active, sky, i, xs[maybe], xe[maybe])
            return ok, first
    return _evaluate_screened(active, sky, i, xs, xe)


#: Node spacing of the Sun's altitude in :func:`_maybe_dark` [s].
DARK_STEP_S = 600.0


def _maybe_dark(night: NightConstraint, sky: SkyModel, xs: FloatArray, xe: FloatArray) -> BoolArray:
    """Blocks [xs, xe] that may touch the night: not every node from the one at or before
    ``xs`` to the one at or after ``xe`` is certainly in daylight (its screen over ±one node
    spacing), so a block outside it fails the night at every instant (anchor epochs in the day
    are never evaluated further)."""
    lo = float(np.min(xs))
    n = math.ceil((float(np.max(xe)) - lo) / DARK_STEP_S) + 2
    nodes = np.asarray(lo + DARK_STEP_S * np.arange(n), dtype=np.float64)
    day = night.screen(sky, 0, nodes, DARK_STEP_S) == -1
    count = np.concatenate([[0], np.cumsum(~day)])
    j0 = np.floor((xs - lo) / DARK_STEP_S).astype(np.int64)
    j1 = np.minimum(np.ceil((xe - lo) / DARK_STEP_S).astype(np.int64), n - 1)
    return np.asarray(count[j1 + 1] - count[j0] > 0)


def _evaluate_screened(
    active: list[Constraint], sky: SkyModel, i: int, xs: FloatArray, xe: FloatArray
) -> tuple[BoolArray, NDArray[np.int64]]:
    """:func:`evaluate_window` without the daylight shortcut."""
    frac = _sample_fractions(xs, xe)
    lo, hi = float(np.min(xs)), float(np.max(xe))
    n_nodes = math.ceil((hi - lo) / SCREEN_STEP_S) + 1
    if n_nodes > 4 * xs.size * frac.size:  # a few blocks over a long span: check them all
        return evaluate_window_exact(active, sky, i, xs, xe)
    ok = np.ones(xs.shape, dtype=bool)
    first = np.full(xs.shape, -1, dtype=np.int64)
    grid = _ScreenGrid(lo, n_nodes, [None] * len(active))
    step = max(1, _MAX_SAMPLES // frac.size)
    for k in range(0, xs.size, step):
        part = slice(k, k + step)
        ok[part], first[part] = _screened(active, grid, sky, i, xs[part], xe[part], frac)
    return ok, first


@dataclass
class _ScreenGrid:
    """Nodes ``lo + k·SCREEN_STEP_S`` and each constraint's screen there (computed for the
    nodes a chunk of blocks needs, when it first needs them; 2 = not computed yet)."""

    lo: float
    n_nodes: int
    codes: list[Int8Array | None]

    def code(
        self, j: int, c: Constraint, sky: SkyModel, i: int, node: NDArray[np.int64]
    ) -> Int8Array:
        """Constraint ``j``'s screen at grid nodes ``node`` (any shape)."""
        codes = self.codes[j]
        if codes is None:
            codes = self.codes[j] = np.full(self.n_nodes, 2, dtype=np.int8)
        todo = np.zeros(self.n_nodes, dtype=bool)
        todo[node.ravel()] = True
        todo &= codes == 2
        if todo.any():
            at = np.flatnonzero(todo)
            x = np.asarray(self.lo + SCREEN_STEP_S * at, dtype=np.float64)
            codes[at] = c.screen(sky, i, x, SCREEN_STEP_S / 2 + 1e-3)  # nearest-node slack
        return codes[node]


def _sample_fractions(xs: FloatArray, xe: FloatArray) -> FloatArray:
    """Sample positions inside a block (0 = start, 1 = end): an odd count keeps the middle."""
    width = float(np.max(xe - xs))
    n = max(3, math.ceil(width / SAMPLE_STEP_S) + 1)
    if n % 2 == 0:
        n += 1
    return np.linspace(0.0, 1.0, n)


def _screened(
    active: list[Constraint],
    grid: _ScreenGrid,
    sky: SkyModel,
    i: int,
    xs: FloatArray,
    xe: FloatArray,
    frac: FloatArray,
) -> tuple[BoolArray, NDArray[np.int64]]:
    """:func:`evaluate_window` for one chunk of blocks, screened on ``grid``.

    A block's screen for a constraint is the least over its samples: −1 (one sample certainly
    fails), 1 (all certainly pass) or 0 (check exactly). Each constraint sees only the blocks
    that passed the ones before it.
    """
    x = xs[:, None] + (xe - xs)[:, None] * frac[None, :]
    node = np.rint((x - grid.lo) / SCREEN_STEP_S).astype(np.int64)
    ok = np.ones(xs.shape, dtype=bool)
    first = np.full(xs.shape, -1, dtype=np.int64)
    pend = np.arange(xs.size)
    for j, c in enumerate(active):
        at = grid.code(j, c, sky, i, node[pend])
        least = at[:, 0].copy()
        for k in range(1, at.shape[1]):
            np.minimum(least, at[:, k], out=least)
        fails = least == -1
        unsure = np.flatnonzero(least == 0)
        if unsure.size:
            fails[unsure] = ~np.all(holds(c, sky, i, x[pend[unsure]]), axis=1)
        first[pend[fails]] = j
        ok[pend[fails]] = False
        pend = pend[~fails]
    return ok, first


def evaluate_window_exact(
    constraints: Iterable[Constraint],
    sky: SkyModel,
    i: int,
    x_start: FloatArray,
    x_end: FloatArray,
) -> tuple[BoolArray, NDArray[np.int64]]:
    """:func:`evaluate_window` evaluating every constraint at every sample (no screening)."""
    active = list(constraints)
    xs = np.asarray(x_start, dtype=np.float64)
    xe = np.asarray(x_end, dtype=np.float64)
    ok = np.ones(xs.shape, dtype=bool)
    first = np.full(xs.shape, -1, dtype=np.int64)
    if not active or xs.size == 0:
        return ok, first
    frac = _sample_fractions(xs, xe)
    step = max(1, _MAX_SAMPLES // frac.size)
    for k in range(0, xs.size, step):
        idx = np.arange(k, min(k + step, xs.size))
        for j, c in enumerate(active):
            idx = idx[ok[idx]]  # blocks that passed every constraint so far
            x = xs[idx, None] + (xe - xs)[idx, None] * frac[None, :]
            fails = idx[~np.all(holds(c, sky, i, x), axis=1)]
            first[fails] = j
            ok[fails] = False
    return ok, first
