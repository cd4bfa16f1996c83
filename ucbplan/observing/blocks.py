"""Observing blocks: an exposure plan centred on an anchor epoch, with its smearing factors.

A block is the unit every export works from: a window of UTC at the site centred on the epoch at
which the argument of latitude reaches the anchor value ``u_star`` (barycentric TDB converted to
site UTC by :mod:`ucbplan.observing.timeconv`).
"""

from __future__ import annotations

from dataclasses import dataclass

from astropy.time import Time

__all__ = ["Block"]


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
