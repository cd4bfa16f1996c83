"""Observing blocks: an exposure plan centred on an anchor epoch, with its smearing factors.

A block is the unit every export works from: a window of UTC at the site centred on the epoch at
which the argument of latitude reaches the anchor value ``u_star`` (barycentric TDB converted to
site UTC by :mod:`ucbplan.observing.observatory.barycentric`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from astropy.time import Time

from ucbplan.core.smearing import comb_attenuation, smear_velocity
from ucbplan.errors import InputError, UcbplanError
from ucbplan.inputs import check_int, check_range

#: Longest block, first exposure start to last exposure end [s]: a block must fit in one night.
MAX_BLOCK_S = 43200.0
#: Longest dead time between two exposures [s].
MAX_READOUT_S = 3600.0
#: Most exposures in one block.
MAX_N_EXP = 10000


@dataclass(frozen=True, slots=True)
class Block:
    """One planned observing block (one row of the master blocks table).

    Times are astropy ``Time`` scalars: ``t_*_utc`` are UTC at the site (light time removed),
    ``t_mid_tdb_bary`` is the barycentric TDB anchor epoch. Altitudes in degrees, durations in
    seconds, velocities in km/s.
    """

    target: str
    block_id: str
    anchor: str
    u_star_rad: float
    t_mid_utc: Time
    t_start_utc: Time
    t_end_utc: Time
    t_mid_tdb_bary: Time
    sigma_t_s: float
    t_alt_utc: Time | None
    exptime_s: float
    n_exp: int
    readout_s: float
    lambda_k: float
    lambda_kappa: float
    smear_kms: float
    alt_start_deg: float
    altitude_deg: float
    alt_end_deg: float
    airmass_start: float
    airmass: float
    airmass_end: float
    moon_sep_deg: float
    moon_illum: float
    ra_deg: float
    dec_deg: float
    night: str
    timezone: str
    period_s: float
    priority: float = 1.0
    session_id: str = ""
    pair_id: str = ""
    delta_kappa: float = float("nan")
    visit_id: str = ""
    sigma_v_kms: float = float("nan")


@dataclass(frozen=True, slots=True)
class ExposurePlan:
    """Exposures of one block: ``n_exp`` × ``exptime_s`` with ``readout_s`` dead time between.

    The block runs from the start of the first exposure to the end of the last; its centre (the
    anchor epoch) is the mid-exposure time of the co-add.
    """

    exptime_s: float = 60.0
    n_exp: int = 1
    readout_s: float = 0.0

    def __post_init__(self) -> None:
        night = "12 h: a block must fit in one night"
        check_range("exptime_s", self.exptime_s, 0.0, MAX_BLOCK_S, "s", night, low_open=True)
        check_int("n_exp", self.n_exp, 1, MAX_N_EXP, "exposures co-added in one block")
        check_range(
            "readout_s", self.readout_s, 0.0, MAX_READOUT_S, "s", "dead time between exposures"
        )
        if self.span_s > MAX_BLOCK_S:
            raise InputError(
                f"n_exp/exptime/readout: the block lasts {self.span_s:.0f} s = "
                f"{self.n_exp} x {self.exptime_s:g} s + {self.n_exp - 1} x {self.readout_s:g} s, "
                f"more than {MAX_BLOCK_S:.0f} s ({night}); use fewer or shorter exposures"
            )

    @property
    def span_s(self) -> float:
        """Block length: first exposure start to last exposure end [s] (the phase window)."""
        return self.n_exp * self.exptime_s + (self.n_exp - 1) * self.readout_s


@dataclass(frozen=True, slots=True)
class Smearing:
    """Smearing of one exposure plan for one target (Appendix B)."""

    lambda_k: float
    lambda_kappa: float
    smear_kms: float
    bin_fraction: float


def block_smearing(plan: ExposurePlan, n_bar: float, k_kms: float | None) -> Smearing:
    """Λ_K, Λ_κ, Δv_smear = K(1 − Λ_K) and the block span as a fraction of the orbit.

    Parameters
    ----------
    plan : ExposurePlan
        Exposures of the block.
    n_bar : float
        Mean orbital rate n̄_b = π f_GW [rad/s].
    k_kms : float or None
        Semi-amplitude for the smear [km/s] (NaN smear if unknown).

    Notes
    -----
    Eqs. Lambda_K, Lambda_kappa, Deltav_smear; exact for a comb of equal exposures
    (:func:`ucbplan.core.smearing.comb_attenuation`).
    """
    lam_k = comb_attenuation(plan.exptime_s, plan.readout_s, plan.n_exp, n_bar, 1)
    lam_kappa = comb_attenuation(plan.exptime_s, plan.readout_s, plan.n_exp, n_bar, 2)
    smear = float("nan") if k_kms is None else float(smear_velocity(k_kms, lam_k))
    return Smearing(lam_k, lam_kappa, smear, plan.span_s * n_bar / (2 * math.pi))


def check_smear_budget(
    name: str,
    sm: Smearing,
    max_smear_kms: float | None,
    max_bin_fraction: float | None,
    sigma_v_kms: float | None,
) -> list[str]:
    """Enforce ``--max-smear`` / ``--max-bin-fraction``; return warnings otherwise.

    Raises
    ------
    UcbplanError
        When an explicit budget is exceeded (the message says how to shorten the block).

    Returns
    -------
    list of str
        A warning when no budget was given and the smear exceeds σ_v/2.
    """
    if max_bin_fraction is not None and sm.bin_fraction > max_bin_fraction:
        raise UcbplanError(
            f"{name}: the block spans {sm.bin_fraction:.3f} of the orbit > `max_bin_fraction` "
            f"{max_bin_fraction:g}; use fewer or shorter exposures (`n_exp`/`exptime`)"
        )
    if max_smear_kms is not None and math.isfinite(sm.smear_kms) and sm.smear_kms > max_smear_kms:
        raise UcbplanError(
            f"{name}: smearing K(1-Lambda_K) = {sm.smear_kms:.3g} km/s exceeds `max_smear` "
            f"{max_smear_kms:.3g} km/s (Lambda_K = {sm.lambda_k:.4f}); shorten `exptime` or `n_exp`"
        )
    if (
        max_smear_kms is None
        and sigma_v_kms is not None
        and math.isfinite(sm.smear_kms)
        and sm.smear_kms > 0.5 * sigma_v_kms
    ):
        return [
            f"{name}: the block smears K by {sm.smear_kms:.1f} km/s (Lambda_K = "
            f"{sm.lambda_k:.4f}) > sigma_v/2; `reduce` divides it out using lambda_k, or set "
            "--max-smear / shorten the exposures"
        ]
    return []
