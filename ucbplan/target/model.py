"""The validated target: :class:`Target` and its :class:`Spectroscopy` defaults.

Both are frozen records; :func:`~ucbplan.target.parse.load_target` builds them from a target file
and :func:`~ucbplan.target.write.write_target` writes them back. Parameters are always referenced
to the *midpoint* of the LISA observation, epochs are TDB at the barycentre.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from astropy import units as u
from astropy.coordinates import SkyCoord
from astropy.time import Time, TimeDelta
from numpy.typing import NDArray

from ucbplan.core.params import PARAM_NAMES, PhaseParams
from ucbplan.errors import TargetFileError

__all__ = ["Spectroscopy", "Target"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class Spectroscopy:
    """Spectroscopy defaults used for tolerances; CLI flags override them.

    Attributes
    ----------
    lines : str
        ``"SB1"`` (one star's lines measured) or ``"SB2"`` (both).
    K1_kms, K2_kms : float or None
        Velocity semi-amplitudes of stars 1 and 2 [km/s].
    K_eff_kms : float or None
        K used for tolerances when given [km/s].
    sigma_v_kms : float or None
        Velocity error of one spectrum [km/s].
    """

    lines: str = "SB2"
    K1_kms: float | None = None
    K2_kms: float | None = None
    K_eff_kms: float | None = None
    sigma_v_kms: float | None = None

    @property
    def k_for_tolerance(self) -> float | None:
        """K used to turn a phase error into a velocity error: K_eff, else K1+K2 (SB2) or K1."""
        if self.K_eff_kms is not None:
            return self.K_eff_kms
        if self.lines == "SB2" and self.K1_kms is not None and self.K2_kms is not None:
            return self.K1_kms + self.K2_kms
        return self.K1_kms


@dataclass(frozen=True, slots=True)
class Target:
    """A validated target, parameters referenced to the LISA observation midpoint (TDB).

    Attributes
    ----------
    name : str
        Target name.
    source : Path or None
        The target file it was read from (absolute), if any.
    ra_deg, dec_deg : float
        ICRS position [deg].
    t_ref : Time
        Reference epoch, the midpoint of the LISA observation (TDB at the barycentre).
    t_obs_s : float
        Length of the LISA observation [s, TDB].
    params : PhaseParams
        Phase-model parameters at ``t_ref`` (SI).
    cov_names : tuple of str
        Parameters of ``cov_matrix``, in its row order (may include cos ι, amplitude, ψ).
    cov_matrix : ndarray
        Covariance of ``cov_names`` in their SI units (0×0 if none was given).
    cos_inclination, amplitude, psi : float or None
        cos ι [1], GW strain amplitude [1], polarisation angle [rad].
    distance_kpc : float or None
        Distance [kpc].
    spectroscopy : Spectroscopy or None
        Tolerance defaults.
    samples : Path or None
        Posterior-samples file (absolute); see :func:`~ucbplan.target.samples.load_samples`.
    priority : float
        Weight in night schedules (> 0).
    vmag : float or None
        V magnitude [mag].
    m1_msun, m2_msun : float or None
        Component masses [M_sun].
    ref_shift_s : float
        Midpoint minus the reference epoch as written (T_obs/2 for ``t_ref_is: start``) [s].
    notes : dict
        Provenance, e.g. ``{"t_ref_converted_from": "utc"}``.
    """

    name: str
    source: Path | None
    ra_deg: float
    dec_deg: float
    t_ref: Time
    t_obs_s: float
    params: PhaseParams
    cov_names: tuple[str, ...]
    cov_matrix: FloatArray
    cos_inclination: float | None = None
    amplitude: float | None = None
    psi: float | None = None
    distance_kpc: float | None = None
    spectroscopy: Spectroscopy | None = None
    samples: Path | None = None
    priority: float = 1.0
    vmag: float | None = None
    m1_msun: float | None = None
    m2_msun: float | None = None
    ref_shift_s: float = 0.0
    notes: dict[str, Any] = field(default_factory=dict)

    @property
    def covariance(self) -> FloatArray:
        """Covariance (7, 7) in PARAM_NAMES order; parameters without uncertainty are zero."""
        full = np.zeros((7, 7))
        idx = [PARAM_NAMES.index(n) for n in self.cov_names if n in PARAM_NAMES]
        sub = [i for i, n in enumerate(self.cov_names) if n in PARAM_NAMES]
        full[np.ix_(idx, idx)] = self.cov_matrix[np.ix_(sub, sub)]
        return full

    @property
    def coord(self) -> SkyCoord:
        """ICRS position."""
        return SkyCoord(self.ra_deg * u.deg, self.dec_deg * u.deg, frame="icrs")

    @property
    def t_start(self) -> Time:
        """Start of the LISA observation (TDB)."""
        return self.t_ref - TimeDelta(self.t_obs_s / 2.0, format="sec")

    @property
    def t_end(self) -> Time:
        """End of the LISA observation (TDB)."""
        return self.t_ref + TimeDelta(self.t_obs_s / 2.0, format="sec")

    @property
    def period_s(self) -> float:
        """Anomalistic orbital period P_b at the reference epoch [s]."""
        return self.params.period_s

    @property
    def sha256(self) -> str | None:
        """SHA-256 of the source file (provenance), if loaded from a file."""
        if self.source is None or not self.source.exists():
            return None
        return hashlib.sha256(self.source.read_bytes()).hexdigest()

    def tau(self, t: Time) -> FloatArray:
        """Seconds since ``t_ref`` (TDB) of barycentric TDB times ``t``."""
        if t.scale != "tdb":
            raise TargetFileError(f"{self.name}: epochs must be TDB, got scale {t.scale!r}")
        out: FloatArray = np.asarray((t - self.t_ref).to_value("s"), dtype=np.float64)
        return out
