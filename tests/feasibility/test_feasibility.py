"""Expected signal magnitudes (paper Sec. 3) against the numbers the paper and docs/method.md print.

Tolerances: the paper prints most coefficients to 2–4 significant figures, so each test allows
half a unit of the last printed digit unless a different reason is stated next to it.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import typer
from hypothesis import given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from ucbplan.core.constants import MONTH_S, YEAR_S
from ucbplan.errors import OutputExistsError, UcbplanError
from ucbplan.feasibility import (
    OpticalEphemeris,
    delta_k_bound,
    delta_v_aps,
    delta_v_cm,
    eccentricity_floor,
    feasibility_report,
    gw_timing_s,
    omega_dot_gr,
    omega_dot_tide,
    optical_ephemeris,
    optical_timing_s,
    plot_apsidal_signal,
    plot_report,
    report_for_target,
    semi_amplitudes,
    tau_chirp_gr_s,
    tertiary_acceleration,
)

ROOT = Path(__file__).resolve().parents[2]
HM_CNC = ROOT / "catalogs" / "hm-cnc-simulated.yaml"
FIDUCIAL = ROOT / "catalogs" / "fiducial-eccentric.yaml"
P_FID = 0.00275386 * 86400.0  # paper Sec. 4.1 [s]
I_FID = 1.4775  # rad
T_OBS = 4 * 31558149.7635  # 4 sidereal years (docs/method.md, "Time scales")
HM_F_ORB = 6.2204944297e-3 / 2  # orbital frequency of HM Cnc (Sec. 4.2 f_GW,0 / 2) [Hz]
KMS = 1e3


# ---------------------------------------------------------------------------- Eq. semiamp_est


def test_semi_amplitudes_fiducial() -> None:
    # Paper Sec. 4.1 / docs/method.md errata: K1 = 585.3, K2 = 712.6 km/s (printed to 0.1 km/s).
    k1, k2 = semi_amplitudes(0.347, 0.285, P_FID, math.sin(I_FID), e=0.0096)
    assert k1 / KMS == pytest.approx(585.3, abs=0.05)
    assert k2 / KMS == pytest.approx(712.6, abs=0.05)
    assert (k1 + k2) / KMS == pytest.approx(1297.9, abs=0.1)


def test_semi_amplitude_coefficient_747() -> None:
    # Eq. semiamp_est: 747 km/s at 0.6 + 0.6 M_sun, P_b = 5 min, sin i = 1, e = 0.
    k1, k2 = semi_amplitudes(0.6, 0.6, 300.0, 1.0)
    assert k1 / KMS == pytest.approx(747.0, abs=0.5) and k1 == pytest.approx(k2, rel=1e-15)


def test_semi_amplitudes_hm_cnc() -> None:
    # Paper Sec. 4.2: K1 ≈ 157, K2 ≈ 924 km/s for 1.0 + 0.17 M_sun, f_GW = 6.2204944297 mHz,
    # cos i = 0.67. Exact Kepler gives 156.2 / 918.6 km/s, 0.55 % / 0.59 % below the paper's
    # rounded figures (inputs "P_b ≈ 5.36 min", "cos i = 0.67" are themselves rounded): 1 %.
    sin_i = math.sqrt(1 - 0.67**2)
    k1, k2 = semi_amplitudes(1.0, 0.17, 2 / 6.2204944297e-3, sin_i)
    assert k1 / KMS == pytest.approx(157.0, rel=0.01)
    assert k2 / KMS == pytest.approx(924.0, rel=0.01)


@given(
    st.floats(0.1, 1.4),
    st.floats(0.1, 1.4),
    st.floats(60.0, 7200.0),
    st.floats(0.05, 1.0),
    st.floats(0.0, 0.5),
)
@settings(max_examples=100, deadline=None)
def test_semi_amplitudes_from_kepler(m1: float, m2: float, p: float, si: float, e: float) -> None:
    # Independent route: K1 + K2 = 2π a sin i / (P sqrt(1-e²)), a³ = G M P²/(4π²); K1/K2 = M2/M1.
    gm = 6.6743e-11 * 1.988409870698051e30 * (m1 + m2)
    a = (gm * p**2 / (4 * math.pi**2)) ** (1 / 3)
    k1, k2 = semi_amplitudes(m1, m2, p, si, e)
    assert k1 + k2 == pytest.approx(2 * math.pi * a * si / (p * math.sqrt(1 - e * e)), rel=1e-12)
    assert k1 / k2 == pytest.approx(m2 / m1, rel=1e-12)


def test_bad_inputs_raise() -> None:
    with pytest.raises(ValueError, match="m1_msun must be finite and > 0"):
        semi_amplitudes(-1.0, 0.5, 300.0, 1.0)
    with pytest.raises(ValueError, match="eccentricity must be in"):
        omega_dot_gr(1.0, 300.0, e=1.0)


# ------------------------------------------------------------------- apsidal rates (GR, tide)


def test_omega_dot_gr_fiducial() -> None:
    # Paper Sec. 4.1: z_ω = 30.097 encodes ω̇_GR = 1.498e-6 rad/s for the fiducial masses.
    # Masses printed to 3 decimals (M_tot = 0.632 ± 0.001 → ±0.1 % in ω̇ ∝ M^{2/3}): rel 1e-3.
    w = omega_dot_gr(0.347 + 0.285, P_FID, e=0.0096)
    assert w == pytest.approx(1.498e-6, rel=1e-3)
    assert w * T_OBS / (2 * math.pi) == pytest.approx(30.097, rel=1e-3)
    # Apsidal period T_GR ≈ 1.6 months (Sec. 3.2).
    assert 2 * math.pi / w / MONTH_S == pytest.approx(1.6, abs=0.05)


def test_omega_dot_gr_coefficient() -> None:
    # Δω_GR = 4.1 rad per month at 1.2 M_sun, P_b = 5 min, e → 0 (text after Eq. omega_dot_GR).
    assert omega_dot_gr(1.2, 300.0) * MONTH_S == pytest.approx(4.1, abs=0.05)
    # 1/(1-e²) dependence, exact.
    assert omega_dot_gr(1.2, 300.0, 0.3) == pytest.approx(omega_dot_gr(1.2, 300.0) / 0.91, 1e-14)


def test_omega_dot_tide_coefficient_and_errata() -> None:
    # Eq. del_om_tide: 3.7 rad per month at 0.6 + 0.6 M_sun, P_b = 5 min (printed to 0.1).
    assert omega_dot_tide(0.6, 0.6, 300.0) * MONTH_S == pytest.approx(3.7, abs=0.05)
    # docs/method.md erratum: 0.347 + 0.285 M_sun gives "≈100 rad/month" at 5 min (93.7; the paper's
    # "≃" is one significant figure → 10 %) and ≈256 at the paper's P_b = 3.97 min (0.5 %).
    assert omega_dot_tide(0.347, 0.285, 300.0) * MONTH_S == pytest.approx(100.0, rel=0.10)
    assert omega_dot_tide(0.347, 0.285, P_FID) * MONTH_S == pytest.approx(256.0, rel=0.005)
    # Tides dominate GR for this system (Sec. 3).
    assert omega_dot_tide(0.347, 0.285, P_FID) > 10 * omega_dot_gr(0.632, P_FID)


def test_omega_dot_tide_scalings() -> None:
    # (5 min / P_b)^{13/3}, M_tot^{-5/3} at fixed masses' 𝒦, and f_tide(e): exact scalings.
    w1, w2 = omega_dot_tide(0.4, 0.3, 300.0), omega_dot_tide(0.4, 0.3, 240.0)
    assert w2 / w1 == pytest.approx((300.0 / 240.0) ** (13 / 3), rel=1e-12)
    e = 0.2
    f_tide = (1 + 1.5 * e**2 + e**4 / 8) / (1 - e**2) ** 5
    assert omega_dot_tide(0.4, 0.3, 300.0, e) / w1 == pytest.approx(f_tide, rel=1e-12)


# -------------------------------------------------------------------- chirp and ΔK bound


def test_tau_chirp_and_delta_k() -> None:
    # Eq. tau_chirp: ≈1e5 yr at M_c = 0.52 M_sun, P_b = 5 min (one significant figure: 10 %).
    m = 0.52 * 2**0.2  # equal masses with chirp mass 0.52
    tau = tau_chirp_gr_s(m, m, 2 / 300.0)
    assert tau / YEAR_S == pytest.approx(1e5, rel=0.10)
    # P_b^{8/3} scaling, exact.
    assert tau_chirp_gr_s(m, m, 1 / 300.0) / tau == pytest.approx(2 ** (8 / 3), rel=1e-12)
    # Eq. DeltaK_bound: 2.5e-3 km/s at K = 747 km/s, T = 1 yr, τ = 1e5 yr.
    dk = delta_k_bound(747e3, YEAR_S, 1e5 * YEAR_S)
    assert dk / KMS == pytest.approx(2.5e-3, abs=0.05e-3)
    # Eq. DeltaK_vs_aps: ΔK / (2Ke) = T/(6 e τ) ≈ 1.7e-4 at e = 0.01.
    assert dk / (2 * 747e3 * 0.01) == pytest.approx(1.7e-4, abs=0.05e-4)


# ----------------------------------------------------------------------- apsidal signal


@given(
    st.floats(1e3, 1e6),
    st.floats(0.0, 0.1),
    st.floats(-10.0, 10.0),
    st.floats(1e-8, 1e-4),
    st.floats(0.0, 1e8),
)
@settings(max_examples=200, deadline=None)
def test_delta_v_aps_product_form(k: float, e: float, w1: float, wdot: float, dt: float) -> None:
    # Eq. apsidal_drift_est0: both forms agree and |Δv_aps| ≤ 2 K e.
    direct = k * e * (math.cos(w1 + wdot * dt) - math.cos(w1))
    value = float(delta_v_aps(k, e, w1, wdot, dt))
    assert value == pytest.approx(direct, abs=1e-9 * k)
    assert abs(value) <= 2 * k * e * (1 + 1e-12)


def test_delta_v_aps_bound_and_floor() -> None:
    # Eq. apsidal_drift_est1: 2 K e = 15 km/s at K = 747 km/s, e = 0.01 (printed to 1 km/s).
    dv = delta_v_aps(747e3, 0.01, 0.0, 1.0, math.pi)  # Δω = π, ω1 = 0: cos π − cos 0 = −2
    assert abs(float(dv)) / KMS == pytest.approx(15.0, abs=0.5)
    # e floor: σ_v = 15 km/s → e ≳ 0.01 for one pair; N spectra lower it by N^{-1/2}.
    assert eccentricity_floor(15e3, 747e3) == pytest.approx(0.01, abs=0.0005)
    assert eccentricity_floor(15e3, 747e3, 4) == pytest.approx(eccentricity_floor(15e3, 747e3) / 2)
    # Fig. apsidal_signal caption: 2 K1 e ≈ 12 km/s at e ~ 0.01 for the fiducial binary (its K1
    # from the masses, period and inclination of Sec. 4.1; "≈ 12" is two figures → ±0.5).
    rep = feasibility_report(
        name="fid", period_s=P_FID, f_gw_hz=2 / P_FID, sin_i=math.sin(I_FID), e=0.01,
        m1_msun=0.347, m2_msun=0.285,
    )  # fmt: skip
    assert rep.delta_v_aps_max_m_s is not None
    assert rep.delta_v_aps_max_m_s / KMS == pytest.approx(12.0, abs=0.5)


def test_delta_v_cm() -> None:
    # Eq. DeltaVcm_est: 3e-3 m/s per year at a_CM = 1e-10 m/s² (one significant figure).
    assert float(delta_v_cm(1e-10, YEAR_S)) == pytest.approx(3e-3, rel=0.1)
    # 1 M_sun at 5 AU: a_CM ≈ 2.3e-4 m/s² and Δv_CM ≈ 0.6 km/s per month (2 and 1 sig. figs).
    a = tertiary_acceleration(1.0, 5.0)
    assert a == pytest.approx(2.3e-4, rel=0.04)
    assert float(delta_v_cm(a, MONTH_S)) / KMS == pytest.approx(0.6, abs=0.05)


# ----------------------------------------------------------------------- optical timing


@pytest.mark.parametrize(
    ("phase", "f_rel", "fdot_rel", "f_orb", "expected"),
    [
        (0.0, 9.6e-9, 3.2e-17, HM_F_ORB, 1.24),  # HM Cnc optical, frequency terms only
        (0.004, 9.6e-9, 3.2e-17, HM_F_ORB, 1.79),  # ... with the reference-phase term
        (0.0014, 3.2e-8, 6.4e-16, HM_F_ORB, 6.52),  # HM Cnc X-ray ephemeris
        (0.0, 7.2e-8, 3.7e-15, 1 / 765.206, 30.85),  # J0651+2844, frequency terms only
    ],
)
def test_optical_timing_errata(
    phase: float, f_rel: float, fdot_rel: float, f_orb: float, expected: float
) -> None:
    # docs/method.md errata (orbital frequency), values printed to 0.01 s, ΔT = 4 Julian years.
    eph = OpticalEphemeris(phase, f_rel, fdot_rel, f_orb)
    assert float(optical_timing_s(eph, 4 * YEAR_S)) == pytest.approx(expected, abs=0.005)


def test_optical_from_period_matches_frequency_form() -> None:
    p = 1 / HM_F_ORB
    eph = OpticalEphemeris.from_period(p, 9.6e-9 * p, 3.2e-17 * p, 0.004 * p)
    ref = OpticalEphemeris(0.004, 9.6e-9, 3.2e-17, HM_F_ORB)
    dt = np.array([0.0, YEAR_S, 4 * YEAR_S])
    np.testing.assert_allclose(optical_timing_s(eph, dt), optical_timing_s(ref, dt), rtol=1e-12)


# ------------------------------------------------------------------ GW timing, full reports


def test_gw_timing_four_years_after_midpoint() -> None:
    from ucbplan.targets import load_target

    # Paper Sec. 5: δt_u ≈ 0.3 s (eccentric source) and 0.9 s (HM Cnc-like) four years after
    # the observation midpoint; one significant figure → ± half a unit of that digit.
    ecc = float(gw_timing_s(load_target(FIDUCIAL), 4 * YEAR_S))
    hm = float(gw_timing_s(load_target(HM_CNC), 4 * YEAR_S))
    assert 0.25 <= ecc < 0.35
    assert 0.85 <= hm < 0.95


def test_report_for_fiducial_target() -> None:
    from ucbplan.targets import load_target

    rep = report_for_target(load_target(FIDUCIAL), baseline_s=30 * 86400.0)
    # Masses from the file; K1 from the target's own P_b and cos i (Table 3) ≈ 585.3 km/s.
    assert rep.k1_m_s is not None and rep.k1_m_s / KMS == pytest.approx(585.3, abs=0.5)
    assert rep.omega_dot_source == "target file"
    assert rep.omega_dot_used == pytest.approx(1.496836e-6, rel=1e-12)
    assert rep.omega_dot_gr == pytest.approx(1.498e-6, rel=1e-3)
    assert rep.e_floor == pytest.approx(15e3 / (2 * rep.k1_m_s), rel=1e-12)
    assert rep.delta_v_aps_max_m_s == pytest.approx(2 * rep.k1_m_s * rep.e, rel=1e-12)
    assert rep.gw_timing_s is not None and rep.optical_timing_s is None
    doc = rep.to_dict()
    json.dumps(doc, allow_nan=False)  # inf/NaN mapped to None


def test_report_without_masses_degrades_gracefully() -> None:
    rep = feasibility_report(name="x", period_s=300.0, f_gw_hz=2 / 300.0)
    assert rep.k1_m_s is None and rep.e_floor is None and rep.omega_dot_used == 0.0
    assert any("--m1/--m2" in n for n in rep.notes)
    assert rep.to_dict()["apsidal_period_s"] is None  # inf → null in JSON


def test_plot_apsidal_signal(tmp_path: Path) -> None:
    out = tmp_path / "aps.png"
    plot_apsidal_signal(out, k1_m_s=585.3e3, omega_dot_rad_s=1.498e-6, target_e=0.0096,
                        target_omega1=math.pi / 4)  # fmt: skip
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(ValueError, match="omega_dot is 0"):
        plot_apsidal_signal(out, k1_m_s=585.3e3, omega_dot_rad_s=0.0)
    with pytest.raises(OutputExistsError):  # figures are never clobbered silently
        plot_apsidal_signal(out, k1_m_s=585.3e3, omega_dot_rad_s=1.498e-6)


def test_plot_report_needs_k1_and_rate(tmp_path: Path) -> None:
    rep = feasibility_report(name="x", period_s=300.0, f_gw_hz=2 / 300.0)
    with pytest.raises(UcbplanError, match="no K1 or no apsidal rate"):
        plot_report(rep, tmp_path / "aps.png")
    assert not (tmp_path / "aps.png").exists()


def test_optical_ephemeris_styles() -> None:
    assert optical_ephemeris(300.0) is None
    eph = optical_ephemeris(300.0, sigma_f_rel=1e-8)
    assert eph == OpticalEphemeris(0.0, 1e-8, 0.0, 1 / 300.0)
    eph = optical_ephemeris(300.0, sigma_t0_s=3.0)
    assert eph is not None and eph.sigma_phase_cycles == pytest.approx(0.01, rel=1e-15)
    with pytest.raises(UcbplanError, match="not both"):
        optical_ephemeris(300.0, sigma_p_s=1e-6, sigma_fdot_rel_s=1e-17)


# ------------------------------------------------------------------------------------- CLI


def _app() -> typer.Typer:
    from ucbplan.cli.feasibility import register

    app = typer.Typer()

    @app.callback()
    def _root() -> None:
        """Test shell."""

    register(app)
    return app


def test_cli_feasibility_json(tmp_path: Path) -> None:
    out = tmp_path / "f.json"
    plot = tmp_path / "aps.png"
    args = [
        "feasibility", str(FIDUCIAL), "--format", "json", "-o", str(out), "--plot", str(plot),
        "--baseline", "30 d", "--optical-sigma-phase", "0.004", "--optical-sigma-f-rel", "9.6e-9",
        "--optical-sigma-fdot-rel", "3.2e-17",
    ]  # fmt: skip
    res = CliRunner().invoke(_app(), args)
    assert res.exit_code == 0, res.output
    doc = json.loads(out.read_text())
    assert doc["k1_m_s"] / KMS == pytest.approx(585.3, abs=0.5)
    assert doc["baseline_s"] == 30 * 86400.0
    assert len(doc["optical_timing_s"]) == len(doc["timing_years"]) == len(doc["gw_timing_s"])
    assert plot.read_bytes()[:4] == b"\x89PNG"


def test_cli_feasibility_table_and_overrides() -> None:
    res = CliRunner().invoke(_app(), ["feasibility", str(HM_CNC), "--m1", "1.0", "--m2", "0.17"])
    assert res.exit_code == 0, res.output
    assert "K2" in res.output and "918.6" in res.output  # rich table on stderr (mixed here)


def test_cli_feasibility_rejects_mixed_optical_styles() -> None:
    args = ["feasibility", str(HM_CNC), "--optical-sigma-p", "1e-6", "--optical-sigma-f-rel", "1"]
    res = CliRunner().invoke(_app(), args)
    assert isinstance(res.exception, UcbplanError)
    assert "not both" in str(res.exception)


def test_cli_feasibility_bad_baseline() -> None:
    res = CliRunner().invoke(_app(), ["feasibility", str(HM_CNC), "--baseline", "soon"])
    assert isinstance(res.exception, UcbplanError)
    # the library names its parameter; the command line prints it as --baseline (cli/_flags.py)
    assert str(res.exception).startswith("baseline: got 'soon'")


def test_cli_optical_epoch_shifts_the_optical_baseline(tmp_path: Path) -> None:
    # An optical ephemeris referenced 4 Julian years before the LISA midpoint (2037-01-01 TDB)
    # has, at the midpoint, the error the same ephemeris has 4 yr after its own epoch.
    out = tmp_path / "f.json"
    args = [
        "feasibility", str(HM_CNC), "--format", "json", "-o", str(out),
        "--optical-sigma-phase", "0.004", "--optical-sigma-f-rel", "9.6e-9",
        "--optical-sigma-fdot-rel", "3.2e-17", "--optical-epoch", "2033-01-01T00:00:00",
    ]  # fmt: skip
    res = CliRunner().invoke(_app(), args)
    assert res.exit_code == 0, res.output
    doc = json.loads(out.read_text())
    # 2033-01-01 → 2037-01-01 is 1461 days = 4 Julian years exactly: 1.79 s (docs/method.md errata).
    assert doc["timing_years"][0] == 0.0
    assert doc["optical_timing_s"][0] == pytest.approx(1.79, abs=0.005)
    res = CliRunner().invoke(_app(), [*args[:-1], "someday", "--overwrite"])
    assert isinstance(res.exception, UcbplanError)
    assert str(res.exception).startswith("optical_epoch: ")


@pytest.mark.parametrize("style", ["frequency", "period"])
def test_cli_optical_timing_uses_the_node_to_node_period(tmp_path: Path, style: str) -> None:
    """An eclipse ephemeris repeats node to node, P = 2/f_gw, not 2π/(πf − ω̇) (issue 26, item 5).

    Reference: Eq. optical_timing_prec evaluated here by hand with P = 2/f_gw (the target schema's
    ``timing.period`` definition). The fiducial source's ω̇/(πf) = 5.7e-5 is far above the 1e-9
    relative tolerance (float64 rounding of a few operations).
    """
    from ucbplan.targets import load_target

    f_gw = load_target(FIDUCIAL).params.f_gw
    P = 2.0 / f_gw
    if style == "frequency":
        opts = ["--optical-sigma-phase", "0.004", "--optical-sigma-f-rel", "9.6e-9"]
        opts += ["--optical-sigma-fdot-rel", "3.2e-17"]
        s_phase_s, s_f_rel, s_fdot_rel = 0.004 * P, 9.6e-9, 3.2e-17
    else:
        opts = ["--optical-sigma-p", "2e-6", "--optical-sigma-pdot", "1e-13"]
        opts += ["--optical-sigma-t0", "0.5"]
        s_phase_s, s_f_rel, s_fdot_rel = 0.5, 2e-6 / P, 1e-13 / P
    out = tmp_path / "f.json"
    args = ["feasibility", str(FIDUCIAL), "--format", "json", "-o", str(out), *opts]
    res = CliRunner().invoke(_app(), args)
    assert res.exit_code == 0, res.output
    doc = json.loads(out.read_text())
    dt = np.asarray(doc["timing_years"]) * YEAR_S
    expected = np.sqrt(s_phase_s**2 + (s_f_rel * dt) ** 2 + (0.5 * s_fdot_rel * dt**2) ** 2)
    np.testing.assert_allclose(doc["optical_timing_s"], expected, rtol=1e-9, atol=0.0)
