"""The waveform kernel as it was before issue 14 (commit 7938afd), kept only as the "today"
peer of ``benchmarks/waveform.py``: the speed-up is measured side by side in one process. Not
used by ucbplan; its numbers are pinned by ``tests/golden/lisa_bands.npz``.
"""

# ruff: noqa
# mypy: ignore-errors
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ucbplan.lisa.response import LINKS, ResponseGrid, band_transform, tdi_coefficients

__all__ = [
    "LINES",
    "FourLineModel",
    "Line",
    "SourceParams",
    "line_amplitudes",
]


@dataclass(frozen=True, slots=True)
class Line:
    """One spectral line: harmonic n, apsidal shift sign s (f_p = n f0/2 + s wdot/2pi)."""

    name: str
    harmonic: int
    shift: int


LINES: tuple[Line, ...] = (
    Line("n=1+", 1, +1),
    Line("n=1-", 1, -1),
    Line("n=2", 2, 0),
    Line("n=3", 3, -1),
)


@dataclass(frozen=True, slots=True)
class SourceParams:
    """Waveform parameters referenced to the START of the LISA observation (SI units).

    Attributes
    ----------
    amplitude : float
        Strain amplitude A (paper Eq. f_amp).
    f_gw : float
        n = 2 frequency f0 [Hz].
    fdot : float
        Frequency derivative [Hz/s].
    cos_inclination : float
        cos(iota).
    psi : float
        Polarization angle [rad] (FastGB convention).
    phase : float
        n = 2 phase phi0 at t = 0 [rad].
    eta, kappa : float
        Laplace-Lagrange pair at t = 0 (e sin w, e cos w).
    omega_dot : float
        Apsidal advance rate [rad/s].
    fddot : float
        Second frequency derivative [Hz/s^2].
    """

    amplitude: float
    f_gw: float
    fdot: float
    cos_inclination: float
    psi: float
    phase: float
    eta: float = 0.0
    kappa: float = 0.0
    omega_dot: float = 0.0
    fddot: float = 0.0


def line_frequencies(f_gw: ArrayLike, omega_dot: ArrayLike) -> NDArray[np.float64]:
    """Line frequencies at t = 0 [Hz], shape (4, ...) in the order of LINES.

    Notes
    -----
    Appendix apsidal_mcmc: f0/2 +- wdot/2pi and 3 f0/2 - wdot/2pi; the carrier is unshifted.
    """
    f = np.asarray(f_gw, dtype=float)
    w = np.asarray(omega_dot, dtype=float) / (2.0 * np.pi)
    return np.stack([0.5 * line.harmonic * f + line.shift * w for line in LINES])


def line_amplitudes(
    amplitude: ArrayLike, cos_inclination: ArrayLike, eta: ArrayLike, kappa: ArrayLike
) -> NDArray[np.complex128]:
    """Source-frame complex amplitudes (H+, Hx) of the four lines.

    Returns
    -------
    numpy.ndarray
        Shape (4, 2, ...): line (order of LINES), polarization (+, x).

    Notes
    -----
    The four-line table of docs/method.md ("Waveform and noise"), equivalent to paper Eqs.
    app:final_form_h_plus and app:final_form_h_cross (not Appendix E's C_lm, whose conjugation
    convention differs).
    """
    a = np.asarray(amplitude, dtype=float)
    c = np.asarray(cos_inclination, dtype=float)
    et = np.asarray(eta, dtype=float)
    ka = np.asarray(kappa, dtype=float)
    a_plus = a * (1.0 + c * c)
    a_cross = 2.0 * a * c
    b1 = (1.0 - c * c) / (2.0 * (1.0 + c * c))
    minus = ka - 1j * et
    plus = ka + 1j * et
    h = np.empty((4, 2, *np.broadcast(a, c, et, ka).shape), dtype=complex)
    h[0, 0], h[0, 1] = -a_plus * (-0.75) * plus, 1j * a_cross * (-0.75) * plus
    h[1, 0], h[1, 1] = -a_plus * (-b1) * minus, 0.0
    h[2, 0], h[2, 1] = -a_plus, 1j * a_cross
    h[3, 0], h[3, 1] = -a_plus * 2.25 * minus, 1j * a_cross * 2.25 * minus
    return h


#: Walkers per internal block of :meth:`FourLineModel.bands` (cache blocking).
_CHUNK = 16

#: Most Taylor terms of the walker-dependent link phase (enough for |beta delay| <= 1.5 rad).
_K_MAX = 24


def _taylor_terms(x: float) -> int:
    """Smallest K >= 2 with x^K / K! < 1e-10 (relative truncation error of the link phase)."""
    term, k = 1.0, 0
    while term >= 1e-10 or k < 2:
        k += 1
        term *= x / k
        if k >= _K_MAX:
            raise ValueError(
                f"link phase correction {x:.3g} rad too large for the Taylor expansion; "
                "the source is outside the targeted prior (|f - f_c| or fdot too large)"
            )
    return k


def _cis(x: NDArray[np.float64]) -> NDArray[np.complex128]:
    """exp(i x) for real x (cos/sin written into a complex buffer; faster than np.exp(1j x))."""
    out = np.empty(x.shape, dtype=complex)
    np.cos(x, out=out.real)
    np.sin(x, out=out.imag)
    return out


class FourLineModel:
    """TDI A, E of the four-line source in fixed heterodyned bands (one per harmonic).

    Parameters
    ----------
    grid : ResponseGrid
        Observation geometry (slow-time grid of N + 1 samples, fixed sky).
    f_center_hz : float
        Search / injection n = 2 frequency that fixes the band centres:
        q_n = round(n f_center T / 2), band bins q_n - N/2 .. q_n + N/2 - 1.
    harmonics : tuple of int
        Harmonics to model: (1, 2, 3) eccentric, (2,) circular.

    Notes
    -----
    Injection and templates must use the same N and band centres (docs/method.md, "Waveform and
    noise").
    Approximations (all verified against the brute-force time-domain TDI in the tests):
    theta(t - delay) = theta(t) - 2 pi f_p(t) delay (neglects pi fdot delay^2 < 1e-8 rad);
    the TDI link delays inside the slow envelopes use the band-centre frequency (phase error
    <= 2 pi (N/2T) 3L/c ~ 3e-4 rad at the band edge; the (1 - D^2) factor is exact per bin);
    the walker-dependent part of the link phases, exp(-i beta (d_j + L)), is summed as a Taylor
    series with source-independent spacecraft moments (truncation < 1e-10 relative).
    """

    def __init__(
        self, grid: ResponseGrid, f_center_hz: float, harmonics: tuple[int, ...] = (1, 2, 3)
    ) -> None:
        self.grid = grid
        self.harmonics = tuple(sorted(harmonics))
        t_obs, n = grid.t_obs_s, grid.n
        self.band_bins = np.array(
            [round(0.5 * h * f_center_hz * t_obs) for h in self.harmonics], dtype=np.int64
        )
        k = np.arange(-n // 2, n // 2)
        self.freqs_hz = (self.band_bins[:, None] + k[None, :]) / t_obs
        self.lines = tuple(
            (li, self.harmonics.index(line.harmonic))
            for li, line in enumerate(LINES)
            if line.harmonic in self.harmonics
        )
        # Per band: weights (channel, pol) x spacecraft for emitted and received light.
        emit = np.zeros((len(self.harmonics), 4, 3, grid.t_s.size), dtype=complex)
        recv = np.zeros_like(emit)
        for b, q in enumerate(self.band_bins):
            w = tdi_coefficients(q / t_obs, grid.arm_s)
            for li, (s, r) in enumerate(LINKS):
                for ch in range(2):
                    for pol, proj in enumerate((grid.proj_plus, grid.proj_cross)):
                        emit[b, 2 * ch + pol, s] += w[ch, li] * proj[li]
                        recv[b, 2 * ch + pol, r] += w[ch, li] * proj[li]
        # Every link factor exp(-2 pi i f_p(t) delay) is split into a fixed part at the reference
        # frequency (f = n f_c / 2) and a walker-dependent part exp(-i beta_p(t) delay) with
        # beta_p = n pi (f(t) - f_c) + s wdot, the same for all spacecraft. Its Taylor series in
        # beta has moments sum_j delay_j^k (weights)_j that do not depend on the source, so the
        # sum over spacecraft is done once here: MOM[b, k] = (-i)^k / k! sum_j
        # [(d_j + L)^k emit_j - d_j^k recv_j] (emitters carry the arm delay L).
        self.f_center_hz = float(f_center_hz)
        self._f_het = round(f_center_hz * t_obs) / (2.0 * t_obs)  # c1 heterodyne [Hz]
        d = grid.delay_s  # (3, M)
        moments = np.empty((len(self.harmonics), _K_MAX, 4, grid.t_s.size), dtype=complex)
        for b, h in enumerate(self.harmonics):
            dop0 = np.exp(-1j * np.pi * h * f_center_hz * d)  # (3, M)
            arm0 = np.exp(-1j * np.pi * h * f_center_hz * grid.arm_s)
            e_w = emit[b] * (dop0 * arm0)[None]
            r_w = recv[b] * dop0[None]
            for order in range(_K_MAX):
                fac = (-1j) ** order / math.factorial(order)
                moments[b, order] = fac * (
                    np.einsum("cjm,jm->cm", e_w, (d + grid.arm_s) ** order)
                    - np.einsum("cjm,jm->cm", r_w, d**order)
                )
        # (band, pol, K * channel * M) for one matmul with the (W, pol) amplitudes
        self._moments = np.ascontiguousarray(
            moments.reshape(len(self.harmonics), _K_MAX, 2, 2, -1).transpose(0, 3, 1, 2, 4)
        )
        self._delay_max = float(np.max(np.abs(d)) + grid.arm_s)
        self._emit = emit
        self._recv = recv
        offs = [
            h * round(f_center_hz * t_obs) / 2.0 - q
            for h, q in zip(self.harmonics, self.band_bins, strict=True)
        ]
        self._band_rot = np.exp(2j * np.pi * np.outer(offs, grid.t_s) / t_obs)  # (n_bands, M)

    @property
    def n_bands(self) -> int:
        """Number of frequency bands (one per modelled harmonic)."""
        return len(self.harmonics)

    def bands(
        self,
        amplitude: ArrayLike,
        f_gw: ArrayLike,
        fdot: ArrayLike,
        cos_inclination: ArrayLike,
        psi: ArrayLike,
        phase: ArrayLike,
        eta: ArrayLike = 0.0,
        kappa: ArrayLike = 0.0,
        omega_dot: ArrayLike = 0.0,
        fddot: ArrayLike = 0.0,
    ) -> NDArray[np.complex128]:
        """Compute A and E in every band for a batch of W parameter sets.

        Parameters are SI scalars or arrays broadcastable to shape (W,), referenced to the
        start of the observation (see :class:`SourceParams`).

        Returns
        -------
        numpy.ndarray
            Shape (W, n_bands, 2, N) complex: one-sided Fourier transform [1/Hz, fractional
            frequency] of TDI A (index 0) and E (index 1) on ``freqs_hz``.
        """
        arrs = np.broadcast_arrays(
            *(
                np.atleast_1d(np.asarray(x, dtype=float))
                for x in (
                    amplitude,
                    f_gw,
                    fdot,
                    cos_inclination,
                    psi,
                    phase,
                    eta,
                    kappa,
                    omega_dot,
                    fddot,
                )
            )
        )
        flat = [a.ravel() for a in arrs]
        n_walk = flat[0].size
        if n_walk > _CHUNK:  # cache blocking: working set of ~16 walkers stays in L2
            return np.concatenate(
                [self._bands([a[i : i + _CHUNK] for a in flat]) for i in range(0, n_walk, _CHUNK)]
            )
        return self._bands(flat)

    def _bands(self, flat: list[NDArray[np.float64]]) -> NDArray[np.complex128]:
        amp, f0, fd, ci, ps, ph, et, ka, wd, fdd = flat
        g = self.grid
        t = g.t_s[None, :]
        n_walk = f0.size
        h = line_amplitudes(amp, ci, et, ka)  # (4, 2, W)
        c2, s2 = np.cos(2.0 * ps), np.sin(2.0 * ps)
        hp = h[:, 0] * c2 - h[:, 1] * s2  # (4, W)
        hx = h[:, 0] * s2 + h[:, 1] * c2
        # Orbital-phase carrier c1 = exp(i theta_2 / 2) heterodyned at f_het; line n is c1^n
        # times fixed band rotations and exp(i s wdot t) (all lines share one orbital phase).
        df_t = (f0 - self.f_center_hz)[:, None] + fd[:, None] * t + 0.5 * fdd[:, None] * t * t
        chirp = np.pi * (fd[:, None] * t * t + fdd[:, None] * t**3 / 3.0)
        c1 = _cis(
            0.5 * ph[:, None] + 2.0 * np.pi * (0.5 * f0 - self._f_het)[:, None] * t + 0.5 * chirp
        )
        powers = {1: c1}
        if max(self.harmonics) >= 2:
            powers[2] = c1 * c1
        if max(self.harmonics) >= 3:
            powers[3] = powers[2] * c1
        shifted = any(LINES[li].shift for li, _ in self.lines)
        apsis = _cis(wd[:, None] * t) if shifted else np.ones((1, 1), dtype=complex)
        # Taylor order for exp(-i beta delay): error (beta delay)^K / K! < 1e-10.
        beta_max = np.pi * 3.0 * float(np.max(np.abs(df_t))) + float(np.max(np.abs(wd)))
        n_terms = _taylor_terms(beta_max * self._delay_max)
        slow = np.zeros((n_walk, self.n_bands, 2, t.size), dtype=complex)
        for li, b in self.lines:
            line = LINES[li]
            n_h, s = line.harmonic, line.shift
            carrier = powers[n_h] * self._band_rot[b][None, :]
            if s == 1:
                carrier = carrier * apsis
            elif s == -1:
                carrier = carrier * np.conj(apsis)
            mom = self._moments[b]  # (pol, K, ch, M)
            beta = ((n_h * np.pi) * df_t + (s * wd)[:, None])[:, None, None, :]  # (W,1,1,M)
            acc = mom[:, n_terms - 1] * beta + mom[:, n_terms - 2]  # (W, pol, ch, M)
            for k in range(n_terms - 3, -1, -1):
                acc *= beta
                acc += mom[:, k]
            acc = hp[li][:, None, None] * acc[:, 0] + hx[li][:, None, None] * acc[:, 1]
            slow[:, b] += acc * carrier[:, None, :]
        out = np.empty((n_walk, self.n_bands, 2, g.n), dtype=complex)
        for b in range(self.n_bands):
            out[:, b] = band_transform(slow[:, b], g.t_obs_s, self.freqs_hz[b], g.arm_s)
        return out

    def bands_for(self, p: SourceParams) -> NDArray[np.complex128]:
        """:meth:`bands` for a single :class:`SourceParams`; shape (n_bands, 2, N)."""
        return self.bands(
            p.amplitude,
            p.f_gw,
            p.fdot,
            p.cos_inclination,
            p.psi,
            p.phase,
            p.eta,
            p.kappa,
            p.omega_dot,
            p.fddot,
        )[0]
