"""Keck starlist and ING catalogue: golden files, column rules checked against the blocks table."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from astropy.coordinates import Angle
from astropy.table import Table
from hypothesis import given, settings
from hypothesis import strategies as st
from support.exports import SDSS, SDSS_VMAG_META, golden, golden_export, ms, written_table

from ucbplan.errors import InputFileError
from ucbplan.observing.blocks.cells import sexagesimal
from ucbplan.observing.exports import ExportOptions, export_blocks

KECK = "exports_keck_starlist.txt"
ING = "exports_ing.cat"
KECK_COORDS = re.compile(r"(\d\d \d\d \d\d\.\d\d) ([+-]\d\d \d\d \d\d\.\d) 2000")
KECK_COMMENT = re.compile(
    r"# (\S+) u\*=(\S+) \((\S+)\) UTC-mid (\S+) \+/-(\S+) s exp (\d+)x(\S+) s"
)
KECK_TOTAL = re.compile(r"# (\S+) (\d+) exposures?, (\S+) s shutter in (\d+) visits?")
ING_LINE = re.compile(
    r"(\S{1,20}) +(\d\d \d\d \d\d\.\d\d) ([+-]\d\d \d\d \d\d\.\d) J2000"
    r" ! (\d+) exposures?, (\S+) s shutter in (\d+) visits?"
)
ING_BLOCK = re.compile(r"! (\S{1,20}) UTC-mid (\S+) \+/-(\S+) s exp (\d+)x(\S+) s")


@pytest.fixture(scope="module")
def table(tmp_path_factory: pytest.TempPathFactory) -> Table:
    return written_table(tmp_path_factory.mktemp("exports"))


def _row_of(table: Table, short: str) -> Table.Row:
    return next(r for r in table if str(r["target"]).replace(" ", "_") == short)


def _check_coordinates(row: Table.Row, ra: str, dec: str, ra_dec: int, dec_dec: int) -> None:
    """RA (hours) and Dec (degrees) strings agree with the table to half their last digit."""
    assert abs(Angle(ra, unit="hourangle").deg - row["ra_deg"]) <= 0.5 * 10**-ra_dec * 15 / 3600
    assert abs(Angle(dec, unit="deg").deg - row["dec_deg"]) <= 0.5 * 10**-dec_dec / 3600


def _check_time_and_sigma(row: Table.Row, mid: str, sigma: str, decimals: int) -> None:
    """A written UTC mid-time and σ agree with the table (to the digits written)."""
    error = abs(ms(mid) - ms(row["t_mid_utc"])) / np.timedelta64(1, "ms")
    assert error <= 0.5 * 10 ** (3 - decimals)
    assert float(sigma) == pytest.approx(row["sigma_t_s"], rel=0.05)  # two significant figures


# ---------------------------------------------------------------------------------------- Keck


def test_keck_golden(table: Table) -> None:
    assert golden_export(table, KECK) == golden(KECK), (
        f"{KECK} differs; see tests/support/exports.py"
    )


def _nearest_block(table: Table, short: str, mid: str) -> Table.Row:
    """The block of target ``short`` whose t_mid_utc is closest to ``mid``."""
    rows = [r for r in table if str(r["target"]).replace(" ", "_") == short]
    return min(rows, key=lambda r: abs(ms(r["t_mid_utc"]) - ms(mid)))


def _check_keck_target(line: str, table: Table, pending: list[Table.Row]) -> str:
    """A target line: fixed columns, coordinates and vmag of the table, after its comments."""
    name = line[:16].rstrip()  # name in columns 1-16, at most 15 characters, no blanks
    assert 0 < len(name) <= 15 and " " not in name and line[15] == " "
    ra, dec = KECK_COORDS.fullmatch(line[16:44]).groups()  # type: ignore[union-attr]
    row = _row_of(table, name)
    _check_coordinates(row, ra, dec, 2, 1)
    pairs = dict(kv.split("=") for kv in line[45:].split())
    vmag = row["vmag"] if math.isfinite(row["vmag"]) else SDSS_VMAG_META
    assert pairs == {"vmag": f"{vmag:.1f}", "rotmode": "vertical"}
    # The comments just above are this target's blocks, all of them, in time order.
    own = table[table["target"] == row["target"]]
    assert [r["block_id"] for r in pending] == list(own[np.argsort(own["t_mid_utc"])]["block_id"])
    return name


def test_keck_golden_follows_the_starlist_columns(table: Table) -> None:
    text = golden(KECK).decode("ascii")
    assert "\t" not in text and text.endswith("\n")
    lines = text.splitlines()
    assert lines[0].startswith("# ucbplan ") and "Paranal" in lines[0]
    pending: list[Table.Row] = []
    targets: list[str] = []
    for line in lines[1:]:
        if not line.startswith("#"):
            targets.append(_check_keck_target(line, table, pending))
            pending = []
            continue
        if KECK_TOTAL.fullmatch(line):
            continue  # the target's totals: checked in test_exports_counts
        match = KECK_COMMENT.fullmatch(line)
        assert match, line
        short, u_star, anchor, mid, sigma, n_exp, exptime = match.groups()
        row = _nearest_block(table, short, mid)
        assert (int(n_exp), float(exptime)) == (row["n_exp"], row["exptime_s"])
        assert anchor == row["anchor"]
        assert float(u_star) == pytest.approx(row["u_star_rad"], abs=1e-5)
        _check_time_and_sigma(row, mid, sigma, 1)
        pending.append(row)
    assert not pending
    assert sorted(targets) == sorted({str(n).replace(" ", "_") for n in table["target"]})


def test_keck_truncates_long_names_and_refuses_collisions(table: Table) -> None:
    t = Table(table, copy=True)
    t["target"] = t["target"].astype("U40")
    t["target"][t["target"] == "HM Cnc"] = "A very long target name 1"
    res = export_blocks(t, "keck-starlist", ExportOptions(force=True))
    assert any("truncated" in n for n in res.notes)
    assert "A_very_long_tar 08 06 23.20" in res.content.decode()
    t["target"][t["target"] == SDSS] = "A very long target name 2"
    with pytest.raises(InputFileError, match="both become 'A_very_long_tar'"):
        export_blocks(t, "keck-starlist", ExportOptions(force=True))


# ----------------------------------------------------------------------------------------- ING


def test_ing_golden(table: Table) -> None:
    assert golden_export(table, ING) == golden(ING), f"{ING} differs; see tests/support/exports.py"


def test_ing_golden_follows_the_catalogue_format(table: Table) -> None:
    lines = golden(ING).decode("ascii").splitlines()
    names = []
    pending: list[Table.Row] = []
    for line in lines:
        block = ING_BLOCK.fullmatch(line)
        if block:  # every block of the target above, in time order, with its exposures
            short, mid, sigma, n_exp, exptime = block.groups()
            row = _nearest_block(table, short, mid)
            _check_time_and_sigma(row, mid, sigma, 1)
            assert (int(n_exp), float(exptime)) == (row["n_exp"], row["exptime_s"])
            pending.append(row)
            continue
        _check_ing_pending(table, pending)
        name, ra, dec, count, shutter, _ = ING_LINE.fullmatch(line).groups()  # type: ignore[union-attr]
        assert not set(name) & {":", "\t"}
        row = _row_of(table, name)
        _check_coordinates(row, ra, dec, 2, 1)
        own = table[table["target"] == row["target"]]
        assert int(count) == sum(own["n_exp"])
        assert float(shutter) == pytest.approx(float(sum(own["n_exp"] * own["exptime_s"])))
        names.append(name)
        pending = []
    _check_ing_pending(table, pending)
    assert sorted(names) == sorted({str(n).replace(" ", "_") for n in table["target"]})


def _check_ing_pending(table: Table, pending: list[Table.Row]) -> None:
    """The block lines below a target line are all its blocks, in time order."""
    if pending:
        own = table[table["target"] == pending[0]["target"]]
        order = list(own[np.argsort(own["t_mid_utc"])]["block_id"])
        assert [r["block_id"] for r in pending] == order


def test_ing_names_lose_colons_and_stay_short(table: Table) -> None:
    t = Table(table, copy=True)
    t["target"] = t["target"].astype("U40")
    t["target"][t["target"] == SDSS] = "Gaia DR3 1234:5678 with a long tail"
    lines = export_blocks(t, "ing-cat", ExportOptions(force=True)).content.decode().splitlines()
    line = next(x for x in lines if not x.startswith(("!", "HM_Cnc")))
    assert line.startswith("Gaia_DR3_1234_5678_w ")


# ------------------------------------------------------------------------------- sexagesimal


@pytest.mark.parametrize(
    ("value", "decimals", "signed", "expected"),
    [
        (10.9999999, 2, False, "11 00 00.00"),  # carry: never 59 60.00
        (23.99999999, 2, False, "00 00 00.00"),  # RA wraps at 24 h
        (-0.5, 1, True, "-00 30 00.0"),
        (-0.000001, 1, True, "+00 00 00.0"),  # rounds to zero: no '-0'
        (-12.5083333333, 1, True, "-12 30 30.0"),
    ],
)
def test_sexagesimal(value: float, decimals: int, signed: bool, expected: str) -> None:
    assert sexagesimal(value, decimals, " ", signed) == expected


@given(st.floats(0.0, 24.0, exclude_max=True), st.integers(0, 3))
@settings(max_examples=200, deadline=None)
def test_sexagesimal_round_trip(hours: float, decimals: int) -> None:
    # Parsing the string back differs from the input by at most half a unit of the last digit
    # (modulo the 24 h wrap).
    text = sexagesimal(hours, decimals, " ", False)
    h, m, s = (float(x) for x in text.split())
    back = h + m / 60 + s / 3600
    err = abs((back - hours + 12) % 24 - 12) * 3600
    assert err <= 0.5 * 10**-decimals + 1e-9
    assert 0 <= m < 60 and 0 <= s < 60
