"""Proposal table: golden ECSV/CSV/LaTeX, read back by astropy or parsed, checked by hand."""

from __future__ import annotations

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
from astropy.table import Table
from test_exports_fixture import (
    GOLDEN_ACQUISITION_S,
    HM_P_S,
    SDSS,
    SDSS_VMAG_META,
    golden,
    golden_export,
    ms,
    written_table,
)

from ucbplan.errors import InputFileError
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
    "windows_per_month": None,
    "windows_by_month": None,
    "exposure_per_visit_s": "s",
    "overhead_per_visit_s": "s",
    "integration_h": "h",
    "overhead_h": "h",
    "total_h": "h",
    "time_critical": None,
    "ephemeris": None,
    "constraints": None,
}


@pytest.fixture(scope="module")
def table(tmp_path_factory: pytest.TempPathFactory) -> Table:
    return written_table(tmp_path_factory.mktemp("exports"))


@pytest.mark.parametrize(
    "name", ["exports_proposal.ecsv", "exports_proposal.csv", "exports_proposal.tex"]
)
def test_golden(table: Table, name: str) -> None:
    assert golden_export(table, name) == golden(name), f"{name} differs; see test_exports_fixture"


# -------------------------------------------------------------------- the table, by hand


def _seconds(texts: Any) -> np.ndarray:
    return np.array([(ms(t) - ms("2037-01-01")) / np.timedelta64(1, "ms") / 1e3 for t in texts])


def _semester_mid(table: Table) -> float:
    """Midpoint of first block start .. last block end [s after 2037-01-01]."""
    return float((_seconds(table["t_start_utc"]).min() + _seconds(table["t_end_utc"]).max()) / 2)


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
        sigma_mid = np.interp(_semester_mid(table), _seconds(rows["t_mid_utc"]), rows["sigma_t_s"])
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
            "window_half_width_s": max(3 * sigma_mid, 10.0),
            "n_blocks": len(rows),
            "n_visits": visits,
            "windows_per_month": visits / n_months,
            "windows_by_month": " ".join(
                f"{m}:{c}"
                for m, c in sorted(Counter(str(t)[:7] for t in rows["t_start_utc"]).items())
            ),
            "exposure_per_visit_s": exposure / visits,
            "overhead_per_visit_s": overhead / visits,
            "integration_h": exposure / 3600,
            "overhead_h": overhead / 3600,
            "total_h": (exposure + overhead) / 3600,
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
        assert math.isnan(float(row["tolerance_rad"]))  # no tol_rad column
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


def test_sessions_are_one_visit(table: Table) -> None:
    # Two blocks of one planner session: one acquisition, readout in both blocks.
    pair = Table(table[table["target"] == "HM Cnc"][:2], copy=True)
    pair["session_id"] = ["HM_Cnc-S01", "HM_Cnc-S01"]
    (row,) = proposal_table(pair, ExportOptions(acquisition_s=600.0), [])
    assert row["n_blocks"] == 2 and row["n_visits"] == 1
    # Exposure 2 x 40 s; overheads 600 s acquisition once + 2 x 2 x 10 s readout.
    assert row["exposure_per_visit_s"] == 80.0 and row["overhead_per_visit_s"] == 640.0
    assert row["total_h"] == pytest.approx(720.0 / 3600.0, rel=1e-12)


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


def _tabular(text: str) -> tuple[int, list[list[str]]]:
    """Column count of the tabular spec and the cells of every row."""
    match = re.search(r"\\begin\{tabular\}\{([^}]*)\}(.*)\\end\{tabular\}", text, re.S)
    assert match, "no tabular"
    spec, body = match.groups()
    n_cols = len(re.findall(r"p\{[^}]*\}|[lcr]", spec))
    rows = [r.strip() for r in re.split(r"\\\\", body) if r.strip() and r.strip() != "\\hline"]
    return n_cols, [[c.strip() for c in re.split(r"(?<!\\)&", row)] for row in rows]


def test_golden_latex_parses_with_the_hand_values(table: Table) -> None:
    text = golden("exports_proposal.tex").decode()
    _check_balanced(text)
    n_cols, rows = _tabular(text)
    assert n_cols == 12 and all(len(cells) == n_cols for cells in rows)
    header, *body, total = rows
    assert header[0] == "Target" and header[-1] == "Total [h]"
    expected = _by_hand(table)
    assert [cells[0] for cells in body] == list(expected)
    for cells in body:
        hand = expected[cells[0]]
        assert cells[1] == hand["ra_hms"] and cells[2] == hand["dec_dms"].replace("-", "$-$")
        assert cells[7] == str(hand["n_visits"])
        assert float(cells[-1]) == pytest.approx(hand["total_h"], abs=0.005)
    assert total[0] == "Total" and float(total[-1]) == pytest.approx(0.75, abs=0.005)


def test_golden_latex_compiles(tmp_path: Path) -> None:
    pdflatex = shutil.which("pdflatex")
    if pdflatex is None:
        pytest.skip("pdflatex not installed; the LaTeX table is only parsed")
    (tmp_path / "table.tex").write_bytes(golden("exports_proposal.tex"))
    doc = tmp_path / "doc.tex"
    doc.write_text("\\documentclass{article}\n\\begin{document}\n\\input{table}\n\\end{document}\n")
    result = subprocess.run(
        [pdflatex, "-interaction=nonstopmode", "-halt-on-error", doc.name],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert result.returncode == 0, result.stdout[-2000:]


def test_proposal_latex_escapes_underscores(table: Table) -> None:
    t = Table(table, copy=True)
    t["target"] = t["target"].astype("U40")
    t["target"][t["target"] == SDSS] = "ZTF_J1539+5027"
    latex = write_proposal(proposal_table(t, ExportOptions(), []), "latex")
    assert r"ZTF\_J1539+5027" in latex
    outside_math = re.sub(r"\$[^$]*\$", "", latex)
    assert not re.search(r"(?<!\\)_", outside_math)  # every _ outside math mode is escaped
    _check_balanced(latex)
