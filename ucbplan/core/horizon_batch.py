"""Horizon tables of many targets at once: the columns of Tables 4 and 7, vectorised over targets.

:func:`horizon_columns` is what :func:`ucbplan.core.forecast.horizon_table` computes for one
target (tolerance, σ_u at the end of the information, T_valid and δt_u per anchor × α, and for a
timing ephemeris the same before T0), for arrays of parameters and covariances in one pass: the
per-target cost is a few array operations (:mod:`ucbplan.core.horizon_poly`), not a Python loop.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ucbplan.core.constants import DAY_S
from ucbplan.core.forecast import (
    AFTER,
    BEFORE,
    anchor_kind,
    anchor_u_values,
    t_valid_batch,
    tolerance,
)
from ucbplan.core.horizon_grid import anchor_sigma_batch

__all__ = ["horizon_columns"]

FloatArray = NDArray[np.float64]


def _max_sigma(
    pars: FloatArray, covs: FloatArray, tau: FloatArray, us: Sequence[float], star: int
) -> FloatArray:
    """Largest anchor σ_u over the anchor's u★ at one epoch per target [rad], shape (n,)."""
    vals = [anchor_sigma_batch(pars, covs, tau[:, None], u, star)[:, 0] for u in us]
    out: FloatArray = np.max(vals, axis=0)
    return out


def _timing_error(
    pars: FloatArray, covs: FloatArray, tau: FloatArray, us: Sequence[float], star: int
) -> FloatArray:
    """δt_u = σ_u/Φ̇_asc at τ per target (Eq. timing_unc) [s]."""
    rate = math.pi * (pars[:, 1] + pars[:, 2] * tau + pars[:, 3] * tau**2 / 2)
    out: FloatArray = _max_sigma(pars, covs, tau, us, star) / np.abs(rate)
    return out


def horizon_columns(
    pars: ArrayLike,
    covs: ArrayLike,
    t_obs_s: ArrayLike,
    sigma_v: ArrayLike,
    k_eff: ArrayLike,
    alphas: Sequence[float] = (0.5, 1.0),
    anchors: Sequence[str | float] = ("conjunction", "quadrature"),
    n_epochs: int = 2,
    star: int = 1,
    two_sided: ArrayLike = False,
) -> dict[str, FloatArray]:
    """Horizon columns for n targets, keyed ``"{field}:{anchor}:{alpha:g}"`` [units in field].

    Parameters
    ----------
    pars : (n, 7) parameters at the reference (midpoint); covs : (n, 7, 7);
    t_obs_s : (n,) information span T_obs [s] (0 for a timing ephemeris);
    sigma_v, k_eff : (n,) or float, RV precision and semi-amplitude [km/s];
    two_sided : (n,) bool, horizons before the reference too (timing ephemerides).

    Returns
    -------
    dict
        Per anchor: ``delta_u_tol_rad``, ``sigma_u_end_rad``; per anchor × α: ``t_valid_days``,
        ``dt_u_s``, and ``t_valid_before_days``/``dt_u_before_s`` (NaN for one-sided rows).
        Keys are ``field:anchor`` or ``field:anchor:alpha``.
    """
    p = np.atleast_2d(np.asarray(pars, dtype=np.float64))
    c = np.asarray(covs, dtype=np.float64).reshape(-1, 7, 7)
    n = p.shape[0]
    t_obs = np.broadcast_to(np.asarray(t_obs_s, dtype=np.float64), (n,))
    pair = np.column_stack(
        [np.broadcast_to(np.asarray(v, dtype=np.float64), (n,)) for v in (sigma_v, k_eff)]
    )
    pairs, which = np.unique(pair, axis=0, return_inverse=True)
    both = np.broadcast_to(np.asarray(two_sided, dtype=bool), (n,))
    back = np.nonzero(both)[0]
    out: dict[str, FloatArray] = {}
    for anchor in anchors:
        label, us = anchor_u_values(anchor)
        kind = anchor_kind(label, us)
        tol = np.array([tolerance(kind, sv, kk, n_epochs, us[0]) for sv, kk in pairs])
        tol = tol[which.reshape(-1)]
        out[f"delta_u_tol_rad:{label}"] = tol
        out[f"sigma_u_end_rad:{label}"] = _max_sigma(p, c, t_obs / 2.0, us, star)
        for alpha in alphas:
            key = f"{label}:{alpha:g}"
            tv = t_valid_batch(p, c, t_obs, alpha * tol, us, star, AFTER)
            out[f"t_valid_days:{key}"] = tv / DAY_S
            out[f"dt_u_s:{key}"] = _timing_error(p, c, t_obs / 2.0 + tv, us, star)
            tb = np.full(n, np.nan)
            dtb = np.full(n, np.nan)
            if back.size:
                pb, cb, ob = p[back], c[back], t_obs[back]
                tb[back] = t_valid_batch(pb, cb, ob, alpha * tol[back], us, star, BEFORE)
                dtb[back] = _timing_error(pb, cb, -ob / 2.0 - tb[back], us, star)
            out[f"t_valid_before_days:{key}"] = tb / DAY_S
            out[f"dt_u_before_s:{key}"] = dtb
    return out
