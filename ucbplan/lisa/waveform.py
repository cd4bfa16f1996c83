"""Small-eccentricity four-line waveform through the LISA response, batched over parameter sets.

Source model (SCIENCE.md "Waveform"; paper Eqs. app:final_form_h_plus, app:final_form_h_cross,
Appendix apsidal_mcmc). With A+ = A(1 + cos^2 i), Ax = 2 A cos i,
b1 = sin^2 i / (2 (1 + cos^2 i)), each line is h = Re[H exp(i theta)],
theta = phi_p + 2 pi f_p t + pi fdot_p t^2 (t = chi, the wave variable):

=======  =====================  ========  ========  =======================  ======================
line     f_p                    fdot_p    phi_p     H+                       Hx
=======  =====================  ========  ========  =======================  ======================
n=2      f0                     fdot      phi0      -A+                      +i Ax
n=3      3 f0/2 - wdot/2pi      3fdot/2   3phi0/2   -A+ (9/4)(k0 - i e0)     +i Ax (9/4)(k0 - i e0)
n=1 (+)  f0/2 + wdot/2pi        fdot/2    phi0/2    -A+ (-3/4)(k0 + i e0)    +i Ax (-3/4)(k0 + i e0)
n=1 (-)  f0/2 - wdot/2pi        fdot/2    phi0/2    -A+ (-b1)(k0 - i e0)     0
=======  =====================  ========  ========  =======================  ======================

(e0, k0) = (eta, kappa) at the start of the observation (t = 0), where all parameters of this
module are referenced. The polarization angle rotates (H+, Hx) by 2 psi (FastGB convention).
All lines share one orbital phase: theta_p = (n/2) theta_2 + s wdot t with s = 0, -1, +1, -1.
"""

from __future__ import annotations

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
    "line_frequencies",
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
    SCIENCE.md four-line table, equivalent to paper Eqs. app:final_form_h_plus and
    app:final_form_h_cross (not Appendix E's C_lm, whose conjugation convention differs).
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
    Injection and templates must use the same N and band centres (SCIENCE.md "Waveform").
    The link delay factors inside the slow envelopes use the band-centre frequency (phase error
    <= 2 pi (N/2T) 3L/c ~ 3e-4 rad at the band edge); the (1 - D^2) factor is applied per bin.
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
        self._emit = emit
        self._recv = recv

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
        amp, f0, fd, ci, ps, ph, et, ka, wd, fdd = (a.ravel() for a in arrs)
        g = self.grid
        t = g.t_s[None, :]
        t_obs = g.t_obs_s
        n_walk = f0.size
        h = line_amplitudes(amp, ci, et, ka)  # (4, 2, W)
        c2, s2 = np.cos(2.0 * ps), np.sin(2.0 * ps)
        hp = h[:, 0] * c2 - h[:, 1] * s2  # (4, W)
        hx = h[:, 0] * s2 + h[:, 1] * c2
        f_t = f0[:, None] + fd[:, None] * t + 0.5 * fdd[:, None] * t * t  # (W, M)
        dop = np.exp(-1j * np.pi * f_t[:, None, :] * g.delay_s[None])  # (W, 3, M)
        arm = np.exp(-1j * np.pi * f_t * g.arm_s)  # (W, M)
        chirp = np.pi * (fd[:, None] * t * t + fdd[:, None] * t**3 / 3.0)  # (W, M)
        out = np.zeros((n_walk, self.n_bands, 2, g.n), dtype=complex)
        slow = np.zeros((n_walk, self.n_bands, 2, t.size), dtype=complex)
        for li, b in self.lines:
            line = LINES[li]
            n_h, s = line.harmonic, line.shift
            fb = self.band_bins[b] / t_obs
            f_off = 0.5 * n_h * f0 + s * wd / (2.0 * np.pi) - fb  # (W,)
            het = 0.5 * n_h * ph[:, None] + 2.0 * np.pi * f_off[:, None] * t + 0.5 * n_h * chirp
            carrier = np.exp(1j * het)  # (W, M)
            if n_h == 2:
                dop_p, arm_p = dop * dop, arm * arm
            elif n_h == 1:
                dop_p, arm_p = dop, arm
            else:
                dop_p, arm_p = dop * dop * dop, arm * arm * arm
            if s != 0:
                dop_p = dop_p * np.exp(-1j * s * wd[:, None, None] * g.delay_s[None])
                arm_p = arm_p * np.exp(-1j * s * wd * g.arm_s)[:, None]
            # K[w, (ch,pol), m] = sum_j dop_p[w,j,m] (arm_p emit - recv)[ (ch,pol), j, m]
            k_e = np.einsum("wjm,cjm->wcm", dop_p, self._emit[b])
            k_r = np.einsum("wjm,cjm->wcm", dop_p, self._recv[b])
            kk = arm_p[:, None, :] * k_e - k_r  # (W, 4, M)
            kk *= carrier[:, None, :]
            slow[:, b, 0] += hp[li][:, None] * kk[:, 0] + hx[li][:, None] * kk[:, 1]
            slow[:, b, 1] += hp[li][:, None] * kk[:, 2] + hx[li][:, None] * kk[:, 3]
        for b in range(self.n_bands):
            out[:, b] = band_transform(slow[:, b], t_obs, self.freqs_hz[b], g.arm_s)
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
