"""The phase-model parameter record and reference-epoch transforms (SI floats, no astropy).

Kept apart from :mod:`ucbplan.targets` (YAML parsing) so the numerical core imports nothing heavy;
:class:`EphemerisSource` is the little the core asks of a target (duck-typed, no import of it).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

#: Order of the phase-model parameters everywhere (covariance rows, Jacobian columns).
PARAM_NAMES: tuple[str, ...] = ("phase", "f_gw", "fdot", "fddot", "eta", "kappa", "omega_dot")
#: SI unit of each parameter, as astropy unit strings.
PARAM_UNITS: dict[str, str] = {
    "phase": "rad",
    "f_gw": "Hz",
    "fdot": "Hz / s",
    "fddot": "Hz / s2",
    "eta": "",
    "kappa": "",
    "omega_dot": "rad / s",
}


@dataclass(frozen=True, slots=True)
class PhaseParams:
    """GW phase model and Laplace–Lagrange eccentricity pair at a reference epoch (SI units).

    Attributes
    ----------
    phase : float
        φ_ref, GW phase of the dominant (n=2) mode at the reference epoch [rad].
    f_gw : float
        GW carrier frequency f = n̄_b/π at the reference epoch [Hz].
    fdot, fddot : float
        First and second GW frequency derivatives [Hz/s, Hz/s²].
    eta, kappa : float
        η = e sin ω, κ = e cos ω of star 1 at the reference epoch [1].
    omega_dot : float
        Apsidal advance rate ω̇ [rad/s].
    """

    phase: float
    f_gw: float
    fdot: float
    fddot: float = 0.0
    eta: float = 0.0
    kappa: float = 0.0
    omega_dot: float = 0.0

    def as_array(self) -> NDArray[np.float64]:
        """Parameters as a float64 vector in :data:`PARAM_NAMES` order."""
        return np.array([getattr(self, n) for n in PARAM_NAMES], dtype=np.float64)

    @classmethod
    def from_array(cls, a: NDArray[np.float64] | list[float]) -> PhaseParams:
        """Inverse of :meth:`as_array`."""
        v = np.asarray(a, dtype=np.float64)
        return cls(**{n: float(x) for n, x in zip(PARAM_NAMES, v, strict=True)})

    @property
    def eccentricity(self) -> float:
        """e = |η + iκ| [1]."""
        return math.hypot(self.eta, self.kappa)

    @property
    def omega_rad(self) -> float:
        """Argument of periastron of star 1, ω = atan2(η, κ) [rad] (0 for a circular orbit)."""
        return math.atan2(self.eta, self.kappa) % (2 * math.pi)

    @property
    def is_eccentric(self) -> bool:
        """True when e > 0 or ω̇ ≠ 0."""
        return self.eccentricity > 0.0 or self.omega_dot != 0.0

    @property
    def n_bar(self) -> float:
        """Mean orbital rate from the node, n̄_b = πf [rad/s]."""
        return math.pi * self.f_gw

    @property
    def n_b(self) -> float:
        """Anomalistic mean motion n_b = n̄_b − ω̇ [rad/s]."""
        return math.pi * self.f_gw - self.omega_dot

    @property
    def period_s(self) -> float:
        """Anomalistic orbital period P_b = 2π/n_b [s]."""
        return 2 * math.pi / self.n_b

    @property
    def nodal_period_s(self) -> float:
        """Node-to-node period 2π/n̄_b = 2/f [s]: what an eclipse or light-curve ephemeris repeats.

        Eclipses recur at fixed u (u₁ = π/2, 3π/2), whose mean rate is n̄_b = πf, not the
        anomalistic n_b (``timing.period`` of a target file is this period).
        """
        return 2.0 / self.f_gw


class EphemerisSource(Protocol):
    """What the core needs of a target: its phase model, covariance and observation length.

    :class:`ucbplan.targets.Target` satisfies it; so does any object with these attributes (a
    notebook record, a row of a catalogue), which keeps the core free of the target layer.
    Optional attributes read with defaults: ``kind`` (``"lisa"``; ``"timing"`` makes horizons
    two-sided, :func:`ucbplan.core.forecast.two_sided`) and ``has_pi_mode`` (True; False drops
    the φ_ref + π alternative of :func:`ucbplan.core.ephemeris.find_epochs`).
    """

    @property
    def params(self) -> PhaseParams:
        """Phase-model parameters at the reference epoch (the LISA midpoint, or T0)."""
        ...

    @property
    def covariance(self) -> NDArray[np.float64]:
        """Their covariance (7, 7) in :data:`PARAM_NAMES` order (SI units)."""
        ...

    @property
    def t_obs_s(self) -> float:
        """Length of the LISA observation T_obs [s]; it ends T_obs/2 after the reference (0 for
        a timing ephemeris: its information ends at T0, on both sides)."""
        ...


def shift_jacobian(p: PhaseParams, dt_s: float) -> NDArray[np.float64]:
    """Jacobian ∂p(t_ref + dt)/∂p(t_ref) of :func:`shift_reference` (7×7, PARAM_NAMES order)."""
    dt = dt_s
    w = p.omega_dot * dt
    c, s = math.cos(w), math.sin(w)
    eta_new = p.eta * c + p.kappa * s
    kap_new = p.kappa * c - p.eta * s
    j = np.eye(7)
    two_pi = 2 * math.pi
    j[0, 1] = two_pi * dt
    j[0, 2] = two_pi * dt**2 / 2
    j[0, 3] = two_pi * dt**3 / 6
    j[1, 2] = dt
    j[1, 3] = dt**2 / 2
    j[2, 3] = dt
    j[4, 4], j[4, 5], j[4, 6] = c, s, dt * kap_new
    j[5, 4], j[5, 5], j[5, 6] = -s, c, -dt * eta_new
    return j


def shift_reference(
    p: PhaseParams, cov: NDArray[np.float64], dt_s: float
) -> tuple[PhaseParams, NDArray[np.float64]]:
    """Move the reference epoch by ``dt_s`` seconds (start → midpoint: ``dt_s = +T_obs/2``).

    Parameters
    ----------
    p : PhaseParams
        Parameters at the old reference epoch.
    cov : ndarray, shape (7, 7)
        Their covariance in :data:`PARAM_NAMES` order (SI units).
    dt_s : float
        New reference minus old reference [s].

    Returns
    -------
    PhaseParams, ndarray
        Parameters at the new epoch (φ wrapped to [0, 2π)) and the covariance propagated with the
        same (exact, linear-in-parameters except ω̇) Jacobian.

    Notes
    -----
    ``docs/method.md`` ("Time scales") and paper Sec. 4.1: φ_mid = φ_0 + 2π(f_0 T/2 + ḟ(T/2)²/2 +
    f̈(T/2)³/6), f_mid = f_0 + ḟT/2 + f̈(T/2)²/2, ḟ_mid = ḟ + f̈T/2, (η, κ) rotated by ω̇T/2
    (Eq. kappa_lisa_prediction).
    """
    dt = float(dt_s)
    cycles = _exact_cycles(p.f_gw, p.fdot, p.fddot, dt)
    w = p.omega_dot * dt
    c, s = math.cos(w), math.sin(w)
    new = PhaseParams(
        phase=(p.phase + 2 * math.pi * cycles) % (2 * math.pi),
        f_gw=p.f_gw + p.fdot * dt + p.fddot * dt**2 / 2,
        fdot=p.fdot + p.fddot * dt,
        fddot=p.fddot,
        eta=p.eta * c + p.kappa * s,
        kappa=p.kappa * c - p.eta * s,
        omega_dot=p.omega_dot,
    )
    j = shift_jacobian(p, dt)
    new_cov = j @ np.asarray(cov, dtype=np.float64) @ j.T
    return new, 0.5 * (new_cov + new_cov.T)


def shift_columns(
    cols: Mapping[str, ArrayLike], dt_s: float, defaults: Mapping[str, float] | None = None
) -> dict[str, NDArray[np.float64]]:
    """:func:`shift_reference` applied to posterior samples (arrays per parameter).

    Parameters
    ----------
    cols : mapping of name → array
        Samples keyed like :data:`PARAM_NAMES`; other keys (cos ι, …) pass through unchanged.
    dt_s : float
        New reference minus old reference [s].
    defaults : mapping, optional
        Fixed values of phase-model parameters that were not sampled (else 0).

    Returns
    -------
    dict
        The same keys, phase-model columns moved to the new epoch (φ wrapped to [0, 2π)).

    Notes
    -----
    Same Taylor shift and (η, κ) rotation as :func:`shift_reference`; each cycle term is reduced
    modulo 1 separately so the phase keeps float64 precision at large f·dt.
    """
    n = np.shape(next(iter(cols.values())))[0]
    fixed = dict(defaults or {})
    arr = {
        k: np.asarray(cols[k], dtype=np.float64) if k in cols else np.full(n, fixed.get(k, 0.0))
        for k in PARAM_NAMES
    }
    dt = float(dt_s)
    cycles = (
        np.mod(arr["f_gw"] * dt, 1.0)
        + np.mod(arr["fdot"] * dt * dt / 2.0, 1.0)
        + np.mod(arr["fddot"] * dt**3 / 6.0, 1.0)
    )
    w = arr["omega_dot"] * dt
    c, s = np.cos(w), np.sin(w)
    shifted = {
        "phase": np.mod(arr["phase"] + 2.0 * math.pi * cycles, 2.0 * math.pi),
        "f_gw": arr["f_gw"] + arr["fdot"] * dt + arr["fddot"] * dt * dt / 2.0,
        "fdot": arr["fdot"] + arr["fddot"] * dt,
        "eta": arr["eta"] * c + arr["kappa"] * s,
        "kappa": arr["kappa"] * c - arr["eta"] * s,
    }
    return {k: shifted.get(k, np.asarray(v, dtype=np.float64)) for k, v in cols.items()}


def _exact_cycles(f: float, fdot: float, fddot: float, dt: float) -> float:
    """Fractional GW cycles f dt + ḟdt²/2 + f̈dt³/6 modulo 1, without float64 cancellation."""
    from fractions import Fraction

    total = (
        Fraction(f) * Fraction(dt)
        + Fraction(fdot) * Fraction(dt) ** 2 / 2
        + Fraction(fddot) * Fraction(dt) ** 3 / 6
    )
    return float(total - math.floor(total))
