"""The fixed blocks table behind every export golden file, and helpers the export tests share.

Golden files live in ``tests/golden/`` and are compared byte for byte (they catch change); each is
paired with an independent check of the format's rules against the blocks table (they catch
error). After an intended format change, regenerate them with
``UCBPLAN_REGEN_GOLDEN=1 pytest tests/observing/exports`` and review the diff before committing.
"""

from __future__ import annotations

import math
import os
from datetime import UTC, datetime
from pathlib import Path

import astropy.units as u
import numpy as np
from astropy.table import Table
from astropy.time import Time

from support.paths import GOLDEN
from ucbplan.observing.blocks.block import Block
from ucbplan.observing.blocks.make import blocks_to_table, make_meta
from ucbplan.observing.blocks.read import read_blocks
from ucbplan.observing.blocks.schema import REQUIRED_COLUMNS
from ucbplan.observing.exports import ExportOptions, export_blocks
from ucbplan.offline import offline

REGEN = os.environ.get("UCBPLAN_REGEN_GOLDEN") == "1"
HM_RA_DEG = (8 + 6 / 60 + 23.2 / 3600) * 15.0  # 08 06 23.20
HM_DEC_DEG = 15 + 27 / 60 + 30.0 / 3600  # +15 27 30.0
HM_P_S = 321.5178508648
SDSS = "SDSS J0000-0030"
SDSS_VMAG_META = 19.3  # only in meta['targets']: the table's vmag is NaN for SDSS

#: Golden file → (``--to``, ``--format``); every golden is made with a 600 s acquisition.
GOLDEN_CASES = {
    "exports_eso_p2.json": ("eso-p2", "ecsv"),
    "exports_keck_starlist.txt": ("keck-starlist", "ecsv"),
    "exports_calendar.ics": ("ics", "ecsv"),
    "exports_proposal.ecsv": ("proposal", "ecsv"),
    "exports_proposal.csv": ("proposal", "csv"),
    "exports_proposal.tex": ("proposal", "latex"),
    "exports_ing.cat": ("ing-cat", "ecsv"),
    "exports_lco.json": ("lco", "ecsv"),
    "exports_gemini.json": ("gemini", "ecsv"),
    "exports_phase_table.ecsv": ("phase-table", "ecsv"),
}
GOLDEN_ACQUISITION_S = 600.0


def _block(
    target: str,
    block_id: str,
    mid_iso: str,
    *,
    u_star: float,
    anchor: str,
    sigma: float,
    exptime: float,
    n_exp: int,
    readout: float,
    ra: float,
    dec: float,
    period: float,
    alt: bool = True,
) -> Block:
    mid = Time(mid_iso, scale="utc", precision=3)
    width = n_exp * exptime + (n_exp - 1) * readout
    half = width / 2 * u.s
    return Block(
        target=target,
        block_id=block_id,
        anchor=anchor,
        u_star_rad=u_star,
        t_mid_utc=mid,
        t_start_utc=mid - half,
        t_end_utc=mid + half,
        t_mid_tdb_bary=mid.tdb + 412.123456 * u.s,
        sigma_t_s=sigma,
        t_alt_utc=(mid + period / 4 * u.s) if alt else None,
        exptime_s=exptime,
        n_exp=n_exp,
        readout_s=readout,
        lambda_k=0.99,
        lambda_kappa=0.97,
        smear_kms=1.2,
        alt_start_deg=55.0,
        altitude_deg=56.0,
        alt_end_deg=57.0,
        airmass_start=1.22,
        airmass=1.21,
        airmass_end=1.20,
        moon_sep_deg=64.5,
        moon_illum=0.3,
        ra_deg=ra,
        dec_deg=dec,
        night=mid_iso[:10],
        timezone="America/Santiago",
        period_s=period,
    )


def _blocks() -> list[Block]:
    hm = {"ra": HM_RA_DEG, "dec": HM_DEC_DEG, "period": HM_P_S, "anchor": "quadrature"}
    sd = {"ra": 15.0 / 3600, "dec": -0.5, "period": 765.2, "anchor": "conjunction"}
    hm_exp = {"exptime": 20.0, "n_exp": 2, "readout": 10.0}
    return [
        _block(
            "HM Cnc", "HM_Cnc-001", "2037-01-15T01:02:03.400", u_star=0.0, sigma=0.6, **hm_exp, **hm
        ),
        _block(
            SDSS,
            "SDSS_J0000-0030-001",
            "2037-01-15T04:30:00.000",
            u_star=math.pi / 2,
            sigma=2.3,
            exptime=120.0,
            n_exp=1,
            readout=0.0,
            alt=False,
            **sd,
        ),
        _block(
            "HM Cnc",
            "HM_Cnc-002",
            "2037-01-16T03:10:11.250",
            u_star=math.pi,
            sigma=0.61,
            **hm_exp,
            **hm,
        ),
        _block(
            "HM Cnc",
            "HM_Cnc-003",
            "2037-02-10T00:20:00.000",
            u_star=0.0,
            sigma=0.65,
            **hm_exp,
            **hm,
        ),
    ]


def fixture_table() -> Table:
    """Fixed two-target blocks table (the source of every golden file)."""
    with offline():
        meta = make_meta(
            site={"name": "Paranal", "lon_deg": -70.4045, "lat_deg": -24.6272, "height_m": 2635},
            targets=[
                {"name": "HM Cnc", "file": "catalogs/hm-cnc.yaml", "sha256": "0" * 64},
                {"name": SDSS, "file": "sdss.yaml", "sha256": "1" * 64, "vmag": SDSS_VMAG_META},
            ],
            constraints=["airmass <= 2.0", "moon separation >= 30 deg", "twilight: nautical"],
            mode="quadrature",
        )
        table = blocks_to_table(_blocks(), meta)
    table.meta["created_utc"] = "2036-12-01T12:00:00+00:00"
    table["vmag"] = [21.0, math.nan, 21.0, 21.0]
    return table


def written_table(folder: Path) -> Table:
    """The fixture table written as ECSV into ``folder`` and read back as `ucbplan export` does."""
    path = folder / "blocks.ecsv"
    fixture_table().write(path, format="ascii.ecsv")
    return read_blocks(path)


def minimal_table(table: Table) -> Table:
    """Only the required columns (+ coordinates), as a table from an older planner would be."""
    out = Table({c: table[c] for c in (*REQUIRED_COLUMNS, "ra_deg", "dec_deg")})
    out.meta = {}
    return out


def golden_export(table: Table, name: str) -> bytes:
    """Export ``table`` as the golden file ``name`` is made (rewriting it when regenerating)."""
    to, fmt = GOLDEN_CASES[name]
    # force: the fixture is a Paranal plan; the Keck/ING/LCO goldens test the formats, not the site.
    opts = ExportOptions(proposal_format=fmt, acquisition_s=GOLDEN_ACQUISITION_S, force=True)
    content = export_blocks(table, to, opts).content
    if REGEN:
        GOLDEN.mkdir(exist_ok=True)
        (GOLDEN / name).write_bytes(content)
    return content


def golden(name: str) -> bytes:
    """Bytes of the golden file ``name``."""
    return (GOLDEN / name).read_bytes()


def utc(text: str) -> datetime:
    """Aware UTC datetime of a naive ISO text."""
    return datetime.fromisoformat(text).replace(tzinfo=UTC)


def ms(text: str) -> np.datetime64:
    """An ISO time as numpy datetime64 in milliseconds (a second, independent time arithmetic)."""
    return np.datetime64(text, "ms")
