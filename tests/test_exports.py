"""Observatory exports: golden files per format, window arithmetic, starlist columns, ICS rules.

Golden files live in ``tests/golden/`` and are compared byte for byte. After an intended format
change, regenerate them with ``UCBPLAN_REGEN_GOLDEN=1 pytest tests/test_exports.py`` and review the
diff before committing.
"""

from __future__ import annotations

import json
import math
import os
import re
from datetime import UTC, datetime, timedelta
from pathlib import Path

import astropy.units as u
import numpy as np
import pytest
import typer
from astropy.table import Table
from astropy.time import Time
from hypothesis import given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from ucbplan.errors import InputFileError, OutputExistsError, UcbplanError
from ucbplan.observing.blocks import Block
from ucbplan.observing.blocktable import blocks_to_table, make_meta, read_blocks
from ucbplan.observing.exports import EXPORTERS, ExportOptions, export_blocks
from ucbplan.observing.exports.base import sexagesimal
from ucbplan.observing.exports.ics import ics_escape, ics_fold
from ucbplan.observing.exports.proposal import proposal_table, write_proposal
from ucbplan.observing.timeconv import quiet_erfa
from ucbplan.offline import configure_offline

GOLDEN = Path(__file__).parent / "golden"
REGEN = os.environ.get("UCBPLAN_REGEN_GOLDEN") == "1"
HM_RA_DEG = (8 + 6 / 60 + 23.2 / 3600) * 15.0  # 08 06 23.20
HM_DEC_DEG = 15 + 27 / 60 + 30.0 / 3600  # +15 27 30.0
HM_P_S = 321.5178508648
SDSS = "SDSS J0000-0030"


@pytest.fixture(autouse=True, scope="module")
def _offline() -> None:
    configure_offline()


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


def fixture_table() -> Table:
    """Fixed two-target blocks table (the source of every golden file)."""
    hm = {"ra": HM_RA_DEG, "dec": HM_DEC_DEG, "period": HM_P_S, "anchor": "quadrature"}
    sd = {"ra": 15.0 / 3600, "dec": -0.5, "period": 765.2, "anchor": "conjunction"}
    with quiet_erfa():
        blocks = [
            _block(
                "HM Cnc",
                "HM_Cnc-001",
                "2037-01-15T01:02:03.400",
                u_star=0.0,
                sigma=0.6,
                exptime=20.0,
                n_exp=2,
                readout=10.0,
                **hm,
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
                exptime=20.0,
                n_exp=2,
                readout=10.0,
                **hm,
            ),
            _block(
                "HM Cnc",
                "HM_Cnc-003",
                "2037-02-10T00:20:00.000",
                u_star=0.0,
                sigma=0.65,
                exptime=20.0,
                n_exp=2,
                readout=10.0,
                **hm,
            ),
        ]
        meta = make_meta(
            site={"name": "Paranal", "lon_deg": -70.4045, "lat_deg": -24.6272, "height_m": 2635},
            targets=[
                {"name": "HM Cnc", "file": "catalogs/hm-cnc.yaml", "sha256": "0" * 64},
                {"name": SDSS, "file": "sdss.yaml", "sha256": "1" * 64, "vmag": 19.3},
            ],
            constraints=["airmass <= 2.0", "moon separation >= 30 deg", "twilight: nautical"],
            mode="quadrature",
        )
        table = blocks_to_table(blocks, meta)
    table.meta["created_utc"] = "2036-12-01T12:00:00+00:00"
    table["vmag"] = [21.0, math.nan, 21.0, 21.0]
    return table


@pytest.fixture(scope="module")
def blocks_path(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("exports") / "blocks.ecsv"
    fixture_table().write(path, format="ascii.ecsv")
    return path


@pytest.fixture(scope="module")
def table(blocks_path: Path) -> Table:
    return read_blocks(blocks_path)


def _minimal(table: Table) -> Table:
    """Only the required columns (+ coordinates), as a table from an older planner would be."""
    from ucbplan.observing.blocktable import REQUIRED_COLUMNS

    out = Table({c: table[c] for c in (*REQUIRED_COLUMNS, "ra_deg", "dec_deg")})
    out.meta = {}
    return out


GOLDEN_CASES = [
    ("eso-p2", "ecsv", "exports_eso_p2.json"),
    ("keck-starlist", "ecsv", "exports_keck_starlist.txt"),
    ("ics", "ecsv", "exports_calendar.ics"),
    ("proposal", "ecsv", "exports_proposal.ecsv"),
    ("proposal", "csv", "exports_proposal.csv"),
    ("proposal", "latex", "exports_proposal.tex"),
    ("ing-cat", "ecsv", "exports_ing.cat"),
    ("lco", "ecsv", "exports_lco.json"),
]


@pytest.mark.parametrize(("to", "fmt", "name"), GOLDEN_CASES)
def test_golden(table: Table, to: str, fmt: str, name: str) -> None:
    # Byte-for-byte: any change to an observatory format must be deliberate (regenerate + review).
    result = export_blocks(table, to, ExportOptions(proposal_format=fmt, acquisition_s=600.0))
    path = GOLDEN / name
    if REGEN:
        GOLDEN.mkdir(exist_ok=True)
        path.write_bytes(result.content)
    assert result.content == path.read_bytes(), f"{name} differs; see the module docstring"


def test_every_registered_format_has_a_golden() -> None:
    assert {to for to, _, _ in GOLDEN_CASES} == set(EXPORTERS)


def test_unknown_format_lists_known_names(table: Table) -> None:
    with pytest.raises(UcbplanError, match="expected one of eso-p2, keck-starlist, ics, proposal"):
        export_blocks(table, "eso", ExportOptions())


# ----------------------------------------------------------------------------------------- ESO


def _utc(text: str) -> datetime:
    return datetime.fromisoformat(text).replace(tzinfo=UTC)


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
    assert ob["obx_absolute_times_list"] == (
        'absolute_times_list "{2037-01-15T00:51:00 2037-01-15T00:52:00 0} "'
    )
    assert ob["rounding_widening_s"] == pytest.approx(28.4 + 11.6, abs=1e-6)  # µs arithmetic


def test_eso_every_window_contains_its_exact_window(table: Table) -> None:
    opts = ExportOptions(acquisition_s=300.0, tolerance_sigma=5.0)
    doc = json.loads(export_blocks(table, "eso-p2", opts).content)
    for ob in doc["obs"]:
        (win,) = ob["absoluteTimeConstraints"]
        lo, hi = _utc(win["from"]), _utc(win["to"])
        assert lo.second == hi.second == 0
        assert lo <= _utc(ob["window_exact_utc"]["from"])
        assert hi >= _utc(ob["window_exact_utc"]["to"])
        # Outward rounding adds < 1 min at each end.
        assert (hi - lo) - timedelta(seconds=2 * ob["window_half_width_s"]) < timedelta(minutes=2)
        assert ob["window_half_width_s"] == max(5.0 * ob["sigma_t_s"], 10.0)


def test_eso_warns_when_rounding_is_large_fraction_of_period(table: Table) -> None:
    # HM_Cnc-001 widens by 40 s = 0.124 P_b (P_b = 321.5 s) > 0.1 -> warned; 0.2 -> silent.
    res = export_blocks(table, "eso-p2", ExportOptions(acquisition_s=600.0))
    assert any("HM_Cnc-001" in n and "0.12 P_b" in n for n in res.notes)
    quiet = ExportOptions(acquisition_s=600.0, rounding_warn_fraction=0.5)
    assert not [n for n in export_blocks(table, "eso-p2", quiet).notes if "rounding" in n]


def test_eso_target_list_csv(table: Table) -> None:
    doc = json.loads(export_blocks(table, "eso-p2", ExportOptions(acquisition_s=0.0)).content)
    assert doc["target_list_csv"] == [
        "HM_Cnc,08:06:23.200,+15:27:30.000,J2000",
        "SDSS_J0000-0030,00:00:01.000,-00:30:00.000,J2000",
    ]


def _pair_table(table: Table, gap_s: float) -> Table:
    """Two HM Cnc blocks ``gap_s`` apart (a quadrature pair in one session)."""
    rows = table[table["block_id"] == "HM_Cnc-001"]
    pair = Table(rows, copy=True)
    pair.add_row(rows[0])
    pair["block_id"][1] = "HM_Cnc-001b"
    for col in ("t_mid_utc", "t_start_utc", "t_end_utc", "t_alt_utc"):
        with quiet_erfa():
            shifted = Time(pair[col][0], scale="utc", precision=3) + gap_s * u.s
            pair[col] = [pair[col][0], shifted.isot]
    return pair


def test_eso_overlapping_windows_error_or_merge(table: Table) -> None:
    pair = _pair_table(table, HM_P_S / 2)  # u=0 then u=pi, 160.8 s apart: windows overlap
    with pytest.raises(UcbplanError, match=r"HM_Cnc-001 and HM_Cnc-001b overlap.*--merge-overlaps"):
        export_blocks(pair, "eso-p2", ExportOptions(acquisition_s=600.0, tolerance_floor_s=90.0))
    merged = ExportOptions(acquisition_s=600.0, tolerance_floor_s=90.0, merge_overlaps=True)
    doc = json.loads(export_blocks(pair, "eso-p2", merged).content)
    (ob,) = doc["obs"]
    assert ob["block_ids"] == ["HM_Cnc-001", "HM_Cnc-001b"]
    offsets = [v["mid_offset_from_ob_start_s"] for v in ob["merged_visits"]]
    # mid - OB start = acquisition + half block (25 s); second visit P_b/2 later (ms rounding).
    assert offsets == pytest.approx([625.0, 625.0 + HM_P_S / 2], abs=1e-3)


def test_eso_distant_blocks_do_not_overlap(table: Table) -> None:
    pair = _pair_table(table, 3600.0)
    doc = json.loads(export_blocks(pair, "eso-p2", ExportOptions(acquisition_s=600.0)).content)
    assert len(doc["obs"]) == 2


# ---------------------------------------------------------------------------------------- Keck


def test_keck_lines_match_exports_md_example(table: Table) -> None:
    text = export_blocks(table, "keck-starlist", ExportOptions()).content.decode()
    lines = text.splitlines()
    # The exact example of EXPORTS.md (same block, same coordinates, vmag 21.0).
    assert "# HM_Cnc u*=0 (quadrature) UTC-mid 2037-01-15T01:02:03.4 +/-0.6 s" in lines
    assert "HM_Cnc          08 06 23.20 +15 27 30.0 2000 vmag=21.0 rotmode=vertical" in lines
    sdss = [ln for ln in lines if ln.startswith("SDSS")]
    # Dec between 0 and -1 deg keeps its sign as -00; vmag from meta targets (19.3).
    assert sdss == ["SDSS_J0000-0030 00 00 01.00 -00 30 00.0 2000 vmag=19.3 rotmode=vertical"]


def test_keck_column_layout(table: Table) -> None:
    text = export_blocks(table, "keck-starlist", ExportOptions()).content.decode("ascii")
    assert "\t" not in text
    for line in text.splitlines():
        if line.startswith("#"):
            continue
        assert len(line[:16].rstrip()) <= 15 and line[15] == " "
        assert re.fullmatch(r"\d\d \d\d \d\d\.\d\d [+-]\d\d \d\d \d\d\.\d 2000", line[16:44])
        assert all(re.fullmatch(r"\w+=\S+", kv) for kv in line[45:].split())


def test_keck_truncates_long_names_and_refuses_collisions(table: Table) -> None:
    t = Table(table, copy=True)
    t["target"] = t["target"].astype("U40")
    t["target"][t["target"] == "HM Cnc"] = "A very long target name 1"
    res = export_blocks(t, "keck-starlist", ExportOptions())
    assert any("truncated" in n for n in res.notes)
    assert "A_very_long_tar 08 06 23.20" in res.content.decode()
    t["target"][t["target"] == SDSS] = "A very long target name 2"
    with pytest.raises(InputFileError, match="both become 'A_very_long_tar'"):
        export_blocks(t, "keck-starlist", ExportOptions())


@pytest.mark.parametrize(
    ("value", "decimals", "signed", "expected"),
    [
        (10.9999999, 2, False, "10 59 60.00".replace("10 59 60.00", "11 00 00.00")),  # carry
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


# ----------------------------------------------------------------------------------------- ICS


def _unfold(text: str) -> list[str]:
    return text.replace("\r\n ", "").split("\r\n")[:-1]


def test_ics_structure(table: Table) -> None:
    raw = export_blocks(table, "ics", ExportOptions()).content
    assert raw.endswith(b"\r\n")
    assert b"\n" not in raw.replace(b"\r\n", b"")  # CRLF only
    assert all(len(line) <= 75 for line in raw.split(b"\r\n"))  # folded at 75 octets
    lines = _unfold(raw.decode())
    assert lines[0] == "BEGIN:VCALENDAR" and lines[-1] == "END:VCALENDAR"
    assert lines.count("BEGIN:VEVENT") == len(table) == lines.count("END:VEVENT")
    uids = [ln for ln in lines if ln.startswith("UID:")]
    assert len(set(uids)) == len(table)
    assert all(ln == "DTSTAMP:20361201T120000Z" for ln in lines if ln.startswith("DTSTAMP"))


def test_ics_times_cover_blocks(table: Table) -> None:
    lines = _unfold(export_blocks(table, "ics", ExportOptions()).content.decode())
    starts = [ln[8:] for ln in lines if ln.startswith("DTSTART:")]
    ends = [ln[6:] for ln in lines if ln.startswith("DTEND:")]
    order = np.argsort(table["t_mid_utc"])
    for k, i in enumerate(order):
        t0 = datetime.strptime(starts[k], "%Y%m%dT%H%M%SZ").replace(tzinfo=UTC)
        t1 = datetime.strptime(ends[k], "%Y%m%dT%H%M%SZ").replace(tzinfo=UTC)
        b0, b1 = _utc(table["t_start_utc"][i]), _utc(table["t_end_utc"][i])
        # Rounded outward to whole seconds: covers the block, adds < 1 s at each end.
        assert t0 <= b0 < t0 + timedelta(seconds=1)
        assert t1 - timedelta(seconds=1) < b1 <= t1
    first = next(ln for ln in lines if ln.startswith("DTSTART:"))
    assert first == "DTSTART:20370115T010138Z"


def test_ics_description_escapes(table: Table) -> None:
    lines = _unfold(export_blocks(table, "ics", ExportOptions()).content.decode())
    desc = next(ln for ln in lines if ln.startswith("DESCRIPTION:"))
    assert "quadrature\\, u*=0 rad" in desc
    assert "+/- 0.6 s (1 sigma)\\, at Paranal" in desc
    assert "\\n" in desc


@given(st.text(alphabet=st.characters(blacklist_categories=("Cs",)), max_size=300))
@settings(max_examples=200, deadline=None)
def test_ics_fold_round_trip(text: str) -> None:
    line = "DESCRIPTION:" + ics_escape(text)
    folded = ics_fold(line)
    parts = folded.encode("utf-8").split(b"\r\n")
    assert all(len(p) <= 75 for p in parts)  # each part decodes: never split inside a character
    assert folded.replace("\r\n ", "") == line
    assert "\n" not in ics_escape(text) and "," not in ics_escape(text).replace("\\,", "")


# ------------------------------------------------------------------------------------ proposal


def test_proposal_totals_and_counts(table: Table) -> None:
    notes: list[str] = []
    summary = proposal_table(table, ExportOptions(acquisition_s=600.0), notes)
    hm = summary[summary["target"] == "HM Cnc"][0]
    sd = summary[summary["target"] == SDSS][0]
    assert hm["n_visits"] == 3 and sd["n_visits"] == 1
    # 2 x 20 s exposure + (600 s acquisition + 2 x 10 s readout) per visit.
    assert hm["exposure_per_visit_s"] == 40.0
    assert hm["overhead_per_visit_s"] == 620.0
    assert hm["total_h"] == pytest.approx(3 * 660.0 / 3600, rel=1e-12)
    for row in summary:
        assert row["total_h"] == pytest.approx(row["integration_h"] + row["overhead_h"], 1e-12)
    assert summary.meta["total_h"] == pytest.approx((3 * 660 + 720) / 3600, rel=1e-12)
    # Blocks span January and February 2037: 2 calendar months.
    assert hm["windows_per_month"] == 1.5 and hm["windows_by_month"] == "2037-01:2 2037-02:1"
    assert hm["p_orb_min"] == pytest.approx(HM_P_S / 60, rel=1e-12)
    assert sd["vmag"] == 19.3 and hm["vmag"] == 21.0
    assert hm["time_critical"] and "airmass <= 2.0" in hm["constraints"]
    assert hm["anchors"] == "quadrature 0,3.142"


def test_proposal_sigma_at_semester_midpoint(table: Table) -> None:
    summary = proposal_table(table, ExportOptions(acquisition_s=600.0), [])
    mid = _utc(summary.meta["semester_mid_utc"])
    # Semester = 2037-01-15T01:01:38.4 .. 2037-02-10T00:20:25; midpoint lies between HM_Cnc-002
    # (2037-01-16T03:10:11.25, 0.61 s) and HM_Cnc-003 (2037-02-10T00:20:00, 0.65 s).
    t2, t3 = _utc("2037-01-16T03:10:11.250"), _utc("2037-02-10T00:20:00")
    w = (mid - t2) / (t3 - t2)
    expected = 0.61 + w * (0.65 - 0.61)
    hm = summary[summary["target"] == "HM Cnc"][0]
    assert hm["sigma_t_mid_s"] == pytest.approx(expected, abs=1e-6)  # mid rounded to 1 s


def test_proposal_latex_escapes_underscores(table: Table) -> None:
    t = Table(table, copy=True)
    t["target"] = t["target"].astype("U40")
    t["target"][t["target"] == SDSS] = "ZTF_J1539+5027"
    latex = write_proposal(proposal_table(t, ExportOptions(), []), "latex")
    assert r"ZTF\_J1539+5027" in latex
    outside_math = re.sub(r"\$[^$]*\$", "", latex)
    assert not re.search(r"(?<!\\)_", outside_math)  # every _ outside math mode is escaped
    assert r"$P_\mathrm{orb}$ [min]" in latex and "Total" in latex


def test_proposal_unknown_format(table: Table) -> None:
    with pytest.raises(InputFileError, match="expected one of ecsv, csv, latex"):
        write_proposal(proposal_table(table, ExportOptions(), []), "xlsx")


# ------------------------------------------------------------------- robustness, missing extras


def test_minimal_table_uses_documented_defaults(table: Table) -> None:
    small = _minimal(table)
    res = export_blocks(small, "proposal", ExportOptions())
    text = " ".join(res.notes)
    assert "assuming 600 s acquisition" in text
    assert "P_b estimated as 4|t_alt_utc - t_mid_utc|" in text
    assert "readout taken as block width" in text
    summary = Table.read(res.content.decode(), format="ascii.ecsv")
    hm = summary[summary["target"] == "HM Cnc"][0]
    # Readout from the block width: 50 s - 2 x 20 s = 10 s (same as the readout column gives).
    assert hm["overhead_per_visit_s"] == pytest.approx(610.0, abs=1e-6)
    assert hm["p_orb_min"] == pytest.approx(HM_P_S / 60, abs=2e-3 / 60)  # ms ISO times: 4 x 0.5 ms
    for to in ("eso-p2", "keck-starlist", "ics", "ing-cat", "lco"):
        assert export_blocks(small, to, ExportOptions()).content


def test_missing_coordinates_is_a_clear_error(table: Table) -> None:
    small = _minimal(table)
    small.remove_columns(["ra_deg", "dec_deg"])
    with pytest.raises(InputFileError, match="neither ra_deg/dec_deg nor ra_hms/dec_dms"):
        export_blocks(small, "keck-starlist", ExportOptions())


def test_bad_time_is_a_clear_error(table: Table) -> None:
    t = Table(table, copy=True)
    t["t_mid_utc"] = t["t_mid_utc"].astype("U30")
    t["t_mid_utc"][0] = "yesterday"
    with pytest.raises(InputFileError, match="column t_mid_utc row 0: got 'yesterday'"):
        export_blocks(t, "ics", ExportOptions())


def test_empty_table(table: Table) -> None:
    with pytest.raises(InputFileError, match="no rows"):
        export_blocks(table[:0], "ics", ExportOptions())


# ----------------------------------------------------------------------------------------- CLI


def _app() -> typer.Typer:
    from ucbplan.cli.export import register

    app = typer.Typer()

    @app.callback()
    def _root() -> None:
        """Test shell."""

    register(app)
    return app


def test_cli_export_writes_file_and_refuses_overwrite(blocks_path: Path, tmp_path: Path) -> None:
    out = tmp_path / "plan.ics"
    runner = CliRunner()
    args = ["export", str(blocks_path), "--to", "ics", "-o", str(out)]
    res = runner.invoke(_app(), args)
    assert res.exit_code == 0, res.output
    assert out.read_bytes() == (GOLDEN / "exports_calendar.ics").read_bytes()
    res = runner.invoke(_app(), args)
    assert isinstance(res.exception, OutputExistsError)
    res = runner.invoke(_app(), [*args, "--overwrite"])
    assert res.exit_code == 0


def test_cli_export_proposal_latex_to_stdout(blocks_path: Path) -> None:
    res = CliRunner().invoke(
        _app(),
        [
            "export",
            str(blocks_path),
            "--to",
            "proposal",
            "--format",
            "latex",
            "--acquisition",
            "600",
        ],
    )
    assert res.exit_code == 0
    assert res.stdout.encode() == (GOLDEN / "exports_proposal.tex").read_bytes()


def test_cli_export_unknown_format(blocks_path: Path) -> None:
    res = CliRunner().invoke(_app(), ["export", str(blocks_path), "--to", "nope"])
    assert isinstance(res.exception, UcbplanError)
    assert "unknown export format 'nope'" in str(res.exception)


def test_time_columns_give_the_same_export(table: Table) -> None:
    # A table holding astropy Time columns instead of ISO strings exports identically.
    t = Table(table, copy=True)
    with quiet_erfa():
        for col in ("t_mid_utc", "t_start_utc", "t_end_utc"):
            t[col] = Time(list(t[col]), scale="utc", precision=3)
    for to in ("eso-p2", "ics", "keck-starlist"):
        opts = ExportOptions(acquisition_s=600.0)
        assert export_blocks(t, to, opts).content == export_blocks(table, to, opts).content


def test_iso_rounding_is_half_up() -> None:
    from ucbplan.observing.exports.base import iso_ms

    t = datetime(2037, 1, 16, 3, 10, 11, 250000, tzinfo=UTC)
    assert iso_ms(t, 1) == "2037-01-16T03:10:11.3"
    assert iso_ms(t.replace(second=59, microsecond=960000), 1) == "2037-01-16T03:11:00.0"


def test_sessions_are_one_visit(table: Table) -> None:
    # A planner session (u = 0 then u = pi, P_b/2 apart) is one acquisition: one ESO OB listing
    # both blocks, one visit in the proposal with one acquisition overhead.
    pair = _pair_table(table, HM_P_S / 2)
    pair["session_id"] = ["HM_Cnc-S01", "HM_Cnc-S01"]
    opts = ExportOptions(acquisition_s=600.0)
    doc = json.loads(export_blocks(pair, "eso-p2", opts).content)
    (ob,) = doc["obs"]
    assert ob["block_ids"] == ["HM_Cnc-001", "HM_Cnc-001b"]
    offsets = [v["mid_offset_from_ob_start_s"] for v in ob["merged_visits"]]
    assert offsets == pytest.approx([625.0, 625.0 + HM_P_S / 2], abs=1e-3)  # ms ISO times
    (row,) = proposal_table(pair, opts, [])
    assert row["n_blocks"] == 2 and row["n_visits"] == 1
    # Exposure 2 x 40 s; overheads 600 s acquisition once + 2 x 2 x 10 s readout.
    assert row["exposure_per_visit_s"] == 80.0 and row["overhead_per_visit_s"] == 640.0
    assert row["total_h"] == pytest.approx(720.0 / 3600.0, rel=1e-12)


def test_acquisition_from_plan_meta_and_vmag_from_target_file(table: Table) -> None:
    import hashlib

    hm_file = Path(__file__).resolve().parents[1] / "catalogs" / "hm-cnc.yaml"
    t = _minimal(table)
    digest = hashlib.sha256(hm_file.read_bytes()).hexdigest()
    t.meta = {
        "overhead_s": 300.0,
        "targets": [{"name": "HM Cnc", "file": str(hm_file), "sha256": digest}],
    }
    res = export_blocks(t, "keck-starlist", ExportOptions())
    # vmag 21.1 is in catalogs/hm-cnc.yaml; the table itself has no vmag.
    assert "HM_Cnc          08 06 23.20 +15 27 30.0 2000 vmag=21.1 rotmode=vertical" in (
        res.content.decode().splitlines()
    )
    doc = json.loads(export_blocks(t, "eso-p2", ExportOptions()).content)
    assert {ob["acquisition_s"] for ob in doc["obs"]} == {300.0}
    # A file that changed since planning (sha256 mismatch) is not trusted: no vmag.
    t.meta["targets"][0]["sha256"] = "0" * 64
    assert "vmag=" not in export_blocks(t, "keck-starlist", ExportOptions()).content.decode()
