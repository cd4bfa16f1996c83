"""The paper's small-e h+, hx against the exact Keplerian quadrupole waveform.

Exact: Eqs. hplus_exact and hcross_exact (Appendix D) on a Kepler orbit (Kepler's equation solved
by Newton to 1e-15), with r, rdot, r udot from the orbit. Small-e: Eqs. app:final_form_h_plus /
app:final_form_h_cross with Phi = M + omega (mean phase), (eta, kappa) = e (sin w, cos w).
The difference must be O(e^2): |dh| / A+ < 10 e^2 and it must scale by 4 when e halves. This
independently checks the 9/4, -3/4 and b1 coefficients of the four-line table (an error in any
of them leaves an O(e) residual that fails both checks).
"""

from __future__ import annotations

import numpy as np
import pytest


def _kepler(mean_anomaly: np.ndarray, e: float) -> np.ndarray:
    ecc_anom = mean_anomaly + e * np.sin(mean_anomaly)
    for _ in range(30):
        ecc_anom -= (ecc_anom - e * np.sin(ecc_anom) - mean_anomaly) / (1 - e * np.cos(ecc_anom))
    return ecc_anom


def _exact(e: float, w: float, cos_i: float, phi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eqs. hplus_exact / hcross_exact with a = n_b = G M = 1 and amplitude A = 1."""
    mean = phi - w
    ecc_anom = _kepler(mean, e)
    nu = 2 * np.arctan2(
        np.sqrt(1 + e) * np.sin(ecc_anom / 2), np.sqrt(1 - e) * np.cos(ecc_anom / 2)
    )
    r = 1 - e * np.cos(ecc_anom)
    p_semi = 1 - e * e
    rdot = e * np.sin(nu) / np.sqrt(p_semi)
    r_udot = (1 + e * np.cos(nu)) / np.sqrt(p_semi)
    u = w + nu
    q = rdot**2 - r_udot**2 - 1 / r
    a_plus, a_cross = 1 + cos_i**2, 2 * cos_i
    sin2 = 1 - cos_i**2
    hp = a_plus / 2 * (q * np.cos(2 * u) - 2 * rdot * r_udot * np.sin(2 * u)) + sin2 / 2 * (
        q + 2 * r_udot**2
    )
    hx = a_cross / 2 * (q * np.sin(2 * u) + 2 * rdot * r_udot * np.cos(2 * u))
    return hp, hx


def _small_e(e: float, w: float, cos_i: float, phi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Paper Eqs. app:final_form_h_plus / app:final_form_h_cross with A = 1."""
    kap, eta = e * np.cos(w), e * np.sin(w)
    b1 = (1 - cos_i**2) / (2 * (1 + cos_i**2))
    hp = -(1 + cos_i**2) * (
        np.cos(2 * phi)
        + kap * (2.25 * np.cos(3 * phi) - (0.75 + b1) * np.cos(phi))
        + eta * (2.25 * np.sin(3 * phi) + (0.75 - b1) * np.sin(phi))
    )
    hx = (
        -2
        * cos_i
        * (
            np.sin(2 * phi)
            + kap * (2.25 * np.sin(3 * phi) - 0.75 * np.sin(phi))
            - eta * (2.25 * np.cos(3 * phi) + 0.75 * np.cos(phi))
        )
    )
    return hp, hx


@pytest.mark.parametrize("w", [np.pi / 4, 2.0, -1.0])
@pytest.mark.parametrize("cos_i", [0.093, 0.7, 1.0])
def test_small_e_waveform_is_kepler_to_first_order(w: float, cos_i: float) -> None:
    phi = np.linspace(0, 2 * np.pi, 2001)
    resid = []
    for e in (0.0096, 0.0048):
        hp_x, hx_x = _exact(e, w, cos_i, phi)
        hp_s, hx_s = _small_e(e, w, cos_i, phi)
        resid.append(max(np.max(np.abs(hp_x - hp_s)), np.max(np.abs(hx_x - hx_s))))
    # relative to the largest polarization amplitude max(A+, Ax) = 1 + cos^2 i
    assert resid[0] / (1 + cos_i**2) < 10 * 0.0096**2
    # O(e^2): halving e divides the residual by 4 (3.5..4.5 allows the O(e^3) part)
    assert 3.5 < resid[0] / resid[1] < 4.5


def test_first_order_residual_would_be_caught() -> None:
    """Control: flipping the sign of b1 (the difference with 2026arXiv260322377B's basis) leaves
    an O(e) residual that the test above rejects."""
    phi = np.linspace(0, 2 * np.pi, 2001)
    e, w, cos_i = 0.0096, np.pi / 4, 0.093
    hp_x, _ = _exact(e, w, cos_i, phi)
    hp_s, _ = _small_e(e, w, cos_i, phi)
    b1 = (1 - cos_i**2) / (2 * (1 + cos_i**2))
    kap, eta = e * np.cos(w), e * np.sin(w)
    flipped = hp_s - (1 + cos_i**2) * 2 * b1 * (kap * np.cos(phi) + eta * np.sin(phi))
    assert np.max(np.abs(hp_x - flipped)) > 10 * e**2
