"""Inter-session fixed-u differences: Δκ_spec vs Δκ_LISA, Δv_CM, a_los (paper Secs. 3.1.4, 3.2).

Spectra are grouped by (session, u★) in :mod:`ucbplan.reduce.groups` (re-exported here): each
group's velocities are first moved to the exact u★ with the fitted semi-amplitude
(v − s K Λ_K (cos u − cos u★), a first-order phase-mismatch correction of at most K|Δu sin u★|),
then averaged with inverse-variance weights. Consecutive groups of the same u★ in different
sessions form a pair (α, β); pairs give

* Δv_j = v̄_j(β) − v̄_j(α) with σ² = σ_α² + σ_β² (Eq. app:unc_of_Delta_v);
* SB2: Δκ_spec (Eq. delta_kappa_spec_binned, generalised below) vs Δκ_LISA (Eq. delta_kappa_LISA),
  Δv_CM = (K2 Δv1 + K1 Δv2)/(K1 + K2) (the WIL41-on-differences intercept/(1 + q) of one pair,
  Eq. intercept_Deltav_cm), and the Δv1–Δv2 line with slope −q (Eq. SB2_fixedu_diff_WIL41);
* circular: Δv_CM = Δv_j (Eq. cir_deltaVcm, inverse-variance mean of the two stars for SB2);
* SB1 eccentric: Δv_CM from the difference of zero-crossing averages (Eq. rvzero_average), else
  Δv − K Δκ_LISA;
* a_los = −Δv_CM/ΔT, ḟ_acc = (f/c) a_los (Eq. fdot_acc_spectroscopy).

Finite windows at a general anchor u★ (from Eq. vbar_master with Eq. Phi_c): the fixed-u velocity is
γ ± K[Λ_K cos u★ + A κ + B η] + O(e²) with A = 2Λ_K sin²u★ + Λ_κ cos 2u★ and
B = (Λ_κ − Λ_K) sin 2u★,
so Δκ_spec = (Δv1 − Δv2)/((K1 + K2)A) − (B/A) Δη_LISA. At a quadrature A = Λ_κ, B = 0: exactly
Eq. delta_kappa_spec_binned; for Λ = 1, A = 1, B = 0: Eq. delta_kappa_spec.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from itertools import pairwise

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ucbplan.core.constants import C_M_S
from ucbplan.reduce.groups import MATCH_TOL_RAD, Group
from ucbplan.reduce.regression import LineFit, weighted_line

F64 = NDArray[np.float64]

#: Non-detections (|x| < 2σ) are reported as upper limits |x| < |x̂| + 2σ.
UPPER_LIMIT_NSIGMA = 2.0


@dataclass(frozen=True, slots=True)
class Pair:
    """One fixed-u pair of groups (α earlier than β) at the same u★.

    All velocities in km/s, ΔT in s; ``dkappa_*`` dimensionless; ``z_kappa`` is
    (Δκ_spec − Δκ_LISA)/√(σ_spec² + σ_LISA²). Fields not applicable are NaN.
    """

    alpha: str
    beta: str
    u_star: float
    dT_s: float
    dv: tuple[float, ...]
    sigma_dv: tuple[float, ...]
    dkappa_spec: float
    sigma_dkappa_spec: float
    dkappa_lisa: float
    sigma_dkappa_lisa: float
    z_kappa: float
    dv_cm: float
    sigma_dv_cm: float


def _ab(u_star: float, lam_k: float, lam_kap: float) -> tuple[float, float]:
    A = 2.0 * lam_k * math.sin(u_star) ** 2 + lam_kap * math.cos(2.0 * u_star)
    B = (lam_kap - lam_k) * math.sin(2.0 * u_star)
    return A, B


def make_pairs(
    groups: Sequence[Group],
    *,
    K: Sequence[float],
    eccentric: bool,
    ll_at: LLPredictor,
) -> list[Pair]:
    """Form consecutive same-u★ pairs from different sessions and evaluate each.

    Parameters
    ----------
    groups : sequence of Group
        From :func:`group_spectra`.
    K : sequence of float
        Semi-amplitudes per component [km/s].
    eccentric : bool
        Whether the target has e > 0 or ω̇ ≠ 0 (decides the Δv_CM estimator).
    ll_at : LLPredictor
        Predicts Δη_LISA, Δκ_LISA and their σ between two epochs.

    Returns
    -------
    list of Pair
    """
    by_anchor: dict[float, list[Group]] = {}
    for g in groups:
        by_anchor.setdefault(g.u_star, []).append(g)
    pairs = [
        _pair(ga, gb, K, eccentric, ll_at)
        for gs in by_anchor.values()
        for ga, gb in pairwise(sorted(gs, key=lambda g: g.tau_s))
        if ga.session != gb.session
    ]
    pairs.sort(key=lambda p: (p.u_star, p.dT_s))
    return pairs


def _pair(ga: Group, gb: Group, K: Sequence[float], eccentric: bool, ll_at: LLPredictor) -> Pair:
    """Differences β − α of two same-u★ groups and the Δκ, Δv_CM estimates they give."""
    a = ga.u_star
    dv = tuple(b - c for b, c in zip(gb.v, ga.v, strict=True))
    sdv = tuple(math.hypot(b, c) for b, c in zip(gb.sigma, ga.sigma, strict=True))
    lisa = ll_at.delta(ga.tau_s, gb.tau_s)
    A, B = _ab(a, 0.5 * (ga.lam_k + gb.lam_k), 0.5 * (ga.lam_kappa + gb.lam_kappa))
    if len(dv) == 2:
        kappa, dv_cm = _sb2_terms(dv, sdv, K, A, B, lisa, eccentric)
    else:
        nan = float("nan")
        kappa, dv_cm = (nan, nan, nan), _sb1_dv_cm(dv[0], sdv[0], K[0], A, B, lisa, eccentric)
    dk_s, sdk_s, z = kappa
    dk_l, sdk_l, _ = lisa
    dT = gb.tau_s - ga.tau_s
    return Pair(ga.session, gb.session, a, dT, dv, sdv, dk_s, sdk_s, dk_l, sdk_l, z, *dv_cm)


def _sb2_terms(
    dv: tuple[float, ...],
    sdv: tuple[float, ...],
    K: Sequence[float],
    A: float,
    B: float,
    lisa: tuple[float, float, float],
    eccentric: bool,
) -> tuple[tuple[float, float, float], tuple[float, float]]:
    """SB2: (Δκ_spec, σ, z vs Δκ_LISA) and (Δv_CM, σ) — K-weighted if eccentric, else the
    inverse-variance mean of the two stars (Eqs. intercept_Deltav_cm, cir_deltaVcm)."""
    dk_l, sdk_l, de_l = lisa
    k1, k2 = K
    dk_s = (dv[0] - dv[1]) / ((k1 + k2) * A) - (B / A) * de_l
    sdk_s = math.hypot(*sdv) / ((k1 + k2) * abs(A))
    z = (dk_s - dk_l) / math.hypot(sdk_s, sdk_l)
    if eccentric:
        dcm = (k2 * dv[0] + k1 * dv[1]) / (k1 + k2)
        sdcm = math.hypot(k2 * sdv[0], k1 * sdv[1]) / (k1 + k2)
    else:
        w = np.array([1.0 / sdv[0] ** 2, 1.0 / sdv[1] ** 2])
        dcm = float((w * np.array(dv)).sum() / w.sum())
        sdcm = float(1.0 / math.sqrt(w.sum()))
    return (dk_s, sdk_s, z), (dcm, sdcm)


def _sb1_dv_cm(
    dv: float,
    sdv: float,
    K: float,
    A: float,
    B: float,
    lisa: tuple[float, float, float],
    eccentric: bool,
) -> tuple[float, float]:
    """SB1: Δv_CM = Δv − K Δκ_LISA-term (eccentric; σ includes σ(Δκ_LISA)), else Δv."""
    dk_l, sdk_l, de_l = lisa
    dcm = dv - (K * (A * dk_l + B * de_l) if eccentric else 0.0)
    sdcm = math.hypot(sdv, K * abs(A) * sdk_l) if eccentric else sdv
    return dcm, sdcm


class LLPredictor:
    """Δκ_LISA, Δη_LISA between epochs with σ from the LISA covariance (Eq. kappa_lisa_prediction).

    Parameters
    ----------
    eta_ref, kappa_ref, omega_dot : float
        Laplace–Lagrange pair at t_ref and ω̇ [1, 1, rad/s].
    cov3 : ndarray, shape (3, 3)
        Covariance of (η_ref, κ_ref, ω̇).
    """

    def __init__(self, eta_ref: float, kappa_ref: float, omega_dot: float, cov3: ArrayLike):
        self.eta = eta_ref
        self.kappa = kappa_ref
        self.omega_dot = omega_dot
        self.cov = np.asarray(cov3, float)

    def _kap_grad(self, tau: float) -> tuple[float, float, F64, F64]:
        c, s = math.cos(self.omega_dot * tau), math.sin(self.omega_dot * tau)
        kap = self.kappa * c - self.eta * s
        eta = self.eta * c + self.kappa * s
        gk = np.array([-s, c, -tau * eta])
        ge = np.array([c, s, tau * kap])
        return kap, eta, gk, ge

    def delta(self, tau_a: float, tau_b: float) -> tuple[float, float, float]:
        """(Δκ_LISA, σ(Δκ_LISA), Δη_LISA) from τ_a to τ_b [s since t_ref] (Eq. delta_kappa_LISA)."""
        ka, ea, gka, _ = self._kap_grad(tau_a)
        kb, eb, gkb, _ = self._kap_grad(tau_b)
        g = gkb - gka
        var = float(g @ self.cov @ g)
        return kb - ka, math.sqrt(max(var, 0.0)), eb - ea


@dataclass(frozen=True, slots=True)
class DriftResult:
    """Combined inter-session results (NaN where not applicable).

    ``dkappa_line``: WIL41-on-differences line (Δv1 vs Δv2) if ≥ 2 disjoint SB2 pairs;
    ``a_los`` [m/s²] and ``fdot_acc`` [Hz/s] are inverse-variance combinations over pairs;
    ``*_upper`` are the 2σ upper limits |x̂| + 2σ when |x̂| < 2σ, else NaN.
    """

    pairs: tuple[Pair, ...]
    zero_crossing: tuple[tuple[str, str, float, float, float], ...]
    wil41_line: LineFit | None
    q_line: float
    sigma_q_line: float
    dv_cm_line: float
    sigma_dv_cm_line: float
    a_los: float
    sigma_a_los: float
    a_los_upper: float
    fdot_acc: float
    sigma_fdot_acc: float
    chi2_kappa: float
    n_kappa: int


def _zero_crossing_pairs(
    groups: Sequence[Group],
) -> list[tuple[str, str, float, float, float]]:
    """SB1: per session the mean of the two zero-crossing γ estimates (Eq. rvzero_average)."""
    per_session: dict[str, dict[float, Group]] = {}
    for g in groups:
        if abs(math.cos(g.u_star)) < math.sin(MATCH_TOL_RAD):
            per_session.setdefault(g.session, {})[round(math.sin(g.u_star))] = g
    means: list[tuple[str, float, float, float]] = []
    for s, d in per_session.items():
        if 1 in d and -1 in d:
            gp, gm = d[1], d[-1]
            means.append(
                (
                    s,
                    0.5 * (gp.tau_s + gm.tau_s),
                    0.5 * (gp.gamma_est[0] + gm.gamma_est[0]),
                    0.5 * math.hypot(gp.gamma_sigma[0], gm.gamma_sigma[0]),
                )
            )
    means.sort(key=lambda m: m[1])
    out = []
    for (sa, ta, va, sga), (sb, tb, vb, sgb) in pairwise(means):
        out.append((sa, sb, tb - ta, vb - va, math.hypot(sga, sgb)))
    return out


def combine(
    pairs: Sequence[Pair],
    groups: Sequence[Group],
    *,
    f_hz: float,
    n_components: int,
    eccentric: bool,
) -> DriftResult:
    """Combine pairs into a_los, ḟ_acc, the Δv1–Δv2 line and the Δκ consistency χ².

    Notes
    -----
    a_los = −Δv_CM/ΔT per pair (Eq. fdot_acc_spectroscopy), combined with inverse-variance weights;
    ḟ_acc = (f/c) a_los (Eq. fdot_acc). For SB1 eccentric targets with both zero crossings in ≥ 2
    sessions, Δv_CM comes from Eq. rvzero_average instead of the fixed-u pairs.
    """
    nan = float("nan")
    zc = _zero_crossing_pairs(groups) if (n_components == 1 and eccentric) else []
    a, sa, up = _a_los(_a_los_estimates(pairs, zc))
    line, ql, sql, dcm, sdcm = _difference_line(_disjoint_sb2(pairs))
    zs = [p.z_kappa for p in pairs if math.isfinite(p.z_kappa)]
    return DriftResult(
        pairs=tuple(pairs),
        zero_crossing=tuple(zc),
        wil41_line=line,
        q_line=ql,
        sigma_q_line=sql,
        dv_cm_line=dcm,
        sigma_dv_cm_line=sdcm,
        a_los=a,
        sigma_a_los=sa,
        a_los_upper=up,
        fdot_acc=f_hz / C_M_S * a if math.isfinite(a) else nan,
        sigma_fdot_acc=f_hz / C_M_S * sa if math.isfinite(sa) else nan,
        chi2_kappa=float(np.sum(np.square(zs))) if zs else nan,
        n_kappa=len(zs),
    )


def _a_los_estimates(
    pairs: Sequence[Pair], zc: list[tuple[str, str, float, float, float]]
) -> list[tuple[float, float]]:
    """(a_los, σ) [m/s²] per zero-crossing difference (SB1 eccentric) or else per pair."""
    if zc:
        return [(-dv * 1e3 / dT, sdv * 1e3 / dT) for _, _, dT, dv, sdv in zc]
    return [
        (-p.dv_cm * 1e3 / p.dT_s, p.sigma_dv_cm * 1e3 / p.dT_s)
        for p in pairs
        if p.dT_s > 0 and math.isfinite(p.dv_cm)
    ]


def _a_los(est: list[tuple[float, float]]) -> tuple[float, float, float]:
    """Inverse-variance mean, its σ and the upper limit (NaN if detected or no estimates)."""
    nan = float("nan")
    if not est:
        return nan, nan, nan
    w = np.array([1.0 / s**2 for _, s in est])
    a = float((w * np.array([x for x, _ in est])).sum() / w.sum())
    sa = float(1.0 / math.sqrt(w.sum()))
    up = abs(a) + UPPER_LIMIT_NSIGMA * sa if abs(a) < UPPER_LIMIT_NSIGMA * sa else nan
    return a, sa, up


def _disjoint_sb2(pairs: Sequence[Pair]) -> list[Pair]:
    """SB2 pairs sharing no (u★, session) group, shortest ΔT first (independent differences)."""
    disjoint: list[Pair] = []
    used: set[tuple[float, str]] = set()
    for p in sorted((p for p in pairs if len(p.dv) == 2), key=lambda p: p.dT_s):
        if (p.u_star, p.alpha) in used or (p.u_star, p.beta) in used:
            continue
        used.update({(p.u_star, p.alpha), (p.u_star, p.beta)})
        disjoint.append(p)
    return disjoint


def _difference_line(
    disjoint: list[Pair],
) -> tuple[LineFit | None, float, float, float, float]:
    """Δv1 vs Δv2 line (Eq. SB2_fixedu_diff_WIL41) of ≥ 3 disjoint pairs: (line, q, σ_q,
    Δv_CM = intercept/(1 + q), σ); errors in both axes by iterating q (NaN if too few pairs)."""
    nan = float("nan")
    if len(disjoint) < 3 or not np.ptp([p.dv[1] for p in disjoint]) > 0:
        return None, nan, nan, nan, nan
    x = np.array([p.dv[1] for p in disjoint])
    y = np.array([p.dv[0] for p in disjoint])
    sx = np.array([p.sigma_dv[1] for p in disjoint])
    sy = np.array([p.sigma_dv[0] for p in disjoint])
    q = 1.0
    for _ in range(29):  # the weights σ_y² + q²σ_x² depend on the slope −q: iterate
        q = -weighted_line(x, y, np.sqrt(sy**2 + q * q * sx**2), scale=False).slope
    line = weighted_line(x, y, np.sqrt(sy**2 + q * q * sx**2), scale=False)
    q = -line.slope
    dcm = line.intercept / (1.0 + q)
    sdcm = math.sqrt(
        line.cov[0, 0] / (1 + q) ** 2
        + line.intercept**2 * line.cov[1, 1] / (1 + q) ** 4
        + 2 * line.intercept * line.cov[0, 1] / (1 + q) ** 3
    )
    return line, q, line.sigma_slope, dcm, sdcm
