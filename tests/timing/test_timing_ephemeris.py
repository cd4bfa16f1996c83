"""`ucbplan ephemeris` on timing targets against the published polynomial in exact arithmetic.

Reference: t(n) = T0 + P n + ½PṖn² evaluated with Python's ``fractions`` (T0, P, Ṗ as the
decimal strings of the file), both sides barycentric TDB (no light time involved). The target is
TEST INPUT with the issue's ZTF J1539+5027 numbers, not a catalog entry.
"""

from __future__ import annotations

import json
import math
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from astropy.time import Time, TimeDelta
from scipy.optimize import brentq
from support.targets import ztf_j1539_doc
from typer.testing import CliRunner

from ucbplan.cli.app import app
from ucbplan.core.constants import DAY_S, YEAR_S
from ucbplan.core.ephemeris import find_epochs
from ucbplan.targets import load_target

runner = CliRunner()

T0_JD = Fraction("2458305.6827886")
P = Fraction("414.7915404")
PDOT = Fraction("-2.373e-11")
#: The issue's timing ephemeris of ZTF J1539+5027 (test input).
DOC: dict[str, Any] = ztf_j1539_doc(pdot="-2.373e-11")
#: Largest allowed |model − polynomial| [s] (the issue's bound; the fourth-order term of the
#: series inversion is 1.2 µs at ±10 yr, the printed BJD has 86 ns steps).
TOL_S = 10e-6


@pytest.fixture
def ztf(tmp_path: Path) -> Path:
    path = tmp_path / "ztf-test-input.yaml"
    path.write_text(yaml.safe_dump(DOC, sort_keys=False))
    return path


def _poly_s(n: Fraction) -> Fraction:
    return P * n + P * PDOT * n * n / 2


def _iso(tau_s: float) -> str:
    t0 = Time(2458305.0, 0.6827886, format="jd", scale="tdb")
    return (t0 + TimeDelta(tau_s, format="sec")).isot


def _predict(path: Path, tau0: float, tau1: float, anchor: str, *extra: str) -> dict[str, Any]:
    res = runner.invoke(
        app,
        [
            "ephemeris",
            str(path),
            "--start",
            _iso(tau0),
            "--end",
            _iso(tau1),
            "--anchor",
            anchor,
            "--format",
            "json",
            *extra,
        ],
    )
    assert res.exit_code == 0, res.output
    doc: dict[str, Any] = json.loads(res.stdout)
    return doc


def _check_rows(rows: list[dict[str, Any]]) -> float:
    """Worst |t★ − t(n)| over the rows [s], from tau_s, the BJD_TDB text and the ISO text."""
    worst = 0.0
    t0 = Time(2458305.0, 0.6827886, format="jd", scale="tdb")
    for r in rows:
        n = Fraction(r["cycle"]).limit_denominator(4)
        exact_s = _poly_s(n)
        worst = max(worst, abs(float(Fraction(r["tau_s"]) - exact_s)))
        bjd_s = (Fraction(r["t_star_bjd_tdb"]) - T0_JD) * 86400
        worst = max(worst, abs(float(bjd_s - exact_s)))
        iso_s = float((Time(r["t_star_tdb"], scale="tdb") - t0).to_value("s"))
        assert abs(iso_s - float(exact_s)) < TOL_S + 0.5e-6  # ISO text has 1 µs steps
    return worst


def test_conjunctions_agree_with_the_polynomial_over_20_years(ztf: Path) -> None:
    """≥ 2000 conjunctions (primary, n integer; secondary, n half-integer) in 10 windows spread
    over T0 ± 10 yr agree with exact t(n) to ≤ 10 µs, through the CLI's printed numbers."""
    rows: list[dict[str, Any]] = []
    for centre in np.linspace(-10 * YEAR_S, 10 * YEAR_S, 10):
        doc = _predict(ztf, centre - 0.25 * DAY_S, centre + 0.25 * DAY_S, "conjunction")
        rows += doc["rows"]
    assert len(rows) >= 2000
    halves = {Fraction(r["cycle"]).limit_denominator(4).denominator for r in rows}
    assert halves == {1, 2}  # primaries and secondaries
    for r in rows:
        frac = Fraction(r["cycle"]).limit_denominator(4)
        assert (frac.denominator == 1) == (abs(r["u_star_rad"] - math.pi / 2) < 1e-9)
    assert _check_rows(rows) <= TOL_S


def test_quadratures_are_a_quarter_period_from_the_eclipses(ztf: Path) -> None:
    """Star 1's quadratures are u₁ = 0 (max recession, n − ¼: before the primary eclipse) and
    u₁ = π (n + ¼: after it), at t(n ∓ ¼) of the polynomial."""
    rows: list[dict[str, Any]] = []
    for centre in (-9.7 * YEAR_S, -0.3 * YEAR_S, 0.0, 4.1 * YEAR_S, 9.9 * YEAR_S):
        rows += _predict(ztf, centre, centre + 0.1 * DAY_S, "quadrature")["rows"]
    assert len(rows) > 80
    for r in rows:
        frac = Fraction(r["cycle"]).limit_denominator(4) % 1
        assert frac == (Fraction(3, 4) if r["u_star_rad"] < 1.0 else Fraction(1, 4))
    assert _check_rows(rows) <= TOL_S


def test_eclipse_anchor_labels_primary_and_secondary(ztf: Path) -> None:
    doc = _predict(ztf, 5 * YEAR_S, 5 * YEAR_S + 3600, "eclipse")
    rows = doc["rows"]
    assert len(rows) == pytest.approx(2 * 3600 / 414.79, abs=1)
    for r in rows:
        primary = Fraction(r["cycle"]).limit_denominator(4).denominator == 1
        assert r["eclipse"] == ("primary" if primary else "secondary")
        assert r["sigma_t_s"] > 0
    assert _check_rows(rows) <= TOL_S
    # the same events, labelled the same, when asked for star 2's argument of latitude
    star2 = _predict(ztf, 5 * YEAR_S, 5 * YEAR_S + 3600, "eclipse", "--star", "2")["rows"]
    assert [r["eclipse"] for r in star2] == [r["eclipse"] for r in rows]
    assert np.allclose([r["tau_s"] for r in star2], [r["tau_s"] for r in rows], atol=1e-6)


def test_no_pi_mode_columns_for_timing_targets(ztf: Path, hm_cnc_path: Path) -> None:
    doc = _predict(ztf, 0.0, 3600.0, "conjunction")
    assert "t_alt_tdb" not in doc["rows"][0] and "tau_alt_s" not in doc["rows"][0]
    assert "alt_epoch" not in doc["meta"]
    assert doc["meta"]["t0_bjd_tdb"] == "2458305.6827886000000"
    assert doc["meta"]["t0_marks"] == "primary_eclipse"
    res = runner.invoke(
        app, ["ephemeris", str(ztf), "--start", _iso(0), "--end", _iso(3600), "--format", "csv"]
    )
    assert res.exit_code == 0 and "t_alt" not in res.stdout.splitlines()[0]
    res = runner.invoke(app, ["ephemeris", str(ztf), "--start", _iso(0), "--end", _iso(3600)])
    assert res.exit_code == 0 and "π-mode" not in res.output
    # LISA posteriors keep their π-mode alternative
    t = load_target(hm_cnc_path)
    es = find_epochs(t, 0.0, 3600.0, "conjunction")
    assert np.all(np.isfinite(es.tau_alt_s))
    assert np.all(np.isnan(find_epochs(load_target(ztf), 0.0, 3600.0, "conjunction").tau_alt_s))


def _eccentric(tmp_path: Path, eta: float, kappa: float, omega_dot: float) -> Path:
    doc = json.loads(json.dumps(DOC))
    doc["timing"]["pdot"] = 0.0
    doc["timing"]["eccentricity"] = {"eta": eta, "kappa": kappa, "omega_dot": omega_dot}
    doc["timing"]["covariance"]["exact"] = ["eta", "kappa", "omega_dot"]  # no σ (issue 33)
    path = tmp_path / "ecc.yaml"
    path.write_text(yaml.safe_dump(doc))
    return path


def _first_order_conjunction(u_mark: float, eta: float, kappa: float) -> float:
    """Φ_asc where u₁ = u★ in the first-order model, by a bracketing solver."""

    def g(x: float) -> float:
        return x + 2 * kappa * math.sin(x) - 2 * eta * math.cos(x) - u_mark

    return float(brentq(g, u_mark - 1.0, u_mark + 1.0, xtol=1e-15))


@pytest.mark.parametrize(("eta", "kappa"), [(0.0, 0.01), (0.005, -0.02), (0.03, 0.0)])
def test_secondary_eclipse_offset_by_the_eccentricity(
    tmp_path: Path, eta: float, kappa: float
) -> None:
    """t₂ − t₁ − P/2 is the exact first-order value (to 1 µs) and ≈ 2Pκ/π (to O(e²)P)."""
    t = load_target(_eccentric(tmp_path, eta, kappa, 0.0))
    es = find_epochs(t, 1e5, 1e5 + 20 * 414.8, "eclipse")
    tau = es.tau_s
    prim = np.abs(es.u_star_rad - math.pi / 2) < 1e-9
    # each primary with the secondary that follows it
    pairs = [(tau[i], tau[i + 1]) for i in range(len(tau) - 1) if prim[i] and not prim[i + 1]]
    assert len(pairs) >= 15
    phi1 = _first_order_conjunction(math.pi / 2, eta, kappa)
    phi2 = _first_order_conjunction(3 * math.pi / 2, eta, kappa)
    exact = (phi2 - phi1) / (math.pi * t.params.f_gw) - 414.7915404 / 2
    approx = 2 * 414.7915404 * kappa / math.pi
    for t1, t2 in pairs:
        offset = (t2 - t1) - 414.7915404 / 2
        assert offset == pytest.approx(exact, abs=1e-6)
        e2 = eta**2 + kappa**2
        assert offset == pytest.approx(approx, abs=4 * e2 * 414.79 + 1e-6)


def test_secondary_offset_follows_the_precessing_kappa(tmp_path: Path) -> None:
    """With ω̇, the offset tracks 2Pκ(t)/π as κ(t) = κ cos ω̇τ − η sin ω̇τ rotates."""
    omega_dot = 2 * math.pi / (30 * DAY_S)
    t = load_target(_eccentric(tmp_path, 0.0, 0.01, omega_dot))
    for tau0 in (0.0, 7.5 * DAY_S, 15 * DAY_S):
        es = find_epochs(t, tau0, tau0 + 3 * 414.8, "eclipse")
        prim = np.flatnonzero(np.abs(es.u_star_rad - math.pi / 2) < 1e-9)
        i = int(prim[0])
        offset = (es.tau_s[i + 1] - es.tau_s[i]) - 414.7915404 / 2
        kappa = 0.01 * math.cos(omega_dot * es.tau_s[i])
        assert offset == pytest.approx(2 * 414.7915404 * kappa / math.pi, abs=0.02)  # s, O(e²)


def test_u_at_t0_is_the_mark_through_the_cli(tmp_path: Path) -> None:
    """A secondary-eclipse T0 is a secondary eclipse (φ_ref = 3π kept), at cycle 0."""
    doc = json.loads(json.dumps(DOC))
    doc["timing"]["t0_marks"] = "secondary_eclipse"
    path = tmp_path / "sec.yaml"
    path.write_text(yaml.safe_dump(doc))
    rows = _predict(path, -100.0, 100.0, "eclipse")["rows"]
    at_t0 = [r for r in rows if abs(r["tau_s"]) < 1e-6]
    assert len(at_t0) == 1
    assert at_t0[0]["eclipse"] == "secondary" and at_t0[0]["cycle"] == 0.0


def test_windows_beyond_the_horizons_warn_on_either_side(ztf: Path) -> None:
    """The target's σ_v and K give T_valid(quadrature) ≈ 12.8 yr either side of T0."""
    for tau0 in (-20 * YEAR_S, 20 * YEAR_S):
        res = runner.invoke(
            app, ["ephemeris", str(ztf), "--start", _iso(tau0), "--end", _iso(tau0 + 3600)]
        )
        assert res.exit_code == 0
        side = "before" if tau0 < 0 else "after"
        assert f"{side} T0 have σ_u above the phase tolerance" in " ".join(res.output.split())
    res = runner.invoke(app, ["ephemeris", str(ztf), "--start", _iso(0), "--end", _iso(3600)])
    assert "warning" not in res.output
