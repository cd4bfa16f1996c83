"""Chunked percentiles equal numpy.percentile of the whole sample, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from ucbplan.reduce.quantiles import BracketMissed, ChunkedPercentiles

QS = (15.865525393145708, 50.0, 84.13447460685429)


@pytest.mark.parametrize("n", [1, 2, 7, 1000, 123_457])
@pytest.mark.parametrize("chunk", [1000, 50_000])
def test_equals_numpy(n: int, chunk: int) -> None:
    rng = np.random.default_rng(n + chunk)
    x = rng.lognormal(0, 2, n)
    x[rng.random(n) < 0.01] = np.nan  # dropped, as summarize() drops them
    acc = ChunkedPercentiles(QS, n)
    for s in range(0, n, chunk):
        acc.add(x[s : s + chunk])
    finite = x[np.isfinite(x)]
    ref = np.percentile(finite, QS) if finite.size else [np.nan] * 3
    got = acc.result()
    assert acc.n_finite == finite.size
    np.testing.assert_array_equal(got, ref)


def test_a_biased_first_chunk_is_detected() -> None:
    """A first chunk unlike the rest (not i.i.d.) misses its bracket and says so."""
    acc = ChunkedPercentiles((50.0,), 20_000)
    acc.add(np.arange(10_000.0))
    acc.add(np.arange(10_000.0) + 1e6)
    with pytest.raises(BracketMissed):
        acc.result()
