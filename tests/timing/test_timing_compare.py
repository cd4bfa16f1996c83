"""`ucbplan ephemeris compare A B [--at EPOCH]`: offsets of two ephemerides of one system.

Reference: a second ephemeris built from the first in exact arithmetic (its T0 at cycle N of the
first, moved by a known δ, with the local period P(1 + ṖN) and dP/dt = Ṗ/(1 + ṖN): the same
polynomial re-referenced), so the offset is known. Test input
with the issue's ZTF J1539+5027 numbers, not a catalog entry.
"""

from __future__ import annotations

import copy
import json
import math
import subprocess
import sys
from decimal import Decimal
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from support.targets import ztf_j1539_doc
from typer.testing import CliRunner

from ucbplan.cli.app import app
from ucbplan.core.forecast import sigma_u
from ucbplan.core.timing import compare_sources, midway
from ucbplan.targets import load_target

runner = CliRunner()

P = Decimal("414.7915404")
PDOT = Decimal("-2.373e-11")
T0 = Decimal("2458305.6827886")
A_DOC: dict[str, Any] = ztf_j1539_doc("ZTF J1539+5027 (test input A)", spectroscopy=False)


def _b_doc(n_cycles: int, delta_s: Decimal, mark: str = "primary_eclipse") -> dict[str, Any]:
    """A's ephemeris re-referenced to its cycle ``n_cycles`` (exact), T0 moved by ``delta_s``."""
    n = Decimal(n_cycles) + (Decimal("0.5") if mark == "secondary_eclipse" else 0)
    t_n = T0 + (P * n + P * PDOT * n * n / 2 + delta_s) / 86400
    doc = copy.deepcopy(A_DOC)
    doc["name"] = "ZTF J1539+5027 (test input B)"
    doc["timing"]["t0"] = f"BJD_TDB {t_n:.16f}"
    doc["timing"]["t0_marks"] = mark
    doc["timing"]["period"] = f"{P * (1 + PDOT * n)} s"
    doc["timing"]["pdot"] = float(PDOT / (1 + PDOT * n))
    doc["timing"]["covariance"] = {"sigma": {"t0": "0.5 s", "period": "1e-6 s", "pdot": 1e-14}}
    return doc


def _write(tmp_path: Path, name: str, doc: dict[str, Any]) -> Path:
    path = tmp_path / name
    path.write_text(yaml.safe_dump(doc))
    return path


@pytest.mark.parametrize("mark", ["primary_eclipse", "secondary_eclipse"])
@pytest.mark.parametrize("delta", ["0", "3.0", "-41.5"])
def test_known_offset_is_recovered(tmp_path: Path, mark: str, delta: str) -> None:
    """B predicts every eclipse δ later than A: t_A − t_B = −δ and u_A − u_B = u̇δ, at the
    default epoch (midway) and elsewhere; both count the same cycles between their epochs."""
    a = load_target(_write(tmp_path, "a.yaml", A_DOC))
    b = load_target(_write(tmp_path, "b.yaml", _b_doc(300_000, Decimal(delta), mark)))
    for at in (None, a.t_ref, b.t_ref):
        rep = compare_sources(a, b, at)
        r = rep.result
        assert r.dt_s == pytest.approx(-float(delta), abs=2e-6)  # s; µs-level model agreement
        assert r.du_rad == pytest.approx(float(delta) * r.rate_rad_s, abs=1e-7)
        # a constant shift is no disagreement on the number of orbits between the epochs (up to
        # |ν̇ δ τ| ≈ 7e-7 cycles: B's frequency is A's of δ earlier)
        assert r.cycle_difference == pytest.approx(0.0, abs=1e-6)
        half = 0.5 if mark == "secondary_eclipse" else 0.0
        local_p = float(P * (1 + PDOT * (300_000 + Decimal(half))))  # P at B's epoch
        assert r.cycles_a == pytest.approx(300_000 + half + float(delta) / local_p, abs=1e-7)
        assert rep.alternatives == ()
    rep = compare_sources(a, b)
    assert float(abs(rep.epoch - midway(a.t_ref, b.t_ref)).to_value("s")) == 0.0


def test_sigma_combines_both_covariances(tmp_path: Path) -> None:
    a = load_target(_write(tmp_path, "a.yaml", A_DOC))
    b = load_target(_write(tmp_path, "b.yaml", _b_doc(200_000, Decimal("2.0"))))
    rep = compare_sources(a, b)
    tau_a = float((rep.epoch - a.t_ref).to_value("s"))
    tau_b = float((rep.epoch - b.t_ref).to_value("s"))
    sa = float(sigma_u(a.params, a.covariance, np.array([tau_a]))[0])
    sb = float(sigma_u(b.params, b.covariance, np.array([tau_b]))[0])
    r = rep.result
    assert r.sigma_du_rad == pytest.approx(math.hypot(sa, sb), rel=1e-12)
    assert r.significance == pytest.approx(abs(r.du_rad) / r.sigma_du_rad, rel=1e-12)
    assert r.sigma_dt_s == pytest.approx(r.sigma_du_rad / r.rate_rad_s, rel=1e-12)


def test_whole_cycle_disagreement_shows_in_the_cycle_count(tmp_path: Path) -> None:
    """B's period 1e-4 s longer: over the 3e5 cycles between the epochs its events drift by 30 s;
    the cycle counts from A's epoch to B's differ by that drift, whatever the wrapped phase says."""
    b_doc = _b_doc(300_000, Decimal(0))
    b_doc["timing"]["period"] = f"{P * (1 + PDOT * 300_000) + Decimal('1e-4')} s"
    a = load_target(_write(tmp_path, "a.yaml", A_DOC))
    b = load_target(_write(tmp_path, "b.yaml", b_doc))
    r = compare_sources(a, b).result
    # B counts the 3e5 cycles between the epochs with a period longer by 1e-4 s: 30 s / P fewer
    assert r.cycle_difference == pytest.approx(30.0 / float(P), rel=0.01)
    assert r.sigma_cycle_difference > 0


def test_lisa_side_adds_its_pi_mode(tmp_path: Path, hm_cnc_path: Path) -> None:
    a = load_target(hm_cnc_path)
    b = load_target(_write(tmp_path, "b.yaml", A_DOC))
    rep = compare_sources(a, b)
    assert [s for s, _ in rep.alternatives] == ["a"]
    alt = rep.alternatives[0][1]
    # φ_ref + π moves u by π/2: the alternative offset differs by a quarter orbit
    quarter = math.remainder(alt.du_rad - rep.result.du_rad, 2 * math.pi)
    assert abs(quarter) == pytest.approx(math.pi / 2, abs=1e-9)


def test_compare_cli_json_and_table(tmp_path: Path) -> None:
    a = _write(tmp_path, "a.yaml", A_DOC)
    b = _write(tmp_path, "b.yaml", _b_doc(100_000, Decimal("1.5")))
    res = runner.invoke(app, ["ephemeris", "compare", str(a), str(b), "--format", "json"])
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout)
    assert doc["a"]["kind"] == doc["b"]["kind"] == "timing"
    assert doc["time_offset_s"] == pytest.approx(-1.5, abs=1e-5)
    assert doc["whole_cycle_difference"] == 0 and doc["pi_mode"] == []
    for key in ("sigma_phase_offset_rad", "sigma_time_offset_s", "significance", "epoch_tdb"):
        assert key in doc
    res = runner.invoke(
        app,
        ["ephemeris", "compare", str(a), str(b), "--at", "BJD_TDB 2459000.5", "--format", "json"],
    )
    assert res.exit_code == 0, res.output
    assert json.loads(res.stdout)["epoch_bjd_tdb"] == "2459000.5000000000000"
    res = runner.invoke(
        app, ["ephemeris", "compare", str(a), str(b), "--at", "2021-01-01T00:00:00"]
    )
    assert res.exit_code == 0, res.output
    assert "time offset" in res.output and "significance" in res.output
    out = tmp_path / "cmp.json"
    res = runner.invoke(app, ["ephemeris", "compare", str(a), str(b), "-o", str(out)])
    assert res.exit_code == 0 and json.loads(out.read_text())["b"]["name"].endswith("B)")


def test_compare_refuses_bad_epochs_in_one_line(tmp_path: Path) -> None:
    a = _write(tmp_path, "a.yaml", A_DOC)
    for at in ("HJD 2459000.5", "BJD_TDB 59000.5"):
        proc = subprocess.run(
            [sys.executable, "-m", "ucbplan", "ephemeris", "compare", str(a), str(a), "--at", at],
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert proc.returncode == 2, proc.stderr
        lines = [ln for ln in proc.stderr.splitlines() if ln.strip()]
        assert len(lines) == 1 and "--at" in lines[0] and "Traceback" not in proc.stderr
    for at in ("BJD_XYZ 1", "not a date", "x" * 5000):
        res = runner.invoke(app, ["ephemeris", "compare", str(a), str(a), "--at", at])
        # the exception names the parameter; the command line prints it as --at (cli/_flags.py)
        assert res.exit_code != 0 and str(res.exception).startswith("at: ")


def test_compare_warns_for_different_systems(tmp_path: Path, hm_cnc_path: Path) -> None:
    a = _write(tmp_path, "a.yaml", A_DOC)
    res = runner.invoke(app, ["ephemeris", "compare", str(hm_cnc_path), str(a), "--format", "json"])
    assert res.exit_code == 0
    assert "one system" in res.output
