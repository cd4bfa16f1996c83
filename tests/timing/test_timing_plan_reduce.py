"""Timing targets through plan and reduce: both sides of T0, no π-mode (issue 10, item 2)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from astropy.time import Time
from support.cli import run_cli

from ucbplan.core.phase import arg_latitude
from ucbplan.reduce.velocities import VelocityTable, check_validity
from ucbplan.targets import load_target

ROOT = Path(__file__).resolve().parents[2]
SYN = ROOT / "catalogs" / "examples" / "synthetic-eclipsing.yaml"
HM = ROOT / "catalogs" / "hm-cnc-simulated.yaml"


@pytest.mark.parametrize("night", ["2020-01-15", "2031-01-15"])
def test_plan_timing_target_before_and_after_t0(tmp_path: Path, night: str) -> None:
    """T0 = 2025-11-21: nights 6 yr before and 5 yr after are both inside T_valid (~12 yr)."""
    out = tmp_path / "blocks.json"
    code, err = run_cli(["plan", str(SYN), "--site", "paranal", "--night", night, "-o", str(out)])
    assert code == 0, err[-500:]
    rows = json.loads(out.read_text())
    rows = rows["rows"] if isinstance(rows, dict) else rows
    assert rows, "no block planned"
    target = load_target(SYN)
    for r in rows:
        assert r["t_alt_utc"] in ("", None)  # a timing ephemeris has no π-mode
        t = Time(r["t_mid_tdb_bary"], scale="tdb")
        u = float(arg_latitude(target.params, float(target.tau(t))))
        # the block is centred on its anchor: |u(t_mid) − u★| < 1e-6 rad (t_mid printed to 1 µs)
        d = (u - r["u_star_rad"] + np.pi) % (2 * np.pi) - np.pi
        assert abs(d) < 1e-6


def test_plan_refuses_nights_before_the_window(tmp_path: Path) -> None:
    code, err = run_cli(["plan", str(SYN), "--site", "paranal", "--night", "2005-01-15"])
    assert code == 2 and "before the validity window" in err
    code, err = run_cli(["plan", str(HM), "--site", "paranal", "--night", "2030-01-15"])
    assert code == 2 and "before the LISA observation starts" in err


def _table(target_path: Path, times: list[str]) -> VelocityTable:
    from ucbplan.reduce.velocities import read_velocities

    csv = target_path.parent / "v.csv"
    rows = "\n".join(f"{t},60,100,5" for t in times)
    csv.write_text("bjd_tdb,exptime_s,v,sigma_v\n" + rows + "\n")
    return read_velocities(csv)


def test_reduce_accepts_spectra_before_t0(tmp_path: Path) -> None:
    target = load_target(SYN)
    before = Time("2024-01-01T00:00:00", scale="tdb").jd
    after = Time("2027-01-01T00:00:00", scale="tdb").jd
    table = _table(tmp_path / "x", [f"{before:.6f}", f"{after:.6f}"])
    tau = check_validity(table, target)
    assert tau[0] < 0 < tau[1]
    far = Time("1990-01-01T00:00:00", scale="tdb").jd
    with pytest.raises(ValueError, match="more than 20 yr from the ephemeris epoch T0"):
        check_validity(_table(tmp_path / "x", [f"{far:.6f}", f"{after:.6f}"]), target)


def test_plan_terminal_has_no_pi_mode_column_for_timing_targets(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from ucbplan.cli._console import err_console

    monkeypatch.setattr(err_console, "width", 250)  # wide enough that no header is cut
    code, err = run_cli(["plan", str(SYN), "--site", "paranal", "--night", "2026-01-15"])
    assert code == 0, err[-300:]
    assert "π-mode" not in err and "-21474836" not in err
    code, err = run_cli(["plan", str(HM), "--site", "paranal", "--night", "2040-02-15", "--wide"])
    assert code == 0 and "π-mode alt. UTC" in err  # --wide: every column
