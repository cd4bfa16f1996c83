"""Builders of blocks and blocks-table meta for the blocks-table tests."""

from __future__ import annotations

import astropy.units as u
import numpy as np
from astropy.time import Time

from ucbplan.observing.blocks.block import Block
from ucbplan.observing.blocks.make import make_meta
from ucbplan.offline import offline


def _make_block(i: int, alt: bool) -> Block:
    mid = Time("2040-02-16T02:00:00", scale="utc") + i * 300.0 * u.s
    half = 150.0 * u.s
    return Block(
        target="HM Cnc",
        block_id=f"HM_Cnc-{i:03d}",
        anchor="quadrature",
        u_star_rad=0.0 if i % 2 == 0 else np.pi,
        t_mid_utc=mid,
        t_start_utc=mid - half,
        t_end_utc=mid + half,
        t_mid_tdb_bary=Time("2040-02-16T02:03:12.123456", scale="tdb"),
        sigma_t_s=1.5,
        t_alt_utc=(mid + 80.0 * u.s) if alt else None,
        exptime_s=60.0,
        n_exp=4,
        readout_s=15.0,
        lambda_k=0.97,
        lambda_kappa=0.9,
        smear_kms=float("nan"),
        alt_start_deg=50.0,
        altitude_deg=51.0,
        alt_end_deg=52.0,
        airmass_start=1.3,
        airmass=1.28,
        airmass_end=1.26,
        moon_sep_deg=80.0,
        moon_illum=0.4,
        ra_deg=121.5967,
        dec_deg=15.4583,
        night="2040-02-15",
        timezone="America/Santiago",
        period_s=321.5,
    )


def make_block(i: int, alt: bool = True) -> Block:
    with offline():
        return _make_block(i, alt)


def block_meta() -> dict:
    return make_meta(
        site={"name": "Paranal", "lon_deg": -70.4, "lat_deg": -24.6, "height_m": 2635.0},
        targets=[{"name": "HM Cnc", "file": "catalogs/hm-cnc-simulated.yaml", "sha256": "0" * 64}],
        constraints=["airmass <= 2"],
        mode="quadrature",
    )
