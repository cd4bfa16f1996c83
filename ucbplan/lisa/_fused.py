"""Optional compiled (numba) loops of :class:`ucbplan.lisa.waveform.FourLineModel`.

With numba installed (``pip install ucbplan[fast]``) the carriers, their products with the link
sums and the band accumulation, and the per-bin weighting after the FFT run as two fused loops
instead of about ten numpy passes over the (walker, band, channel, sample) arrays; the link sums
stay one BLAS product per line. Both paths compute the same sums (to ~1e-14;
tests/lisa/test_lisa_waveform_kernel.py compares them).

Compiling costs seconds (measured: import 0.8-1 s, compilation 2-6 s on a shared two-core
machine; nothing is cached on disk) and saves some 30 us per waveform, so the loops are used only
when asked for: ``UCBPLAN_NUMBA=1`` in the environment. Off by default, every process of a run
takes the numpy path, so serial and parallel runs agree bit for bit; with it on, every process
takes the compiled path (the two paths agree to ~1e-15, not bit for bit).
"""

from __future__ import annotations

import os
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from ucbplan.errors import UcbplanError

#: Environment variable that switches the compiled loops on (value ``1``).
ENV = "UCBPLAN_NUMBA"

_kernels: tuple[Callable[..., None], Callable[..., None]] | None = None


def requested() -> bool:
    """Whether the environment asks for the compiled loops (``UCBPLAN_NUMBA=1``)."""
    return os.environ.get(ENV, "") == "1"


def kernels() -> tuple[Callable[..., None], Callable[..., None]] | None:
    """(assemble, weigh) compiled by numba when :data:`ENV` asks for them, else None.

    Raises
    ------
    UcbplanError
        If they are asked for and numba is not installed.
    """
    global _kernels
    if not requested():
        return None
    if _kernels is None:
        try:
            import numba
        except ImportError:
            raise UcbplanError(
                f"{ENV}=1 asks for the compiled waveform loops but numba is not installed: "
                f"pip install 'ucbplan[fast]', or unset {ENV}"
            ) from None
        jit = numba.njit(cache=False, nogil=True, error_model="numpy")
        _kernels = (jit(_assemble), jit(_weigh))
    return _kernels


def _assemble(
    sums: NDArray[np.complex128],
    lines: NDArray[np.int64],
    tables: NDArray[np.complex128],
    n_q: int,
    x: NDArray[np.complex128],
    jump: NDArray[np.complex128],
) -> None:
    """Multiply every line's link sum by its carrier and add it into its band.

    sums (L, W, 2, M): link sums of the modelled lines; lines (L, 3): band, harmonic n and
    apsidal sign s of each. tables (W, 5, >= P, Q) holds, for m = n_q p + q, the orbital carrier
    c1 = exp(i theta_2 / 2) = A_p B_q D_q^p and the apsidal rotation exp(i wdot t) = H_p G_q
    as rows A (first P entries), B, D, H (first P entries), G (see
    :func:`ucbplan.lisa.numerics.quadratic_cis`); D_q^p is kept by one product per row.
    The carrier of a line is c1^n exp(i s wdot t). Writes samples m < N into x
    (W, bands, 2, N) and Y(T) - Y(0) into jump (W, bands, 2), overwriting both (lines of one
    band must be adjacent; every band must have a line).
    """
    n_lines, n_walk, m_all = sums.shape[0], sums.shape[1], sums.shape[3]
    n = m_all - 1
    z = np.empty(m_all, dtype=np.complex128)  # c1
    rot = np.empty(m_all, dtype=np.complex128)  # exp(i wdot t)
    car = np.empty(m_all, dtype=np.complex128)
    e = np.empty(n_q, dtype=np.complex128)
    for w in range(n_walk):
        for q in range(n_q):
            e[q] = tables[w, 1, q]
        for m0 in range(0, m_all, n_q):
            p = m0 // n_q
            if p > 0:
                for q in range(n_q):
                    e[q] = e[q] * tables[w, 2, q]
            for q in range(min(n_q, m_all - m0)):
                z[m0 + q] = tables[w, 0, p] * e[q]
                rot[m0 + q] = tables[w, 3, p] * tables[w, 4, q]
        for i in range(n_lines):
            b, h, s = lines[i, 0], lines[i, 1], lines[i, 2]
            first = i == 0 or lines[i - 1, 0] != b
            for m in range(m_all):
                c = z[m] if h == 1 else (z[m] * z[m] if h == 2 else z[m] * z[m] * z[m])
                if s == 1:
                    c = c * rot[m]
                elif s == -1:
                    c = c * rot[m].conjugate()
                car[m] = c
            for ch in range(2):
                row = sums[i, w, ch]
                out = x[w, b, ch]
                if first:
                    for m in range(n):
                        out[m] = row[m] * car[m]
                    jump[w, b, ch] = row[n] * car[n] - row[0] * car[0]
                else:
                    for m in range(n):
                        out[m] += row[m] * car[m]
                    jump[w, b, ch] += row[n] * car[n] - row[0] * car[0]


def _weigh(
    spec: NDArray[np.complex128],
    jump: NDArray[np.complex128],
    dft_w: NDArray[np.complex128],
    jump_w: NDArray[np.complex128],
) -> None:
    """spec = spec dft_w + jump jump_w in place: spec (W, bands, 2, N), jump (W, bands, 2),
    weights (bands, N) (:func:`ucbplan.lisa.response.band_weights`)."""
    n_walk, n_bands, n_ch, n = spec.shape
    for w in range(n_walk):
        for b in range(n_bands):
            for ch in range(n_ch):
                dj = jump[w, b, ch]
                for k in range(n):
                    spec[w, b, ch, k] = spec[w, b, ch, k] * dft_w[b, k] + dj * jump_w[b, k]


def describe() -> str:
    """Which waveform path runs now: 'numba <version>' (compiled loops) or 'numpy'."""
    if kernels() is None:
        return "numpy"
    import numba

    return f"numba {numba.__version__}"
