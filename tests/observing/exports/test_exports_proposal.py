"""Proposal table: golden ECSV/CSV/LaTeX, read back by astropy or parsed, checked by hand."""

from __future__ import annotations

import functools
import math
import re
import shutil
import subprocess
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from astropy.coordinates import Angle
from astropy.table import Table, vstack
from hypothesis import given, settings
from hypothesis import strategies as st
from support.exports import (
    GOLDEN_ACQUISITION_S,
    HM_P_S,
    SDSS,
    SDSS_VMAG_META,
    golden,
    golden_export,
    ms,
    written_table,
)

from ucbplan.errors import InputError, InputFileError
from ucbplan.observing.exports import ExportOptions
from ucbplan.observing.exports.proposal import proposal_table, write_proposal

#: The proposal table's columns and units (docs/exports.md, "Proposal technical section").
UNITS = {
    "target": None,
    "ra_hms": None,
    "dec_dms": None,
    "vmag": "mag",
    "p_orb_min": "min",
    "sigma_t_mid_s": "s",
    "anchors": None,
    "tolerance_rad": "rad",
    "window_half_width_s": "s",
    "n_blocks": None,
    "n_visits": None,
    "n_exposures": None,
    "windows_per_month": None,
    "windows_by_month": None,
    "exposure_per_visit_s": "s",
    "overhead_per_visit_s": "s",
    "idle_per_visit_s": "s",
    "integration_h": "h",
    "overhead_h": "h",
    "idle_h": "h",
    "total_h": "h",
    "efficiency": None,
    "time_critical": None,
    "ephemeris": None,
    "constraints": None,
}


@functools.lru_cache(maxsize=1)
def _written() -> Table:
    import tempfile

    with tempfile.TemporaryDirectory() as folder:
        return written_table(Path(folder))


def written_table_cached() -> Table:
    """The fixture table as written and read back (cached: hypothesis calls it often)."""
    return _written()


@pytest.fixture(scope="module")
def table(tmp_path_factory: pytest.TempPathFactory) -> Table:
    return written_table(tmp_path_factory.mktemp("exports"))


@pytest.mark.parametrize(
    "name", ["exports_proposal.ecsv", "exports_proposal.csv", "exports_proposal.tex"]
)
def test_golden(table: Table, name: str) -> None:
    assert golden_export(table, name) == golden(name), (
        f"{name} differs; see tests/support/exports.py"
    )


# -------------------------------------------------------------------- the table, by hand


def _seconds(texts: Any) -> np.ndarray:
    return np.array([(ms(t) - ms("2037-01-01")) / np.timedelta64(1, "ms") / 1e3 for t in texts])


#: The fixture is a Paranal plan of Jan-Feb 2037: ESO period P138 = 2036-10-01 .. 2037-03-31
#: (P110 began 2022-10-01; 28 periods of 6 months later), midpoint 2036-12-31 00:00 UTC (91 of
#: its 182 days), before every block: sigma_T there is the first block's.
P138_MID = "2036-12-31T00:00:00"


def _anchors(rows: Table) -> str:
    groups: dict[str, set[float]] = {}
    for row in rows:
        groups.setdefault(str(row["anchor"]), set()).add(round(float(row["u_star_rad"]), 9))
    return "; ".join(f"{a} {','.join(f'{v:.4g}' for v in sorted(vs))}" for a, vs in groups.items())


def _by_hand(table: Table) -> dict[str, dict[str, Any]]:
    """Every proposal column per target, recomputed from the blocks table (600 s acquisition;
    no session_id, so every block is its own visit; readout n_exp x readout_s per block)."""
    months_of = [str(t)[:7] for t in table["t_start_utc"]]
    first, last = min(months_of), max(months_of)
    n_months = (int(last[:4]) - int(first[:4])) * 12 + int(last[5:]) - int(first[5:]) + 1
    meta_vmag = {t["name"]: t.get("vmag") for t in table.meta["targets"]}
    out = {}
    for target in dict.fromkeys(table["target"]):
        rows = table[table["target"] == target]
        rows = rows[np.argsort(_seconds(rows["t_mid_utc"]))]
        assert not any(rows["session_id"])  # no sessions: one visit per block
        visits = len(rows)
        exposure = float(np.sum(rows["n_exp"] * rows["exptime_s"]))
        overhead = visits * GOLDEN_ACQUISITION_S + float(np.sum(rows["n_exp"] * rows["readout_s"]))
        assert ms(P138_MID) < ms(rows["t_mid_utc"][0])
        sigma_mid = float(rows["sigma_t_s"][0])
        vmag = rows["vmag"][0] if math.isfinite(rows["vmag"][0]) else meta_vmag[target]
        out[str(target)] = {
            "ra_hms": Angle(rows["ra_deg"][0], "deg").to_string(
                "hourangle", sep=":", precision=2, pad=True
            ),
            "dec_dms": Angle(rows["dec_deg"][0], "deg").to_string(
                sep=":", precision=1, pad=True, alwayssign=True
            ),
            "vmag": vmag,
            "p_orb_min": float(np.median(rows["period_s"])) / 60,
            "sigma_t_mid_s": sigma_mid,
            "anchors": _anchors(rows),
            "tolerance_rad": 2 * math.pi * max(3 * sigma_mid, 10.0) / float(rows["period_s"][0]),
            "window_half_width_s": max(3 * sigma_mid, 10.0),
            "n_blocks": len(rows),
            "n_visits": visits,
            "n_exposures": int(np.sum(rows["n_exp"])),
            "windows_per_month": visits / n_months,
            "windows_by_month": " ".join(
                f"{m}:{c}"
                for m, c in sorted(Counter(str(t)[:7] for t in rows["t_start_utc"]).items())
            ),
            "exposure_per_visit_s": exposure / visits,
            "overhead_per_visit_s": overhead / visits,
            "idle_per_visit_s": 0.0,  # one block per visit: no waits
            "integration_h": exposure / 3600,
            "overhead_h": overhead / 3600,
            "idle_h": 0.0,
            "total_h": (exposure + overhead) / 3600,
            "efficiency": exposure / (exposure + overhead),
            "ephemeris": next(t["file"] for t in table.meta["targets"] if t["name"] == target),
            "constraints": "; ".join(table.meta["constraints"]),
        }
    return out


def test_by_hand_matches_the_fixture(table: Table) -> None:
    # The hand computation itself, against numbers worked out on paper.
    hm = _by_hand(table)["HM Cnc"]
    assert hm["ra_hms"] == "08:06:23.20" and hm["dec_dms"] == "+15:27:30.0"
    assert hm["overhead_per_visit_s"] == 620.0  # 600 s acquisition + 2 x 10 s readout
    assert hm["total_h"] == pytest.approx(3 * 660 / 3600) and hm["windows_per_month"] == 1.5
    assert hm["p_orb_min"] == pytest.approx(HM_P_S / 60)
    assert _by_hand(table)[SDSS]["vmag"] == SDSS_VMAG_META


def _check_against_hand(summary: Table, table: Table) -> None:
    expected = _by_hand(table)
    assert list(summary["target"]) == list(expected)
    for row in summary:
        for key, value in expected[str(row["target"])].items():
            if isinstance(value, str):
                assert str(row[key]) == value, key
            else:
                assert float(row[key]) == pytest.approx(value, rel=1e-9), key
        assert str(row["time_critical"]) == "True"


def test_golden_ecsv_reads_back_with_columns_units_and_hand_values(table: Table) -> None:
    summary = Table.read(golden("exports_proposal.ecsv").decode(), format="ascii.ecsv")
    assert summary.colnames == list(UNITS)
    assert {c: (str(summary[c].unit) if summary[c].unit else None) for c in UNITS} == UNITS
    _check_against_hand(summary, table)
    expected = _by_hand(table)
    assert summary.meta["total_h"] == pytest.approx(sum(r["total_h"] for r in expected.values()))
    assert summary.meta["total_h"] == pytest.approx(0.75)  # (3 x 660 + 720) s
    assert summary.meta["site"]["name"] == "Paranal"


def test_golden_csv_reads_back_with_columns_and_hand_values(table: Table) -> None:
    summary = Table.read(golden("exports_proposal.csv").decode(), format="ascii.csv")
    assert summary.colnames == list(UNITS)
    assert all(summary[c].unit is None for c in UNITS)  # plain CSV: units only in the ECSV
    _check_against_hand(summary, table)


def _session_pair(table: Table, gap_s: float) -> Table:
    """The first HM Cnc block and a copy starting ``gap_s`` after its end, in one session."""
    first = Table(table[table["target"] == "HM Cnc"][:1], copy=True)
    second = Table(first, copy=True)
    shift = (ms(first["t_end_utc"][0]) - ms(first["t_start_utc"][0])) + np.timedelta64(
        round(gap_s * 1000), "ms"
    )
    for col in ("t_start_utc", "t_mid_utc", "t_end_utc"):
        second[col] = [str(ms(first[col][0]) + shift)]
    second["block_id"] = ["HM_Cnc-001b"]
    pair = vstack([first, second])
    pair["session_id"] = ["HM_Cnc-S01", "HM_Cnc-S01"]
    pair.meta = dict(table.meta)
    return pair


def test_sessions_are_one_visit_and_their_gaps_are_idle(table: Table) -> None:
    # Two 50 s blocks of one session, the second 170 s after the first ends (a half orbit
    # later); readout_s = 10 s after each of the 2 x 2 exposures.
    pair = _session_pair(table, 170.0)
    (row,) = proposal_table(pair, ExportOptions(acquisition_s=600.0), [])
    assert row["n_blocks"] == 2 and row["n_visits"] == 1 and row["n_exposures"] == 4
    assert row["exposure_per_visit_s"] == 80.0  # 4 x 20 s
    assert row["overhead_per_visit_s"] == 640.0  # 600 s acquisition once + 4 x 10 s readout
    # The gap minus the readout of the first block's last exposure is the wait for the phase.
    assert row["idle_per_visit_s"] == pytest.approx(160.0, abs=1e-3)
    # Wall time: acquisition + first start .. second end + the last readout.
    wall = 600.0 + (50.0 + 170.0 + 50.0) + 10.0
    assert row["total_h"] * 3600 == pytest.approx(wall, abs=1e-3)
    assert row["efficiency"] == pytest.approx(80.0 / wall, rel=1e-6)


def test_plan_accounting_is_used_as_written(table: Table) -> None:
    t = Table(table, copy=True)
    entry = {"visits": 3, "exposures": 6, "shutter_s": 120.0, "overhead_s": 1860.0}
    accounting = {
        "total": {},
        "targets": {
            "HM Cnc": {**entry, "idle_s": 500.0, "efficiency": 0.05},
            SDSS: {
                "visits": 1,
                "exposures": 1,
                "shutter_s": 120.0,
                "overhead_s": 600.0,
                "idle_s": 0.0,
                "efficiency": 0.17,
            },
        },
    }
    t.meta["time_accounting"] = accounting
    notes: list[str] = []
    summary = proposal_table(t, ExportOptions(acquisition_s=600.0), notes)
    hm = summary[summary["target"] == "HM Cnc"][0]
    assert hm["idle_h"] * 3600 == pytest.approx(500.0)
    assert hm["total_h"] * 3600 == pytest.approx(120.0 + 1860.0 + 500.0)
    assert summary.meta["total_h"] * 3600 == pytest.approx(2480.0 + 720.0)
    assert "plan's time_accounting" in summary.meta["time_source"]
    assert not any("no time_accounting" in n for n in notes)


def test_plan_accounting_missing_a_target_falls_back_with_a_note(table: Table) -> None:
    t = Table(table, copy=True)
    t.meta["time_accounting"] = {"targets": {"HM Cnc": {}}}
    notes: list[str] = []
    proposal_table(t, ExportOptions(acquisition_s=600.0), notes)
    assert any("computed from the blocks" in n for n in notes)


@pytest.mark.parametrize("bad", [math.nan, -1.0, "x", None])
def test_bad_plan_accounting_is_a_one_line_error(table: Table, bad: object) -> None:
    t = Table(table, copy=True)
    good = {"visits": 1, "exposures": 1, "shutter_s": 1.0, "overhead_s": 1.0, "idle_s": 0.0}
    t.meta["time_accounting"] = {"targets": {"HM Cnc": dict(good, idle_s=bad), SDSS: good}}
    with pytest.raises(InputFileError, match=r"time_accounting: targets\.'HM Cnc'\.idle_s") as info:
        proposal_table(t, ExportOptions(), [])
    assert "\n" not in str(info.value) and len(str(info.value)) < 400


def test_every_number_is_finite_without_a_period(table: Table) -> None:
    # No period_s column and no pi-mode time for SDSS: P_b unknown -> blank, never NaN.
    t = Table(table, copy=True)
    t.remove_column("period_s")
    summary = Table.read(
        write_proposal(proposal_table(t, ExportOptions(), []), "ecsv"), format="ascii.ecsv"
    )
    sdss = summary[summary["target"] == SDSS][0]
    assert sdss["tolerance_rad"] is np.ma.masked and sdss["p_orb_min"] is np.ma.masked
    for col in summary.colnames:
        if summary[col].dtype.kind == "f":
            values = np.ma.compressed(np.ma.asarray(summary[col]))
            assert np.all(np.isfinite(values)), col


@pytest.mark.parametrize(
    ("semester", "first", "last"),
    [
        ("2037A", "2037-02-01", "2037-07-31"),
        ("2036B", "2036-08-01", "2037-01-31"),
        ("P138", "2036-10-01", "2037-03-31"),
        ("p139", "2037-04-01", "2037-09-30"),
    ],
)
def test_semester_option(table: Table, semester: str, first: str, last: str) -> None:
    notes: list[str] = []
    summary = proposal_table(table, ExportOptions(semester=semester), notes)
    m = summary.meta
    assert (m["semester"], m["semester_first_night"], m["semester_last_night"]) == (
        semester.upper(),
        first,
        last,
    )
    # Local (Chile) nights: 2037-01-14, 01-14, 01-15 and 02-09.
    nights = {"2037A": 3, "2036B": 1, "P138": 0, "P139": 4}[semester.upper()]
    outside = [n for n in notes if "fall outside" in n]
    assert (f"{nights} of 4 blocks" in outside[0]) if nights else not outside


def test_default_semester_follows_the_site(table: Table) -> None:
    assert proposal_table(table, ExportOptions(), []).meta["semester"] == "P138"  # Paranal
    t = Table(table, copy=True)
    t.meta["site"] = {
        "name": "Mauna Kea",
        "lon_deg": -155.4747,
        "lat_deg": 19.826,
        "timezone": "Pacific/Honolulu",
    }
    # First block 2037-01-15T01:02 UTC = 14 January 15:02 in Hawaii: the night of 14 January.
    assert proposal_table(t, ExportOptions(), []).meta["semester"] == "2036B"


def test_bad_semester_is_a_one_line_error() -> None:
    with pytest.raises(InputError, match=r"^semester: expected YYYYA"):
        ExportOptions(semester="2041C")


def test_proposal_unknown_format(table: Table) -> None:
    with pytest.raises(InputFileError, match="expected one of ecsv, csv, latex"):
        write_proposal(proposal_table(table, ExportOptions(), []), "xlsx")


# ----------------------------------------------------------------------------------- LaTeX


def _check_balanced(text: str) -> None:
    """Braces (not ``\\{``/``\\}``) balance; ``\\begin``/``\\end`` nest; ``$`` pair on each line."""
    depth = 0
    for match in re.finditer(r"(?<!\\)[{}]", text):
        depth += 1 if match.group() == "{" else -1
        assert depth >= 0, f"unbalanced }} at {match.start()}"
    assert depth == 0
    stack: list[str] = []
    for kind, env in re.findall(r"\\(begin|end)\{([^}]*)\}", text):
        if kind == "begin":
            stack.append(env)
        else:
            assert stack and stack.pop() == env, f"\\end{{{env}}} closes nothing"
    assert not stack
    for line in text.splitlines():
        assert len(re.findall(r"(?<!\\)\$", line)) % 2 == 0, line


def _tabular(text: str) -> tuple[str, list[list[str]]]:
    """The tabular column spec and the cells of every row."""
    match = re.search(
        r"\\begin\{tabular\}\{((?:[^{}]|\{[^}]*\})*)\}(.*)\\end\{tabular\}", text, re.S
    )
    assert match, "no tabular"
    spec, body = match.groups()
    rows = [r.strip() for r in re.split(r"\\\\", body)]
    rows = [re.sub(r"^(\\hline\s*)+", "", r) for r in rows]
    rows = [r for r in rows if r and r != "\\hline"]
    return spec, [[c.strip() for c in re.split(r"(?<!\\)&", row)] for row in rows]


def _spec_columns(spec: str) -> list[float | None]:
    """Width of each p{..cm} column [pt], None for l/c/r."""
    cols = re.findall(r"p\{([0-9.]+)cm\}|[lcr]", spec)
    return [float(w) * 72.27 / 2.54 if w else None for w in cols]


def _cm_width_pt(text: str, size_pt: float) -> float:
    """Width of ``text`` set in Computer Modern Roman (matplotlib's cmr10.ttf), scaled to
    ``size_pt``, times 1.1 (cmr8 is up to ~6 % wider than cmr10 scaled to 8 pt; math italic and
    macros are measured by their plain letters)."""
    from matplotlib import font_manager, ft2font

    plain = re.sub(r"\\mathrm\{([^}]*)\}", r"\1", text)
    plain = re.sub(r"\\[a-zA-Z]+|[${}_^]", "", plain.replace("$-$", "-"))
    font = ft2font.FT2Font(font_manager.findfont("cmr10", fallback_to_default=False))
    font.set_size(size_pt, 72)
    font.set_text(plain)
    return 1.1 * font.get_width_height()[0] / 64


def _latex_width_pt(text: str) -> float:
    """Independent width of the tabular: measured glyphs + 2 tabcolsep per column [pt]."""
    assert "\\footnotesize" in text  # 8 pt in a 10 pt article
    sep = float(re.search(r"\\setlength\{\\tabcolsep\}\{([0-9.]+)pt\}", text).group(1))  # type: ignore[union-attr]
    spec, rows = _tabular(text)
    width = 0.0
    for j, fixed in enumerate(_spec_columns(spec)):
        cells = [r[j] for r in rows]
        width += (fixed if fixed else max(_cm_width_pt(c, 8.0) for c in cells)) + 2 * sep
    return width


#: \textwidth of LaTeX's article class at 10 pt [pt].
ARTICLE_TEXTWIDTH_PT = 345.0


def test_golden_latex_parses_with_the_hand_values(table: Table) -> None:
    text = golden("exports_proposal.tex").decode()
    _check_balanced(text)
    spec, rows = _tabular(text)
    n_cols = len(_spec_columns(spec))
    assert n_cols == 11 and all(len(cells) == n_cols for cells in rows)
    header, units, *body, total = rows
    assert header[0] == "Target" and header[-1] == "Total" and units[-1] == "h"
    expected = _by_hand(table)
    assert [cells[0] for cells in body] == list(expected)
    for cells in body:
        hand = expected[cells[0]]
        assert cells[6] == str(hand["n_visits"])
        assert float(cells[5]) == pytest.approx(hand["tolerance_rad"], abs=5e-4)
        assert float(cells[-1]) == pytest.approx(hand["total_h"], abs=0.005)
    assert total[0] == "Total" and float(total[-1]) == pytest.approx(0.75, abs=0.005)


def test_golden_latex_fits_the_article_text_width() -> None:
    text = golden("exports_proposal.tex").decode()
    assert _latex_width_pt(text) <= ARTICLE_TEXTWIDTH_PT
    # The file states the exporter's own estimate; it agrees with the measured one to 15 %.
    stated = float(re.search(r"estimated width (\d+) pt", text).group(1))  # type: ignore[union-attr]
    assert stated == pytest.approx(_latex_width_pt(text), rel=0.15)


@given(
    name=st.text(alphabet="ABCxyz0123456789 -+_", min_size=1, max_size=60).filter(str.strip),
    visits=st.integers(1, 999),
)
@settings(max_examples=25, deadline=None)
def test_latex_fits_for_long_names_and_many_visits(name: str, visits: int) -> None:
    t = written_table_cached()
    t = Table(t, copy=True)
    t["target"] = t["target"].astype("U80")
    t["target"][t["target"] == SDSS] = name
    blocks = {
        "visits": visits,
        "exposures": 2 * visits,
        "shutter_s": 3600.0 * visits,
        "overhead_s": 600.0 * visits,
        "idle_s": 99.0 * visits,
    }
    t.meta["time_accounting"] = {"targets": {"HM Cnc": blocks, name: blocks}}
    text = write_proposal(proposal_table(t, ExportOptions(acquisition_s=600.0), []), "latex")
    _check_balanced(text)
    assert _latex_width_pt(text) <= ARTICLE_TEXTWIDTH_PT


def test_golden_latex_compiles(tmp_path: Path) -> None:
    pdflatex = shutil.which("pdflatex")
    if pdflatex is None:
        pytest.skip("pdflatex not installed; the LaTeX table is only parsed")
    (tmp_path / "table.tex").write_bytes(golden("exports_proposal.tex"))
    doc = tmp_path / "doc.tex"
    doc.write_text("\\documentclass{article}\n\\begin{document}\n\\input{table}\n\\end{document}\n")
    # Overfull boxes would mean the table does not fit the page.
    result = subprocess.run(
        [pdflatex, "-interaction=nonstopmode", "-halt-on-error", doc.name],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert result.returncode == 0, result.stdout[-2000:]
    assert "Overfull \\hbox" not in (tmp_path / "doc.log").read_text(errors="replace")


def test_proposal_latex_escapes_underscores(table: Table) -> None:
    t = Table(table, copy=True)
    t["target"] = t["target"].astype("U40")
    t["target"][t["target"] == SDSS] = "ZTF_J1539+5027"
    latex = write_proposal(proposal_table(t, ExportOptions(), []), "latex")
    assert r"ZTF\_J1539+5027" in latex
    outside_math = re.sub(r"\$[^$]*\$", "", latex)
    assert not re.search(r"(?<!\\)_", outside_math)  # every _ outside math mode is escaped
    _check_balanced(latex)


def test_cli_semester_reaches_the_table(tmp_path: Path) -> None:
    from support.cli import run_cli

    blocks = tmp_path / "blocks.ecsv"
    written_table(tmp_path).write(blocks, format="ascii.ecsv", overwrite=True)
    out = tmp_path / "p.ecsv"
    code, err = run_cli(
        ["export", str(blocks), "--to", "proposal", "--semester", "2037A", "-o", str(out)]
    )
    assert code == 0, err
    assert Table.read(out, format="ascii.ecsv").meta["semester"] == "2037A"
    assert "3 of 4 blocks fall outside semester 2037A" in " ".join(err.split())
    code, err = run_cli(["export", str(blocks), "--to", "ics", "--semester", "2037A"])
    assert code == 2 and "--semester chooses the proposal's semester" in err
    code, err = run_cli(["export", str(blocks), "--to", "proposal", "--semester", "2037C"])
    assert code == 2 and "--semester: expected YYYYA" in err
