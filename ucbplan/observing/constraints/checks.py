"""Whether whole blocks satisfy a constraint set: screened on a grid, exact where uncertain.

:func:`evaluate_window` checks a block at start, middle, end and every ≤ 5 min in between;
most samples are decided by each constraint's screen (:meth:`Constraint.screen`, from bounds on
how fast the sky changes), the rest exactly (:func:`evaluate_window_exact`, which tests compare).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, field

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
    night: NightScreens | None = None,
) -> tuple[BoolArray, NDArray[np.int64]]:
    """Check every constraint over whole blocks [x_start, x_end].

    Samples start, middle, end and enough interior points that consecutive samples are at most
    :data:`SAMPLE_STEP_S` apart (altitude is monotonic between samples except near transit, where
    the zenith-hole constraint matters: 5-min sampling resolves a 4° hole for any declination).
    A block fails the first constraint (in iteration order) that fails at one of its samples.

    Many blocks are first screened on a grid of :data:`SCREEN_STEP_S` (:meth:`Constraint.screen`):
    a sample far enough from every limit, given how fast the sky changes, has a certain answer;
    only the others are checked exactly. The result is the exact one
    (:func:`evaluate_window_exact`; tests compare the two). ``night``: the screens of the first
    constraint (a :class:`NightConstraint`, the same for every target), shared by the targets
    of a run (:class:`NightScreens`); the answer is the same with or without.

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
    if not isinstance(active[0], NightConstraint) or xs.ndim != 1:
        return _evaluate_screened(active, sky, i, xs, xe)
    if night is None or night.night != active[0] or night.sky is not sky:
        night = NightScreens(active[0], sky)
    maybe = _maybe_dark(night.dark, xs, xe)
    if not maybe.all():  # the others certainly fail the night, the first constraint
        ok, first = np.zeros(xs.shape, dtype=bool), np.zeros(xs.shape, dtype=np.int64)
        if maybe.any():
            ok[maybe], first[maybe] = _evaluate_screened(
                active, sky, i, xs[maybe], xe[maybe], night.screen
            )
        return ok, first
    return _evaluate_screened(active, sky, i, xs, xe, night.screen)


@dataclass
class LatticeScreen:
    """One constraint's screen (:meth:`Constraint.screen`, over ±``slack_s``) at the nodes
    ``k·step_s`` of the plan's axis, computed for the nodes asked for when first asked: a
    constraint that is the same for every target (the night) is screened once per run.

    ``codes[k − k0]`` is node k's screen (2: not computed yet)."""

    constraint: Constraint
    sky: SkyModel
    step_s: float
    slack_s: float
    k0: int = 0
    codes: Int8Array = field(default_factory=lambda: np.zeros(0, dtype=np.int8))

    def at(self, k: NDArray[np.int64], offset: int = 0) -> Int8Array:
        """The screen at nodes ``k + offset`` (any shape). Nodes already screened (every one
        for a run's later targets) are only looked up."""
        if k.size == 0:
            return np.zeros(k.shape, dtype=np.int8)
        self._cover(int(np.min(k)) + offset, int(np.max(k)) + offset)
        idx = k + (offset - self.k0)
        got = self.codes[idx]
        missing = got == 2
        if missing.any():
            todo = np.zeros(self.codes.size, dtype=bool)
            todo[idx[missing]] = True
            at = np.flatnonzero(todo)
            x = np.asarray(self.step_s * (at + self.k0), dtype=np.float64)
            self.codes[at] = self.constraint.screen(self.sky, 0, x, self.slack_s)
            got = self.codes[idx]
        return got

    def _cover(self, lo: int, hi: int) -> None:
        """Extend ``codes`` (not computed) to hold nodes ``lo`` … ``hi``."""
        k1 = self.k0 + self.codes.size - 1
        if self.codes.size and lo >= self.k0 and hi <= k1:
            return
        new_k0 = min(lo, self.k0) if self.codes.size else lo
        new_k1 = max(hi, k1) if self.codes.size else hi
        codes = np.full(new_k1 - new_k0 + 1, 2, dtype=np.int8)
        codes[self.k0 - new_k0 : self.k0 - new_k0 + self.codes.size] = self.codes
        self.k0, self.codes = new_k0, codes


class NightScreens:
    """The night's screens shared by the targets of a run: on the :data:`DARK_STEP_S` nodes
    (blocks that may touch the night) and on the :data:`SCREEN_STEP_S` nodes (samples), of
    one sky model."""

    def __init__(self, night: NightConstraint, sky: SkyModel) -> None:
        self.night, self.sky = night, sky
        self.dark = LatticeScreen(night, sky, DARK_STEP_S, DARK_STEP_S)
        self.screen = LatticeScreen(night, sky, SCREEN_STEP_S, SCREEN_STEP_S / 2 + 1e-3)


#: Node spacing of the Sun's altitude in :func:`_maybe_dark` [s].
DARK_STEP_S = 600.0


def _maybe_dark(dark: LatticeScreen, xs: FloatArray, xe: FloatArray) -> BoolArray:
    """Blocks [xs, xe] that may touch the night: not every node from the one at or before
    ``xs`` to the one at or after ``xe`` is certainly in daylight (its screen over ±one node
    spacing, ``dark``), so a block outside it fails the night at every instant (anchor epochs
    in the day are never evaluated further)."""
    j0 = np.floor(xs / dark.step_s).astype(np.int64)
    j1 = np.ceil(xe / dark.step_s).astype(np.int64)
    lo = int(np.min(j0))
    day = dark.at(np.arange(lo, int(np.max(j1)) + 1, dtype=np.int64)) == -1
    count = np.concatenate([[0], np.cumsum(~day)])
    return np.asarray(count[j1 - lo + 1] - count[j0 - lo] > 0)


def _evaluate_screened(
    active: list[Constraint],
    sky: SkyModel,
    i: int,
    xs: FloatArray,
    xe: FloatArray,
    shared: LatticeScreen | None = None,
) -> tuple[BoolArray, NDArray[np.int64]]:
    """:func:`evaluate_window` without the daylight shortcut; ``shared``: the first
    constraint's screen on the :data:`SCREEN_STEP_S` nodes of the plan's axis."""
    frac = _sample_fractions(xs, xe)
    lo, hi = float(np.min(xs)), float(np.max(xe))
    if shared is not None:  # the shared screen's nodes: multiples of SCREEN_STEP_S
        lo = SCREEN_STEP_S * math.floor(lo / SCREEN_STEP_S)
    n_nodes = math.ceil((hi - lo) / SCREEN_STEP_S) + 1
    if n_nodes > 4 * xs.size * frac.size:  # a few blocks over a long span: check them all
        return evaluate_window_exact(active, sky, i, xs, xe)
    if np.array_equal(xs, xe):  # instants: every sample is the same, x = xs + 0·frac
        frac = frac[:1]
    ok = np.ones(xs.shape, dtype=bool)
    first = np.full(xs.shape, -1, dtype=np.int64)
    grid = _ScreenGrid(lo, n_nodes, [None] * len(active), shared)
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
    #: The first constraint's screen on the plan axis's nodes, shared by a run's targets.
    shared: LatticeScreen | None = None

    def code(
        self, j: int, c: Constraint, sky: SkyModel, i: int, node: NDArray[np.int64]
    ) -> Int8Array:
        """Constraint ``j``'s screen at grid nodes ``node`` (any shape)."""
        if j == 0 and self.shared is not None:
            k0 = round(self.lo / SCREEN_STEP_S)  # lo is a node of the plan's axis here
            return self.shared.at(node, k0)
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
        at = grid.code(j, c, sky, i, node if pend.size == xs.size else node[pend])
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
