"""ESO p2 export: the golden file, the p2 window rules checked against the blocks table, OBs."""

from __future__ import annotations

import json
import math
import re
from itertools import pairwise

import astropy.units as u
import numpy as np
import pytest
from astropy.coordinates import Angle
from astropy.table import Table
from astropy.time import Time
from hypothesis import given, settings
from hypothesis import strategies as st
from support.exports import GOLDEN_ACQUISITION_S, HM_P_S, golden, golden_export, ms, written_table

from ucbplan.errors import UcbplanError
from ucbplan.observing.exports import ExportOptions, export_blocks
from ucbplan.observing.exports.eso_p2 import ESO_NAME_MAX, _ob_names
from ucbplan.offline import offline

NAME = "exports_eso_p2.json"
P2_MINUTE = re.compile(r"\d{4}-\d\d-\d\dT\d\d:\d\d")  # p2 absolute times: UTC, whole minutes
TARGET_CSV = re.compile(r"([^,\s]+),(\d\d:\d\d:\d\d\.\d{3}),([+-]\d\d:\d\d:\d\d\.\d{3}),J2000")
MINUTE = np.timedelta64(1, "m")


@pytest.fixture(scope="module")
def table(tmp_path_factory: pytest.TempPathFactory) -> Table:
    return written_table(tmp_path_factory.mktemp("exports"))


def test_golden(table: Table) -> None:
    # Byte for byte: any change to the format must be deliberate (regenerate + review).
    assert golden_export(table, NAME) == golden(NAME), (
        f"{NAME} differs; see tests/support/exports.py"
    )


def _p2_minute(text: str) -> np.datetime64:
    assert P2_MINUTE.fullmatch(text), text
    return np.datetime64(text, "m")


def _expected_window(row: Table.Row, k: float, floor_s: float) -> tuple[np.datetime64, ...]:
    """(OB start, window from, window to) by hand: t_start − acquisition ± max(k σ, floor),
    rounded outward to whole minutes (numpy datetime64: a second, independent arithmetic)."""
    half = np.timedelta64(round(max(k * row["sigma_t_s"], floor_s) * 1000), "ms")
    ob_start = ms(row["t_start_utc"]) - np.timedelta64(round(GOLDEN_ACQUISITION_S * 1000), "ms")
    lo, hi = ob_start - half, ob_start + half
    lo_min = lo.astype("datetime64[m]")  # floor (dates after 1970)
    hi_min = hi.astype("datetime64[m]")
    hi_min = hi_min if hi_min == hi else hi_min + MINUTE
    return ob_start, lo_min, hi_min


def test_golden_follows_the_p2_window_rules(table: Table) -> None:
    doc = json.loads(golden(NAME))
    rows = {str(r["block_id"]): r for r in table}
    windows = []
    for ob in doc["obs"]:
        (win,) = ob["absoluteTimeConstraints"]
        lo, hi = _p2_minute(win["from"]), _p2_minute(win["to"])
        for block_id in ob["block_ids"]:
            ob_start, exp_lo, exp_hi = _expected_window(rows.pop(block_id), 3.0, 10.0)
            assert lo <= exp_lo < ob_start < exp_hi <= hi
            if len(ob["block_ids"]) == 1:
                assert (lo, hi) == (exp_lo, exp_hi)  # a lone block: exactly its rounded window
        assert ob["obx_absolute_times_list"] == (
            f'absolute_times_list "{{{win["from"]}:00 {win["to"]}:00 0}} "'
        )
        windows.append((lo, hi))
    assert not rows, f"blocks without an OB: {sorted(rows)}"
    windows.sort()
    assert all(a_hi <= b_lo for (_, a_hi), (b_lo, _) in pairwise(windows))  # no overlaps


def test_golden_target_list_matches_the_table(table: Table) -> None:
    lines = json.loads(golden(NAME))["target_list_csv"]
    assert len(lines) == len(set(table["target"]))
    for line in lines:
        name, ra, dec = TARGET_CSV.fullmatch(line).groups()  # type: ignore[union-attr]
        row = table[[n.replace(" ", "_") == name for n in table["target"]]][0]
        assert abs(Angle(ra, unit="hourangle").deg - row["ra_deg"]) <= 0.0005 * 15 / 3600
        assert abs(Angle(dec, unit="deg").deg - row["dec_deg"]) <= 0.0005 / 3600


def test_eso_window_is_ob_start_with_acquisition_rounded_outward(table: Table) -> None:
    doc = json.loads(export_blocks(table, "eso-p2", ExportOptions(acquisition_s=600.0)).content)
    ob = {o["block_ids"][0]: o for o in doc["obs"]}["HM_Cnc-001"]
    # By hand: mid 01:02:03.400, block 2x20 s + 10 s readout = 50 s -> start 01:01:38.400;
    # OB start = start - 600 s = 00:51:38.400; half-width max(3*0.6, 10) = 10 s.
    assert ob["ob_start_utc"] == "2037-01-15T00:51:38.400"
    assert ob["window_exact_utc"] == {
        "from": "2037-01-15T00:51:28.400",
        "to": "2037-01-15T00:51:48.400",
    }
    assert ob["absoluteTimeConstraints"] == [{"from": "2037-01-15T00:51", "to": "2037-01-15T00:52"}]
    assert ob["rounding_widening_s"] == pytest.approx(28.4 + 11.6, abs=1e-6)  # µs arithmetic


def test_eso_wide_tolerance_uses_k_sigma(table: Table) -> None:
    # k = 20: HM Cnc half-width 20 x 0.6 = 12 s > 10 s floor; SDSS 20 x 2.3 = 46 s.
    opts = ExportOptions(acquisition_s=300.0, tolerance_sigma=20.0)
    doc = json.loads(export_blocks(table, "eso-p2", opts).content)
    half = {ob["block_ids"][0]: ob["window_half_width_s"] for ob in doc["obs"]}
    assert half["HM_Cnc-001"] == pytest.approx(12.0) and half["SDSS_J0000-0030-001"] == 46.0
    sdss = next(ob for ob in doc["obs"] if ob["target"] != "HM Cnc")
    # SDSS start 04:29:00.000 - 300 s = 04:24:00 +/- 46 s -> 04:23:14 .. 04:24:46 -> 04:23 .. 04:25
    assert sdss["absoluteTimeConstraints"] == [
        {"from": "2037-01-15T04:23", "to": "2037-01-15T04:25"}
    ]


def test_eso_warns_when_rounding_is_large_fraction_of_period(table: Table) -> None:
    # HM_Cnc-001 widens by 40 s = 0.124 P_b (P_b = 321.5 s) > 0.1 -> warned; 0.5 -> silent.
    res = export_blocks(table, "eso-p2", ExportOptions(acquisition_s=600.0))
    assert any("HM_Cnc-001" in n and "0.12 P_b" in n for n in res.notes)
    quiet = ExportOptions(acquisition_s=600.0, rounding_warn_fraction=0.5)
    assert not [n for n in export_blocks(table, "eso-p2", quiet).notes if "rounding" in n]


def _pair_table(table: Table, gap_s: float) -> Table:
    """Two HM Cnc blocks ``gap_s`` apart (a quadrature pair in one session)."""
    rows = table[table["block_id"] == "HM_Cnc-001"]
    pair = Table(rows, copy=True)
    pair.add_row(rows[0])
    pair["block_id"][1] = "HM_Cnc-001b"
    for col in ("t_mid_utc", "t_start_utc", "t_end_utc", "t_alt_utc"):
        with offline():
            shifted = Time(pair[col][0], scale="utc", precision=3) + gap_s * u.s
            pair[col] = [pair[col][0], shifted.isot]
    return pair


def test_eso_overlapping_windows_error_or_merge(table: Table) -> None:
    pair = _pair_table(table, HM_P_S / 2)  # u=0 then u=pi, 160.8 s apart: windows overlap
    with pytest.raises(UcbplanError, match=r"HM_Cnc-001 and HM_Cnc-001b overlap.*`merge_overlaps`"):
        export_blocks(pair, "eso-p2", ExportOptions(acquisition_s=600.0, tolerance_floor_s=90.0))
    merged = ExportOptions(acquisition_s=600.0, tolerance_floor_s=90.0, merge_overlaps=True)
    doc = json.loads(export_blocks(pair, "eso-p2", merged).content)
    (ob,) = doc["obs"]
    assert ob["block_ids"] == ["HM_Cnc-001", "HM_Cnc-001b"]
    offsets = [v["mid_offset_from_ob_start_s"] for v in ob["merged_visits"]]
    # mid - OB start = acquisition + half block (25 s); second visit P_b/2 later (ms rounding).
    assert offsets == pytest.approx([625.0, 625.0 + HM_P_S / 2], abs=1e-3)


def test_eso_overlap_of_different_targets_is_refused(table: Table) -> None:
    pair = _pair_table(table, HM_P_S / 2)
    pair["target"] = ["HM Cnc", "V407 Vul"]
    merged = ExportOptions(acquisition_s=600.0, tolerance_floor_s=90.0, merge_overlaps=True)
    with pytest.raises(UcbplanError, match="different targets"):
        export_blocks(pair, "eso-p2", merged)


def test_eso_distant_blocks_do_not_overlap(table: Table) -> None:
    pair = _pair_table(table, 3600.0)
    doc = json.loads(export_blocks(pair, "eso-p2", ExportOptions(acquisition_s=600.0)).content)
    assert len(doc["obs"]) == 2


def test_sessions_are_one_ob(table: Table) -> None:
    # A planner session (u = 0 then u = pi, P_b/2 apart) is one acquisition: one ESO OB listing
    # both blocks with their mid-exposure offsets from the OB start.
    pair = _pair_table(table, HM_P_S / 2)
    pair["session_id"] = ["HM_Cnc-S01", "HM_Cnc-S01"]
    doc = json.loads(export_blocks(pair, "eso-p2", ExportOptions(acquisition_s=600.0)).content)
    (ob,) = doc["obs"]
    assert ob["block_ids"] == ["HM_Cnc-001", "HM_Cnc-001b"]
    offsets = [v["mid_offset_from_ob_start_s"] for v in ob["merged_visits"]]
    assert offsets == pytest.approx([625.0, 625.0 + HM_P_S / 2], abs=1e-3)  # ms ISO times


@given(
    st.lists(
        st.text(alphabet="abcXYZ_-0123456789 é", min_size=1, max_size=60).filter(
            lambda s: any(c.isalnum() for c in s) and s == " ".join(s.split())
        ),
        min_size=1,
        max_size=12,
        unique_by=lambda s: "_".join(s.split()),
    )
)
@settings(max_examples=60, deadline=None)
def test_ob_names_are_unique_short_and_stable(blocks: list[str]) -> None:
    # Block ids that differ only after 32 characters must still give distinct OB names.
    ids = [f"{'long_common_prefix_of_a_block_id_'}{b}" for b in blocks]
    try:
        names = _ob_names(ids, [])
    except UcbplanError as exc:  # only a transliteration collision may remain (both named)
        assert "both become" in str(exc)
        return
    assert len(set(names.values())) == len(ids)
    assert all(len(n) <= ESO_NAME_MAX and n.isascii() for n in names.values())
    assert _ob_names(list(reversed(ids)), []) == names  # a block's name does not depend on order


def test_ob_bodies_carry_target_constraints_and_exposures(table: Table) -> None:
    doc = json.loads(golden(NAME))
    rows = {str(r["block_id"]): r for r in table}
    for ob in doc["obs"]:
        body = ob["ob"]
        row = rows[ob["block_ids"][0]]
        target = body["target"]
        # Read back by astropy: the p2 sexagesimal strings are the table's coordinates.
        assert Angle(target["ra"], unit="hourangle").deg == pytest.approx(row["ra_deg"], abs=2e-7)
        assert Angle(target["dec"], unit="deg").deg == pytest.approx(row["dec_deg"], abs=3e-6)
        assert target["equinox"] == "J2000" and target["epoch"] == 2000.0
        assert body["constraints"] == {
            "name": "ucbplan constraints",
            "airmass": 2.0,  # from the plan's "airmass <= 2.0"
            "moonDistance": 30,  # from "moon separation >= 30 deg"
            "seeing": 1.0,
        }
        science = body["templates"][1]["parameters"]
        assert science["exposure_time_s"] == row["exptime_s"] and science["n_exp"] == row["n_exp"]
        assert body["obsDescription"]["name"] == ob["name"]
        assert all(b in body["obsDescription"]["userComments"] for b in ob["block_ids"])


def test_ob_constraints_follow_the_plan_and_options(table: Table) -> None:
    t = Table(table, copy=True)
    t.meta["constraints"] = ["airmass <= 1.5", "moon separation >= 45.0 deg"]
    opts = ExportOptions(acquisition_s=600.0, seeing_arcsec=0.8, instrument="xshooter-uvb")
    res = export_blocks(t, "eso-p2", opts)
    body = json.loads(res.content)["obs"][0]["ob"]
    assert (body["constraints"]["airmass"], body["constraints"]["moonDistance"]) == (1.5, 45)
    assert body["constraints"]["seeing"] == 0.8
    science = body["templates"][1]["parameters"]
    assert science["instrument"] == "xshooter-uvb" and science["readout_s"] == 34.0
    assert body["templates"][0]["parameters"] == {"acquisition_s": 409.0}
    t.meta["constraints"] = []
    res = export_blocks(t, "eso-p2", opts)
    assert any("names no airmass limit" in n for n in res.notes)


@pytest.mark.parametrize("seeing", [0.0, -1.0, 6.0, math.nan])
def test_bad_seeing_is_refused(seeing: float) -> None:
    with pytest.raises(UcbplanError, match=r"^seeing: expected a number in"):
        ExportOptions(seeing_arcsec=seeing)
