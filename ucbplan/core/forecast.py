"""Forecast: σ_u(t) from the ephemeris covariance, phase tolerances, and the horizon T_valid.

Paper Sec. 4 (Eqs. sigma_u_from_PhiGW, T_valid_alpha, tol_conj_main, tol_quad_conj_main,
timing_unc) and Appendix C (Eqs. tol_gen, tol_conj, tol_quad, horizon_condition).

A LISA posterior's information ends with the observation, so its horizon is measured after the
end of the observation (the paper's Tables 4 and 7). A timing ephemeris (``kind == "timing"``,
T_obs = 0) is informed on both sides of its epoch T0, and σ_u grows both ways: its horizon is
reported before and after T0 separately. The backward horizon is the forward one of the
time-reversed model (ω̇ → −ω̇ and the covariance signs of f, f̈, ω̇ flipped: ∂u/∂θ(−τ; ω̇) =
∂u/∂θ(τ; −ω̇)·D, D = diag(1, −1, 1, −1, 1, 1, −1)), so both directions run the same search.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ucbplan.core.constants import DAY_S, YEAR_S
from ucbplan.core.ephemeris import ANCHORS, resolve_anchor
from ucbplan.core.params import EphemerisSource, PhaseParams
from ucbplan.core.phase import jacobian_kernel, sigma_u_from_jacobian, u_jacobian
from ucbplan.errors import UcbplanError

__all__ = [
    "AFTER",
    "BEFORE",
    "HorizonRow",
    "anchor_sigma_u",
    "horizon_s",
    "horizon_table",
    "sigma_u",
    "sigma_u_end",
    "sigma_u_from_jacobian",
    "t_valid",
    "t_valid_batch",
    "tolerance",
    "two_sided",
    "u_jacobian",
    "valid_window_s",
]

FloatArray = NDArray[np.float64]
#: A target, or its (parameters, covariance, T_obs [s]) directly.
SourceLike = EphemerisSource | tuple[PhaseParams, FloatArray, float]
#: Horizons are searched up to this long after the LISA observation [s].
HORIZON_CAP_S = 300.0 * YEAR_S
#: Directions of a horizon: after the end of the information (+1), before its start (−1).
AFTER, BEFORE = 1, -1
#: Signs of the parameters' columns of ∂u/∂θ under time reversal (see the module docstring).
_REVERSAL = np.array([1.0, -1.0, 1.0, -1.0, 1.0, 1.0, -1.0])


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
    out = _anchor_sigma_batch(p.as_array()[None, :], np.asarray(cov)[None], tau[None], u_star, star)
    return out[0]


def _anchor_sigma_batch(
    pars: FloatArray, covs: FloatArray, tau: FloatArray, u_star: float, star: int = 1
) -> FloatArray:
    """Batched :func:`anchor_sigma_u`: pars (n, 7), covs (n, 7, 7), tau (n, G) → (n, G)."""
    eta0, kap0, wdot = pars[:, 4:5], pars[:, 5:6], pars[:, 6:7]
    eps = 0.0 if star == 1 else math.pi
    w = wdot * tau
    cw, sw = np.cos(w), np.sin(w)
    phi_a = np.full_like(tau, u_star - eps)
    if np.any(eta0 != 0.0) or np.any(kap0 != 0.0):
        eta = eta0 * cw + kap0 * sw
        kap = kap0 * cw - eta0 * sw
        for _ in range(2):  # Φ_asc = u★ − ε − δ(Φ_asc): contraction 2e, two steps leave O(e³)
            phi_a = u_star - eps - (2 * kap * np.sin(phi_a) - 2 * eta * np.cos(phi_a))
    jac = jacobian_kernel(eta0, kap0, wdot, tau, np.sin(phi_a), np.cos(phi_a), (cw, sw))
    var = np.sum(np.matmul(jac, covs) * jac, axis=-1)
    out: FloatArray = np.sqrt(np.maximum(var, 0.0))
    return out


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
    if label == "eclipse":
        return "conjunction"
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


_OFFSETS = np.concatenate([[0.0], np.geomspace(60.0, HORIZON_CAP_S, 320)])
_REFINE = np.linspace(0.0, 1.0, 65)


def _oscillating(pars: FloatArray, covs: FloatArray) -> NDArray[np.bool_]:
    """Rows whose anchor σ_u oscillates (apsidal period): ω̇ ≠ 0 and e or its σ non-zero."""
    ecc = (pars[:, 4] != 0) | (pars[:, 5] != 0) | np.any(covs[:, 4:7, :] != 0, axis=(1, 2))
    out: NDArray[np.bool_] = (pars[:, 6] != 0) & ecc
    return out


def t_valid_batch(
    pars: FloatArray,
    covs: FloatArray,
    t_obs_s: FloatArray,
    thr_rad: FloatArray | float,
    anchor_u_star: Sequence[float],
    star: int = 1,
    direction: int = AFTER,
) -> FloatArray:
    """Vectorised horizons: closing τ − T/2 of the first window σ_u ≤ thr [s] (0 if none).

    Parameters
    ----------
    pars : (n, 7) parameters at the midpoint; covs : (n, 7, 7); t_obs_s : (n,);
    thr_rad : (n,) thresholds α·δu_tol; anchor_u_star : the anchor's u★ values (max σ_u used);
    direction : :data:`AFTER` (after the end of the observation, the default) or
    :data:`BEFORE` (before its start: the result is then −T/2 − τ of the closing, also ≥ 0).
    """
    pars = np.atleast_2d(np.asarray(pars, dtype=np.float64))
    covs = np.asarray(covs, dtype=np.float64).reshape(-1, 7, 7)
    if direction == BEFORE:
        pars, covs = _time_reversed(pars, covs)
    elif direction != AFTER:
        raise UcbplanError(f"direction must be +1 (after) or -1 (before), got {direction!r}")
    t_obs = np.broadcast_to(np.asarray(t_obs_s, dtype=np.float64), (pars.shape[0],))
    thr = np.broadcast_to(np.asarray(thr_rad, dtype=np.float64), (pars.shape[0],))
    out = np.zeros(pars.shape[0])
    osc = _oscillating(pars, covs)
    for mask, size in ((~osc, 256), (osc, 32)):  # small chunks: fine grids differ per row
        idx = np.nonzero(mask)[0]
        for start in range(0, idx.size, size):
            sel = idx[start : start + size]
            out[sel] = _t_valid_chunk(
                pars[sel], covs[sel], t_obs[sel], thr[sel], anchor_u_star, star, bool(osc[sel[0]])
            )
    return out


def _time_reversed(pars: FloatArray, covs: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Parameters and covariances whose σ_u at +τ is the original's at −τ (exactly)."""
    rev = pars.copy()
    rev[:, 6] = -rev[:, 6]
    return rev, covs * np.outer(_REVERSAL, _REVERSAL)[None, :, :]


def _t_valid_chunk(
    pars: FloatArray,
    covs: FloatArray,
    t_obs: FloatArray,
    thr: FloatArray,
    us: Sequence[float],
    star: int,
    oscillating: bool,
) -> FloatArray:
    def fn(tau: FloatArray) -> FloatArray:
        vals = [_anchor_sigma_batch(pars, covs, tau, u, star) for u in us]
        return np.max(vals, axis=0)

    tau_end = t_obs / 2.0
    grid = tau_end[:, None] + _OFFSETS[None, :]
    vals = fn(grid)
    if oscillating:
        grid, vals = _resolve_oscillation(fn, grid, vals, thr, pars[:, 6])
        vals = _with_peaks(grid, vals)
    ok = vals <= thr[:, None]
    has = ok.any(axis=1)
    first = np.argmax(ok, axis=1)
    cols = np.arange(grid.shape[1])[None, :]
    rest = (~ok) & (cols >= first[:, None])
    closes = rest.any(axis=1)
    close = np.argmax(rest, axis=1)
    rows = np.arange(grid.shape[0])
    a = grid[rows, np.maximum(close - 1, 0)]
    # an interpolated peak at ``close`` may lie up to one step beyond it
    b = grid[rows, np.minimum(close + 1, grid.shape[1] - 1) if oscillating else close]
    for _ in range(3):  # three 64-fold subdivisions: 6 % grid step → 2e-7 relative
        g = a[:, None] + (b - a)[:, None] * _REFINE[None, :]
        above = fn(g) > thr[:, None]
        j = np.argmax(above, axis=1)
        j = np.where(above.any(axis=1), j, _REFINE.size - 1)
        j = np.maximum(j, 1)
        a, b = g[rows, j - 1], g[rows, j]
    tau_close = np.where(closes, 0.5 * (a + b), grid[:, -1])
    res: FloatArray = np.where(has, np.maximum(tau_close - tau_end, 0.0), 0.0)
    return res


def _with_peaks(grid: FloatArray, vals: FloatArray) -> FloatArray:
    """Replace sampled local maxima by their parabolic peak value (sampling-independent peaks).

    At P_aps/24 sampling a sinusoid's maximum can be under-sampled by up to 1 %; a peak that
    touches the threshold between samples still closes the window.
    """
    x0, x1, x2 = grid[:, :-2], grid[:, 1:-1], grid[:, 2:]
    v0, v1, v2 = vals[:, :-2], vals[:, 1:-1], vals[:, 2:]
    with np.errstate(divide="ignore", invalid="ignore"):
        d1 = (v1 - v0) / (x1 - x0)
        d2 = (v2 - v1) / (x2 - x1)
        a = (d2 - d1) / (x2 - x0)
        b = (d1 * (x2 - x1) + d2 * (x1 - x0)) / (x2 - x0)
        peak = np.where((v1 >= v0) & (v1 >= v2) & (a < 0), v1 - b * b / (4 * a), v1)
    out = vals.copy()
    out[:, 1:-1] = np.maximum(v1, np.nan_to_num(peak, nan=0.0, posinf=0.0, neginf=0.0))
    return out


def _resolve_oscillation(
    fn: Callable[[FloatArray], FloatArray],
    grid: FloatArray,
    vals: FloatArray,
    thr: FloatArray,
    wdot: FloatArray,
) -> tuple[FloatArray, FloatArray]:
    """Add a P_aps/24 grid wherever the coarse σ_u is within 30 % of the threshold."""
    ok = vals <= thr[:, None]
    near = np.abs(vals - thr[:, None]) < 0.3 * thr[:, None]
    first = np.where(near.any(axis=1), np.argmax(near, axis=1), 0)
    cols = np.arange(grid.shape[1])[None, :]
    beyond = (~ok) & (cols >= first[:, None])
    last = np.where(beyond.any(axis=1), np.argmax(beyond, axis=1), grid.shape[1] - 1)
    rows = np.arange(grid.shape[0])
    lo = grid[rows, np.maximum(first - 1, 0)]
    hi = grid[rows, np.minimum(last + 1, grid.shape[1] - 1)]
    period = 2 * math.pi / np.abs(wdot)
    n_fine = int(np.clip(np.max(np.ceil((hi - lo) / (period / 24.0))), 2, 20_000))
    fine = lo[:, None] + (hi - lo)[:, None] * np.linspace(0.0, 1.0, n_fine + 1)[None, :]
    merged = np.sort(np.concatenate([grid, fine], axis=1), axis=1)
    return merged, fn(merged)


def t_valid(
    target: SourceLike,
    tol_rad: float,
    anchor_u_star: Sequence[float] | float,
    alpha: float = 1.0,
    star: int = 1,
    direction: int = AFTER,
) -> float:
    """Horizon T_valid [s after the end of the LISA observation] for one tolerance.

    Parameters
    ----------
    target : EphemerisSource or (PhaseParams, covariance, t_obs_s)
        Parameters referenced to the observation midpoint.
    tol_rad : float
        δu_tol [rad].
    anchor_u_star : float or sequence of float
        u★ of the anchor; with several (quadrature: 0, π) the larger σ_u is used (conservative).
    alpha : float
        Planning margin α (Eq. T_valid_alpha).
    star : {1, 2}
        Component.
    direction : {AFTER, BEFORE}
        After the end of the information (default) or, mirrored, before its start.

    Returns
    -------
    float
        Closing time of the first admissible window σ_u ≤ α δu_tol open at or after the end of
        the LISA observation, measured from that end [s]; 0 if there is none. With
        ``direction=BEFORE`` the same before the start (a positive duration). For a timing
        ephemeris both ends are T0.

    Notes
    -----
    Eq. T_valid_alpha and the text around Table 4. When ω̇ ≠ 0, σ_u oscillates on the apsidal
    period; the grid is refined to P_aps/24 around the threshold so the first closing is found.
    """
    p, cov, t_obs = _unpack(target)
    us = [float(anchor_u_star)] if np.isscalar(anchor_u_star) else list(anchor_u_star)  # type: ignore[arg-type]
    res = t_valid_batch(
        p.as_array()[None], cov[None], np.array([t_obs]), alpha * tol_rad, us, star, direction
    )
    return float(res[0])


def two_sided(target: SourceLike) -> bool:
    """Whether horizons are reported both before and after the reference (timing ephemerides).

    A target with ``kind == "timing"`` is; a LISA posterior (or a bare parameter tuple) is not.
    """
    return not isinstance(target, tuple) and getattr(target, "kind", "lisa") == "timing"


def valid_window_s(
    target: SourceLike,
    tol_rad: float,
    anchor_u_star: Sequence[float] | float,
    alpha: float = 1.0,
    star: int = 1,
) -> tuple[float, float]:
    """(first, last) τ [s from t_ref] where the ephemeris meets the tolerance α·δu_tol.

    A LISA posterior: from the start of the observation (−T_obs/2) to T_valid after its end. A
    timing ephemeris: T_valid before T0 to T_valid after it. For planners and reductions that
    must accept epochs on both sides of a timing ephemeris' reference.
    """
    _, _, t_obs = _unpack(target)
    after = t_obs / 2.0 + t_valid(target, tol_rad, anchor_u_star, alpha, star)
    if not two_sided(target):
        return -t_obs / 2.0, after
    before = t_valid(target, tol_rad, anchor_u_star, alpha, star, BEFORE)
    return -t_obs / 2.0 - before, after


def _unpack(
    target: SourceLike,
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
    t_valid_before_days: float | None = None
    dt_u_before_s: float | None = None

    @property
    def two_sided(self) -> bool:
        """Whether the row has a horizon before the reference too (timing ephemerides)."""
        return self.t_valid_before_days is not None

    def as_dict(self) -> dict[str, float | str | int]:
        """JSON-ready mapping (snake_case, units in the key names).

        A two-sided (timing) row adds ``t_valid_before_days`` and ``dt_u_before_s``; there
        ``t_valid_days``/``dt_u_s`` are after T0 and ``sigma_u_end_rad`` is σ_u at T0.
        """
        out: dict[str, float | str | int] = {
            "anchor": self.anchor,
            "alpha": self.alpha,
            "tolerance_rad": self.tolerance_rad,
            "delta_u_tol_rad": self.delta_u_tol_rad,
            "t_valid_days": self.t_valid_days,
            "dt_u_s": self.dt_u_s,
            "sigma_u_end_rad": self.sigma_u_end_rad,
            "n_epochs": self.n_epochs,
        }
        if self.t_valid_before_days is not None and self.dt_u_before_s is not None:
            out["t_valid_before_days"] = self.t_valid_before_days
            out["dt_u_before_s"] = self.dt_u_before_s
        return out


def horizon_table(
    target: SourceLike,
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
    observation is reported per anchor. For a timing ephemeris (:func:`two_sided`) each row also
    holds the horizon before T0 and δt_u there.
    """
    p, cov, t_obs = _unpack(target)
    both = two_sided(target)
    rows: list[HorizonRow] = []
    for anchor in anchors:
        label, us = _anchor_u_values(anchor)
        tol = tolerance(_anchor_kind(label, us), sigma_v, k_eff, n_epochs, us[0])
        sig_end = _max_anchor_sigma(p, cov, t_obs / 2.0, us, star)
        for alpha in alphas:
            tv = t_valid((p, cov, t_obs), tol, us, alpha, star)
            before: dict[str, float] = {}
            if both:
                tb = t_valid((p, cov, t_obs), tol, us, alpha, star, BEFORE)
                before = {
                    "t_valid_before_days": tb / DAY_S,
                    "dt_u_before_s": _timing_error(p, cov, -t_obs / 2.0 - tb, us, star),
                }
            rows.append(
                HorizonRow(
                    anchor=label,
                    alpha=float(alpha),
                    delta_u_tol_rad=tol,
                    tolerance_rad=alpha * tol,
                    t_valid_days=tv / DAY_S,
                    dt_u_s=_timing_error(p, cov, t_obs / 2.0 + tv, us, star),
                    sigma_u_end_rad=sig_end,
                    n_epochs=n_epochs,
                    **before,
                )
            )
    return rows


def horizon_s(
    target: SourceLike,
    sigma_v: float,
    k_eff: float,
    anchor: str | float = "quadrature",
    alpha: float = 1.0,
    n_epochs: int = 2,
    star: int = 1,
) -> float:
    """T_valid for one anchor and margin α [s after the end of the LISA observation].

    The tolerance is :func:`tolerance` of the anchor's kind for σ_v and K (same units);
    see :func:`t_valid` for the horizon itself and :func:`horizon_table` for all rows at once.
    """
    label, us = _anchor_u_values(anchor)
    tol = tolerance(_anchor_kind(label, us), sigma_v, k_eff, n_epochs, us[0])
    return t_valid(target, tol, us, alpha, star)


def sigma_u_end(target: SourceLike, anchor: str | float = "quadrature", star: int = 1) -> float:
    """σ_u at the end of the LISA observation for an anchor (the larger over its u★) [rad].

    Parameters
    ----------
    target : EphemerisSource or (PhaseParams, covariance, t_obs_s)
        Parameters referenced to the observation midpoint.
    anchor : str or float
        ``quadrature``, ``conjunction``, ``zero-crossing`` or a numeric u★ [rad].
    star : {1, 2}
        Component.
    """
    p, cov, t_obs = _unpack(target)
    _, us = _anchor_u_values(anchor)
    return _max_anchor_sigma(p, cov, t_obs / 2.0, us, star)


def _max_anchor_sigma(
    p: PhaseParams, cov: FloatArray, tau_s: float, us: Sequence[float], star: int
) -> float:
    """Largest :func:`anchor_sigma_u` over the anchor's u★ values at one epoch [rad]."""
    tau = np.array([tau_s])
    return max(float(anchor_sigma_u(p, cov, tau, u, star)[0]) for u in us)


def _timing_error(
    p: PhaseParams, cov: FloatArray, tau_s: float, us: Sequence[float], star: int
) -> float:
    """δt_u = σ_u/Φ̇_asc at ``tau_s`` (Eq. timing_unc), σ_u the larger over the anchor's u★ [s]."""
    rate = math.pi * (p.f_gw + p.fdot * tau_s + p.fddot * tau_s**2 / 2)
    return _max_anchor_sigma(p, cov, tau_s, us, star) / abs(rate)
