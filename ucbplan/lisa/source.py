"""The small-eccentricity source: waveform parameters and the four lines they make.

Source model (docs/method.md, "Waveform and noise"; paper Eqs. app:final_form_h_plus,
app:final_form_h_cross, Appendix apsidal_mcmc). With A+ = A(1 + cos^2 i), Ax = 2 A cos i,
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
:mod:`ucbplan.lisa.waveform` carries the lines through the LISA response.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray


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
