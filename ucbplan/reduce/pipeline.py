"""``ucbplan reduce``: velocities + target → K_j, γ_j, masses, Δκ and Δv_CM (paper Secs. 3–5).

Data flow: :mod:`~ucbplan.reduce.velocities` (read, validate) → this module's :func:`reduce`
(ephemeris evaluation per spectrum, regressions, Monte Carlo) using
:mod:`~ucbplan.reduce.regression`, :mod:`~ucbplan.reduce.masses`, :mod:`~ucbplan.reduce.drifts`
→ :mod:`~ucbplan.reduce.report` (dict, JSON/YAML, terminal) and :mod:`~ucbplan.reduce.plots`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ucbplan.core.constants import C_KM_S
from ucbplan.core.params import PARAM_NAMES, PhaseParams
from ucbplan.core.smearing import lambda_k, lambda_kappa
from ucbplan.reduce import drifts as _drifts
from ucbplan.reduce import masses as _masses
from ucbplan.reduce.regression import (
    ComponentFit,
    WilsonFit,
    binned_design,
    fit_component,
    lambda_k_to_x,
    phase_sensitivity,
    wilson_fit,
)
from ucbplan.reduce.velocities import VelocityTable, check_validity, read_velocities

if TYPE_CHECKING:
    from ucbplan.target import Target

__all__ = [
    "ReduceOptions",
    "Reduction",
    "design_jacobian",
    "read_samples",
    "read_velocities",
    "reduce",
    "window_factors",
]

F64 = NDArray[np.float64]
EXTRA_NAMES = ("cos_inclination", "amplitude")


@dataclass(frozen=True, slots=True)
class ReduceOptions:
    """Options of :func:`reduce`.

    Attributes
    ----------
    n_samples : int
        Monte-Carlo samples for masses (drawn from the samples file or the Gaussian posterior).
    seed : int or None
        Seed of the ``numpy.random.Generator`` (None: fresh entropy, reported).
    light_time : bool
        Correct each velocity for the light travel time across the binary orbit (beyond the paper).
    mass_radius : str or None
        WD mass–radius relation for the redshift comparison (``eggleton``, ``nauenberg``).
    cos_i_sigma : float
        1σ spread of cos ι when neither the covariance nor the samples carry it (default 0: fixed).
    """

    n_samples: int = 20_000
    seed: int | None = None
    light_time: bool = False
    mass_radius: str | None = None
    cos_i_sigma: float = 0.0


@dataclass(frozen=True)
class Reduction:
    """Everything :func:`reduce` found; :mod:`~ucbplan.reduce.report` formats it."""

    target: Target
    table: VelocityTable
    options: ReduceOptions
    seed: int
    tau_s: F64
    u_rad: F64
    F: F64
    design: tuple[F64, ...]
    lam_k: F64
    lam_kappa: F64
    fits: tuple[ComponentFit, ...]
    dK: F64
    dgamma: F64
    sigma_K_phase: tuple[float, ...]
    sigma_gamma_phase: tuple[float, ...]
    sigma_u: F64
    attenuation: tuple[float, ...]
    wilson: WilsonFit | None
    light_time: dict[str, float]
    samples: dict[str, F64]
    summaries: dict[str, _masses.Summary]
    groups: tuple[_drifts.Group, ...]
    drift: _drifts.DriftResult
    warnings: tuple[str, ...] = field(default_factory=tuple)

    @property
    def eccentric(self) -> bool:
        """Whether the target has e > 0 or ω̇ ≠ 0."""
        return self.target.params.is_eccentric


def window_factors(table: VelocityTable, f_hz: float) -> tuple[F64, F64]:
    """Λ_K and Λ_κ per spectrum from the window widths (or the given Λ_K).

    Notes
    -----
    Eqs. Lambda_K, Lambda_kappa with n̄_b = π f. Where only Λ_K is known, x = n̄_b Δt/2 is
    recovered by inverting sin x/x and Λ_κ = sin 2x/2x.
    """
    nbar = math.pi * f_hz
    w = table.window_s
    lk = np.where(np.isfinite(w), lambda_k(np.nan_to_num(w), nbar), table.lambda_k)
    x = np.zeros_like(lk)
    given = ~np.isfinite(w)
    if np.any(given):
        x[given] = lambda_k_to_x(table.lambda_k[given])
    lkap = np.where(given, np.sinc(2.0 * x / np.pi), lambda_kappa(np.nan_to_num(w), nbar))
    return np.asarray(lk, float), np.asarray(lkap, float)


def _orbit(p: PhaseParams, tau: F64) -> tuple[F64, F64, F64, F64]:
    from ucbplan.core import ephemeris

    phi = np.asarray(ephemeris.phase_asc(p, tau), float)
    eta, kap = ephemeris.ll_pair(p, tau)
    u = np.asarray(ephemeris.arg_latitude(p, tau, star=1), float)
    return phi, np.asarray(eta, float), np.asarray(kap, float), u


def design_jacobian(p: PhaseParams, tau: F64, lam_k: F64, lam_kap: F64) -> F64:
    """∂G_i/∂θ for θ in PARAM_NAMES order, shape (n, 7) (analytic, Eq. vbar_master).

    Notes
    -----
    Φ = φ_ref/2 + π(fτ + ḟτ²/2 + f̈τ³/6); (η, κ)(τ) rotated at ω̇ (Eq. kappa_lisa_prediction).
    """
    phi, eta, kap, _ = _orbit(p, tau)
    dG_dphi = -lam_k * np.sin(phi) + 2.0 * lam_kap * (
        -kap * np.sin(2 * phi) + eta * np.cos(2 * phi)
    )
    dG_deta = lam_kap * np.sin(2 * phi)
    dG_dkap = lam_kap * np.cos(2 * phi)
    w = p.omega_dot * tau
    c, s = np.cos(w), np.sin(w)
    jac = np.empty((tau.size, 7))
    jac[:, 0] = 0.5 * dG_dphi
    jac[:, 1] = math.pi * tau * dG_dphi
    jac[:, 2] = math.pi * tau**2 / 2.0 * dG_dphi
    jac[:, 3] = math.pi * tau**3 / 6.0 * dG_dphi
    jac[:, 4] = dG_deta * c - dG_dkap * s  # ∂/∂η_ref
    jac[:, 5] = dG_deta * s + dG_dkap * c  # ∂/∂κ_ref
    jac[:, 6] = dG_deta * tau * kap - dG_dkap * tau * eta  # ∂/∂ω̇
    return jac


def _designs(
    p: PhaseParams, tau: F64, lam_k: F64, lam_kap: F64, ncomp: int, K: tuple[float, ...] | None
) -> tuple[F64, ...]:
    """Design G per component; with K given, evaluated at the emission time τ − ΔR_j."""
    out = []
    for j in range(ncomp):
        t = tau
        if K is not None:
            _, _, _, u = _orbit(p, tau)
            nb = math.pi * p.f_gw - p.omega_dot
            sign = 1.0 if j == 0 else -1.0
            t = tau - sign * K[j] / (C_KM_S * nb) * np.sin(u)
        phi, eta, kap, _ = _orbit(p, t)
        out.append(binned_design(phi, eta, kap, lam_k, lam_kap))
    return tuple(out)


def _fit_all(table: VelocityTable, designs: tuple[F64, ...]) -> tuple[ComponentFit, ...]:
    fits = []
    for j, (v, s) in enumerate(zip(table.v, table.sigma, strict=True)):
        fits.append(fit_component(designs[j], v, s, star=j + 1))
    return tuple(fits)


def _ext_cov(target: Target) -> tuple[F64, F64]:
    """Mean and covariance of (PARAM_NAMES…, cos ι, amplitude) from the target (9 entries)."""
    names = (*PARAM_NAMES, *EXTRA_NAMES)
    mean = np.array(
        [
            *target.params.as_array(),
            target.cos_inclination if target.cos_inclination is not None else 0.0,
            target.amplitude if target.amplitude is not None else 0.0,
        ]
    )
    cov = np.zeros((9, 9))
    idx = [names.index(n) for n in target.cov_names if n in names]
    sub = [i for i, n in enumerate(target.cov_names) if n in names]
    cov[np.ix_(idx, idx)] = np.asarray(target.cov_matrix)[np.ix_(sub, sub)]
    return mean, cov


def _posterior_samples(
    target: Target, n: int, rng: np.random.Generator, cos_i_sigma: float, warn: list[str]
) -> F64:
    """(n, 9) samples of (PARAM_NAMES…, cos ι, amplitude): samples file if any, else Gaussian."""
    mean, cov = _ext_cov(target)
    if "cos_inclination" not in target.cov_names and target.cos_inclination is not None:
        cov[7, 7] = cos_i_sigma**2
        if cos_i_sigma == 0.0:
            warn.append(
                "cos ι has no uncertainty in the target (covariance or samples): it is "
                "held fixed, so mass σ exclude the inclination; pass --cos-i-sigma or "
                "add cos_inclination to the covariance"
            )
    vals, vecs = np.linalg.eigh(cov)
    L = vecs * np.sqrt(np.clip(vals, 0.0, None))
    out = mean + rng.standard_normal((n, 9)) @ L.T
    if target.samples is not None:
        cols = read_samples(target.samples)
        size = len(next(iter(cols.values())))
        idx = rng.choice(size, size=n, replace=size < n)
        for k, name in enumerate((*PARAM_NAMES, *EXTRA_NAMES)):
            if name in cols:
                out[:, k] = cols[name][idx]
    out[:, 7] = np.clip(out[:, 7], -1.0, 1.0)
    return out


def read_samples(path: Path) -> dict[str, F64]:
    """Numeric columns of a posterior-samples ECSV (bare SI values, PARAM_NAMES column names).

    Fast path: the ECSV data block parsed with ``numpy.loadtxt`` (10⁵ rows in ~0.1 s); anything
    it cannot parse falls back to astropy's ECSV reader.

    Raises
    ------
    InputFileError
        Unreadable file or no rows.
    """
    from ucbplan.errors import InputFileError

    try:
        lines = path.read_text(encoding="utf-8").splitlines()
        delim = " "
        for ln in lines:
            if ln.startswith("# delimiter:"):
                delim = ln.split(":", 1)[1].strip().strip("'\"") or " "
        body = [ln for ln in lines if ln.strip() and not ln.startswith("#")]
        names = body[0].split(None if delim == " " else delim)
        data = np.loadtxt(body[1:], delimiter=None if delim == " " else delim, ndmin=2)
        cols = {nm.strip().strip('"'): data[:, k] for k, nm in enumerate(names)}
    except (OSError, ValueError, IndexError):
        from astropy.table import Table

        try:
            tab = Table.read(path, format="ascii.ecsv")
        except Exception as exc:
            raise InputFileError(f"{path}: cannot read posterior samples ({exc})") from exc
        cols = {
            nm: np.asarray(tab[nm], float)
            for nm in tab.colnames
            if np.issubdtype(np.asarray(tab[nm]).dtype, np.number)
        }
    if not cols or len(next(iter(cols.values()))) == 0:
        raise InputFileError(f"{path}: posterior samples file has no rows")
    return cols


def reduce(target: Target, table: VelocityTable, options: ReduceOptions | None = None) -> Reduction:
    """Reduce a velocity table against a target (the library behind ``ucbplan reduce``).

    Parameters
    ----------
    target : Target
        LISA ephemeris and posterior.
    table : VelocityTable
        Measured velocities (:func:`read_velocities`).
    options : ReduceOptions, optional
        Monte-Carlo size, seed, light-time correction, mass–radius relation.

    Returns
    -------
    Reduction

    Raises
    ------
    VelocityFileError
        Times outside the target's validity window.
    ValueError
        Fewer than two distinct phases.

    Notes
    -----
    Eqs. v1v2_ecc_rv, F_definition, vbar_master (regression); semimajor_axis_j, Kepler_mtot,
    M1M2_cir_and_ecc (masses); delta_kappa_spec_binned, intercept_Deltav_cm, rvzero_average,
    fdot_acc_spectroscopy (drifts).
    """
    opts = options or ReduceOptions()
    seed = opts.seed
    if seed is None:
        seed = int(np.random.SeedSequence().generate_state(1)[0])
    rng = np.random.default_rng(seed)
    warn: list[str] = []
    p = target.params
    tau = check_validity(table, target)
    lam_k, lam_kap = window_factors(table, p.f_gw)
    _, _, kap, u = _orbit(p, tau)
    F = np.cos(u) + kap
    plain = _designs(p, tau, lam_k, lam_kap, len(table.v), None)
    fits0 = _fit_all(table, plain)
    K0 = tuple(f.K for f in fits0)
    lt_designs = _designs(p, tau, lam_k, lam_kap, len(table.v), K0)
    lt_designs = _designs(
        p, tau, lam_k, lam_kap, len(table.v), tuple(f.K for f in _fit_all(table, lt_designs))
    )
    fits_lt = _fit_all(table, lt_designs)
    nb = math.pi * p.f_gw - p.omega_dot
    light = {
        "max_delay_s": max(abs(k) for k in K0) / (C_KM_S * nb),
        **{f"dK{j + 1}": fits_lt[j].K - fits0[j].K for j in range(len(K0))},
        **{f"dgamma{j + 1}": fits_lt[j].gamma - fits0[j].gamma for j in range(len(K0))},
        "applied": float(opts.light_time),
    }
    fits, designs = (fits_lt, lt_designs) if opts.light_time else (fits0, plain)
    cov7 = target.covariance
    jacG = design_jacobian(p, tau, lam_k, lam_kap)
    from ucbplan.core import ephemeris

    ju = np.asarray(ephemeris.u_jacobian(p, tau), float)
    sigma_u = np.sqrt(np.clip(np.einsum("ni,ij,nj->n", ju, cov7, ju), 0.0, None))
    dK, dg, sKp, sgp, att = [], [], [], [], []
    for j, f in enumerate(fits):
        sign = 1.0 if j == 0 else -1.0
        a, b = phase_sensitivity(designs[j], table.sigma[j], jacG, f.K, sign)
        dK.append(a)
        dg.append(b)
        sKp.append(math.sqrt(max(float(a @ cov7 @ a), 0.0)))
        sgp.append(math.sqrt(max(float(b @ cov7 @ b), 0.0)))
        w = 1.0 / table.sigma[j] ** 2
        att.append(float(f.K * (w * sigma_u**2).sum() / w.sum() / 2.0))
        n_out = int(f.line.outliers.sum())
        if n_out:
            rows = np.flatnonzero(f.line.outliers)[:5] + 1
            warn.append(
                f"star {j + 1}: {n_out} spectra deviate by > 4σ (rows {rows.tolist()}); "
                "they are kept — check them"
            )
        if f.line.dof > 0 and f.line.chi2 / f.line.dof > 2.0:
            warn.append(
                f"star {j + 1}: χ²/dof = {f.line.chi2 / f.line.dof:.2f}; errors were "
                "inflated by √(χ²/dof) — check σ_v or outliers"
            )
    if len(fits) == 1 and fits[0].K < 0:
        warn.append(
            "SB1: K < 0, i.e. the visible star moves like star 2 of the LISA convention "
            "(u_2 = u_1 + π); |K| is its semi-amplitude"
        )
    wil = None
    if len(fits) == 2:
        wil = wilson_fit(
            table.v[0], table.sigma[0], table.v[1], table.sigma[1], q0=fits[0].K / fits[1].K
        )
    samples, summaries = _monte_carlo(target, fits, np.array(dK), np.array(dg), opts, rng, warn)
    groups, drift = _inter_session(target, table, tau, u, designs, fits, lam_k, lam_kap)
    return Reduction(
        target=target,
        table=table,
        options=opts,
        seed=seed,
        tau_s=tau,
        u_rad=u,
        F=F,
        design=designs,
        lam_k=lam_k,
        lam_kappa=lam_kap,
        fits=fits,
        dK=np.array(dK),
        dgamma=np.array(dg),
        sigma_K_phase=tuple(sKp),
        sigma_gamma_phase=tuple(sgp),
        sigma_u=sigma_u,
        attenuation=tuple(att),
        wilson=wil,
        light_time=light,
        samples=samples,
        summaries=summaries,
        groups=tuple(groups),
        drift=drift,
        warnings=tuple(warn),
    )


def _monte_carlo(
    target: Target,
    fits: tuple[ComponentFit, ...],
    dK: F64,
    dg: F64,
    opts: ReduceOptions,
    rng: np.random.Generator,
    warn: list[str],
) -> tuple[dict[str, F64], dict[str, _masses.Summary]]:
    """Joint Monte Carlo over the LISA posterior and the (γ_j, K_j) regression covariance."""
    n = opts.n_samples
    theta = _posterior_samples(target, n, rng, opts.cos_i_sigma, warn)
    dtheta = theta[:, :7] - theta[:, :7].mean(axis=0)
    Ks, gs = [], []
    for j, f in enumerate(fits):
        z = rng.standard_normal((n, 2)) @ np.linalg.cholesky(f.cov + 1e-30 * np.eye(2)).T
        # Re-regressing on the design of sample θ shifts K by −∂K/∂θ·δθ (phase_sensitivity).
        Ks.append(f.K + z[:, 1] - dtheta @ dK[j])
        gs.append(f.gamma + z[:, 0] - dtheta @ dg[j])
    out: dict[str, F64] = {"K1": Ks[0], "gamma1": gs[0]}
    if len(fits) == 2:
        out |= {"K2": Ks[1], "gamma2": gs[1]}
        if target.cos_inclination is None:
            warn.append(
                "target has no lisa.cos_inclination: component masses not computed; add "
                "it (and its σ) to the target file"
            )
        else:
            out |= _masses.derive(
                K1_km_s=Ks[0],
                K2_km_s=Ks[1],
                gamma1_km_s=gs[0],
                gamma2_km_s=gs[1],
                f_hz=theta[:, 1],
                fdot_hz_s=theta[:, 2],
                eta=theta[:, 4],
                kappa=theta[:, 5],
                omega_dot=theta[:, 6],
                cos_i=theta[:, 7],
                amplitude=theta[:, 8] if target.amplitude is not None else None,
                mass_radius=opts.mass_radius,
            )
    else:
        nb = math.pi * theta[:, 1] - theta[:, 6]
        e = np.hypot(theta[:, 4], theta[:, 5])
        k = Ks[0] * 1e3
        out["mass_function"] = (k**3 * (1 - e**2) ** 1.5 / (nb * _masses.G_SI)) / _masses.MSUN_KG
        warn[:] = [w for w in warn if not w.startswith("cos ι")]  # f(M) does not use ι
        warn.append(
            "SB1: only the mass function f(M) = P K³(1−e²)^{3/2}/(2πG) is reported; "
            "component masses need both stars' velocities"
        )
    summaries = {k: _masses.summarize(v) for k, v in out.items()}
    return out, summaries


def _inter_session(
    target: Target,
    table: VelocityTable,
    tau: F64,
    u: F64,
    designs: tuple[F64, ...],
    fits: tuple[ComponentFit, ...],
    lam_k: F64,
    lam_kap: F64,
) -> tuple[list[_drifts.Group], _drifts.DriftResult]:
    p = target.params
    us = _drifts.assign_anchors(u, table.u_star)
    K = tuple(f.K for f in fits)
    groups = _drifts.group_spectra(
        sessions=table.session,
        tau_s=tau,
        u_rad=u,
        u_star=us,
        velocities=table.v,
        sigmas=table.sigma,
        K=K,
        design=designs[0],
        lam_k=lam_k,
        lam_kappa=lam_kap,
    )
    cov = target.covariance
    ll = _drifts.LLPredictor(p.eta, p.kappa, p.omega_dot, cov[np.ix_([4, 5, 6], [4, 5, 6])])
    pairs = _drifts.make_pairs(groups, K=K, eccentric=p.is_eccentric, ll_at=ll)
    res = _drifts.combine(
        pairs, groups, f_hz=p.f_gw, n_components=len(fits), eccentric=p.is_eccentric
    )
    return groups, res
