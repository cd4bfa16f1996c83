"""Analytic equal-arm LISA orbits (first order in the orbital eccentricity).

The constellation follows the rigid-triangle, first-order-in-eccentricity Keplerian orbits used by
FastGB / GBGPU (Cornish & Littenberg 2007; Rubbo, Cornish & Poujade 2004): the guiding centre
moves on a circle of radius 1 au in the ecliptic, the triangle is inclined by 60 degrees to the
ecliptic and cartwheels once per year. Positions are barycentric, ecliptic Cartesian, metres.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ucbplan.core.constants import AU_M, C_M_S, SIDEREAL_YEAR_S

LISA_ARM_M = 2.5e9


@dataclass(frozen=True, slots=True)
class EqualArmOrbits:
    """Analytic LISA orbits with (to first order) equal, constant arms.

    Parameters
    ----------
    arm_length_m : float
        Nominal arm length L [m] (Sangria: 2.5e9 m).
    radius_m : float
        Radius of the guiding-centre orbit [m] (1 au).
    year_s : float
        Orbital period of the constellation [s].
    initial_phase_rad : float
        Ecliptic longitude of the guiding centre at t = 0 [rad] (FastGB ``kappa``; default 0).
    initial_orientation_rad : float
        Orientation of the triangle at t = 0 [rad] (FastGB ``lambda``; default 0).
    """

    arm_length_m: float = LISA_ARM_M
    radius_m: float = AU_M
    year_s: float = SIDEREAL_YEAR_S
    initial_phase_rad: float = 0.0
    initial_orientation_rad: float = 0.0

    @property
    def eccentricity(self) -> float:
        """Orbital eccentricity e = L / (2 sqrt(3) R) of each spacecraft orbit."""
        return self.arm_length_m / (2.0 * np.sqrt(3.0) * self.radius_m)

    @property
    def arm_light_time_s(self) -> float:
        """One-way light travel time along an arm, L / c [s]."""
        return self.arm_length_m / C_M_S

    def positions(self, t_s: ArrayLike) -> NDArray[np.float64]:
        """Barycentric ecliptic positions of the three spacecraft.

        Parameters
        ----------
        t_s : array_like
            Times since the start of the observation [s].

        Returns
        -------
        numpy.ndarray
            Shape ``(3, 3) + shape(t_s)``: spacecraft index, Cartesian component, time [m].

        Notes
        -----
        FastGB's ``spacecraft()`` (Cornish & Littenberg 2007, Eq. 46 of Rubbo et al. 2004):
        x = R cos a + e R (sin a cos a sin b - (1 + sin^2 a) cos b), etc., with
        a = 2 pi t / yr + kappa and b = 2 pi (i - 1) / 3 + lambda.
        """
        t = np.asarray(t_s, dtype=float)
        alpha = 2.0 * np.pi * t / self.year_s + self.initial_phase_rad
        sa, ca = np.sin(alpha), np.cos(alpha)
        r, ec = self.radius_m, self.eccentricity
        out = np.empty((3, 3, *t.shape))
        for i in range(3):
            beta = 2.0 * np.pi * i / 3.0 + self.initial_orientation_rad
            sb, cb = np.sin(beta), np.cos(beta)
            out[i, 0] = r * ca + r * ec * (sa * ca * sb - (1.0 + sa * sa) * cb)
            out[i, 1] = r * sa + r * ec * (sa * ca * cb - (1.0 + ca * ca) * sb)
            out[i, 2] = -np.sqrt(3.0) * r * ec * (ca * cb + sa * sb)
        return out
