"""Night schedules: anchor epochs → site UTC → constraint-checked blocks → sessions per night.

Pipeline for every target (all vectorised over epochs): the planning modes name the anchors
(Appendix A2); :func:`~ucbplan.core.ephemeris.find_epochs` gives the barycentric epochs t★
with σ_t and the φ_ref π-mode alternative; the light time is removed with one shared site track
(:mod:`ucbplan.observing.timeconv`); blocks are checked against every constraint over their whole
length (:mod:`ucbplan.observing.constraints`); sessions (a u = 0 / π pair, both RV zero crossings,
or single blocks) are then placed night by night in priority order without overlaps, with a
slew/acquisition overhead before each session. Whatever could not be placed is reported with the
reason.
"""

from __future__ import annotations

import math
import re
from collections import Counter
from dataclasses import dataclass, field, replace
from datetime import date, datetime, time, timedelta
from typing import TYPE_CHECKING

import numpy as np
from astropy import units as u
from astropy.coordinates import EarthLocation
from astropy.time import Time, TimeDelta
from numpy.typing import NDArray

from ucbplan.errors import UcbplanError
from ucbplan.observing.blocks import (
    Block,
    ExposurePlan,
    Smearing,
    block_smearing,
    check_smear_budget,
)
from ucbplan.observing.constraints import (
    AirmassConstraint,
    Constraint,
    MoonIlluminationConstraint,
    MoonSeparationConstraint,
    NightConstraint,
    SkyModel,
    ZenithHoleConstraint,
    airmass_from_alt,
    evaluate_window,
)
from ucbplan.observing.sites import Site
from ucbplan.observing.timeconv import DelayInterpolator, SiteTrack, quiet_erfa

if TYPE_CHECKING:
    from ucbplan.target import Target

__all__ = [
    "MODES",
    "Candidates",
    "PlanResult",
    "PlanSettings",
    "Unplaced",
    "candidate_blocks",
    "delta_kappa",
    "night_windows",
    "parse_mode",
    "plan_nights",
]

FloatArray = NDArray[np.float64]
MODES = ("quadrature", "conjunction", "zero-crossing", "fixed-u-pairs", "u=VALUE")
_SLEW_PAD_S = 0.0


@dataclass(frozen=True, slots=True)
class ModeSpec:
    """What a planning mode means for epochs, tolerances and sessions."""

    label: str
    anchor: str | float  # passed to find_epochs
    u_values: tuple[float, ...]  # for T_valid
    tol_kind: str
    paired: bool  # sessions of two blocks at alternating anchors


def parse_mode(text: str) -> ModeSpec:
    """``--mode`` → :class:`ModeSpec`.

    Raises
    ------
    UcbplanError
        For an unknown mode (lists the valid ones).
    """
    t = text.strip().lower()
    if t == "quadrature":
        return ModeSpec("quadrature", "quadrature", (0.0, math.pi), "quadrature", True)
    if t == "conjunction":
        return ModeSpec(
            "conjunction", "conjunction", (math.pi / 2, 3 * math.pi / 2), "conjunction", False
        )
    if t in ("zero-crossing", "zero_crossing"):
        return ModeSpec(
            "zero-crossing", "zero-crossing", (math.pi / 2, 3 * math.pi / 2), "conjunction", True
        )
    if t in ("fixed-u-pairs", "fixed-u", "pairs"):
        return ModeSpec("fixed-u-pairs", 0.0, (0.0,), "quadrature", False)
    m = re.fullmatch(r"u\s*=\s*([-+0-9.eE]+)", t)
    if m:
        try:
            value = float(m.group(1))
        except ValueError:
            value = float("nan")
        if math.isfinite(value):
            return ModeSpec(f"u={value:g}", value, (value,), "generic", False)
    raise UcbplanError(
        f"--mode: unknown mode {text!r}; expected quadrature, conjunction, zero-crossing, "
        "fixed-u-pairs or u=VALUE (radians, e.g. u=0.785)"
    )


@dataclass(frozen=True, slots=True)
class PlanSettings:
    """Everything the planner needs besides targets, site and nights (CLI options)."""

    mode: str = "quadrature"
    twilight: str = "nautical"
    airmass_max: float = 2.0
    moon_sep_deg: float = 30.0
    moon_illum_max: float | None = None
    zenith_hole_deg: float | None = None  # None: the site's value
    exposure: ExposurePlan = field(default_factory=ExposurePlan)
    alpha: float = 1.0
    n_epochs: int = 2
    sigma_v_kms: float | None = None
    k_eff_kms: float | None = None
    max_smear: str | None = None
    max_bin_fraction: float | None = None
    overhead_s: float = 300.0
    sessions_per_night: int = 1
    max_pair_baseline_days: float = 365.0
    star: int = 1

    def constraints(self, site: Site) -> list[Constraint]:
        """The constraint set for this run (night first: it explains most failures)."""
        out: list[Constraint] = [
            NightConstraint(self.twilight),
            AirmassConstraint(self.airmass_max),
        ]
        hole = self.zenith_hole_deg if self.zenith_hole_deg is not None else site.zenith_hole_deg
        if hole:
            out.append(ZenithHoleConstraint(hole))
        if self.moon_sep_deg > 0:
            out.append(MoonSeparationConstraint(self.moon_sep_deg))
        if self.moon_illum_max is not None:
            out.append(MoonIlluminationConstraint(self.moon_illum_max))
        return out


@dataclass(frozen=True, slots=True)
class Unplaced:
    """A target/night for which nothing (or less than asked) could be placed, and why."""

    target: str
    night: str
    reason: str


@dataclass(frozen=True)
class PlanResult:
    """Blocks (sorted by time), what could not be placed, warnings, provenance facts."""

    blocks: list[Block]
    unplaced: list[Unplaced]
    warnings: list[str]
    constraints: list[str]
    valid_until: dict[str, Time]


def night_windows(site: Site, nights: list[date]) -> list[tuple[str, Time, Time]]:
    """(label, start, end) UTC windows from local noon of each date to local noon the next day."""
    zone = site.zone
    out = []
    for d in nights:
        start = datetime.combine(d, time(12, 0), tzinfo=zone)
        end = datetime.combine(d + timedelta(days=1), time(12, 0), tzinfo=zone)
        with quiet_erfa():
            out.append((d.isoformat(), Time(start, scale="utc"), Time(end, scale="utc")))
    return out


@dataclass(frozen=True)
class Candidates:
    """All anchor epochs of one target in a span, as blocks on the site axis (arrays)."""

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


def candidate_blocks(
    target: Target,
    i: int,
    mode: ModeSpec,
    origin: Time,
    span_x: tuple[float, float],
    interp: DelayInterpolator,
    sky: SkyModel,
    constraints: list[Constraint],
    plan: ExposurePlan,
    star: int = 1,
) -> Candidates:
    """Every anchor epoch whose block centre lies in ``span_x`` (site TDB s after ``origin``).

    Notes
    -----
    Epochs from Eq. u_precessing_app (Newton, :func:`ucbplan.core.ephemeris.find_epochs`); site time
    t = t★ − Δ(t★) from the light-time spline; constraints over the whole block.
    """
    from ucbplan.core.ephemeris import find_epochs

    with quiet_erfa():
        offset = float((origin - target.t_ref).to_value(u.s))  # x = tau - offset
    lo, hi = span_x
    tau_lo, tau_hi = lo + offset - 600.0, hi + offset + 600.0
    es = find_epochs(target, tau_lo, tau_hi, mode.anchor, star)
    x_star = (es.origin_s - offset) + es.dt_s
    x_mid = interp.site_x(x_star)
    x_alt = interp.site_x(es.tau_alt_s - offset)
    keep = (x_mid >= lo) & (x_mid < hi)
    half = plan.span_s / 2.0
    x_mid = x_mid[keep]
    ok, first = evaluate_window(constraints, sky, i, x_mid - half, x_mid + half)
    return Candidates(
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
        airmass_mid=airmass_from_alt(sky.target_alt_deg(i, x_mid)),
    )


def delta_kappa(eta_a: float, kappa_a: float, theta: NDArray[np.floating]) -> FloatArray:
    """Δκ_LISA = −2 sin(Θ/2)[κ_α sin(Θ/2) + η_α cos(Θ/2)], Θ = ω̇ ΔT.

    Notes
    -----
    Eq. delta_kappa_rewrite; |Δκ| ≤ 2e, nulls at Θ = 2πm and at ω_α + Θ/2 = mπ (the apsidal nulls
    of Fig. apsidal_signal_omega1_dependence).
    """
    h = np.asarray(theta, dtype=np.float64) / 2.0
    return np.asarray(-2.0 * np.sin(h) * (kappa_a * np.sin(h) + eta_a * np.cos(h)))


@dataclass
class _Session:
    target_i: int
    night_i: int
    idx: tuple[int, ...]
    x0: float
    x1: float
    score: float


def _sessions(c: Candidates, paired: bool) -> tuple[NDArray[np.int64], FloatArray, FloatArray]:
    """Group blocks into sessions: partner index (−1 for single blocks), ok mask and score.

    A paired session starts with block j and continues with the first later block at the other
    anchor that starts after block j ends (u = 0 then π half an orbit later, or the next orbit if
    the blocks are longer than half an orbit).
    """
    n = c.x_mid.size
    if not paired or n == 0:
        return np.full(n, -1, dtype=np.int64), c.ok.astype(np.float64), c.airmass_mid
    nxt = np.minimum(np.searchsorted(c.x_start, c.x_end, side="left"), n - 1)
    same = np.isclose(np.mod(c.u_star[nxt] - c.u_star, 2 * math.pi), 0.0, atol=1e-6)
    nxt = np.where(same, nxt + 1, nxt)
    valid = (nxt < n) & (nxt > np.arange(n))
    nxt = np.minimum(nxt, n - 1).astype(np.int64)
    ok = valid & c.ok & c.ok[nxt]
    score = np.asarray(np.maximum(c.airmass_mid, c.airmass_mid[nxt]), dtype=np.float64)
    return nxt, ok.astype(np.float64), score


def _slug(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9]+", "_", name).strip("_") or "target"


def _tolerance_and_validity(
    target: Target, mode: ModeSpec, settings: PlanSettings
) -> tuple[float, Time, float | None, float | None]:
    """(δu_tol, valid-until TDB, σ_v, K) for a target; errors say which number is missing."""
    from ucbplan.core.forecast import t_valid, tolerance

    spec = target.spectroscopy
    sigma_v = settings.sigma_v_kms or (spec.sigma_v_kms if spec else None)
    k = settings.k_eff_kms or (spec.k_for_tolerance if spec else None)
    if sigma_v is None or k is None:
        raise UcbplanError(
            f"{target.name}: the tolerance needs sigma_v and K: add spectroscopy.sigma_v and "
            "K_eff (or K1/K2) to the target file, or pass --sigma-v and --k-eff (km/s)"
        )
    u_star = mode.u_values[0] if mode.tol_kind == "generic" else None
    tol = tolerance(mode.tol_kind, sigma_v, k, settings.n_epochs, u_star)
    tv = t_valid(target, tol, mode.u_values, settings.alpha, settings.star)
    with quiet_erfa():
        until = target.t_end + TimeDelta(tv * u.s)
    return tol, until, sigma_v, k


def _no_session_reason(
    c: Candidates,
    constraints: list[Constraint],
    sky: SkyModel,
    i: int,
    window: tuple[float, float],
) -> str:
    """Explain why no usable session exists in a night window."""
    night = constraints[0]
    assert isinstance(night, NightConstraint)
    xs = np.arange(window[0], window[1], 300.0)
    sun = sky.sun_alt_deg(xs)
    if sun.min() > night.sun_alt_max_deg:
        return (
            f"no {night.twilight} night: the Sun stays above {night.sun_alt_max_deg:g} deg "
            f"(lowest {sun.min():.1f} deg; polar day or summer at high latitude)"
        )
    dark = xs[sun <= night.sun_alt_max_deg]
    alt = sky.target_alt_deg(i, dark)
    am_limit = constraints[1]
    assert isinstance(am_limit, AirmassConstraint)
    if np.all(airmass_from_alt(alt) > am_limit.max_airmass):
        return (
            f"never at airmass <= {am_limit.max_airmass:g} during {night.twilight} night "
            f"(highest altitude {alt.max():.1f} deg)"
        )
    in_win = (c.x_mid >= window[0]) & (c.x_mid < window[1])
    fails = Counter(int(f) for f in c.first_failed[in_win] if f >= 0)
    if not fails:
        return "no session fits: the second block of each pair fails the constraints"
    worst = fails.most_common(1)[0][0]
    return f"every block {constraints[worst].reason()}"


def _conflicts(s: _Session, taken: list[tuple[float, float]], overhead_s: float) -> bool:
    """True if ``s`` (with its overhead before the start) overlaps any taken interval."""
    a0 = s.x0 - overhead_s
    return any(a0 < b1 and b0 - overhead_s < s.x1 for b0, b1 in taken)


@dataclass
class _TargetRun:
    target: Target
    cand: Candidates
    partner: NDArray[np.int64]
    ok: FloatArray
    score: FloatArray
    valid: NDArray[np.bool_]
    until: Time
    smearing: Smearing
    k_kms: float | None


def _make_blocks(
    run: _TargetRun,
    js: NDArray[np.int64],
    labels: list[tuple[str, str, str]],
    *,
    site: Site,
    location: EarthLocation,
    sky: SkyModel,
    i: int,
    origin: Time,
    settings: PlanSettings,
) -> list[Block]:
    """:class:`Block` records for candidates ``js`` of one target (UTC exact via astropy, in one
    vectorised conversion); ``labels`` = (night, block_id, session_id) per block."""
    if js.size == 0:
        return []
    c, t, sm = run.cand, run.target, run.smearing
    xs = np.stack([c.x_start[js], c.x_mid[js], c.x_end[js]], axis=1)
    alt = sky.target_alt_deg(i, xs)
    am = airmass_from_alt(alt)
    n_s = max(3, math.ceil(settings.exposure.span_s / 300.0) + 1)
    fine = c.x_start[js][:, None] + np.linspace(0, 1, n_s)[None, :] * settings.exposure.span_s
    sep = np.min(sky.moon_sep_deg(i, fine), axis=1)
    illum = sky.moon_illum(c.x_mid[js])
    with quiet_erfa():
        x_all = np.concatenate([xs, c.x_alt[js][:, None]], axis=1)
        utc = (Time(origin, location=location) + TimeDelta(x_all * u.s)).utc
        tdb = t.t_ref + TimeDelta(c.tau_origin_s * u.s) + TimeDelta(c.dt_s[js] * u.s)
    anchor = parse_mode(settings.mode).label
    out = []
    for k, j in enumerate(js):
        night, block_id, session_id = labels[k]
        out.append(
            Block(
                target=t.name,
                block_id=block_id,
                anchor=anchor,
                u_star_rad=float(np.mod(c.u_star[j], 2 * math.pi)),
                t_mid_utc=utc[k, 1],
                t_start_utc=utc[k, 0],
                t_end_utc=utc[k, 2],
                t_mid_tdb_bary=tdb[k],
                sigma_t_s=float(c.sigma_t_s[j]),
                t_alt_utc=utc[k, 3],
                exptime_s=settings.exposure.exptime_s,
                n_exp=settings.exposure.n_exp,
                readout_s=settings.exposure.readout_s,
                lambda_k=sm.lambda_k,
                lambda_kappa=sm.lambda_kappa,
                smear_kms=sm.smear_kms,
                alt_start_deg=float(alt[k, 0]),
                altitude_deg=float(alt[k, 1]),
                alt_end_deg=float(alt[k, 2]),
                airmass_start=float(am[k, 0]),
                airmass=float(am[k, 1]),
                airmass_end=float(am[k, 2]),
                moon_sep_deg=float(sep[k]),
                moon_illum=float(illum[k]),
                ra_deg=t.ra_deg,
                dec_deg=t.dec_deg,
                night=night,
                timezone=site.timezone,
                period_s=t.period_s,
                priority=t.priority,
                session_id=session_id,
            )
        )
    return out


def _prepare(
    targets: list[Target],
    site: Site,
    windows: list[tuple[str, Time, Time]],
    settings: PlanSettings,
) -> tuple[Time, SkyModel, list[_TargetRun], list[str], list[Constraint]]:
    """Shared sky model and light-time track, candidates and sessions for every target."""
    from astropy.coordinates import SkyCoord

    mode = parse_mode(settings.mode)
    constraints = settings.constraints(site)
    origin = Time(windows[0][1], location=site.location)
    with quiet_erfa():
        origin = Time(origin.tdb, location=site.location)
        x_hi = float((windows[-1][2] - origin).to_value(u.s))
    coords = SkyCoord([t.ra_deg for t in targets] * u.deg, [t.dec_deg for t in targets] * u.deg)
    sky = SkyModel.build(site.location, origin, (0.0, x_hi), coords)
    track = SiteTrack.build(origin, (0.0, x_hi), site.location)
    budget_warn: list[str] = []
    runs = []
    for i, t in enumerate(targets):
        _, until, sigma_v, k = _tolerance_and_validity(t, mode, settings)
        spec = t.spectroscopy
        k_smear = (spec.K1_kms if spec and spec.K1_kms else None) or k
        sm = block_smearing(settings.exposure, t.params.n_bar, k_smear)
        from ucbplan.core.smearing import parse_smear_budget

        max_smear = parse_smear_budget(settings.max_smear, sigma_v) if settings.max_smear else None
        budget_warn += check_smear_budget(t.name, sm, max_smear, settings.max_bin_fraction, sigma_v)
        interp = track.delay_interpolator(t.coord)
        cand = candidate_blocks(
            t,
            i,
            mode,
            origin,
            (0.0, x_hi),
            interp,
            sky,
            constraints,
            settings.exposure,
            settings.star,
        )
        with quiet_erfa():
            until_tau = float((until - t.t_ref).to_value(u.s))
        valid = (cand.tau_origin_s + cand.dt_s) <= until_tau
        partner, ok, score = _sessions(cand, mode.paired)
        valid = valid & ((partner < 0) | valid[np.maximum(partner, 0)])
        runs.append(_TargetRun(t, cand, partner, ok, score, valid, until, sm, k))
    return origin, sky, runs, budget_warn, constraints


def _place(
    runs: list[_TargetRun],
    win_x: list[tuple[str, float, float]],
    settings: PlanSettings,
    sky: SkyModel,
    constraints: list[Constraint],
) -> tuple[list[_Session], list[Unplaced]]:
    """Greedy night schedule: targets by priority, each night's best sessions (lowest airmass)
    that keep the overhead gap to everything already placed."""
    taken: dict[int, list[tuple[float, float]]] = {n: [] for n in range(len(win_x))}
    placed: list[_Session] = []
    unplaced: list[Unplaced] = []
    order = sorted(range(len(runs)), key=lambda k: -runs[k].target.priority)
    for i in order:
        run, c = runs[i], runs[i].cand
        name = run.target.name
        for n, (label, x0, x1) in enumerate(win_x):
            j0, j1 = np.searchsorted(c.x_mid, [x0, x1])
            if j1 == j0:
                unplaced.append(Unplaced(name, label, "no anchor epoch in the night window"))
                continue
            js = np.arange(j0, j1)
            usable = js[(run.ok[js] > 0) & run.valid[js]]
            if usable.size == 0:
                if not np.any(run.valid[js]):
                    reason = (
                        f"past T_valid: {parse_mode(settings.mode).label} epochs are valid until "
                        f"{run.until.utc.iso[:16]} UTC (alpha={settings.alpha:g}); pick an "
                        "earlier night or a larger --alpha"
                    )
                else:
                    reason = _no_session_reason(c, constraints, sky, i, (x0, x1))
                unplaced.append(Unplaced(name, label, reason))
                continue
            usable = usable[np.argsort(run.score[usable], kind="stable")]
            count = 0
            for j in usable:
                idx = (int(j),) if run.partner[j] < 0 else (int(j), int(run.partner[j]))
                sess = _Session(i, n, idx, float(c.x_start[idx[0]]), float(c.x_end[idx[-1]]), 0.0)
                if _conflicts(sess, taken[n], settings.overhead_s):
                    continue
                taken[n].append((sess.x0, sess.x1))
                placed.append(sess)
                count += 1
                if count == settings.sessions_per_night:
                    break
            if count == 0:
                unplaced.append(
                    Unplaced(
                        name,
                        label,
                        f"all {usable.size} usable sessions overlap higher-priority blocks "
                        f"(with {settings.overhead_s:g} s slew/acquisition overhead)",
                    )
                )
            elif count < settings.sessions_per_night:
                unplaced.append(
                    Unplaced(
                        name, label, f"only {count} of {settings.sessions_per_night} sessions fit"
                    )
                )
    return placed, unplaced


def plan_nights(
    targets: list[Target],
    site: Site,
    nights: list[date],
    settings: PlanSettings,
) -> PlanResult:
    """Plan blocks for ``targets`` at ``site`` on the given local evening dates.

    Parameters
    ----------
    targets : list of Target
        Loaded targets (priorities from the files).
    site : Site
        Observatory.
    nights : list of date
        Local dates of the evenings the nights start.
    settings : PlanSettings
        Mode, constraints, exposure plan, tolerance inputs, overheads.

    Returns
    -------
    PlanResult

    Raises
    ------
    UcbplanError
        For missing tolerance inputs, exceeded smearing budgets or bad options.

    Notes
    -----
    Anchor epochs: Eq. u_precessing_app (Appendix A2); σ_t: Eq. sigma_tstar; validity: Eq.
    T_valid_alpha; smearing: Eqs. Lambda_K, Lambda_kappa; fixed-u pairs: Eq. delta_kappa_rewrite.
    """
    from ucbplan.observing.timeconv import coverage_warnings

    if not targets:
        raise UcbplanError("no targets given; pass one or more target YAML files")
    if not nights:
        raise UcbplanError("--nights must be >= 1")
    mode = parse_mode(settings.mode)
    if mode.label == "fixed-u-pairs":
        for t in targets:
            if t.params.omega_dot == 0.0 or t.params.eccentricity == 0.0:
                raise UcbplanError(
                    f"{t.name}: Delta-kappa_LISA is 0 (circular orbit or no apsidal motion); "
                    "fixed-u pairs would only measure Delta-v_CM: use --mode quadrature or u=VALUE"
                )
    windows = night_windows(site, nights)
    origin, sky, runs, warns, constraints = _prepare(targets, site, windows, settings)
    with quiet_erfa():
        win_x = [
            (lab, float((a - origin).to_value(u.s)), float((b - origin).to_value(u.s)))
            for lab, a, b in windows
        ]
    placed, unplaced = _place(runs, win_x, settings, sky, constraints)
    blocks: list[Block] = []
    counters: Counter[tuple[int, int]] = Counter()
    sessions_seen: Counter[tuple[int, int]] = Counter()
    per_target: dict[int, tuple[list[int], list[tuple[str, str, str]]]] = {}
    for sess in sorted(placed, key=lambda s: (s.target_i, s.x0)):
        run = runs[sess.target_i]
        label = win_x[sess.night_i][0]
        slug = f"{_slug(run.target.name)}-{label.replace('-', '')}"
        js, labels = per_target.setdefault(sess.target_i, ([], []))
        sessions_seen[(sess.target_i, sess.night_i)] += 1
        session_id = f"{slug}-S{sessions_seen[(sess.target_i, sess.night_i)]:02d}"
        for j in sess.idx:
            counters[(sess.target_i, sess.night_i)] += 1
            js.append(j)
            block_id = f"{slug}-{counters[(sess.target_i, sess.night_i)]:02d}"
            labels.append((label, block_id, session_id))
    location = site.location
    for i, (js, labels) in per_target.items():
        blocks += _make_blocks(
            runs[i],
            np.asarray(js, dtype=np.int64),
            labels,
            site=site,
            location=location,
            sky=sky,
            i=i,
            origin=origin,
            settings=settings,
        )
    if mode.label == "fixed-u-pairs":
        blocks, more = _pair_blocks(blocks, runs, site, settings)
        unplaced += more
    blocks.sort(key=lambda b: (b.t_mid_utc.jd1, b.t_mid_utc.jd2))
    warns = warns + coverage_warnings(windows[0][1], windows[-1][2])
    return PlanResult(
        blocks=blocks,
        unplaced=unplaced,
        warnings=warns,
        constraints=[c.describe() for c in constraints],
        valid_until={r.target.name: r.until for r in runs},
    )


def _pair_blocks(
    firsts: list[Block], runs: list[_TargetRun], site: Site, settings: PlanSettings
) -> tuple[list[Block], list[Unplaced]]:
    """For each first epoch, the second epoch maximising |Δκ_LISA| inside T_valid."""
    from ucbplan.core.ephemeris import ll_pair

    out: list[Block] = []
    unplaced: list[Unplaced] = []
    by_name = {r.target.name: r for r in runs}
    for n, first in enumerate(firsts):
        run = by_name[first.target]
        t, p = run.target, run.target.params
        with quiet_erfa():
            tau_a = float((first.t_mid_tdb_bary - t.t_ref).to_value(u.s))
        eta_arr, kappa_arr = ll_pair(p, np.array([tau_a]))
        eta_a, kappa_a = float(eta_arr[0]), float(kappa_arr[0])
        night0 = date.fromisoformat(first.night)
        with quiet_erfa():
            days_valid = (run.until - first.t_mid_tdb_bary).to_value(u.d)
        max_days = int(min(days_valid - 1, settings.max_pair_baseline_days))
        if max_days < 1:
            unplaced.append(Unplaced(t.name, first.night, "no second night inside T_valid"))
            out.append(first)
            continue
        days = np.arange(1, max_days + 1)
        dk = delta_kappa(eta_a, kappa_a, p.omega_dot * days * 86400.0)
        order = days[np.argsort(-np.abs(dk), kind="stable")]
        good = order[np.abs(dk[order - 1]) >= 0.8 * np.abs(dk).max()][:12]
        second = None
        for d in good:
            single = replace(settings, mode="u=0", sessions_per_night=1)
            res = plan_nights([t], site, [night0 + timedelta(days=int(d))], single)
            if res.blocks:
                second = res.blocks[0]
                break
        pair = f"{_slug(t.name)}-P{n + 1:02d}"
        if second is None:
            unplaced.append(
                Unplaced(
                    t.name,
                    first.night,
                    f"no observable second epoch on the {good.size} nights with |Delta-kappa| "
                    ">= 0.8 of its maximum inside T_valid",
                )
            )
            out.append(replace(first, pair_id=pair))
            continue
        with quiet_erfa():
            dt = float((second.t_mid_tdb_bary - first.t_mid_tdb_bary).to_value(u.s))
        dk_pair = float(delta_kappa(eta_a, kappa_a, np.array([p.omega_dot * dt]))[0])
        out.append(replace(first, pair_id=pair, delta_kappa=dk_pair))
        out.append(
            replace(
                second,
                anchor="fixed-u-pairs",
                pair_id=pair,
                delta_kappa=dk_pair,
                session_id=second.session_id,
            )
        )
    return out, unplaced
