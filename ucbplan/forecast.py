"""Forecast: σ_u(t) from the LISA covariance, phase tolerances, and the horizon T_valid.

Paper Sec. 4 (Eqs. sigma_u_from_PhiGW, T_valid_alpha, tol_conj_main, tol_quad_conj_main,
timing_unc) and Appendix C (Eqs. tol_gen, tol_conj, tol_quad, horizon_condition).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ucbplan.ephemeris import ANCHORS, _jacobian_at, resolve_anchor, u_jacobian
from ucbplan.errors import UcbplanError
from ucbplan.params import PhaseParams

if TYPE_CHECKING:
    from ucbplan.target import Target

__all__ = [
    "HorizonRow",
    "anchor_sigma_u",
    "horizon_table",
    "sigma_u",
    "sigma_u_from_jacobian",
    "t_valid",
    "tolerance",
    "u_jacobian",
]

FloatArray = NDArray[np.float64]
DAY_S = 86400.0
YEAR_S = 365.25 * DAY_S
#: Horizons are searched up to this long after the LISA observation [s].
HORIZON_CAP_S = 300.0 * YEAR_S


def sigma_u_from_jacobian(jac: FloatArray, cov: FloatArray) -> FloatArray:
    """σ_u = √(J C Jᵀ) for a stack of Jacobians ``jac`` (..., 7) [rad]."""
    var = np.einsum("...i,ij,...j->...", jac, cov, jac)
    out: FloatArray = np.sqrt(np.maximum(var, 0.0))
    return out


def sigma_u(p: PhaseParams, cov: FloatArray, tau_s: ArrayLike, star: int = 1) -> FloatArray:
    """Predicted 1σ uncertainty of u at ``tau_s`` (seconds from the reference epoch) [rad].

    Notes
    -----
    σ_u² = J C Jᵀ with the analytic Jacobian of Eq. arg_latitude_main over all seven
    parameters (rows/columns of parameters without uncertainty are zero in ``cov``).
    """
    return sigma_u_from_jacobian(u_jacobian(p, tau_s, star), cov)


def anchor_sigma_u(
    p: PhaseParams, cov: FloatArray, tau_s: ArrayLike, u_star: float, star: int = 1
) -> FloatArray:
    """σ_u at virtual anchor epochs: times ``tau_s`` with Φ_asc placed so that u = u★.

    The eccentric terms of σ_u depend on where in the orbit the epoch falls; this evaluates
    them at the anchor, so the result varies only on the apsidal period (smooth in τ).
    """
    tau = np.asarray(tau_s, dtype=np.float64)
    eps = 0.0 if star == 1 else math.pi
    w = p.omega_dot * tau
    eta = p.eta * np.cos(w) + p.kappa * np.sin(w)
    kap = p.kappa * np.cos(w) - p.eta * np.sin(w)
    phi_a = np.full_like(tau, u_star - eps)
    for _ in range(3):  # Φ_asc = u★ − ε − δ(Φ_asc): fixed point, contraction factor 2e
        phi_a = u_star - eps - (2 * kap * np.sin(phi_a) - 2 * eta * np.cos(phi_a))
    return sigma_u_from_jacobian(_jacobian_at(p, tau, np.sin(phi_a), np.cos(phi_a)), cov)


ToleranceKind = Literal["conjunction", "quadrature", "generic"]


def tolerance(
    kind: str,
    sigma_v: float,
    k: float,
    n_epochs: int = 2,
    u_star: float | None = None,
) -> float:
    """Phase tolerance δu_tol [rad] for an anchor, RV precision σ_v and semi-amplitude K.

    Parameters
    ----------
    kind : {"conjunction", "quadrature", "zero-crossing", "generic"}
        Anchor type; zero-crossing uses the conjunction form (|sin u★| ≈ 1 there).
    sigma_v, k : float
        Velocity precision per epoch and semi-amplitude (same units).
    n_epochs : {1, 2}
        Single epoch (N=1) or two-epoch difference (N=2, σ_Δ = √2 σ_v).
    u_star : float, optional
        Required for ``generic`` [rad].

    Returns
    -------
    float
        δu_tol [rad].

    Raises
    ------
    UcbplanError
        For non-positive σ_v or K, unknown kind or N.

    Notes
    -----
    Appendix C summary: N=1: σ_v/(K|sin u★|), σ_v/K, (2σ_v/K)^½; N=2: same generic and
    conjunction (Eqs. tol_gen, tol_conj), quadrature (√2σ_v/K)^½ (Eq. tol_quad). The generic form
    diverges at quadrature where the quadratic term takes over, so it is capped at the quadrature
    value (a choice of ucbplan, not in the paper).
    """
    if not (sigma_v > 0 and k > 0 and math.isfinite(sigma_v) and math.isfinite(k)):
        raise UcbplanError(f"tolerance needs σ_v > 0 and K > 0, got σ_v={sigma_v}, K={k}")
    if n_epochs not in (1, 2):
        raise UcbplanError(f"--epochs must be 1 or 2, got {n_epochs}")
    quad = math.sqrt((2.0 if n_epochs == 1 else math.sqrt(2.0)) * sigma_v / k)
    if kind in ("conjunction", "zero-crossing"):
        return sigma_v / k
    if kind == "quadrature":
        return quad
    if kind == "generic":
        if u_star is None:
            raise UcbplanError("generic tolerance needs u★")
        s = abs(math.sin(u_star))
        return quad if s == 0 else min(sigma_v / (k * s), quad)
    raise UcbplanError(f"unknown tolerance kind {kind!r}: expected conjunction|quadrature|generic")


def _anchor_kind(label: str, u_values: Sequence[float]) -> str:
    if label in ("conjunction", "quadrature", "zero-crossing"):
        return label
    u = u_values[0] % (2 * math.pi)
    if min(abs(u), abs(u - math.pi), abs(u - 2 * math.pi)) < 1e-12:
        return "quadrature"
    if min(abs(u - math.pi / 2), abs(u - 3 * math.pi / 2)) < 1e-12:
        return "conjunction"
    return "generic"


def _anchor_u_values(anchor: str | float) -> tuple[str, list[float]]:
    label, targets = resolve_anchor(anchor)
    if label == "zero-crossing":
        return label, list(ANCHORS["zero-crossing"])
    return label, [float(t) for t in targets]


def _oscillates(p: PhaseParams, cov: FloatArray) -> bool:
    """σ_u at a fixed anchor oscillates (apsidal period) only when ω̇ ≠ 0 and e matters."""
    if p.omega_dot == 0.0:
        return False
    return bool(np.any(cov[4:7, :] != 0.0)) or p.eccentricity > 0


def _refine(fn: Callable[[FloatArray], FloatArray], a: float, b: float, thr: float) -> float:
    """Crossing of fn = thr inside [a, b] (one sign change), by two 64-point subdivisions."""
    for _ in range(3):
        grid = np.linspace(a, b, 65)
        above = fn(grid) > thr
        idx = int(np.argmax(above != above[0]))
        if idx == 0:
            return b
        a, b = float(grid[idx - 1]), float(grid[idx])
    return 0.5 * (a + b)


def _close_time(
    fn: Callable[[FloatArray], FloatArray], tau_end: float, thr: float, period: float | None
) -> float:
    """Closing τ of the first admissible window (fn ≤ thr) open at/after ``tau_end`` (nan: none).

    ``period``: apsidal period when fn oscillates; the grid is then refined to resolve it.
    """
    offsets = np.concatenate([[0.0], np.geomspace(60.0, HORIZON_CAP_S, 900)])
    grid = tau_end + offsets
    vals = fn(grid)
    ok = vals <= thr
    if period is not None:
        # resolve the apsidal oscillation wherever the coarse grid is near the threshold
        near = np.abs(vals - thr) < 0.5 * thr
        if np.any(near):
            first = int(np.argmax(near))
            lo = grid[max(first - 1, 0)]
            hi_idx = int(np.argmax(~ok[first:])) + first if np.any(~ok[first:]) else grid.size - 1
            hi = grid[min(hi_idx + 1, grid.size - 1)]
            n = int(min(max((hi - lo) / (period / 32.0), 2), 400_000))
            fine = np.linspace(lo, hi, n + 1)
            grid = np.union1d(grid, fine)
            vals = fn(grid)
            ok = vals <= thr
    if not np.any(ok):
        return math.nan
    start = int(np.argmax(ok))
    rest = ~ok[start:]
    if not np.any(rest):
        return float(grid[-1])
    close = start + int(np.argmax(rest))
    return _refine(fn, float(grid[close - 1]), float(grid[close]), thr)


def t_valid(
    target: Target | tuple[PhaseParams, FloatArray, float],
    tol_rad: float,
    anchor_u_star: Sequence[float] | float,
    alpha: float = 1.0,
    star: int = 1,
) -> float:
    """Horizon T_valid [s after the end of the LISA observation] for one tolerance.

    Parameters
    ----------
    target : Target or (PhaseParams, covariance, t_obs_s)
        Parameters referenced to the observation midpoint.
    tol_rad : float
        δu_tol [rad].
    anchor_u_star : float or sequence of float
        u★ of the anchor; with several (quadrature: 0, π) the larger σ_u is used (conservative).
    alpha : float
        Planning margin α (Eq. T_valid_alpha).
    star : {1, 2}
        Component.

    Returns
    -------
    float
        Closing time of the first admissible window σ_u ≤ α δu_tol open at or after the end of
        the LISA observation, measured from that end [s]; 0 if there is none.

    Notes
    -----
    Eq. T_valid_alpha and the text around Table 4. When ω̇ ≠ 0, σ_u oscillates on the apsidal
    period; the grid is refined to P_aps/32 around the threshold so the first closing is found.
    """
    p, cov, t_obs = _unpack(target)
    us = [float(anchor_u_star)] if np.isscalar(anchor_u_star) else list(anchor_u_star)  # type: ignore[arg-type]

    def fn(tau: FloatArray) -> FloatArray:
        return np.max([anchor_sigma_u(p, cov, tau, u, star) for u in us], axis=0)

    period = 2 * math.pi / abs(p.omega_dot) if _oscillates(p, cov) else None
    close = _close_time(fn, t_obs / 2.0, alpha * tol_rad, period)
    return 0.0 if math.isnan(close) else max(close - t_obs / 2.0, 0.0)


def _unpack(
    target: Target | tuple[PhaseParams, FloatArray, float],
) -> tuple[PhaseParams, FloatArray, float]:
    if isinstance(target, tuple):
        p, cov, t_obs = target
        return p, np.asarray(cov, dtype=np.float64), float(t_obs)
    return target.params, target.covariance, target.t_obs_s


@dataclass(frozen=True, slots=True)
class HorizonRow:
    """One row of the Table-4/Table-7 style horizon table."""

    anchor: str
    alpha: float
    delta_u_tol_rad: float
    tolerance_rad: float
    t_valid_days: float
    dt_u_s: float
    sigma_u_end_rad: float
    n_epochs: int

    def as_dict(self) -> dict[str, float | str | int]:
        """JSON-ready mapping (snake_case, units in the key names)."""
        return {
            "anchor": self.anchor,
            "alpha": self.alpha,
            "tolerance_rad": self.tolerance_rad,
            "delta_u_tol_rad": self.delta_u_tol_rad,
            "t_valid_days": self.t_valid_days,
            "dt_u_s": self.dt_u_s,
            "sigma_u_end_rad": self.sigma_u_end_rad,
            "n_epochs": self.n_epochs,
        }


def horizon_table(
    target: Target | tuple[PhaseParams, FloatArray, float],
    sigma_v: float,
    k_eff: float,
    alphas: Sequence[float] = (0.5, 1.0),
    anchors: Sequence[str | float] = ("conjunction", "quadrature"),
    n_epochs: int = 2,
    star: int = 1,
) -> list[HorizonRow]:
    """Horizon rows (Tables 4 and 7) for each anchor × α.

    Notes
    -----
    δt_u = σ_u/|u̇| at T_valid (Eq. timing_unc with the full u̇); σ_u at the end of the LISA
    observation is reported per anchor.
    """
    p, cov, t_obs = _unpack(target)
    rows: list[HorizonRow] = []
    for anchor in anchors:
        label, us = _anchor_u_values(anchor)
        kind = _anchor_kind(label, us)
        tol = tolerance(kind, sigma_v, k_eff, n_epochs, us[0])
        tau_end = np.array([t_obs / 2.0])
        sig_end = max(float(anchor_sigma_u(p, cov, tau_end, u, star)[0]) for u in us)
        for alpha in alphas:
            tv = t_valid((p, cov, t_obs), tol, us, alpha, star)
            tau = np.array([t_obs / 2.0 + tv])
            sig = max(float(anchor_sigma_u(p, cov, tau, u, star)[0]) for u in us)
            rate = math.pi * (p.f_gw + p.fdot * tau[0] + p.fddot * tau[0] ** 2 / 2)
            rows.append(
                HorizonRow(
                    anchor=label,
                    alpha=float(alpha),
                    delta_u_tol_rad=tol,
                    tolerance_rad=alpha * tol,
                    t_valid_days=tv / DAY_S,
                    dt_u_s=sig / rate,
                    sigma_u_end_rad=sig_end,
                    n_epochs=n_epochs,
                )
            )
    return rows
