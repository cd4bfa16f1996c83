"""Covariances with a dynamic range of 1e40 and strong correlations: draws and inverses are exact.

Regression for issue 11: ``eigh`` on the unscaled covariance drew ḟ with ~90× its σ. The checks
here compare Monte-Carlo moments with the input: with n = 200 000 draws the standard error of a
sample σ is σ/√(2n) ≈ 0.16 % and of a sample correlation (1 − ρ²)/√n ≤ 0.22 %; the tolerances
(1 % on σ, 0.01 on ρ) are > 4 standard errors.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ucbplan.core.mvnormal import (
    _SERIAL_MNK,
    correlation_split,
    inverse_scaled,
    row_blocks,
    rows_times,
    sample_normal,
    sqrt_factor,
)

# σ's of (φ, f, ḟ, f̈, η, κ, ω̇, cos ι, A): realistic LISA sizes, ratio 1e25 .. 1e40 with f̈ shrunk
SIGMAS = np.array([0.02, 7.7e-12, 4.7e-19, 3.7e-27, 1e-3, 1e-3, 1e-9, 0.05, 1e-23])


def _dense_correlation(seed: int, strength: float) -> np.ndarray:
    """Every parameter correlated with every other, plus strong φ–ḟ and (η, κ, ω̇) links."""
    a = np.random.default_rng(seed).standard_normal((9, 9))
    load = np.zeros((9, 2))
    load[[0, 2], 0] = [3.0, -3.0]  # φ_ref – ḟ
    load[[4, 5, 6], 1] = [3.0, 2.5, -2.5]  # η – κ – ω̇
    c = 0.25 * a @ a.T + 4.0 * load @ load.T + strength * np.eye(9)
    d = np.sqrt(np.diag(c))
    return np.asarray(c / np.outer(d, d))


def _realistic(seed: int, strength: float, ratio_extra: float = 1.0) -> np.ndarray:
    sig = SIGMAS.copy()
    sig[3] *= ratio_extra
    return _dense_correlation(seed, strength) * np.outer(sig, sig)


@pytest.mark.parametrize(
    ("seed", "strength", "extra"), [(0, 0.5, 1.0), (40, 0.5, 1e-15), (8, 0.05, 1.0), (3, 5.0, 1.0)]
)
def test_sample_moments_reproduce_covariance(seed: int, strength: float, extra: float) -> None:
    cov = _realistic(seed, strength, extra)
    sig = np.sqrt(np.diag(cov))
    corr = cov / np.outer(sig, sig)
    assert sig.max() / sig.min() >= 1e25  # the dynamic range that breaks a raw decomposition
    if extra < 1e-14:
        assert sig.max() / sig.min() >= 1e40  # the acceptance range
    if strength < 1:
        assert np.abs(corr - np.eye(9)).max() > 0.9  # strong correlations present
    mean = np.arange(9.0) * sig
    x = sample_normal(mean, cov, 200_000, np.random.default_rng(7))
    z = (x - mean) / sig
    np.testing.assert_allclose(x.std(axis=0) / sig, 1.0, rtol=0.01)
    np.testing.assert_allclose(np.corrcoef(z.T), cov / np.outer(sig, sig), atol=0.01)
    np.testing.assert_allclose(z.mean(axis=0), 0.0, atol=0.01)


def test_raw_eigh_would_fail_here() -> None:
    """The same check on a raw eigh factor fails for this matrix: the test can catch the bug."""
    cov = _realistic(40, 0.5)
    sig = np.sqrt(np.diag(cov))
    vals, vecs = np.linalg.eigh(cov)
    raw = vecs * np.sqrt(np.clip(vals, 0, None))
    implied = np.sqrt(np.diag(raw @ raw.T)) / sig
    assert implied.max() > 10.0  # ḟ, f̈ drawn with > 10x their σ by the raw factor


def test_zero_variance_parameter_is_held_fixed() -> None:
    cov = np.diag([1e-20, 0.0, 4.0])
    x = sample_normal([1.0, 2.0, 3.0], cov, 1000, np.random.default_rng(1))
    assert np.all(x[:, 1] == 2.0)
    sigma, corr = correlation_split(cov)
    np.testing.assert_allclose(sigma, [1e-10, 0.0, 2.0], rtol=1e-15)
    np.testing.assert_allclose(corr, np.eye(3), rtol=0, atol=1e-15)


def test_semidefinite_factor_reconstructs() -> None:
    # a parameter that equals another exactly: rank-deficient but valid
    cov = np.array([[1e-30, 1e-30], [1e-30, 1e-30]])
    root = sqrt_factor(cov)
    np.testing.assert_allclose(root @ root.T, cov, rtol=1e-12, atol=0)


@settings(max_examples=60, deadline=None)
@given(
    st.lists(st.floats(-45, 5), min_size=2, max_size=7),
    st.floats(-0.95, 0.95),
    st.integers(0, 2**31),
)
def test_inverse_scaled_round_trip(log_sig: list[float], rho: float, seed: int) -> None:
    """F⁻¹ F = I in scaled form for σ's spanning up to 1e50 and |ρ| ≤ 0.95 (1e-8 on R's scale)."""
    d = len(log_sig)
    sig = 10.0 ** np.array(log_sig)
    rng = np.random.default_rng(seed)
    a = rng.standard_normal((d, d))
    corr = a @ a.T + d * np.eye(d)
    corr /= np.sqrt(np.outer(np.diag(corr), np.diag(corr)))
    corr[0, 1] = corr[1, 0] = rho * 0.5 if d > 1 else 0.0
    fisher = np.linalg.inv(corr) / np.outer(sig, sig)  # Fisher of a covariance D R D
    cov = inverse_scaled(fisher)
    np.testing.assert_allclose(cov / np.outer(sig, sig), corr, atol=1e-8)


def test_inverse_scaled_refuses_unconstrained() -> None:
    with pytest.raises(np.linalg.LinAlgError):
        inverse_scaled(np.diag([1.0, 0.0]))


@pytest.mark.parametrize("n", [0, 1, 5, 1023, 1024, 2047, 2048, 2049, 20_000, 20_001, 65_537])
def test_row_blocks_cover_the_rows_in_aligned_serial_blocks(n: int) -> None:
    """Blocks tile 0…n in order, start at multiples of 1024 (9 × 9 factors), are never a lone
    row unless n = 1, and stay at or below OpenBLAS's one-thread size."""
    blocks = row_blocks(n, 81)
    assert blocks[0][0] == 0 and blocks[-1][1] == n
    assert all(a[1] == b[0] for a, b in itertools.pairwise(blocks))
    assert all(lo % 1024 == 0 for lo, _ in blocks)
    assert all((hi - lo) * 81 <= _SERIAL_MNK for lo, hi in blocks)
    assert n < 2 or all(hi - lo >= 2 for lo, hi in blocks)


@pytest.mark.parametrize("n", [3, 1024, 3000, 20_001])
def test_rows_times_is_each_rows_product(n: int) -> None:
    """Every row of the blocked product is that row's product in any aligned blocking: the
    same doubles as 64-row blocks (one thread each), bit for bit."""
    rng = np.random.default_rng(n)
    z, f = rng.standard_normal((n, 9)), rng.standard_normal((9, 9))
    ref = np.concatenate([z[lo : lo + 64] @ f for lo in range(0, n, 64)])
    assert np.array_equal(rows_times(z, f), ref)
