"""`feasibility` and every export format on a timing target (issue 10, item 2).

The target is the bundled synthetic eclipsing binary (`catalogs/examples/synthetic-eclipsing.yaml`):
T0 = BJD_TDB 2461000.5, P = 400 s, Ṗ = −2e-11, σ(T0) = 1 s, σ(P) = 5e-6 s, σ(Ṗ) = 1e-13,
K1 = 300 km/s, σ_v = 20 km/s, masses 0.6 + 0.3 M☉, no inclination. Every command must either work
or stop with one short line (exit 2, no traceback). Numbers are checked against values computed
here by hand from the file: the timing error of T0 + Pn + ½PṖn², the chirp time P/|Ṗ|, Kepler's K.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from astropy.table import Table
from support.cli import check_outcome, run_cli

ROOT = Path(__file__).resolve().parents[2]
SYN = ROOT / "catalogs" / "examples" / "synthetic-eclipsing.yaml"


YEAR_S = 365.25 * 86400.0
P_S, PDOT = 400.0, -2.0e-11
SIG_T0_S, SIG_P_S, SIG_PDOT = 1.0, 5.0e-6, 1.0e-13
G_SI, MSUN_KG = 6.6743e-11, 1.988409870698051e30


def _timing_sigma_s(dt_s: float) -> float:
    """1σ of t(n) = T0 + Pn + ½PṖn² at n = ΔT/P, σ's of T0, P, Ṗ independent (by hand)."""
    n = dt_s / P_S
    d_p = n + 0.5 * PDOT * n * n  # ∂t/∂P
    d_pdot = 0.5 * P_S * n * n  # ∂t/∂Ṗ
    return math.sqrt(SIG_T0_S**2 + (d_p * SIG_P_S) ** 2 + (d_pdot * SIG_PDOT) ** 2)


def _feasibility_json(tmp_path: Path, target: Path, *extra: str) -> dict:
    out = tmp_path / "feas.json"
    code, err = run_cli(["feasibility", str(target), "--format", "json", "-o", str(out), *extra])
    assert code == 0, err[-600:]
    return json.loads(out.read_text())


def test_feasibility_table_runs_on_a_timing_target() -> None:
    code, err = run_cli(["feasibility", str(SYN)])
    check_outcome(code, err)
    assert code == 0
    assert "Synthetic eclipsing dWD" in err and "Timing error" in err


def test_feasibility_numbers_of_a_timing_target(tmp_path: Path) -> None:
    rep = _feasibility_json(tmp_path, SYN)
    assert rep["period_s"] == pytest.approx(P_S, rel=1e-12)
    assert rep["f_gw_hz"] == pytest.approx(2.0 / P_S, rel=1e-12)
    # τ_chirp = f/ḟ with f = 2/P, ḟ = −2Ṗ/P²: P/|Ṗ| = 2e13 s
    assert rep["tau_chirp_s"] == pytest.approx(P_S / abs(PDOT), rel=1e-9)
    assert rep["k1_m_s"] == pytest.approx(300e3)  # spectroscopy.K1 of the file
    assert rep["sigma_v_m_s"] == pytest.approx(20e3)
    # the timing error is the error of the published polynomial, ΔT after T0
    for years, sig in zip(rep["timing_years"], rep["gw_timing_s"], strict=True):
        assert sig == pytest.approx(_timing_sigma_s(years * YEAR_S), rel=1e-3), years
    assert rep["gw_timing_s"][0] == pytest.approx(SIG_T0_S, rel=1e-9)
    # the note names the field a timing file has (timing.inclination), not only cos_inclination
    assert any("timing.inclination" in n for n in rep["notes"])


def test_feasibility_timing_column_matches_the_optical_formula(tmp_path: Path) -> None:
    """The phase-model error of a timing target and Eq. optical_timing_prec with the same σ's agree
    (two independent code paths; the optical one neglects the n² term of ∂t/∂P)."""
    rep = _feasibility_json(
        tmp_path,
        SYN,
        "--optical-epoch",
        "2461000.5",
        "--optical-sigma-t0",
        str(SIG_T0_S),
        "--optical-sigma-p",
        str(SIG_P_S),
        "--optical-sigma-pdot",
        str(SIG_PDOT),
    )
    for gw, opt in zip(rep["gw_timing_s"], rep["optical_timing_s"], strict=True):
        assert opt == pytest.approx(gw, rel=1e-4)


def test_feasibility_kepler_k_from_timing_inclination(tmp_path: Path) -> None:
    """With timing.inclination and masses (no K1 in the file), K_j follow Kepler's third law."""
    text = SYN.read_text().replace(
        'spectroscopy: {lines: SB1, K1: "300 km/s", sigma_v: "20 km/s"}',
        'spectroscopy: {lines: SB2, sigma_v: "20 km/s"}',
    )
    text = text.replace(
        "  t0_marks: primary_eclipse\n", '  t0_marks: primary_eclipse\n  inclination: "80 deg"\n'
    )
    target = tmp_path / "incl.yaml"
    target.write_text(text)
    rep = _feasibility_json(tmp_path, target)
    m1, m2, sin_i = 0.6 * MSUN_KG, 0.3 * MSUN_KG, math.sin(math.radians(80.0))
    a = (G_SI * (m1 + m2) * P_S**2 / (4 * math.pi**2)) ** (1 / 3)
    k1 = 2 * math.pi * a * sin_i / P_S * m2 / (m1 + m2)
    assert rep["sin_i"] == pytest.approx(sin_i, rel=1e-9)
    assert rep["k1_m_s"] == pytest.approx(k1, rel=1e-4)
    assert rep["k2_m_s"] == pytest.approx(k1 * m1 / m2, rel=1e-4)
    assert not any("inclination" in n for n in rep["notes"])


@pytest.mark.parametrize("epoch", ["BJD_TDB 2461000.5", "HJD 2461000.5", "2461000.5 UTC"])
def test_feasibility_optical_epoch_labels_work_or_fail_in_one_line(epoch: str) -> None:
    """`--optical-epoch` with a scale word: accepted, or one line naming the option (exit 2)."""
    code, err = run_cli(
        ["feasibility", str(SYN), "--optical-epoch", epoch, "--optical-sigma-t0", "1"]
    )
    check_outcome(code, err)
    if code == 2:
        assert "--optical-epoch" in err.strip().splitlines()[-1]


def test_feasibility_optical_epoch_bjd_word_equals_bare_number(tmp_path: Path) -> None:
    """Regression: "BJD_TDB 2461000.5" was refused ("expected an ISO epoch") although the help
    says BJD_TDB is accepted; it must give exactly the bare number's result."""
    args = ["--optical-sigma-t0", str(SIG_T0_S), "--optical-sigma-p", str(SIG_P_S)]
    worded = _feasibility_json(tmp_path, SYN, "--optical-epoch", "BJD_TDB 2461000.5", *args)
    bare = _feasibility_json(tmp_path, SYN, "--optical-epoch", "2461000.5", "--overwrite", *args)
    assert worded["optical_timing_s"] == bare["optical_timing_s"]


@pytest.fixture(scope="module")
def blocks(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Blocks of the synthetic timing target at Paranal on the night of 2026-11-24."""
    out = tmp_path_factory.mktemp("timing-export") / "blocks.ecsv"
    code, err = run_cli(
        ["plan", str(SYN), "--site", "paranal", "--night", "2026-11-24", "-o", str(out)]
    )
    assert code == 0, err[-600:]
    return out


def _export(blocks: Path, fmt: str, suffix: str, *extra: str) -> tuple[str, str]:
    out = blocks.parent / f"export-{fmt}{''.join(extra)}{suffix}"
    code, err = run_cli(["export", str(blocks), "--to", fmt, "-o", str(out), "--overwrite", *extra])
    check_outcome(code, err)
    assert code == 0, err[-600:]
    return out.read_text(), err


def test_plan_of_a_timing_target_has_blocks_and_no_pi_mode(blocks: Path) -> None:
    table = Table.read(blocks, format="ascii.ecsv")
    assert len(table) >= 1
    assert all(str(v) in ("", "--") for v in table["t_alt_utc"])
    assert all(p == pytest.approx(P_S, rel=1e-6) for p in table["period_s"])


def test_export_eso_p2(blocks: Path) -> None:
    text, _ = _export(blocks, "eso-p2", ".json")
    doc = json.loads(text)
    assert doc["target_list_csv"] == ["Synthetic_eclipsing_dWD,08:00:00.000,-20:00:00.000,J2000"]
    ids = sorted(b for ob in doc["obs"] for b in ob["block_ids"])
    assert ids == sorted(Table.read(blocks, format="ascii.ecsv")["block_id"])


def test_export_keck_starlist(blocks: Path) -> None:
    text, _ = _export(blocks, "keck-starlist", ".txt", "--force")  # Paranal plan
    assert "Synthetic_eclip 08 00 00.00 -20 00 00.0 2000" in text  # 15-character Keck name


def test_export_ing_catalogue(blocks: Path) -> None:
    text, _ = _export(blocks, "ing-cat", ".cat", "--force")  # Paranal plan
    assert "08 00 00.00 -20 00 00.0 J2000" in text


def test_export_lco(blocks: Path) -> None:
    text, _ = _export(blocks, "lco", ".json", "--force")  # Paranal plan
    doc = json.loads(text)
    tgt = doc["requests"][0]["configurations"][0]["target"]
    assert tgt["ra"] == pytest.approx(120.0) and tgt["dec"] == pytest.approx(-20.0)


def test_export_ics_events_start_at_the_blocks(blocks: Path) -> None:
    text, _ = _export(blocks, "ics", ".ics")
    table = Table.read(blocks, format="ascii.ecsv")
    starts = [ln.split(":", 1)[1] for ln in text.splitlines() if ln.startswith("DTSTART")]
    expect = [str(s)[:19].replace("-", "").replace(":", "") + "Z" for s in table["t_start_utc"]]
    assert starts == expect


def test_export_ics_has_no_pi_mode_line_for_a_timing_target(blocks: Path) -> None:
    text, _ = _export(blocks, "ics", ".ics")
    assert "pi-mode" not in text


@pytest.mark.parametrize(("fmt", "suffix"), [("ecsv", ".ecsv"), ("csv", ".csv"), ("latex", ".tex")])
def test_export_proposal(blocks: Path, fmt: str, suffix: str) -> None:
    text, _ = _export(blocks, "proposal", suffix, "--format", fmt)
    assert "Synthetic" in text
    if fmt != "latex":
        row = Table.read(text, format="ascii." + fmt)[0]
        assert row["p_orb_min"] == pytest.approx(P_S / 60.0, rel=1e-6)


def test_feasibility_plot_of_a_timing_target(tmp_path: Path) -> None:
    """K1 from the file and ω̇ (GR + tide from the masses) are enough for the Δv_aps plot."""
    png = tmp_path / "aps.png"
    code, err = run_cli(["feasibility", str(SYN), "--plot", str(png)])
    assert code == 0, err[-600:]
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_feasibility_refuses_to_overwrite_in_one_line(tmp_path: Path) -> None:
    out = tmp_path / "feas.json"
    out.write_text("keep me\n")
    code, err = run_cli(["feasibility", str(SYN), "--format", "json", "-o", str(out)])
    check_outcome(code, err)
    assert code == 2 and out.read_text() == "keep me\n"
    assert "--overwrite" in err.strip().splitlines()[-1]


def test_export_to_another_observatory_needs_force(blocks: Path) -> None:
    """A Paranal plan exported as a Keck starlist is refused in one line unless --force."""
    out = blocks.parent / "refused.txt"
    code, err = run_cli(["export", str(blocks), "--to", "keck-starlist", "-o", str(out)])
    assert code == 2 and "--force" in err.strip().splitlines()[-1]
    assert not out.exists()
