"""Mass relations of ``ucbplan reduce`` against the paper's numbers and round trips."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ucbplan.core import binary, constants
from ucbplan.reduce import masses as m

F_FID = 8.4062899940e-3  # Hz (Table 3, f_mid)
OMEGA_DOT_FID = 1.496836e-6  # rad/s
E_FID = math.hypot(0.0068, 0.0068)
M1_FID, M2_FID = 0.347, 0.285
COS_I = math.cos(1.4775)


def _k_from_masses(m1: float, m2: float, f: float, od: float, e: float, cos_i: float):  # type: ignore[no-untyped-def]
    """Independent forward model: Kepler's third law → a, then K_j = n_b a_j sin ι/√(1−e²)."""
    nb = math.pi * f - od
    mt = (m1 + m2) * constants.MSUN_KG
    a = (constants.G_SI * mt / nb**2) ** (1 / 3)
    k = nb * a * math.sqrt(1 - cos_i**2) / math.sqrt(1 - e * e)
    return k * m2 / (m1 + m2) / 1e3, k * m1 / (m1 + m2) / 1e3


def _derive(k1: float, k2: float, **kw: float) -> dict[str, np.ndarray]:
    args = (
        dict(
            f_hz=F_FID,
            fdot_hz_s=1.640367e-15,
            eta=0.0068,
            kappa=0.0068,
            omega_dot=OMEGA_DOT_FID,
            cos_i=COS_I,
        )
        | kw
    )
    return m.derive(
        K1_km_s=np.array(k1),
        K2_km_s=np.array(k2),
        gamma1_km_s=None,
        gamma2_km_s=None,
        **{k: np.array(v) for k, v in args.items()},
    )


def test_fiducial_semi_amplitudes() -> None:
    """K1 = 585.3, K2 = 712.6 km/s for M1 = 0.347, M2 = 0.285 (docs/method.md, "Errata of the
    paper"; 0.1 km/s: the printed precision)."""
    k1, k2 = _k_from_masses(M1_FID, M2_FID, F_FID, OMEGA_DOT_FID, E_FID, COS_I)
    assert k1 == pytest.approx(585.3, abs=0.1)
    assert k2 == pytest.approx(712.6, abs=0.1)


@settings(max_examples=60, deadline=None)
@given(
    st.floats(0.15, 1.2),
    st.floats(0.15, 1.2),
    st.floats(1e-3, 2e-2),
    st.floats(0.0, 0.05),
    st.floats(-0.95, 0.95),
)
def test_masses_round_trip(m1: float, m2: float, f: float, e: float, cos_i: float) -> None:
    """masses → (K1, K2) by Kepler → derive() returns the masses (relative 1e-10)."""
    od = 1e-6
    k1, k2 = _k_from_masses(m1, m2, f, od, e, cos_i)
    d = _derive(k1, k2, f_hz=f, omega_dot=od, eta=e * 0.6, kappa=e * 0.8, cos_i=cos_i)
    assert float(d["M1"]) == pytest.approx(m1, rel=1e-10)
    assert float(d["M2"]) == pytest.approx(m2, rel=1e-10)
    assert float(d["q"]) == pytest.approx(m2 / m1, rel=1e-12)


def test_omega_dot_gr_paper_value() -> None:
    """Eq. ecc_mcmc_inj text: ω̇_GR = 1.498e-6 rad/s for the fiducial masses (5e-4 relative)."""
    k1, k2 = _k_from_masses(M1_FID, M2_FID, F_FID, OMEGA_DOT_FID, E_FID, COS_I)
    d = _derive(k1, k2)
    assert float(d["omega_dot_GR"]) == pytest.approx(1.498e-6, rel=5e-4)
    assert float(d["M_tot_omega_dot"]) == pytest.approx(M1_FID + M2_FID, rel=2e-3)
    # inverse relation is exact
    assert float(
        binary.mass_from_omega_dot(d["omega_dot_GR"], d["P_b"], d["e"])
    ) / constants.MSUN_KG == (pytest.approx(float(d["M_tot"]), rel=1e-12))


def test_fdot_gw_only_matches_injection() -> None:
    """Eq. ecc_mcmc_inj: log10 ḟ = −14.7850265 at f0 = 8.406186457145e-3 Hz for the fiducial
    chirp mass (circular quadrupole formula; the paper's injection has no F(e) factor, so e = 0
    here; 2e-3 relative covers the three-digit masses)."""
    mc = float(binary.chirp_mass(M1_FID * constants.MSUN_KG, M2_FID * constants.MSUN_KG))
    fd = float(binary.fdot_gw_only(mc, 8.406186457145e-3, 0.0))
    assert math.log10(fd) == pytest.approx(-14.7850265, abs=1e-3)
    back = float(binary.chirp_mass_from_fdot(fd, 8.406186457145e-3, 0.0))
    assert back == pytest.approx(mc, rel=1e-12)
    assert np.isnan(binary.chirp_mass_from_fdot(-1e-15, 8.4e-3))


def test_distance_from_amplitude_round_trip_and_fiducial() -> None:
    """Eq. GW_amplitude: log10 𝒜 = −21.309 with the fiducial M_c and f gives d ≈ 0.577 kpc (the
    catalog distance; 2 % covers the 3-digit masses) and d → 𝒜 → M_c round-trips to 1e-12."""
    mc = float(binary.chirp_mass(M1_FID * constants.MSUN_KG, M2_FID * constants.MSUN_KG))
    d = float(binary.distance_from_amplitude_m(mc, F_FID, 10**-21.309))
    assert d / 3.0856775814913673e19 == pytest.approx(0.577, rel=0.02)
    assert float(binary.chirp_mass_from_amplitude(10**-21.309, F_FID, d)) == pytest.approx(
        mc, rel=1e-12
    )


def test_white_dwarf_radii() -> None:
    """Eggleton and Nauenberg radii: R → 0 at M_ch; agree within 5 % at 0.6–1.0 M☉ ("close to
    Nauenberg at high masses", Verbunt & Rappaport 1988); the 0.6 M☉ surface redshift
    GM/(Rc) ≈ 30 km/s (the well-known WD value, 27–34 km/s)."""
    for mm in (0.6, 0.8, 1.0):
        assert float(binary.radius_eggleton(mm)) == pytest.approx(
            float(binary.radius_nauenberg(mm)), rel=0.05
        )
    assert float(binary.radius_eggleton(1.4399)) < 0.002
    assert np.isnan(binary.radius_eggleton(1.5)) and np.isnan(binary.radius_nauenberg(0.0))
    r = float(binary.radius_eggleton(0.6)) * constants.RSUN_M
    z = constants.G_SI * 0.6 * constants.MSUN_KG / (r * constants.C_M_S) / 1e3
    assert 27.0 < z < 34.0


def test_redshift_orbital_term_paper_fraction() -> None:
    """Sec. 3.1.2: at P_b ≃ 5 min the radius-independent terms reach ~20 % of the differential
    surface redshift for unequal masses, one third of it from the second-order Doppler. Check the
    1/3 split exactly and the sign: 3G(M2−M1)/(2ac) < 0 for M1 > M2."""
    a = 0.07 * constants.RSUN_M
    tot = float(
        binary.redshift_difference_orbital(
            M1_FID * constants.MSUN_KG, M2_FID * constants.MSUN_KG, a
        )
    )
    doppler = (
        constants.G_SI
        * (M2_FID**2 - M1_FID**2)
        * constants.MSUN_KG
        / ((M1_FID + M2_FID) * 2 * a * constants.C_M_S)
    )
    assert doppler / tot == pytest.approx(1 / 3, rel=1e-12)
    assert tot < 0


def test_summary_percentiles() -> None:
    """summarize(): Gaussian samples → median ≈ μ, σ ≈ σ (1 % with 4e5 samples), NaNs ignored."""
    rng = np.random.default_rng(0)
    x = rng.normal(5.0, 2.0, 400_000)
    x[:10] = np.nan
    s = m.summarize(x)
    assert s.value == pytest.approx(5.0, abs=0.02)
    assert s.sigma == pytest.approx(2.0, rel=0.01)
    assert s.n_valid == 400_000 - 10
    assert s.lo < s.value < s.hi
