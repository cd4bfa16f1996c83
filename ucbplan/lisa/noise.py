"""LISA noise: LDC "Sangria" analytic instrument model plus the Galactic confusion foreground.

One-sided power spectral densities of TDI A (= E) in fractional-frequency units [1/Hz]
(docs/method.md, "Waveform and noise"). With x = 2 pi f L / c:

    S_pm = S_acc [1 + (0.4 mHz/f)^2][1 + (f/8 mHz)^4] (2 pi f)^-4 (2 pi f / c)^2
    S_op = S_oms [1 + (2 mHz/f)^4] (2 pi f / c)^2
    S_A  = 8 sin^2 x [(2 + cos x) S_op + 2 (3 + 2 cos x + cos 2x) S_pm]
    S_A,gal = 1.5 * 4 x^2 sin^2 x * S_h(f),
    S_h = A_g exp(-(f/f1)^alpha) f^(-7/3) [1 + tanh((f_k - f)/f2)] / 2.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ucbplan.core.constants import YEAR_S
from ucbplan.lisa.orbits import C_M_S, LISA_ARM_M


@dataclass(frozen=True, slots=True)
class NoiseModel:
    """Instrument noise levels and the foreground switch.

    Attributes
    ----------
    s_acc : float
        Test-mass acceleration noise [m^2 s^-4 Hz^-1].
    s_oms : float
        Optical metrology noise [m^2 Hz^-1].
    arm_length_m : float
        Arm length L [m].
    foreground : bool
        Add the Galactic confusion foreground for the observation length.
    """

    s_acc: float = (2.4e-15) ** 2
    s_oms: float = (7.9e-12) ** 2
    arm_length_m: float = LISA_ARM_M
    foreground: bool = True


SANGRIA = NoiseModel()
SCIRDV1 = NoiseModel(s_acc=(3.0e-15) ** 2, s_oms=(15.0e-12) ** 2)


def galactic_strain_psd(f_hz: ArrayLike, t_obs_s: float) -> NDArray[np.float64]:
    """Galactic confusion strain PSD S_h(f) [1/Hz] after an observation of ``t_obs_s`` [s].

    Notes
    -----
    LDC Sangria fit (docs/method.md, "Waveform and noise"); T in years of 365.25 d.
    """
    f = np.asarray(f_hz, dtype=float)
    t_yr = t_obs_s / YEAR_S
    a_g, alpha, f2 = 1.28265531e-44, 1.629667, 4.81078e-4
    f1 = 10.0 ** (-0.2235 * np.log10(t_yr) - 2.70408)
    fk = 10.0 ** (-0.36098 * np.log10(t_yr) - 2.37822)
    return (
        a_g
        * np.exp(-((f / f1) ** alpha))
        * f ** (-7.0 / 3.0)
        * 0.5
        * (1.0 + np.tanh((fk - f) / f2))
    )


def psd_a(
    f_hz: ArrayLike, t_obs_s: float | None = None, model: NoiseModel = SANGRIA
) -> NDArray[np.float64]:
    """One-sided PSD of TDI A (equal to E) [1/Hz, fractional frequency].

    Parameters
    ----------
    f_hz : array_like
        Frequencies [Hz] (> 0).
    t_obs_s : float, optional
        Observation length [s] for the foreground; required when ``model.foreground``.
    model : NoiseModel
        Instrument model (default Sangria with foreground).
    """
    f = np.asarray(f_hz, dtype=float)
    x = 2.0 * np.pi * f * model.arm_length_m / C_M_S
    s_pm = (
        model.s_acc
        * (1.0 + (0.4e-3 / f) ** 2)
        * (1.0 + (f / 8e-3) ** 4)
        * (2.0 * np.pi * f) ** -4
        * (2.0 * np.pi * f / C_M_S) ** 2
    )
    s_op = model.s_oms * (1.0 + (2e-3 / f) ** 4) * (2.0 * np.pi * f / C_M_S) ** 2
    sx = np.sin(x)
    s = (
        8.0
        * sx**2
        * ((2.0 + np.cos(x)) * s_op + 2.0 * (3.0 + 2.0 * np.cos(x) + np.cos(2 * x)) * s_pm)
    )
    if model.foreground:
        if t_obs_s is None:
            raise ValueError("t_obs_s is required for the Galactic foreground")
        s = s + 1.5 * 4.0 * x**2 * sx**2 * galactic_strain_psd(f, t_obs_s)
    return np.asarray(s, dtype=float)
