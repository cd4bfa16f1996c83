"""Horizons of timing ephemerides: σ_u grows before and after T0; T_valid on both sides.

References: the closed form of a pure-period ephemeris (σ_u = 2πσ_P|Δt|/P², so
T_valid = tol·P²/(2πσ_P)), and a brute-force scan of σ_u before T0 for an eccentric, precessing,
correlated case. LISA targets' horizons are unchanged (tests/core/test_forecast.py holds
Tables 4, 7).
"""

from __future__ import annotations

import copy
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from support.targets import ztf_j1539_doc
from typer.testing import CliRunner

from ucbplan.cli.app import app
from ucbplan.core.constants import DAY_S, YEAR_S
from ucbplan.core.forecast import (
    AFTER,
    BEFORE,
    anchor_sigma_u,
    horizon_table,
    t_valid,
    tolerance,
    two_sided,
    valid_window_s,
)
from ucbplan.targets import load_target, target_from_dict

runner = CliRunner()

P_S = 414.7915404
SIGMA_P = 2.9e-6
#: The issue's ZTF J1539+5027 ephemeris (test input, not a catalog entry).
ZTF: dict[str, Any] = ztf_j1539_doc()


def _pure_period() -> Any:
    doc = copy.deepcopy(ZTF)
    doc["timing"]["pdot"] = 0.0
    doc["timing"]["covariance"] = {"sigma": {"period": f"{SIGMA_P} s"}, "exact": ["t0"]}
    return target_from_dict(doc)


@pytest.mark.parametrize("tol", [0.01, 0.1, 0.45])
def test_pure_period_horizon_is_the_closed_form_on_both_sides(tol: float) -> None:
    t = _pure_period()
    expect = tol * P_S**2 / (2 * math.pi * SIGMA_P)
    for anchor in ((0.0, math.pi), (math.pi / 2, 3 * math.pi / 2)):
        after = t_valid(t, tol, anchor)
        before = t_valid(t, tol, anchor, direction=BEFORE)
        assert after == pytest.approx(expect, rel=1e-6)
        assert before == pytest.approx(expect, rel=1e-6)
    tau = np.array([-3 * YEAR_S, -1.0, 1.0, 3 * YEAR_S])
    sig = anchor_sigma_u(t.params, t.covariance, tau, 0.0)
    assert np.allclose(sig, 2 * math.pi * SIGMA_P * np.abs(tau) / P_S**2, rtol=1e-12)


def test_horizons_are_finite_on_both_sides_of_t0() -> None:
    t = target_from_dict(ZTF)
    assert two_sided(t)
    rows = horizon_table(t, 20.0, 1170.0)
    for r in rows:
        assert r.t_valid_before_days is not None and r.dt_u_before_s is not None
        assert 0.0 <= r.t_valid_before_days < 300 * 365.25
        assert 0.0 <= r.t_valid_days < 300 * 365.25
    quad = next(r for r in rows if r.anchor == "quadrature" and r.alpha == 1.0)
    assert 1000 < quad.t_valid_before_days < 20000 and 1000 < quad.t_valid_days < 20000
    # σ_u is not exactly symmetric with Ṗ ≠ 0 (the f–ḟ terms), but nearly so here
    assert quad.t_valid_before_days == pytest.approx(quad.t_valid_days, rel=1e-3)
    assert quad.sigma_u_end_rad == pytest.approx(2 * math.pi * 0.72576 / P_S, rel=1e-4)


def _brute_before(t: Any, thr: float, us: tuple[float, ...]) -> float:
    """First time before T0 (scanning backwards on a fine grid) where σ_u exceeds thr [s]."""
    tau = -np.linspace(0.0, 20 * YEAR_S, 100_001)
    sig = np.max([anchor_sigma_u(t.params, t.covariance, tau, u) for u in us], axis=0)
    above = np.flatnonzero(sig > thr)
    return float(-tau[above[0]]) if above.size else math.inf


def test_backward_horizon_against_a_brute_force_scan(tmp_path: Path) -> None:
    """An eccentric, precessing ephemeris with correlated σ's: the mirrored search gives the
    same first crossing before T0 as a direct scan (grid step 0.07 d); the horizons before and
    after T0 differ here (ω̇ and the correlations break the symmetry)."""
    doc = copy.deepcopy(ZTF)
    doc["timing"]["eccentricity"] = {"eta": 0.004, "kappa": -0.006, "omega_dot": "2e-8 rad/s"}
    doc["timing"]["covariance"] = {
        "sigma": {
            "t0": "0.7 s",
            "period": "2.9e-6 s",
            "pdot": 5e-14,
            "kappa": 0.001,
            "eta": 0.001,
            "omega_dot": "1e-9 rad/s",
        },
        "correlation": {"period,pdot": -0.8, "t0,period": 0.4, "eta,kappa": 0.3},
    }
    t = target_from_dict(doc)
    for thr in (0.05, 0.12):
        for us in ((0.0, math.pi), (math.pi / 2, 3 * math.pi / 2)):
            got = t_valid(t, thr, us, direction=BEFORE)
            ref = _brute_before(t, thr, us)
            assert got == pytest.approx(ref, abs=20 * YEAR_S / 100_000 + 1.0)
            assert abs(got - t_valid(t, thr, us)) > 0.5 * YEAR_S


def test_valid_window_for_both_kinds(hm_cnc_path: Path) -> None:
    t = target_from_dict(ZTF)
    tol = tolerance("quadrature", 20.0, 1170.0)
    lo, hi = valid_window_s(t, tol, (0.0, math.pi))
    assert lo == pytest.approx(-t_valid(t, tol, (0.0, math.pi), direction=BEFORE))
    assert hi == pytest.approx(t_valid(t, tol, (0.0, math.pi), direction=AFTER))
    assert lo < 0 < hi
    lisa = load_target(hm_cnc_path)
    lo, hi = valid_window_s(lisa, 0.45, (0.0, math.pi))
    assert lo == -lisa.t_obs_s / 2
    assert hi == pytest.approx(lisa.t_obs_s / 2 + t_valid(lisa, 0.45, (0.0, math.pi)))
    assert not two_sided(lisa)


def test_lisa_rows_keep_their_keys(hm_cnc_path: Path) -> None:
    rows = horizon_table(load_target(hm_cnc_path), 56.5685, 390.0)
    assert all(not r.two_sided for r in rows)
    assert set(rows[0].as_dict()) == {
        "anchor",
        "alpha",
        "tolerance_rad",
        "delta_u_tol_rad",
        "t_valid_days",
        "dt_u_s",
        "sigma_u_end_rad",
        "n_epochs",
    }


@pytest.fixture
def ztf_file(tmp_path: Path) -> Path:
    path = tmp_path / "ztf-test-input.yaml"
    path.write_text(yaml.safe_dump(ZTF))
    return path


def test_horizon_cli_json_table_and_plot(ztf_file: Path, tmp_path: Path) -> None:
    res = runner.invoke(app, ["horizon", str(ztf_file), "--format", "json"])
    assert res.exit_code == 0, res.output
    rows = json.loads(res.stdout)
    for r in rows:
        assert r["t_valid_before_days"] >= 0 and r["t_valid_days"] >= 0
        assert "dt_u_before_s" in r
    res = runner.invoke(app, ["horizon", str(ztf_file)])
    assert res.exit_code == 0
    assert "before" in res.output and "after" in res.output and "σ_u at T0" in res.output
    png = tmp_path / "h.png"
    res = runner.invoke(app, ["horizon", str(ztf_file), "--plot", str(png), "--format", "csv"])
    assert res.exit_code == 0, res.output
    assert png.stat().st_size > 10_000
    assert "t_valid_before_days" in res.stdout.splitlines()[0]


def test_validate_prints_the_timing_summary(ztf_file: Path) -> None:
    res = runner.invoke(app, ["validate", str(ztf_file), "--format", "json"])
    assert res.exit_code == 0, res.output
    s = json.loads(res.stdout)[0]
    assert s["kind"] == "timing"
    assert s["period_s"] == P_S and s["sigma_period_s"] == pytest.approx(SIGMA_P)
    assert s["pdot"] == -2.373e-11 and s["sigma_pdot"] == pytest.approx(5e-14)
    assert s["t0_bjd_tdb"] == "2458305.6827886000000"
    assert s["sigma_t0_s"] == pytest.approx(8.4e-6 * DAY_S)
    # σ_u at ±1 yr: T0, P and Ṗ terms in quadrature (σ_φ/2 = 2πσ_T0/P, 2πσ_P τ/P², πσ_Ṗ τ²/P²)
    tau = YEAR_S
    expect = math.hypot(
        2 * math.pi * 8.4e-6 * DAY_S / P_S,
        2 * math.pi * SIGMA_P * tau / P_S**2,
        math.pi * 5e-14 * tau**2 / P_S**2,
    )
    assert s["sigma_u_after_1yr_mrad"] == pytest.approx(1e3 * expect, rel=1e-3)
    assert s["sigma_u_before_1yr_mrad"] == pytest.approx(1e3 * expect, rel=1e-3)
    res = runner.invoke(app, ["validate", str(ztf_file)])
    assert res.exit_code == 0 and "σ_u 1 yr before T0" in res.output
    assert "T_asc" not in res.output
