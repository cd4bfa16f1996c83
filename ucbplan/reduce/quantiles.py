"""Exact percentiles of a sample seen in chunks, in memory that does not grow with its size.

The first chunk brackets each wanted order statistic (its own percentiles ± 8 binomial σ in
rank); every chunk then adds the count of values below the bracket and keeps the values inside
it. At the end the bracket holds the wanted ranks (checked; :class:`BracketMissed` otherwise) and
the percentile is interpolated exactly as ``numpy.percentile`` (method ``linear``) does, so the
summaries equal those of the whole sample held at once.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

F64 = NDArray[np.float64]
#: Half-width of a bracket in binomial standard deviations of the rank.
_MARGIN_SIGMA = 8.0


class BracketMissed(RuntimeError):
    """A bracket from the first chunk did not hold the wanted rank: widen and run again."""


def _virtual_index(n: int, q: float) -> float:
    """numpy's linear-method virtual index (n − 1)·q/100."""
    return float((n - 1) * np.true_divide(q, 100))


def percentile_from_order_stats(a: float, b: float, n: int, q: float) -> float:
    """The ``numpy.percentile(x, q)`` value from its two neighbouring order statistics a ≤ b."""
    vi = _virtual_index(n, q)
    t = np.float64(vi - math.floor(vi))
    diff = np.float64(b) - np.float64(a)
    return float(np.float64(b) - diff * (1 - t) if t >= 0.5 else np.float64(a) + diff * t)


class ChunkedPercentiles:
    """Percentiles ``qs`` [%] of the finite values fed by :meth:`add`, exact.

    Parameters
    ----------
    qs : sequence of float
        Percentiles in [0, 100].
    n_total : int
        Number of values that will be fed in all (finite or not).
    widen : float
        Multiplies the bracket half-width (a retry after :class:`BracketMissed`).
    """

    def __init__(self, qs: Sequence[float], n_total: int, widen: float = 1.0) -> None:
        self.qs = tuple(qs)
        self.n_total = n_total
        self.widen = widen
        self.lo: F64 | None = None
        self.hi: F64 | None = None
        self.below = np.zeros(len(self.qs), dtype=np.int64)
        self.inside: list[list[F64]] = [[] for _ in self.qs]
        self.n_finite = 0

    def _bracket(self, x: F64) -> None:
        m = x.size
        lo, hi = [], []
        for q in self.qs:
            p = q / 100.0
            half = self.widen * (_MARGIN_SIGMA * math.sqrt(m * p * (1 - p)) + 2.0)
            r = p * (m - 1)
            lo_r, hi_r = int(max(r - half, 0)), int(min(math.ceil(r + half), m - 1))
            part = np.partition(x, [lo_r, hi_r])
            lo.append(part[lo_r] if lo_r > 0 else -np.inf)
            hi.append(part[hi_r] if hi_r < m - 1 else np.inf)
        self.lo, self.hi = np.array(lo), np.array(hi)

    def add(self, values: F64) -> None:
        """Feed the next chunk (any shape; non-finite values are ignored)."""
        x = np.asarray(values, dtype=np.float64).ravel()
        x = x[np.isfinite(x)]
        self.n_finite += x.size
        if x.size == 0:
            return
        if self.lo is None:
            self._bracket(x)
        assert self.lo is not None and self.hi is not None
        for i in range(len(self.qs)):
            self.below[i] += np.count_nonzero(x < self.lo[i])
            self.inside[i].append(x[(x >= self.lo[i]) & (x <= self.hi[i])])

    def result(self) -> list[float]:
        """The percentiles; NaN if no finite value was fed.

        Raises
        ------
        BracketMissed
            If a wanted order statistic fell outside its bracket.
        """
        n = self.n_finite
        if n == 0:
            return [math.nan] * len(self.qs)
        out = []
        for i, q in enumerate(self.qs):
            vi = _virtual_index(n, q)
            k = min(max(math.floor(vi), 0), n - 1)
            k1 = min(k + 1, n - 1)
            vals = np.sort(np.concatenate(self.inside[i]))
            j, j1 = k - int(self.below[i]), k1 - int(self.below[i])
            if j < 0 or j1 >= vals.size:
                raise BracketMissed(f"percentile {q}: rank {k} outside its bracket")
            out.append(percentile_from_order_stats(vals[j], vals[j1], n, q))
        return out
