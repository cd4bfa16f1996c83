"""The validated target: :class:`Target`, its :class:`Spectroscopy` defaults and its timing section.

All are frozen records; :func:`~ucbplan.targets.parse.load_target` builds them from a target file
and :func:`~ucbplan.targets.write.write_target` writes them back. A target's ephemeris is a LISA
posterior (``kind == "lisa"``: parameters referenced to the *midpoint* of the LISA observation)
or a timing ephemeris (``kind == "timing"``: referenced to its epoch T0, :class:`TimingSection`);
both are the same phase model (:class:`~ucbplan.core.params.PhaseParams` and its covariance).
Epochs are TDB at the barycentre.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from astropy import units as u
from astropy.time import Time, TimeDelta
from numpy.typing import NDArray

from ucbplan.core.params import PARAM_NAMES, PhaseParams
from ucbplan.core.timing import TimingEphemeris
from ucbplan.errors import TargetFileError

if TYPE_CHECKING:  # astropy.coordinates is imported where a position is needed, not to load
    from astropy.coordinates import SkyCoord

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
class TimingSection:
    """The ``timing`` section as given: the ephemeris, its epoch text, covariance and source.

    Attributes
    ----------
    ephemeris : TimingEphemeris
        Mark, P, Ṗ, P̈ and the eccentricity at T0 (SI).
    t0_text : str
        T0 as written (full precision, e.g. ``"BJD_TDB 2458305.6827886"``).
    cov_names : tuple of str
        Timing parameters of ``cov_matrix`` (``t0``, ``period``, ``pdot``, ``pddot``, ``eta``,
        ``kappa``, ``omega_dot``), in its row order.
    cov_matrix : ndarray
        Their covariance in SI units (s² for t0 and period).
    source : str
        Where the ephemeris comes from.
    eccentricity_given : bool
        Whether the file had an ``eccentricity`` mapping (written back only then).
    """

    ephemeris: TimingEphemeris
    t0_text: str
    cov_names: tuple[str, ...]
    cov_matrix: FloatArray
    source: str
    eccentricity_given: bool = False

    def sigma(self, name: str) -> float | None:
        """1σ of timing parameter ``name`` in SI units (None if it has no uncertainty)."""
        if name not in self.cov_names:
            return None
        i = self.cov_names.index(name)
        return float(np.sqrt(max(self.cov_matrix[i, i], 0.0)))


@dataclass(frozen=True, slots=True)
class Target:
    """A validated target: the phase model at its reference epoch t_ref (TDB), and the rest.

    Attributes
    ----------
    name : str
        Target name.
    source : Path or None
        The target file it was read from (absolute), if any.
    ra_deg, dec_deg : float
        ICRS position [deg].
    t_ref : Time
        Reference epoch (TDB at the barycentre): the midpoint of the LISA observation, or T0 of
        a timing ephemeris.
    t_obs_s : float
        Length of the LISA observation [s, TDB]; 0 for a timing ephemeris (its information ends
        at T0, on both sides).
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
        Posterior-samples file (absolute); see :func:`~ucbplan.targets.samples.load_samples`.
    samples_covariance : ndarray or None
        (7, 7) covariance of the samples in PARAM_NAMES order, moved to the midpoint; derived at
        load when ``cov_matrix`` names no phase-model parameter
        (:func:`~ucbplan.targets.samples.with_samples_covariance`), else None.
    priority : float
        Weight in night schedules (> 0).
    vmag : float or None
        V magnitude [mag] (``vmag``, or ``magnitudes.V``).
    m1_msun, m2_msun : float or None
        Component masses [M_sun].
    ref_shift_s : float
        Midpoint minus the reference epoch as written (T_obs/2 for ``t_ref_is: start``) [s].
    notes : dict
        Provenance, e.g. ``{"t_ref_converted_from": "utc"}``.
    kind : str
        ``"lisa"`` (a LISA posterior) or ``"timing"`` (a timing ephemeris).
    timing : TimingSection or None
        The timing ephemeris as given (``kind == "timing"``).
    magnitudes : dict
        Apparent magnitudes by band [mag] (V included when ``vmag`` is given).
    references : dict
        Citation per field path (``"timing.period"`` → ``"2019Natur.571..528B"``).
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
    samples_covariance: FloatArray | None = None
    priority: float = 1.0
    vmag: float | None = None
    m1_msun: float | None = None
    m2_msun: float | None = None
    ref_shift_s: float = 0.0
    notes: dict[str, Any] = field(default_factory=dict)
    kind: str = "lisa"
    timing: TimingSection | None = None
    magnitudes: dict[str, float] = field(default_factory=dict)
    references: dict[str, str] = field(default_factory=dict)

    def __repr__(self) -> str:
        """One line: name, kind, period, sky position, reference epoch and file."""
        where = f", {self.source.name}" if self.source else ""
        epoch = "T0" if self.kind == "timing" else "t_ref"
        return (
            f"<Target {self.name!r} ({self.kind}): P={self.period_s:.10g} s, "
            f"RA={self.ra_deg:.5f}°, Dec={self.dec_deg:+.5f}°, {epoch}={self.t_ref.tdb.isot} "
            f"TDB{where}>"
        )

    @property
    def has_pi_mode(self) -> bool:
        """Whether φ_ref has the second posterior mode φ_ref + π (a LISA property, Appendix A1).

        A timing ephemeris fixes the orbital phase by its mark: no π alternative.
        """
        return self.kind == "lisa"

    @property
    def covariance(self) -> FloatArray:
        """Covariance (7, 7) in PARAM_NAMES order; parameters without uncertainty are zero.

        ``lisa.covariance`` (or the timing covariance) when it names a phase-model parameter,
        else that of the posterior samples (:attr:`samples_covariance`);
        :attr:`covariance_source` says which.
        """
        if self.samples_covariance is not None and not self._has_phase_covariance:
            return self.samples_covariance.copy()
        full = np.zeros((7, 7))
        idx = [PARAM_NAMES.index(n) for n in self.cov_names if n in PARAM_NAMES]
        sub = [i for i, n in enumerate(self.cov_names) if n in PARAM_NAMES]
        full[np.ix_(idx, idx)] = self.cov_matrix[np.ix_(sub, sub)]
        return full

    @property
    def _has_phase_covariance(self) -> bool:
        return any(n in PARAM_NAMES for n in self.cov_names)

    @property
    def covariance_source(self) -> str:
        """Where :attr:`covariance` comes from: the file's covariance, the samples, or none."""
        if self._has_phase_covariance:
            return f"{self.kind}.covariance"
        if self.samples_covariance is not None and self.samples is not None:
            return f"samples file {self.samples.name} (moved to the midpoint)"
        return "none (the ephemeris is treated as exact)"

    @property
    def coord(self) -> SkyCoord:
        """ICRS position."""
        from astropy.coordinates import SkyCoord

        return SkyCoord(self.ra_deg * u.deg, self.dec_deg * u.deg, frame="icrs")

    @property
    def t_start(self) -> Time:
        """Start of the LISA observation (TDB); T0 for a timing ephemeris."""
        return self.t_ref - TimeDelta(self.t_obs_s / 2.0, format="sec")

    @property
    def t_end(self) -> Time:
        """End of the LISA observation (TDB); T0 for a timing ephemeris."""
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
