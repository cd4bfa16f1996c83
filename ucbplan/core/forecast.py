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
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ucbplan.core.constants import DAY_S
from ucbplan.core.ephemeris import ANCHORS, resolve_anchor
from ucbplan.core.params import EphemerisSource, PhaseParams
from ucbplan.core.phase import sigma_u_from_jacobian, u_jacobian
from ucbplan.core.validity_apsidal import t_valid_apsidal
from ucbplan.core.validity_grid import HORIZON_CAP_S, anchor_sigma_batch, oscillating, t_valid_grid
from ucbplan.core.validity_poly import t_valid_poly
from ucbplan.errors import UcbplanError

FloatArray = NDArray[np.float64]
#: A target, or its (parameters, covariance, T_obs [s]) directly.
SourceLike = EphemerisSource | tuple[PhaseParams, FloatArray, float]
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
    out = anchor_sigma_batch(p.as_array()[None, :], np.asarray(cov)[None], tau[None], u_star, star)
    return out[0]


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
        raise UcbplanError(f"epochs must be 1 or 2, got {n_epochs}")
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


def anchor_kind(label: str, u_values: Sequence[float]) -> str:
    """Tolerance kind of an anchor (:func:`tolerance`) from its label and u★ values."""
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


def anchor_u_values(anchor: str | float) -> tuple[str, list[float]]:
    """An anchor's label and its u★ values [rad] (zero-crossing: both crossings)."""
    label, targets = resolve_anchor(anchor)
    if label == "zero-crossing":
        return label, list(ANCHORS["zero-crossing"])
    return label, [float(t) for t in targets]


def t_valid_batch(
    pars: FloatArray,
    covs: FloatArray,
    t_obs_s: FloatArray,
    thr_rad: FloatArray | float,
    anchor_u_star: Sequence[float],
    star: int = 1,
    direction: int = AFTER,
    method: str = "analytic",
) -> FloatArray:
    """Vectorised horizons: closing τ − T/2 of the first window σ_u ≤ thr [s] (0 if none).

    Parameters
    ----------
    pars : (n, 7) parameters at the midpoint; covs : (n, 7, 7); t_obs_s : (n,);
    thr_rad : (n,) thresholds α·δu_tol; anchor_u_star : the anchor's u★ values (max σ_u used);
    direction : :data:`AFTER` (after the end of the observation, the default) or
    :data:`BEFORE` (before its start: the result is then −T/2 − τ of the closing, also ≥ 0);
    method : ``"analytic"`` (default) finds the window from the roots of the polynomial σ_u²(τ)
    (:mod:`ucbplan.core.validity_poly`) wherever σ_u does not oscillate, and for apsidally
    oscillating rows from an envelope bracket and a curvature-certified scan
    (:mod:`ucbplan.core.validity_apsidal`; a row it cannot settle within its sample budget goes
    to the grid); ``"grid"`` samples every row (:mod:`ucbplan.core.validity_grid`).

    A row whose σ_u never exceeds the threshold (e.g. a zero covariance) gets the search cap
    :data:`HORIZON_CAP_S`; one that never meets it gets 0.
    """
    pars = np.atleast_2d(np.asarray(pars, dtype=np.float64))
    covs = np.asarray(covs, dtype=np.float64).reshape(-1, 7, 7)
    if direction == BEFORE:
        pars, covs = time_reversed(pars, covs)
    elif direction != AFTER:
        raise UcbplanError(f"direction must be +1 (after) or -1 (before), got {direction!r}")
    t_obs = np.broadcast_to(np.asarray(t_obs_s, dtype=np.float64), (pars.shape[0],))
    thr = np.broadcast_to(np.asarray(thr_rad, dtype=np.float64), (pars.shape[0],))
    out = np.zeros(pars.shape[0])
    osc = oscillating(pars, covs)
    if method not in ("analytic", "grid"):
        raise UcbplanError(f"method must be 'analytic' or 'grid', got {method!r}")
    sampled = [(osc, 32)]  # small chunks: fine grids differ per row
    if method == "grid":
        sampled.append((~osc, 256))
    else:
        sampled = [(_analytic(pars, covs, t_obs, thr, anchor_u_star, star, osc, out), 32)]
    for mask, size in sampled:
        idx = np.nonzero(mask)[0]
        for start in range(0, idx.size, size):
            sel = idx[start : start + size]
            out[sel] = t_valid_grid(
                pars[sel], covs[sel], t_obs[sel], thr[sel], anchor_u_star, star, bool(osc[sel[0]])
            )
    return out


def _analytic(
    pars: FloatArray,
    covs: FloatArray,
    t_obs: FloatArray,
    thr: FloatArray,
    us: Sequence[float],
    star: int,
    osc: NDArray[np.bool_],
    out: FloatArray,
) -> NDArray[np.bool_]:
    """Fill ``out`` by the σ_u² roots (rows with ``osc`` False) and the apsidal envelope search
    (``osc`` True); return the rows left for the grid search."""
    left = np.zeros(pars.shape[0], dtype=bool)
    flat, prec = np.nonzero(~osc)[0], np.nonzero(osc)[0]
    if flat.size:
        out[flat] = t_valid_poly(
            pars[flat], covs[flat], t_obs[flat], thr[flat], us, star, HORIZON_CAP_S
        )
    if prec.size:
        out[prec], unresolved = t_valid_apsidal(
            pars[prec], covs[prec], t_obs[prec], thr[prec], us, star, HORIZON_CAP_S
        )
        left[prec[unresolved]] = True
    return left


def time_reversed(pars: FloatArray, covs: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Parameters and covariances whose σ_u at +τ is the original's at −τ (exactly)."""
    rev = pars.copy()
    rev[:, 6] = -rev[:, 6]
    return rev, covs * np.outer(_REVERSAL, _REVERSAL)[None, :, :]


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
    period; the first closing is found inside an envelope bracket by a scan whose sample gaps are
    cleared by a curvature bound (:mod:`ucbplan.core.validity_apsidal`).
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
        label, us = anchor_u_values(anchor)
        tol = tolerance(anchor_kind(label, us), sigma_v, k_eff, n_epochs, us[0])
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
    label, us = anchor_u_values(anchor)
    tol = tolerance(anchor_kind(label, us), sigma_v, k_eff, n_epochs, us[0])
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
    _, us = anchor_u_values(anchor)
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
