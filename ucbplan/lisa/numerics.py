"""Numerical building blocks of the four-line waveform (:mod:`ucbplan.lisa.waveform`).

exp(i x) of real phases; tables of exp(i (a + b k + c k^2)) over the slow-time index built from
P + 2Q sines and cosines instead of one per sample; real matrix products in column blocks that
stay on one BLAS thread; the powers of the Taylor variable beta(tau) of the link phases.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

#: Table length of the block split k = Q p + q of the slow-time index (the orbital carrier and the
#: apsidal rotation, :func:`quadratic_cis`).
TABLE_Q = 32

#: Largest m n k of one real matrix product. OpenBLAS runs dgemm on one thread up to
#: 65536 x GEMM_MULTITHREAD_THRESHOLD (4 in numpy's builds) and threads above it; threaded, the
#: link sums run 5-10x slower on a shared two-core machine, so products are split into column
#: blocks below this size.
GEMM_SERIAL = 65536 * 4


def cis(x: NDArray[np.float64]) -> NDArray[np.complex128]:
    """exp(i x) for real x (cos/sin written into a complex buffer; faster than np.exp(1j x))."""
    out = np.empty(x.shape, dtype=complex)
    np.cos(x, out=out.real)
    np.sin(x, out=out.imag)
    return out


def gemm(a: NDArray[np.float64], b: NDArray[np.float64], out: NDArray[np.float64]) -> None:
    """out = a @ b in column blocks of at most GEMM_SERIAL multiply-adds (one BLAS thread)."""
    width = max(1, GEMM_SERIAL // (a.shape[0] * a.shape[1]))
    for j in range(0, b.shape[1], width):
        np.matmul(a, b[:, j : j + width], out=out[:, j : j + width])


def quadratic_tables(
    a: NDArray[np.float64] | None,
    b: NDArray[np.float64],
    c: NDArray[np.float64] | None,
    m: int,
) -> tuple[NDArray[np.complex128], NDArray[np.complex128], NDArray[np.complex128] | None]:
    """Tables of exp(i (a + b k + c k^2)), k = Q p + q < m: (A_p, B_q, D_q), each (W, .).

    The phase is (a + b Q p + c Q^2 p^2) + (b q + c q^2) + 2 c Q p q, so the value is
    A_p B_q D_q^p with A_p = exp(i (a + b Q p + c Q^2 p^2)), B_q = exp(i (b q + c q^2)) and
    D_q = exp(2 i c Q q): P + 2Q sines and cosines per walker instead of m. ``a``, ``c`` None:
    zero (then D is None: a plain outer product).
    """
    n_p = -(-m // TABLE_Q)
    p, q = np.arange(n_p, dtype=float), np.arange(TABLE_Q, dtype=float)
    b = b[:, None]
    rows = (TABLE_Q * b) * p if a is None else a[:, None] + (TABLE_Q * b) * p
    if c is None:
        return cis(rows), cis(b * q), None
    c = c[:, None]
    rows += (TABLE_Q * TABLE_Q) * c * p * p
    return cis(rows), cis(b * q + c * q * q), cis((2.0 * TABLE_Q) * c * q)


def quadratic_cis(
    a: NDArray[np.float64] | None,
    b: NDArray[np.float64],
    c: NDArray[np.float64] | None,
    m: int,
) -> NDArray[np.complex128]:
    """exp(i (a + b k + c k^2)) for k = 0 .. m - 1, shape (W, m), from :func:`quadratic_tables`.

    The powers D_q^p are built by doubling (D^(2j) from D^j squared, the block p + j from the
    block p times D^j), so each value is a product of at most ~2 log2(P) rounded factors: a few
    1e-15 relative.
    """
    rows, cols, step = quadratic_tables(a, b, c, m)
    if step is None:
        return (rows[:, :, None] * cols[:, None, :]).reshape(b.shape[0], -1)[:, :m]
    n_p = rows.shape[1]
    out = np.empty((b.shape[0], n_p, TABLE_Q), dtype=complex)
    out[:, 0] = cols
    done = 1
    while done < n_p:
        size = min(done, n_p - done)
        np.multiply(out[:, :size], step[:, None, :], out=out[:, done : done + size])
        done += size
        if done < n_p:
            step *= step
    out *= rows[:, :, None]
    return out.reshape(b.shape[0], -1)[:, :m]


def n_monomials(n_terms: int, degree: int) -> int:
    """Coefficients of beta^0 .. beta^(n_terms - 1) for beta(tau) of the given degree."""
    return n_terms + degree * n_terms * (n_terms - 1) // 2


def beta_powers(coeffs: NDArray[np.float64], n_terms: int) -> NDArray[np.float64]:
    """Coefficients of beta^k, k < n_terms, in powers of tau: (W, monomials), k-major.

    ``coeffs`` (W, d + 1) holds beta(tau) = sum_j coeffs[:, j] tau^j; beta^k has k d + 1
    coefficients (order of :meth:`FourLineModel._poly_basis`).
    """
    cur = np.ones((coeffs.shape[0], 1))
    out = [cur]
    for _ in range(1, n_terms):
        nxt = np.zeros((cur.shape[0], cur.shape[1] + coeffs.shape[1] - 1))
        for j in range(coeffs.shape[1]):
            nxt[:, j : j + cur.shape[1]] += coeffs[:, j : j + 1] * cur
        out.append(nxt)
        cur = nxt
    return np.concatenate(out, axis=1)
