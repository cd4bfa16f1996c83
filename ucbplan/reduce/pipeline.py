"""``ucbplan reduce``: velocities + target → K_j, γ_j, masses, Δκ and Δv_CM (paper Secs. 3–5).

Data flow: :mod:`~ucbplan.reduce.velocities` (read, validate) → this module's :func:`reduce`,
which runs the steps in order:

1. :mod:`~ucbplan.reduce.design` — window factors and the design variable G per spectrum from the
   LISA ephemeris: the exact Keplerian velocity curve averaged over each exposure (also at the
   emission time, for the light travel time);
2. :mod:`~ucbplan.reduce.regression` — the intra-session fits v_j = γ_j ± K_j G, WIL41, and the
   phase sensitivity ∂(K_j, γ_j)/∂θ of the LISA ephemeris error;
3. :mod:`~ucbplan.reduce.montecarlo` — the joint Monte Carlo to masses
   (:mod:`~ucbplan.reduce.masses`);
4. :mod:`~ucbplan.reduce.groups` and :mod:`~ucbplan.reduce.drifts` — fixed-u groups per
   session and their inter-session pairs: Δκ, Δv_CM, a_los;

→ :mod:`~ucbplan.reduce.report` (dict, JSON/YAML, terminal) and :mod:`~ucbplan.reduce.plots`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ucbplan.core.binary import MASS_RADIUS_MODELS
from ucbplan.core.constants import C_KM_S
from ucbplan.core.kepler import row_chunks, window_rotation
from ucbplan.errors import InputError, VelocityFileError, shorten
from ucbplan.reduce import drifts as _drifts
from ucbplan.reduce import masses as _masses
from ucbplan.reduce.design import (
    OrbitTrack,
    Rotation,
    design_jacobian,
    designs,
    mid_exposure,
    track,
    window_durations,
    window_factors,
)
from ucbplan.reduce.groups import Group, assign_anchors, group_spectra
from ucbplan.reduce.montecarlo import MonteCarlo, monte_carlo
from ucbplan.reduce.regression import (
    ComponentFit,
    WilsonFit,
    fit_component,
    line_slope,
    line_weights,
    phase_sensitivity,
    wilson_fit,
)
from ucbplan.reduce.velocities import MIN_SPECTRA, VelocityTable, check_validity
from ucbplan.targets import load_samples

if TYPE_CHECKING:
    from ucbplan.core.kepler import WindowedVelocity
    from ucbplan.core.params import PhaseParams
    from ucbplan.targets import Target

F64 = NDArray[np.float64]


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
    #: Monte-Carlo draws per quantity; empty above montecarlo.CHUNK samples (chunked run:
    #: the summaries are exact, the draws are not kept).
    samples: dict[str, F64]
    summaries: dict[str, _masses.Summary]
    groups: tuple[Group, ...]
    drift: _drifts.DriftResult
    warnings: tuple[str, ...] = field(default_factory=tuple)

    @property
    def eccentric(self) -> bool:
        """Whether the target has e > 0 or ω̇ ≠ 0."""
        return self.target.params.is_eccentric


def reduce_options(
    *,
    samples: int = 20_000,
    seed: int | None = None,
    light_time: bool = False,
    mass_radius: str | None = None,
    cos_i_sigma: float = 0.0,
) -> ReduceOptions:
    """Checked :class:`ReduceOptions` (``ucbplan reduce`` and :func:`ucbplan.reduce`).

    ``samples`` is the Monte-Carlo size, ``cos_i_sigma`` the 1σ of cos ι [1] and
    ``mass_radius`` a key of ``MASS_RADIUS_MODELS`` in any case (stored lower case).

    Raises
    ------
    InputError
        An unknown mass–radius relation, or a cos ι spread outside [0, 2] (naming the
        parameter; the command line prints its flag).
    """
    if mass_radius is not None and str(mass_radius).lower() not in MASS_RADIUS_MODELS:
        raise InputError(
            f"mass_radius: got {shorten(mass_radius)}, expected one of "
            f"{', '.join(MASS_RADIUS_MODELS)}",
            parameter="mass_radius",
        )
    if not 0.0 <= cos_i_sigma <= 2.0:
        raise InputError(
            f"cos_i_sigma: expected a 1σ of cos ι in [0, 2], got {cos_i_sigma}", "cos_i_sigma"
        )
    return ReduceOptions(
        n_samples=samples,
        seed=seed,
        light_time=light_time,
        mass_radius=mass_radius.lower() if mass_radius else None,
        cos_i_sigma=cos_i_sigma,
    )


def _fit_all(
    table: VelocityTable, design: tuple[F64, ...], weights: tuple[F64, ...]
) -> tuple[ComponentFit, ...]:
    """One regression per star (``weights``: the stars' 1/σ², :func:`_weights`).

    Raises
    ------
    VelocityFileError
        The spectra sample a single value of the design F̄ (one orbital phase): K is undefined.
    """
    fits = []
    for j, (v, s) in enumerate(zip(table.v, table.sigma, strict=True)):
        _check_design(table, j, design[j])
        fits.append(fit_component(design[j], v, s, star=j + 1, weights=weights[j]))
    return tuple(fits)


def _weights(table: VelocityTable) -> tuple[F64, ...]:
    """Each star's 1/σ² (:func:`~ucbplan.reduce.regression.line_weights`), computed once for
    its regressions and phase sensitivities."""
    return tuple(line_weights(s) for s in table.sigma)


def _fit_lines(
    table: VelocityTable, design: tuple[F64, ...], weights: tuple[F64, ...]
) -> tuple[tuple[float, float], ...]:
    """(K_j, γ_j) per star of :func:`_fit_all`'s fits, the same doubles, from the stars'
    :func:`~ucbplan.reduce.regression.line_weights` (the light-time passes need no more)."""
    out = []
    for j, (v, w) in enumerate(zip(table.v, weights, strict=True)):
        _check_design(table, j, design[j])
        slope, intercept = line_slope(design[j], v, w)
        out.append((slope if j == 0 else -slope, intercept))
    return tuple(out)


def _check_design(table: VelocityTable, j: int, g: F64) -> None:
    """Raise VelocityFileError when star ``j``'s design F̄ does not vary (one orbital phase)."""
    if not np.ptp(g) > 1e-9 * max(float(np.max(np.abs(g))), 1e-300):
        raise VelocityFileError(
            f"{table.source}: star {j + 1}: all {g.size} spectra sample the same orbital "
            "phase (F̄ does not vary), so K is undetermined; add spectra at other phases"
        )


@dataclass(frozen=True)
class _IntraSession:
    """The fits used (plain or light-time corrected), their designs and the light-time sizes."""

    fits: tuple[ComponentFit, ...]
    design: tuple[F64, ...]
    light_time: dict[str, float]
    weights: tuple[F64, ...]


def _intra_session(
    p: PhaseParams,
    table: VelocityTable,
    shared: tuple[OrbitTrack, Rotation],
    tau: F64,
    window_s: F64,
    mid_h: F64,
    apply_lt: bool,
) -> _IntraSession:
    """Fits on G at mid-exposure (``mid_h``) and at the emission time (K from two fixed-point
    passes); ``shared``: the orbit at mid-exposure and the windows' rotation."""
    n = len(table.v)
    plain = (mid_h,) * n  # both stars see the same G at mid-exposure
    weights = _weights(table)
    fits0 = _fit_all(table, plain, weights)
    K0 = tuple(f.K for f in fits0)
    lt_design = designs(p, tau, window_s, n, K0, *shared)
    K_lt = tuple(k for k, _ in _fit_lines(table, lt_design, weights))
    lt_design = designs(p, tau, window_s, n, K_lt, *shared)
    fits_lt = _fit_all(table, lt_design, weights) if apply_lt else None
    if fits_lt is None:  # only K and γ of the corrected fits are reported
        lines = _fit_lines(table, lt_design, weights)
    else:
        lines = tuple((f.K, f.gamma) for f in fits_lt)
    nb = math.pi * p.f_gw - p.omega_dot
    light = {
        "max_delay_s": max(abs(k) for k in K0) / (C_KM_S * nb),
        **{f"dK{j + 1}": lines[j][0] - fits0[j].K for j in range(n)},
        **{f"dgamma{j + 1}": lines[j][1] - fits0[j].gamma for j in range(n)},
        "applied": float(apply_lt),
    }
    if fits_lt is not None:
        return _IntraSession(fits_lt, lt_design, light, weights)
    return _IntraSession(fits0, plain, light, weights)


@dataclass(frozen=True)
class _PhaseErrors:
    """Propagation of the LISA ephemeris error σ_u into K_j and γ_j."""

    sigma_u: F64
    dK: F64
    dgamma: F64
    sigma_K: tuple[float, ...]
    sigma_gamma: tuple[float, ...]
    attenuation: tuple[float, ...]


def _phase_errors(
    target: Target,
    table: VelocityTable,
    at: OrbitTrack,
    tau: F64,
    window_s: F64,
    mid: tuple[WindowedVelocity, F64],
    intra: _IntraSession,
) -> _PhaseErrors:
    """σ_u per spectrum, ∂(K_j, γ_j)/∂θ, their σ from the covariance, and the K attenuation."""
    p, cov7 = target.params, target.covariance
    jacG = design_jacobian(p, tau, window_s, at, mid)
    sigma_u = _sigma_u(p, cov7, tau, at)
    dK, dg, sKp, sgp, att = [], [], [], [], []
    for j, f in enumerate(intra.fits):
        sign = 1.0 if j == 0 else -1.0
        w = intra.weights[j]
        a, b = phase_sensitivity(intra.design[j], table.sigma[j], jacG, f.K, sign, w)
        dK.append(a)
        dg.append(b)
        sKp.append(math.sqrt(max(float(a @ cov7 @ a), 0.0)))
        sgp.append(math.sqrt(max(float(b @ cov7 @ b), 0.0)))
        att.append(float(f.K * (w * sigma_u**2).sum() / w.sum() / 2.0))
    return _PhaseErrors(sigma_u, np.array(dK), np.array(dg), tuple(sKp), tuple(sgp), tuple(att))


def _sigma_u(p: PhaseParams, cov7: F64, tau: F64, at: OrbitTrack) -> F64:
    """σ_u per spectrum [rad]: √(J C Jᵀ) with J = ∂u/∂θ (:func:`ucbplan.core.phase.u_jacobian`)
    from the shared orbit (its Φ_asc mod 2π is π·(cycles mod 2) there, the same double as
    2π·(cycles mod 2)/2, and its cos and sin of ω̇τ), chunk by chunk (rows × 7 in cache, not a
    56 MB (n, 7) array)."""
    from ucbplan.core.phase import jacobian_kernel

    out = np.empty(tau.size)
    for sl in row_chunks(tau.size):
        s, c = np.sin(at.phase_mod[sl]), np.cos(at.phase_mod[sl])
        turn = (at.cos_w[sl], at.sin_w[sl])
        ju = np.asarray(jacobian_kernel(p.eta, p.kappa, p.omega_dot, tau[sl], s, c, turn), float)
        out[sl] = np.sqrt(np.clip(np.einsum("ni,ij,nj->n", ju, cov7, ju), 0.0, None))
    return out


def _chi2_limit(dof: int) -> float:
    """The χ² above which a fit's scatter significantly exceeds its σ's: the 99th percentile
    of the χ² distribution with ``dof`` degrees of freedom.

    ``scipy.stats.chi2.ppf(0.99, dof)`` bit for bit (its ``_ppf``), without importing
    ``scipy.stats`` (~0.3 s of a command's start-up; ``scipy.special`` is loaded anyway).
    """
    from scipy.special import gammaincinv

    return float(2.0 * gammaincinv(dof / 2.0, 0.99))


def _fit_warnings(fits: tuple[ComponentFit, ...]) -> list[str]:
    """Outliers (kept), a significant χ² (p < 0.01; errors scaled by √(χ²/dof)) per star; a
    negative SB1 K."""
    warn = []
    for j, f in enumerate(fits):
        n_out = int(f.line.outliers.sum())
        if n_out:
            rows = np.flatnonzero(f.line.outliers)[:5] + 1
            warn.append(
                f"star {j + 1}: {n_out} spectra deviate by > 4σ (rows {rows.tolist()}); "
                "they are kept — check them"
            )
        if f.line.scaled and f.line.chi2 > _chi2_limit(f.line.dof):
            warn.append(
                f"star {j + 1}: χ²/dof = {f.line.chi2 / f.line.dof:.2f} (p < 0.01): the scatter "
                f"exceeds σ_v; errors scaled by √(χ²/dof) = {f.line.scale:.3g}, σ(K) "
                f"{f.sigma_K_input:.3g} → {f.sigma_K:.3g} km/s — check σ_v or outliers"
            )
    if len(fits) == 1 and fits[0].K < 0:
        warn.append(
            "SB1: K < 0, i.e. the visible star moves like star 2 of the LISA convention "
            "(u_2 = u_1 + π); |K| is its semi-amplitude"
        )
    return warn


def _wilson(table: VelocityTable, fits: tuple[ComponentFit, ...]) -> WilsonFit | None:
    """WIL41 v1–v2 line of an SB2 table (None for SB1)."""
    if len(fits) != 2:
        return None
    q0 = fits[0].K / fits[1].K
    return wilson_fit(table.v[0], table.sigma[0], table.v[1], table.sigma[1], q0=q0)


def _resolve_seed(seed: int | None) -> int:
    """The given seed, or fresh entropy (reported in the Reduction)."""
    if seed is None:
        return int(np.random.SeedSequence().generate_state(1)[0])
    return seed


def reduce(target: Target, table: VelocityTable, options: ReduceOptions | None = None) -> Reduction:
    """Reduce a velocity table against a target (the library behind ``ucbplan reduce``).

    Parameters
    ----------
    target : Target
        LISA ephemeris and posterior.
    table : VelocityTable
        Measured velocities [km/s] at barycentric TDB times
        (:func:`~ucbplan.reduce.velocities.read_velocities`).
    options : ReduceOptions, optional
        Monte-Carlo size, seed, light-time correction, mass–radius relation.

    Returns
    -------
    Reduction
        Fits, phase-error propagation, Monte-Carlo masses, groups and drifts.

    Raises
    ------
    VelocityFileError
        Times outside the target's validity window, or too few spectra for the fits.
    TargetFileError
        The target's samples file is unreadable or has no parameter columns
        (:func:`ucbplan.targets.load_samples`, which also moves start-referenced samples to the
        midpoint).

    Notes
    -----
    Eqs. v1v2_ecc_rv, F_definition, vbar_master (regression); semimajor_axis_j, Kepler_mtot,
    M1M2_cir_and_ecc (masses); delta_kappa_spec_binned, intercept_Deltav_cm, rvzero_average,
    fdot_acc_spectroscopy (drifts).
    """
    opts = options or ReduceOptions()
    seed = _resolve_seed(opts.seed)
    p = target.params
    tau = check_validity(table, target)
    _require_spectra(table)
    lam = window_factors(table, p.f_gw)
    window_s = window_durations(table, p.f_gw)
    at = track(p, tau)  # the orbit at mid-exposure, once for every design there
    rot = window_rotation(p.omega_dot, window_s)  # the windows' turn, once for every design
    mid = mid_exposure(p, tau, window_s, at, rot)  # the plain design and its Jacobian, one pass
    intra = _intra_session(p, table, (at, rot), tau, window_s, mid[0].h, opts.light_time)
    phase = _phase_errors(target, table, at, tau, window_s, mid, intra)
    mc = _monte_carlo(target, intra.fits, phase, opts, seed)
    groups, drift = _inter_session(target, table, tau, at, intra, *lam)
    return _reduction(target, table, opts, seed, (tau, at), lam, intra, phase, mc, (groups, drift))


def _require_spectra(table: VelocityTable) -> None:
    """Raise VelocityFileError when the table has fewer than ``MIN_SPECTRA`` spectra."""
    if table.n < MIN_SPECTRA:
        raise VelocityFileError(
            f"{table.source}: {table.n} spectrum; the fit of γ and K needs at least "
            f"{MIN_SPECTRA} spectra at different orbital phases — add one line per spectrum"
        )


def _monte_carlo(
    target: Target,
    fits: tuple[ComponentFit, ...],
    phase: _PhaseErrors,
    opts: ReduceOptions,
    seed: int,
) -> MonteCarlo:
    """The joint Monte Carlo to masses, seeded with ``seed`` (the target's samples if any)."""
    return monte_carlo(
        target,
        fits,
        phase.dK,
        phase.dgamma,
        n_samples=opts.n_samples,
        cos_i_sigma=opts.cos_i_sigma,
        mass_radius=opts.mass_radius,
        rng=np.random.default_rng(seed),
        columns=load_samples(target) if target.samples is not None else None,
    )


def _reduction(
    target: Target,
    table: VelocityTable,
    opts: ReduceOptions,
    seed: int,
    orbit: tuple[F64, OrbitTrack],
    lam: tuple[F64, F64],
    intra: _IntraSession,
    phase: _PhaseErrors,
    mc: MonteCarlo,
    inter: tuple[list[Group], _drifts.DriftResult],
) -> Reduction:
    """The :class:`Reduction` record of the steps' results (``orbit``: τ and the track there)."""
    fits, (tau, at) = intra.fits, orbit
    return Reduction(
        target=target,
        table=table,
        options=opts,
        seed=seed,
        tau_s=tau,
        u_rad=at.u,
        F=at.cos_u + at.kap,
        design=intra.design,
        lam_k=lam[0],
        lam_kappa=lam[1],
        fits=fits,
        dK=phase.dK,
        dgamma=phase.dgamma,
        sigma_K_phase=phase.sigma_K,
        sigma_gamma_phase=phase.sigma_gamma,
        sigma_u=phase.sigma_u,
        attenuation=phase.attenuation,
        wilson=_wilson(table, fits),
        light_time=intra.light_time,
        samples=mc.samples,
        summaries=mc.summaries,
        groups=tuple(inter[0]),
        drift=inter[1],
        warnings=(*_fit_warnings(fits), *mc.warnings),
    )


def _inter_session(
    target: Target,
    table: VelocityTable,
    tau: F64,
    at: OrbitTrack,
    intra: _IntraSession,
    lam_k: F64,
    lam_kap: F64,
) -> tuple[list[Group], _drifts.DriftResult]:
    """Fixed-u groups per session, their pairs, and the combined drifts (Δκ, Δv_CM, a_los),
    from the orbit at mid-exposure (``at``)."""
    p, fits, u = target.params, intra.fits, at.u
    K = tuple(f.K for f in fits)
    groups = group_spectra(
        sessions=table.session,
        tau_s=tau,
        u_rad=u,
        u_star=assign_anchors(u, table.u_star),
        cos_u=at.cos_u,
        velocities=table.v,
        sigmas=table.sigma,
        K=K,
        design=intra.design[0],
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
