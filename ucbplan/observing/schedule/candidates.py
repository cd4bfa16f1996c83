"""Candidate blocks: every anchor epoch of a target in the run's nights, as a block on the plan's
axis (epochs are solved only where the Sun may be below the twilight limit, widened by a block
and two orbits: daytime epochs would all fail the night, :func:`night_search_x`).

For each target (vectorised over epochs): the anchor epochs t★ with σ_t and the φ_ref π-mode
alternative (:func:`ucbplan.core.ephemeris.find_epochs`, Appendix A2), their site arrival times from
one shared light-time track (:mod:`ucbplan.observing.observatory.barycentric`), every constraint
checked over the whole block (:mod:`ucbplan.observing.constraints.checks`), the validity limit
T_valid, the smearing of the exposure plan, and the grouping of blocks into sessions (a u = 0 / π
pair, both RV
zero crossings, or single blocks). All times are on one :class:`TimeAxis`."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np
from astropy import units as u
from astropy.coordinates import SkyCoord
from astropy.time import Time, TimeDelta
from numpy.typing import NDArray

from ucbplan.core.constants import TWO_PI
from ucbplan.core.ephemeris import EpochSet, arg_latitude, find_epochs, with_details
from ucbplan.core.forecast import tolerance, valid_window_s
from ucbplan.core.smearing import parse_smear_budget
from ucbplan.errors import ExposureWarning, SmearingWarning, UcbplanError, UcbplanWarning
from ucbplan.observing.blocks.block import (
    ExposurePlan,
    Smearing,
    block_smearing,
    check_smear_budget,
)
from ucbplan.observing.constraints import ConstraintSet, NightConstraint
from ucbplan.observing.constraints.checks import DARK_STEP_S, NightScreens, evaluate_window
from ucbplan.observing.observatory.barycentric import DelayInterpolator, SiteTrack
from ucbplan.observing.observatory.sites import Site
from ucbplan.observing.observatory.sky import SkyModel, airmass_from_alt
from ucbplan.observing.observatory.time_axis import EpochAxis, TimeAxis
from ucbplan.observing.precision.instruments import MAX_AIRMASS
from ucbplan.observing.precision.strategy import constrains_k
from ucbplan.observing.schedule.exposure import TargetCadence, exposure_sigma_v, target_exposure
from ucbplan.observing.schedule.nights import NightWindow
from ucbplan.observing.schedule.settings import ModeSpec, PlanSettings

if TYPE_CHECKING:
    from ucbplan.targets import Target

FloatArray = NDArray[np.float64]
#: A warning line with the class of its cause.
Warned = tuple[type[UcbplanWarning], str]

#: Epochs are searched this far beyond the span [s]: the light time (≤ 510 s) moves the site
#: arrival of an epoch just outside the span into it.
_EPOCH_PAD_S = 600.0


@dataclass(frozen=True)
class Candidates:
    """All anchor epochs of one target in a span, as blocks on the plan's time axis (arrays).

    ``epochs.time(tau_origin_s, dt_s)`` is the barycentric TDB epoch t★; the ``x_*`` arrays are
    site arrival times [s on the plan's :class:`TimeAxis`]. ``airmass_mid`` is the airmass at
    the block centre of blocks that pass every constraint (``ok``), +inf for the others;
    ``sigma_t_s`` and ``x_alt`` (the π-mode alternative) are computed for those blocks only
    (NaN for the others: only usable blocks are placed).
    """

    epochs: EpochAxis
    tau_origin_s: float
    dt_s: FloatArray
    u_star: FloatArray
    sigma_t_s: FloatArray
    x_mid: FloatArray
    x_start: FloatArray
    x_end: FloatArray
    x_alt: FloatArray
    ok: NDArray[np.bool_]
    first_failed: NDArray[np.int64]
    airmass_mid: FloatArray


def _find_epochs(
    target: Target,
    tau_lo: float,
    tau_hi: float,
    anchor: str | float,
    star: int,
    windows: FloatArray | None = None,
) -> EpochSet:
    """:func:`~ucbplan.core.ephemeris.find_epochs`, also for combined anchors such as
    ``quadrature+conjunction``: each anchor solved on its own, merged on one origin in time
    order (the origins differ by whole seconds at most ~10⁸ s: exact in float64).

    A single anchor's σ_t and π-mode alternative are left to
    :func:`~ucbplan.core.ephemeris.with_details` (only usable blocks need them); a combined
    anchor's are computed here, for every epoch.
    """
    if not isinstance(anchor, str) or not _combined(anchor):
        return find_epochs(target, tau_lo, tau_hi, anchor, star, details=False, windows=windows)
    sets = [
        find_epochs(target, tau_lo, tau_hi, a, star, windows=windows) for a in anchor.split("+")
    ]
    origin = sets[0].origin_s
    dt = np.concatenate([e.dt_s + (e.origin_s - origin) for e in sets])
    order = np.argsort(dt, kind="stable")

    def cat(name: str) -> Any:
        return np.concatenate([getattr(e, name) for e in sets])[order]

    return replace(
        sets[0],
        anchor=anchor,
        u_star_rad=cat("u_star_rad"),
        k=cat("k"),
        dt_s=dt[order],
        sigma_t_s=cat("sigma_t_s"),
        sigma_u_rad=cat("sigma_u_rad"),
        tau_alt_s=cat("tau_alt_s"),
        u_rate=cat("u_rate"),
    )


def grid_epochs(
    target: Target,
    tau_lo: float,
    tau_hi: float,
    step_s: float,
    star: int,
    windows: FloatArray | None = None,
) -> EpochSet:
    """Epochs every ``step_s`` seconds (barycentric TDB) with their u for back-to-back exposures
    (the ``untargeted`` strategy): the exposures fall at whatever phase they do, and each is
    assigned its u from the phase model (Eq. u_precessing_app).

    The grid is anchored on whole multiples of ``step_s`` since the reference epoch, so every
    span of a run sees the same grid; ``windows`` (sorted, disjoint, TDB s since the reference)
    keeps only its epochs inside them, with the values the whole grid gives them.
    """
    k0, k1 = math.ceil(tau_lo / step_s), math.floor(tau_hi / step_s)
    k = np.arange(k0, max(k0, k1 + 1), dtype=np.int64)
    if windows is not None:
        k = k[_inside(np.asarray(k * step_s, dtype=np.float64), windows)]
    origin = float(k0 * step_s)
    dt = np.asarray((k - k0) * step_s, dtype=np.float64)
    nan = np.full(dt.shape, np.nan)
    u = np.mod(arg_latitude(target.params, dt, star, origin), TWO_PI)
    return EpochSet("untargeted", star, u, k, origin, dt, nan, nan.copy(), nan.copy(), nan.copy())


def _inside(tau: FloatArray, windows: FloatArray) -> NDArray[np.bool_]:
    """Whether each ``tau`` lies in one of the sorted, disjoint ``windows`` (m, 2)."""
    if windows.size == 0:
        return np.zeros(tau.shape, dtype=bool)
    j = np.searchsorted(windows[:, 0], tau, side="right") - 1
    return np.asarray((j >= 0) & (tau <= windows[np.maximum(j, 0), 1]))


def _merged(w: FloatArray) -> FloatArray:
    """Intervals (m, 2) merged where they overlap or touch: sorted and disjoint."""
    if w.size == 0:
        return np.zeros((0, 2))
    w = w[np.argsort(w[:, 0], kind="stable")]
    ends = np.maximum.accumulate(w[:, 1])
    first = np.flatnonzero(np.concatenate([[True], w[1:, 0] > ends[:-1]]))
    last = np.concatenate([first[1:] - 1, [w.shape[0] - 1]])
    return np.stack([w[first, 0], ends[last]], axis=1)


def night_search_x(
    night: NightConstraint, sky: SkyModel, span_x: tuple[float, float]
) -> FloatArray:
    """Intervals (m, 2) [s on the plan's axis] that hold every instant of ``span_x`` at which
    the Sun may be below the ``night`` limit.

    The Sun's altitude is screened on nodes
    :data:`~ucbplan.observing.constraints.checks.DARK_STEP_S` apart with the rate bound of the
    constraints (a node certainly in daylight is in daylight for one node spacing either side); each
    run of the other nodes, widened by one spacing, is an interval. An instant at night has its
    nearest node (≤ half a spacing away) in a run.
    """
    lo, hi = float(span_x[0]), float(span_x[1])
    n = math.ceil((hi - lo) / DARK_STEP_S) + 1
    nodes = np.asarray(lo + DARK_STEP_S * np.arange(n), dtype=np.float64)
    maybe = np.concatenate([[False], night.screen(sky, 0, nodes, DARK_STEP_S) != -1, [False]])
    edge = np.flatnonzero(np.diff(maybe.astype(np.int8)))
    first, last = edge[0::2], edge[1::2] - 1
    return np.stack([nodes[first] - DARK_STEP_S, nodes[last] + DARK_STEP_S], axis=1)


def _epoch_windows(
    target: Target, epochs: EpochAxis, search_x: FloatArray, plan: ExposurePlan
) -> FloatArray:
    """The night intervals ``search_x`` as epoch windows (TDB s since the target's reference):
    widened by a block and two orbits (a block that touches the night, and the second block
    of its session) and by the light time (:data:`_EPOCH_PAD_S`), merged."""
    f = abs(float(target.params.f_gw))
    orbit = 2.0 / f if f > 0 else math.inf
    pad = 1.5 * plan.span_s + 2.0 * orbit + _EPOCH_PAD_S
    lag = epochs.from_x(0.0)
    return _merged(np.asarray(search_x + lag + np.array([-pad, pad]), dtype=np.float64))


def _combined(anchor: str | float) -> bool:
    """Whether ``anchor`` combines several (``quadrature+conjunction``)."""
    return isinstance(anchor, str) and "+" in anchor


def candidate_blocks(
    target: Target,
    i: int,
    mode: ModeSpec,
    axis: TimeAxis,
    span_x: tuple[float, float],
    interp: DelayInterpolator,
    sky: SkyModel,
    constraints: ConstraintSet,
    plan: ExposurePlan,
    star: int = 1,
    grid_step_s: float | None = None,
    search_x: FloatArray | None = None,
    night: NightScreens | None = None,
) -> Candidates:
    """Every anchor epoch whose block centre lies in ``span_x`` (s on ``axis``); with
    ``grid_step_s``, every epoch of a back-to-back grid instead (:func:`grid_epochs`).

    With ``search_x`` (the nights, :func:`night_search_x`), epochs are searched only there,
    widened by a block and two orbits: every block that may touch the night, and the second
    block of its session, is found with the values the whole span gives it (≤ 2 ulp of its
    epoch); daytime epochs, which fail the night, are never solved. ``night``: the night's
    screens shared by the run's targets (see :func:`evaluate_window`).

    Notes
    -----
    Epochs from Eq. u_precessing_app (Newton, :func:`ucbplan.core.ephemeris.find_epochs`); site time
    t = t★ − Δ(t★) from the light-time spline; constraints over the whole block.
    """
    epochs = axis.epoch_axis(target.t_ref)
    lo, hi = span_x
    es = _span_epochs(target, epochs, span_x, mode, plan, star, grid_step_s, search_x)
    x_mid = interp.site_x(epochs.to_x(es.origin_s, es.dt_s))
    keep = (x_mid >= lo) & (x_mid < hi)
    half = plan.span_s / 2.0
    x_mid = x_mid[keep]
    ok, first = evaluate_window(constraints, sky, i, x_mid - half, x_mid + half, night)
    if grid_step_s is not None:  # σ_t of usable exposures; no π-mode twin without an anchor
        es = with_details(target, es, np.flatnonzero(keep)[ok], pi_mode=False)
    elif not _combined(mode.anchor):  # σ_t and the π-mode alternative of usable blocks only
        es = with_details(target, es, np.flatnonzero(keep)[ok])
    x_alt = np.full(es.tau_alt_s.shape, np.nan)
    has_alt = np.isfinite(es.tau_alt_s)
    x_alt[has_alt] = interp.site_x(epochs.to_x(es.tau_alt_s[has_alt]))
    return Candidates(
        epochs=epochs,
        tau_origin_s=es.origin_s,
        dt_s=es.dt_s[keep],
        u_star=es.u_star_rad[keep],
        sigma_t_s=es.sigma_t_s[keep],
        x_mid=x_mid,
        x_start=x_mid - half,
        x_end=x_mid + half,
        x_alt=x_alt[keep],
        ok=ok,
        first_failed=first,
        airmass_mid=_airmass_where(ok, sky, i, x_mid),
    )


def _span_epochs(
    target: Target,
    epochs: EpochAxis,
    span_x: tuple[float, float],
    mode: ModeSpec,
    plan: ExposurePlan,
    star: int,
    grid_step_s: float | None,
    search_x: FloatArray | None,
) -> EpochSet:
    """The anchor (or grid) epochs of ``span_x`` padded by :data:`_EPOCH_PAD_S`, searched only
    inside ``search_x`` when given."""
    tau_lo = epochs.from_x(span_x[0]) - _EPOCH_PAD_S
    tau_hi = epochs.from_x(span_x[1]) + _EPOCH_PAD_S
    windows = None if search_x is None else _epoch_windows(target, epochs, search_x, plan)
    if grid_step_s is not None:
        return grid_epochs(target, tau_lo, tau_hi, grid_step_s, star, windows)
    return _find_epochs(target, tau_lo, tau_hi, mode.anchor, star, windows)


def _airmass_where(ok: NDArray[np.bool_], sky: SkyModel, i: int, x: FloatArray) -> FloatArray:
    """Airmass of target ``i`` at ``x`` where ``ok``; +inf elsewhere (never used: only usable
    blocks are scored)."""
    out = np.full(x.shape, np.inf)
    out[ok] = airmass_from_alt(sky.target_alt_deg(i, x[ok]))
    return out


def session_partners(
    c: Candidates, paired: bool
) -> tuple[NDArray[np.int64], FloatArray, FloatArray]:
    """Group blocks into sessions: partner index (−1 for single blocks), ok mask and score.

    A paired session starts with block j and continues with the first later block at the other
    anchor that starts after block j ends (u = 0 then π half an orbit later, or the next orbit if
    the blocks are longer than half an orbit). The score is the session's worst airmass.
    """
    n = c.x_mid.size
    if not paired or n == 0:
        return np.full(n, -1, dtype=np.int64), c.ok.astype(np.float64), c.airmass_mid
    nxt = np.minimum(np.searchsorted(c.x_start, c.x_end, side="left"), n - 1)
    # np.isclose(·, 0.0, atol=1e-6), which is exactly |·| <= 1e-6 + 1e-5·0, without its checks
    same = np.abs(np.mod(c.u_star[nxt] - c.u_star, TWO_PI)) <= 1e-6
    nxt = np.where(same, nxt + 1, nxt)
    valid = (nxt < n) & (nxt > np.arange(n))
    nxt = np.minimum(nxt, n - 1).astype(np.int64)
    ok = valid & c.ok & c.ok[nxt]
    score = np.asarray(np.maximum(c.airmass_mid, c.airmass_mid[nxt]), dtype=np.float64)
    return nxt, ok.astype(np.float64), score


@dataclass(frozen=True)
class PlanFrame:
    """What every target of a run shares: mode, time axis, sky model, light-time track and
    constraints."""

    mode: ModeSpec
    axis: TimeAxis
    span_x: tuple[float, float]
    sky: SkyModel
    track: SiteTrack
    constraints: ConstraintSet
    #: Where anchor epochs are searched (:func:`night_search_x`); None: the whole span.
    search_x: FloatArray | None = None
    #: The night's screens, computed once for all targets (None: each target's own).
    night: NightScreens | None = None


@dataclass(frozen=True)
class TargetRun:
    """One target's candidates with its sessions, validity and smearing.

    Attributes
    ----------
    index : int
        The target's index in the sky model.
    partner : ndarray of int
        Second block of the session starting at each block (−1: single-block session).
    ok, score : ndarray of float
        Session usable (1.0) or not; its worst airmass (placement prefers low scores).
    valid : ndarray of bool
        Session inside the validity window (σ_u ≤ α·δu_tol).
    until : Time
        End of validity (TDB).
    since : Time
        Start of validity (TDB): the LISA observation start, or T_valid before T0 for a timing
        ephemeris.
    exposure : TargetCadence
        The target's exposure plan and visit cadence (smearing floor applied).
    weight : ndarray of float
        Fisher information on K of each block's exposure, (Λ_K cos u)²/σ_v² [(km/s)⁻²] (γ's,
        1/σ_v², for anchors at cos u = 0); NaN where σ_v is unknown, and for sessions (no
        visits: nothing reads it there).
    """

    target: Target
    index: int
    cand: Candidates
    partner: NDArray[np.int64]
    ok: FloatArray
    score: FloatArray
    valid: NDArray[np.bool_]
    until: Time
    smearing: Smearing
    since: Time
    exposure: TargetCadence
    weight: FloatArray


def _weights(
    target: Target, cand: Candidates, settings: PlanSettings, te: TargetCadence
) -> FloatArray:
    """Information of each candidate's exposure (see :class:`TargetRun`), σ_v at its airmass."""
    x = np.clip(np.where(np.isfinite(cand.airmass_mid), cand.airmass_mid, 1.0), 1.0, MAX_AIRMASS)
    sig = exposure_sigma_v(target, settings, te.plan.exptime_s, x)
    if constrains_k(settings.spec.u_values) or te.strategy == "untargeted":
        g = te.lambda_k * np.cos(cand.u_star)
    else:
        g = np.ones_like(cand.u_star)
    return np.asarray((g / sig) ** 2, dtype=np.float64)


def _tolerance_and_validity(
    target: Target, mode: ModeSpec, settings: PlanSettings, exptime_s: float
) -> tuple[Time, Time, float | None, float | None]:
    """(valid-since, valid-until TDB, σ_v, K) for a target; errors say which number is missing.

    The window is where σ_u ≤ α·δu_tol (:func:`~ucbplan.core.forecast.valid_window_s`): from the
    LISA start to T_valid after its end, or T_valid before to T_valid after a timing T0.
    """
    spec = target.spectroscopy
    sigma_v: float | None = float(exposure_sigma_v(target, settings, exptime_s, 1.0))
    sigma_v = sigma_v if sigma_v is not None and np.isfinite(sigma_v) else None
    k = settings.k_eff_kms or (spec.k_for_tolerance if spec else None)
    if sigma_v is None or k is None:
        raise UcbplanError(
            f"{target.name}: the tolerance needs sigma_v and K: add spectroscopy.sigma_v and "
            "K_eff (or K1/K2) to the target file, or pass `sigma_v` and `k_eff` (km/s)"
        )
    u_star = mode.u_values[0] if mode.tol_kind == "generic" else None
    tol = tolerance(mode.tol_kind, sigma_v, k, settings.n_epochs, u_star)
    first, last = valid_window_s(target, tol, mode.u_values, settings.alpha, settings.star)
    since = target.t_ref + TimeDelta(first * u.s)
    until = target.t_ref + TimeDelta(last * u.s)
    return since, until, sigma_v, k


def _smearing(
    target: Target,
    settings: PlanSettings,
    plan: ExposurePlan,
    sigma_v: float | None,
    k: float | None,
) -> tuple[Smearing, list[str]]:
    """Smearing of the exposure plan for ``target``, checked against the budget."""
    spec = target.spectroscopy
    k_smear = (spec.K1_kms if spec and spec.K1_kms else None) or k
    sm = block_smearing(plan, target.params.n_bar, k_smear)
    max_smear = parse_smear_budget(settings.max_smear, sigma_v) if settings.max_smear else None
    warns = check_smear_budget(target.name, sm, max_smear, settings.max_bin_fraction, sigma_v)
    return sm, warns


def _target_run(
    target: Target, i: int, frame: PlanFrame, settings: PlanSettings
) -> tuple[TargetRun, list[Warned]]:
    te = target_exposure(target, settings)
    since, until, sigma_v, k = _tolerance_and_validity(
        target, frame.mode, settings, te.plan.exptime_s
    )
    sm, smeared = _smearing(target, settings, te.plan, sigma_v, k)
    warns: list[Warned] = [(ExposureWarning, n) for n in te.notes]
    warns += [(SmearingWarning, w) for w in smeared]
    cand = candidate_blocks(
        target,
        i,
        frame.mode,
        frame.axis,
        frame.span_x,
        frame.track.delay_interpolator(target.coord),
        frame.sky,
        frame.constraints,
        te.plan,
        settings.star,
        te.step_s if te.strategy == "untargeted" else None,
        frame.search_x,
        frame.night,
    )
    tau = cand.tau_origin_s + cand.dt_s
    valid = (tau >= cand.epochs.tau(since)) & (tau <= cand.epochs.tau(until))
    paired = frame.mode.paired and not settings.plans_visits
    partner, ok, score = session_partners(cand, paired)
    if not te.floor_ok:
        ok = np.zeros_like(ok)  # no exposure keeps the smearing floor
    valid = valid & ((partner < 0) | valid[np.maximum(partner, 0)])
    # only visits read the information of an exposure (goals, back-to-back visits)
    weight = _weights(target, cand, settings, te) if settings.plans_visits else cand.u_star * np.nan
    run = TargetRun(target, i, cand, partner, ok, score, valid, until, sm, since, te, weight)
    return run, warns


def prepare_runs(
    targets: list[Target], site: Site, windows: list[NightWindow], settings: PlanSettings
) -> tuple[PlanFrame, list[TargetRun], list[Warned]]:
    """The shared frame (one sky model and light-time track) and every target's run.

    Returns
    -------
    frame : PlanFrame
    runs : list of TargetRun
        In the order of ``targets``.
    warnings : list of (category, str)
        Exposure notes and smearing warnings, each with its class.

    Raises
    ------
    UcbplanError
        For missing tolerance inputs or an exceeded smearing budget.
    """
    mode, constraints = settings.spec, settings.constraints(site)
    axis = TimeAxis.starting_at(windows[0].start, site.location)
    span_x = (0.0, axis.x(windows[-1].end))
    coords = SkyCoord([t.ra_deg for t in targets] * u.deg, [t.dec_deg for t in targets] * u.deg)
    sky = SkyModel.build(site.location, axis.origin, span_x, coords)
    frame = PlanFrame(
        mode=mode,
        axis=axis,
        span_x=span_x,
        sky=sky,
        track=SiteTrack.build(axis.origin, span_x, site.location),
        constraints=constraints,
        search_x=night_search_x(constraints.night, sky, span_x),
        night=NightScreens(constraints.night, sky),
    )
    runs, warns = [], []
    for i, t in enumerate(targets):
        run, more = _target_run(t, i, frame, settings)
        runs.append(run)
        warns += more
    return frame, runs, warns
