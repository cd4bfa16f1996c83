"""Multivariate normals with huge dynamic range: draw from and invert covariances safely.

A LISA posterior covariance spans more than 40 orders of magnitude (φ ~ 1 rad², f̈ ~ 1e-53 Hz²/s⁴).
Decomposing it directly (``eigh``/``cholesky``/``inv`` on the raw matrix) loses the small
parameters to round-off: the eigenvalues of the large block swamp them at ~1e-16 relative
precision. Every place in ucbplan that draws from or inverts a covariance or Fisher matrix uses
this module instead, which works on the correlation matrix R = D⁻¹ C D⁻¹ (D = diag σ), whose
entries are all of order one, and scales back.

Parameters with zero variance are held fixed at their mean (their rows of R are replaced by the
identity), so a covariance that constrains only some parameters is still usable.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

F64 = NDArray[np.float64]


def correlation_split(cov: ArrayLike) -> tuple[F64, F64]:
    """Split ``cov`` into σ (its diagonal's square root) and the correlation matrix R.

    Rows/columns with σ = 0 get R_ii = 1 and zero correlations; R is symmetrised.

    Raises
    ------
    ValueError
        If ``cov`` is not a finite square matrix or has a negative variance.
    """
    c = np.asarray(cov, dtype=np.float64)
    if c.ndim != 2 or c.shape[0] != c.shape[1] or not np.all(np.isfinite(c)):
        raise ValueError(f"covariance must be a finite square matrix, got shape {c.shape}")
    var = np.diag(c).copy()
    if np.any(var < 0):
        raise ValueError("covariance has a negative variance on its diagonal")
    sigma = np.sqrt(var)
    scale = np.where(sigma > 0, sigma, 1.0)
    corr = c / np.outer(scale, scale)
    corr = 0.5 * (corr + corr.T)
    fixed = sigma == 0
    corr[fixed, :] = 0.0
    corr[:, fixed] = 0.0
    corr[fixed, fixed] = 1.0
    return sigma, corr


def sqrt_factor(cov: ArrayLike) -> F64:
    """A matrix A with A Aᵀ = C, computed in correlation-scaled form (C = D R D).

    R is factored by its eigen-decomposition with negative round-off eigenvalues clipped to zero,
    so a positive semi-definite C (e.g. a parameter fully determined by others) is accepted.
    """
    sigma, corr = correlation_split(cov)
    vals, vecs = np.linalg.eigh(corr)
    root = vecs * np.sqrt(np.clip(vals, 0.0, None))
    return np.asarray(sigma[:, None] * root)


def sample_normal(mean: ArrayLike, cov: ArrayLike, n: int, rng: np.random.Generator) -> F64:
    """``n`` draws (n, d) of N(mean, cov), exact in distribution for any dynamic range of σ.

    Parameters
    ----------
    mean : array (d,)
        Mean vector (any units).
    cov : array (d, d)
        Covariance (units of mean²); positive semi-definite.
    n : int
        Number of draws.
    rng : numpy.random.Generator
        Source of randomness (explicit, for reproducibility).
    """
    m = np.asarray(mean, dtype=np.float64)
    root = sqrt_factor(cov)
    return np.asarray(m + rows_times(rng.standard_normal((n, m.size)), root.T))


#: Largest m·n·k of a matrix product that OpenBLAS runs on the calling thread alone (its
#: ``GEMM_MULTITHREAD_THRESHOLD`` 4 × 65536): a larger one wakes its worker thread, which then
#: spins ~0.1 CPU s waiting for more work, for a product of draws that takes a millisecond.
_SERIAL_MNK = 4 * 65536


def rows_times(z: F64, factor: F64) -> F64:
    """``z @ factor`` for draws ``z`` (n, d), in blocks of rows each small enough for one thread.

    The blocks start at multiples of a power of two (≥ the BLAS kernel's row unroll), the last
    one taking the remainder, so every row is the same double as in the whole product computed
    on one thread (the remainder rows at the end through the same edge code). A product split
    over threads can differ in the rows at the threads' boundaries.
    """
    n, d = z.shape
    k = factor.shape[1]
    out = np.empty((n, k))
    for lo, hi in row_blocks(n, d * k):
        np.matmul(z[lo:hi], factor, out=out[lo:hi])
    return out


def row_blocks(n: int, work_per_row: int) -> list[tuple[int, int]]:
    """(start, stop) of :func:`rows_times`' blocks: starts at multiples of a power of two, the
    last block up to twice as long, each with rows × ``work_per_row`` ≤ :data:`_SERIAL_MNK`."""
    rows = 1 << max((_SERIAL_MNK // (2 * max(work_per_row, 1))).bit_length() - 1, 0)
    cuts = [*range(rows, n - rows + 1, rows)]
    return list(zip([0, *cuts], [*cuts, n], strict=True))


def inverse_scaled(matrix: ArrayLike) -> F64:
    """Inverse of a symmetric positive-definite matrix (e.g. Fisher → covariance), scaled.

    F = D R D with D = √diag F, so F⁻¹ = D⁻¹ R⁻¹ D⁻¹; R is inverted by Cholesky.

    Raises
    ------
    numpy.linalg.LinAlgError
        If the matrix is singular (a parameter the data do not constrain).
    """
    d, corr = correlation_split(matrix)
    if np.any(d == 0):
        raise np.linalg.LinAlgError(
            "matrix has a zero diagonal entry: a parameter is unconstrained"
        )
    chol = np.linalg.cholesky(corr)
    inv_chol = np.linalg.solve(chol, np.eye(len(d)))
    inv_corr = inv_chol.T @ inv_chol
    out = inv_corr / np.outer(d, d)
    return np.asarray(0.5 * (out + out.T))
