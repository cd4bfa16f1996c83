"""Fixed-u groups: spectra of one session at one targeted u★, averaged (paper Sec. 3.1.4).

Each spectrum gets an anchor u★ (the table's ``u_star`` column, else the nearest standard anchor
within :data:`MATCH_TOL_RAD`). A group's velocities are moved to the exact u★ with the fitted
semi-amplitude (v − s K Λ_K (cos u − cos u★), a first-order phase-mismatch correction of at most
K|Δu sin u★|) and averaged with inverse-variance weights; :mod:`ucbplan.reduce.drifts` pairs the
groups across sessions.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

F64 = NDArray[np.float64]

#: Standard anchors (star-1 argument of latitude, rad) used when the table has no u_star column.
ANCHOR_U: tuple[float, ...] = (0.0, 0.5 * math.pi, math.pi, 1.5 * math.pi)
#: A spectrum belongs to the nearest anchor if within this phase distance [rad] (P_b/16).
MATCH_TOL_RAD = math.pi / 8.0
#: The spacing of ANCHOR_U [rad] (they are k·π/2, k = 0 … 3).
_ANCHOR_STEP = 0.5 * math.pi


def _wrap(x: ArrayLike) -> F64:
    return np.asarray((np.asarray(x, float) + math.pi) % (2.0 * math.pi) - math.pi, dtype=float)


def assign_anchors(u_rad: ArrayLike, u_star: ArrayLike | None = None) -> F64:
    """u★ of each spectrum: the given column, else the nearest standard anchor within tolerance.

    Returns
    -------
    ndarray
        u★ in [0, 2π) [rad], NaN for spectra that match no anchor (not used in differences).
    """
    u = np.asarray(u_rad, float) % (2.0 * math.pi)
    if u_star is not None:
        us = np.asarray(u_star, float)
        return np.asarray(np.where(np.isfinite(us), us % (2.0 * math.pi), np.nan), dtype=float)
    anchors = np.asarray(ANCHOR_U)
    # only the nearest anchor can lie within MATCH_TOL_RAD (< π/4, half the anchors' spacing):
    # its distance alone, the same double as in a spectrum-by-anchor table of them
    near = np.rint(u / _ANCHOR_STEP)
    k = np.where(np.isfinite(near), near, 0.0).astype(np.intp) % anchors.size
    ok = np.abs(_wrap(u - anchors[k])) <= MATCH_TOL_RAD
    return np.asarray(np.where(ok, anchors[k], np.nan), dtype=float)


@dataclass(frozen=True, slots=True)
class Group:
    """Inverse-variance mean of the spectra of one session at one u★.

    ``v``/``sigma`` have one entry per component (1 for SB1, 2 for SB2) [km/s]; ``tau_s`` is the
    mean mid-exposure time [s since t_ref]; ``lam_k``/``lam_kappa`` the mean window factors.
    """

    session: str
    u_star: float
    tau_s: float
    n: int
    v: tuple[float, ...]
    sigma: tuple[float, ...]
    gamma_est: tuple[float, ...]
    gamma_sigma: tuple[float, ...]
    lam_k: float
    lam_kappa: float


def group_spectra(
    *,
    sessions: Sequence[str],
    tau_s: ArrayLike,
    u_rad: ArrayLike,
    u_star: ArrayLike,
    velocities: Sequence[ArrayLike],
    sigmas: Sequence[ArrayLike],
    K: Sequence[float],
    design: ArrayLike,
    lam_k: ArrayLike,
    lam_kappa: ArrayLike,
    cos_u: ArrayLike | None = None,
) -> list[Group]:
    """Group spectra by (session, u★) and average them after the mismatch correction.

    Parameters
    ----------
    sessions : sequence of str
        Session label of each spectrum.
    tau_s, u_rad, u_star : array_like
        Mid-exposure time [s since t_ref], star-1 argument of latitude and assigned u★ [rad]
        (NaN: unassigned).
    velocities, sigmas, K : sequence
        Per component (v1[, v2]): velocities and errors per spectrum, fitted semi-amplitude [km/s].
    design, lam_k, lam_kappa : array_like
        Window-averaged orbital factor G (for the zero-crossing γ estimates) and the window
        factors Λ_K, Λ_κ per spectrum [1].
    cos_u : array_like, optional
        cos u per spectrum, when the caller has it (the same doubles as computed here).

    Returns
    -------
    list of Group
        Sorted by time.
    """
    tau = np.asarray(tau_s, float)
    u = np.asarray(u_rad, float)
    us = np.asarray(u_star, float)
    lk = np.broadcast_to(np.asarray(lam_k, float), tau.shape)
    lkap = np.broadcast_to(np.asarray(lam_kappa, float), tau.shape)
    G = np.asarray(design, float)
    k = _group_keys(sessions, us)
    rows = k.rows
    # the phase-mismatch term's cos u − cos u★ of every kept row, once for all components
    cos_rows = np.cos(u[rows]) if cos_u is None else np.asarray(cos_u, float)[rows]
    mismatch = cos_rows - np.cos(k.u_star)
    at = (lk[rows], mismatch, G[rows], k.gid)
    comps = [
        _component_means(np.asarray(v, float)[rows], np.asarray(sg, float)[rows], sK, *at)
        for v, sg, sK in zip(velocities, sigmas, _signed(K), strict=True)
    ]
    means = [_group_mean(x[rows], k.gid, k.counts) for x in (tau, lk, lkap)]
    groups = _build_groups(k.labels, k.u_star[k.starts], k.counts, comps, means)
    groups.sort(key=lambda g: g.tau_s)
    return groups


@dataclass(frozen=True)
class _Keys:
    """The assigned spectra sorted by (session, u★): their rows in the table, each row's u★ and
    group id, and per group its session label, first sorted position and count."""

    rows: NDArray[np.intp]
    u_star: F64
    gid: NDArray[np.intp]
    labels: NDArray[np.str_]
    starts: NDArray[np.intp]
    counts: NDArray[np.intp]


def _group_keys(sessions: Sequence[str], us: F64) -> _Keys:
    """Sort the spectra with a u★ (finite ``us``) by (session, u★) and number the groups."""
    keep = np.nonzero(np.isfinite(us))[0]
    names, code = _session_codes(sessions)
    order = np.lexsort((us[keep], code[keep]))
    rows = keep[order]
    key_s, key_u = code[rows], us[rows]
    new = np.ones(rows.size, dtype=bool)
    new[1:] = (key_s[1:] != key_s[:-1]) | (key_u[1:] != key_u[:-1])
    starts = np.nonzero(new)[0]
    counts = np.diff(np.append(starts, rows.size))
    gid = np.cumsum(new) - 1
    return _Keys(rows, key_u, gid, names[key_s[starts]], starts, counts)


def _session_codes(sessions: Sequence[str]) -> tuple[NDArray[np.str_], NDArray[np.intp]]:
    """The distinct session labels as :func:`numpy.unique` sorts them, and each spectrum's
    index into them: ``np.unique(labels, return_inverse=True)`` of all spectra, found among the
    distinct labels alone (a dictionary of the label objects, not 10⁶ strings sorted)."""
    first = {label: k for k, label in enumerate(dict.fromkeys(sessions))}
    names, inverse = np.unique(np.asarray([str(label) for label in first]), return_inverse=True)
    number = np.fromiter(map(first.__getitem__, sessions), dtype=np.intp, count=len(sessions))
    return names, inverse.reshape(-1)[number]


def _build_groups(
    labels: NDArray[np.str_],
    u_star: F64,
    counts: NDArray[np.intp],
    comps: list[tuple[F64, F64, F64]],
    means: list[F64],
) -> list[Group]:
    """One Group per group: label, u★, count, the components' (mean, σ, γ estimate) and the
    (τ, Λ_K, Λ_κ) means, through Python lists (one conversion per array, not per element)."""
    tau, lk, lkap = (m.tolist() for m in means)
    v, sigma, gamma = (list(zip(*(c[m].tolist() for c in comps), strict=True)) for m in range(3))
    heads = zip(labels.tolist(), u_star.tolist(), counts.tolist(), strict=True)
    return [
        Group(
            session=str(label),
            u_star=u,
            tau_s=tau[g],
            n=n,
            v=v[g],
            sigma=sigma[g],
            gamma_est=gamma[g],
            gamma_sigma=sigma[g],
            lam_k=lk[g],
            lam_kappa=lkap[g],
        )
        for g, (label, u, n) in enumerate(heads)
    ]


def _signed(K: Sequence[float]) -> list[float]:
    """±K_j: star 1 moves with +K_1 G, star 2 with −K_2 G."""
    return [(1.0 if j == 0 else -1.0) * k for j, k in enumerate(K)]


def _group_mean(x: F64, gid: NDArray[np.intp], counts: NDArray[np.intp]) -> F64:
    """Mean of ``x`` per group (rows sorted by group id)."""
    out: F64 = np.bincount(gid, weights=x, minlength=counts.size) / counts
    return out


def _component_means(
    v: F64,
    sigma: F64,
    sK: float,
    lam_k: F64,
    mismatch: F64,
    G: F64,
    gid: NDArray[np.intp],
) -> tuple[F64, F64, F64]:
    """One component of every group: (fixed-u mean, its σ, zero-crossing γ estimate) per group.

    ``sK`` is ±K_j (the star's sign); the velocities are moved to the exact u★ first (by
    ``mismatch`` = cos u − cos u★) and the γ estimate removes the whole orbital term ±K_j G.
    ``gid`` numbers each row's group.
    """
    w = 1.0 / sigma**2
    vc = v - sK * lam_k * mismatch
    gam = v - sK * G
    wsum = np.bincount(gid, weights=w)
    return (
        np.bincount(gid, weights=w * vc) / wsum,
        1.0 / np.sqrt(wsum),
        np.bincount(gid, weights=w * gam) / wsum,
    )
