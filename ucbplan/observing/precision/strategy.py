"""Information per telescope hour: the exposure time and cadence that measure K fastest.

One spectrum of length T centred at argument of latitude u measures v = γ + K Λ_K cos u + noise
(σ_v), Λ_K = sin x / x with x = n̄_b T/2 (Eq. Lambda_K). Its Fisher information on K is
w = (Λ_K cos u)² / σ_v², and spectra balanced between u = 0 and π give σ_K = (Σ w_i)^{-½}
(docs/method.md, "Information per hour"). With a photon-limited σ_v(T) (:mod:`.sigma_model`) a
longer exposure is more precise but more smeared, and its readout and the wait for the next
anchor cost time: this module finds, by an exhaustive scan of whole-second exposure times, the
exposure time of each strategy that collects the most information in a visit, and the best
strategy.

Strategies in a visit of length W (acquisition A included; the rest, S = W − A, holds the
exposures and their readouts r), anchors Δ apart (P_b/2 for quadratures):

``targeted``
    every exposure centred on an anchor; the next one waits for the next anchor it can reach:
    step ⌈(T + r)/Δ⌉·Δ, n = ⌊(S − T − r)/step⌋ + 1 exposures.
``phase-locked``
    T = kΔ − r (the smallest whole k with T > 0, less a small margin): consecutive exposures on
    consecutive reachable anchors without waiting; held to the smearing floor like the others.
``untargeted``
    back-to-back exposures at whatever phase they fall (what an observer does without a phase
    model): n = ⌊(S + r)/(T + r)⌋, each worth ⟨cos² u⟩ = ½ of a targeted one on average.

Every strategy keeps Λ_K ≥ the floor (0.9 by default) unless smeared exposures are allowed, and
T ≥ the instrument's minimum. A goal (σ_K, or anything derived from the K's) needs the
information I = (σ_goal(I = 1)/goal)²; its hours are those of the fewest balanced visits that
hold the spectra (:func:`goal_time`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ucbplan.core.constants import HOUR_S
from ucbplan.core.smearing import lambda_k
from ucbplan.errors import InputError
from ucbplan.observing.precision.goals import MAX_SPECTRA, check_goal_spectra

#: The strategies compared, in the order they are reported.
STRATEGIES = ("targeted", "phase-locked", "untargeted")
#: Mean cos² u of an exposure at a random phase (untargeted).
UNTARGETED_COS2 = 0.5
#: Time kept free in each step of a phase-locked cadence besides the readout [s] (the anchors of
#: an eccentric orbit are not evenly spaced; the light time drifts them by ≤ 0.02 s/min).
LOCK_MARGIN_S = 0.2
#: Longest exposure time scanned [s] (a block fits in a night).
MAX_SCAN_S = 43200.0

F64 = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class VisitShape:
    """What one visit allows a target (all times in seconds).

    Attributes
    ----------
    period_s : float
        Orbital period P_b (anomalistic; the anchors repeat with it).
    n_bar : float
        Mean orbital rate n̄_b [rad/s] (sets Λ_K).
    pattern_u : tuple of float
        Anchor phases u★ of one orbit [rad], evenly spaced (0, π for quadratures).
    readout_s, acquisition_s, visit_s : float
        Readout per exposure, acquisition per visit, visit length (acquisition included).
    min_lambda_k : float
        Smearing floor (0 = none).
    min_exptime_s, granularity_s : float
        Shortest exposure and the step exposure times are chosen in (1 s: whole seconds).
    eccentricity : float
        e (the anchors of an eccentric orbit are up to 2e·Δ closer: phase-locked keeps clear).
    """

    period_s: float
    n_bar: float
    pattern_u: tuple[float, ...]
    readout_s: float
    acquisition_s: float
    visit_s: float
    min_lambda_k: float = 0.9
    min_exptime_s: float = 1.0
    granularity_s: float = 1.0
    eccentricity: float = 0.0

    @property
    def spacing_s(self) -> float:
        """Time between consecutive anchors Δ = P_b/m [s]."""
        return self.period_s / len(self.pattern_u)

    @property
    def science_s(self) -> float:
        """Time for exposures and readouts after the acquisition [s]."""
        return self.visit_s - self.acquisition_s

    def exptimes(self) -> F64:
        """Exposure times scanned: multiples of the granularity from the minimum up to the
        smearing floor and the visit [s]."""
        g = self.granularity_s
        lo = max(g, math.ceil(self.min_exptime_s / g - 1e-9) * g)
        hi = min(self.science_s - self.readout_s, MAX_SCAN_S)
        if self.min_lambda_k > 0:
            hi = min(hi, floor_exptime_s(self.n_bar, self.min_lambda_k))
        if hi < lo:
            return np.zeros(0)
        return np.asarray(lo + g * np.arange(math.floor((hi - lo) / g + 1e-9) + 1), np.float64)


def floor_exptime_s(n_bar: float, floor: float) -> float:
    """Longest single exposure with Λ_K ≥ ``floor`` [s] (sin x/x = floor, x = n̄ T/2)."""
    if floor <= 0:
        return math.inf
    lo, hi = 0.0, math.pi  # sin x / x falls from 1 to 0 on [0, π]
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if math.sin(mid) / mid >= floor else (lo, mid)
    return 2.0 * lo / n_bar


def constrains_k(pattern_u: Sequence[float]) -> bool:
    """Whether some anchor of the pattern measures K (cos u★ ≠ 0); else the anchors (at
    conjunctions or zero crossings) measure γ, and the information counted is γ's."""
    return bool(np.max(np.cos(np.asarray(pattern_u, dtype=np.float64)) ** 2) > 1e-6)


def pattern_weight(pattern_u: Sequence[float]) -> F64:
    """Information weight g² of an exposure at each anchor of the pattern: cos² u★ when the
    pattern constrains K (:func:`constrains_k`), else 1."""
    c2 = np.cos(np.asarray(pattern_u, dtype=np.float64)) ** 2
    return c2 if constrains_k(pattern_u) else np.ones_like(c2)


@dataclass(frozen=True, slots=True)
class StrategyResult:
    """The best exposure time of one strategy and what it buys in one visit.

    Attributes
    ----------
    name : str
        ``targeted``, ``phase-locked`` or ``untargeted``.
    exptime_s : float
        Chosen exposure time [s] (NaN when the strategy is not possible).
    lambda_k : float
        Λ_K of one exposure.
    n_exposures : int
        Exposures in one visit.
    step_s : float
        Centre-to-centre time of consecutive exposures [s].
    sigma_v_kms : float
        σ_v of one exposure at the reference airmass [km/s].
    info_per_visit : float
        Fisher information on K of one visit [(km/s)⁻²] (the expected value for untargeted).
    wall_s : float
        Wall time the visit uses: acquisition + exposures + readouts + waits [s].
    note : str
        Why the strategy is not possible, or what limits it (empty otherwise).
    """

    name: str
    exptime_s: float
    lambda_k: float
    n_exposures: int
    step_s: float
    sigma_v_kms: float
    info_per_visit: float
    wall_s: float
    note: str = ""

    @property
    def possible(self) -> bool:
        """Whether the strategy plans at least one exposure."""
        return self.n_exposures > 0 and self.info_per_visit > 0

    @property
    def info_per_hour(self) -> float:
        """Information per hour of the visit's wall time [(km/s)⁻² h⁻¹]."""
        return self.info_per_visit / (self.wall_s / HOUR_S) if self.wall_s > 0 else 0.0

    @property
    def sigma_k_per_visit(self) -> float:
        """σ_K one visit reaches, (info)^{-½} [km/s] (inf when nothing is measured)."""
        return 1.0 / math.sqrt(self.info_per_visit) if self.info_per_visit > 0 else math.inf


SigmaOfT = Callable[[F64], F64]


def _targeted_counts(shape: VisitShape, t: F64) -> tuple[F64, NDArray[np.int64]]:
    """Step and number of exposures of the targeted cadence for exposure times ``t``."""
    d = shape.spacing_s
    step = np.ceil((t + shape.readout_s) / d * (1.0 - 1e-12)) * d
    n = np.floor((shape.science_s - t - shape.readout_s) / step + 1e-9) + 1
    return step, np.maximum(n, 0).astype(np.int64)


def _pattern_sum(shape: VisitShape, step: F64, n: NDArray[np.int64]) -> F64:
    """Σ g² over n exposures stepping ``step/Δ`` anchors each, from the best starting anchor."""
    g2 = pattern_weight(shape.pattern_u)
    if np.all(g2 == g2[0]):
        return np.asarray(n * float(g2[0]), dtype=np.float64)
    m = g2.size
    k = np.rint(step / shape.spacing_s).astype(np.int64)
    out = np.zeros(n.shape)
    for i in range(n.size):  # the visited anchors repeat within m exposures
        ni = int(n[i])
        if ni <= 0:
            continue
        idx = (np.arange(m)[:, None] + k[i] * np.arange(min(ni, m))[None, :]) % m
        vals = g2[idx]  # (starting anchor, exposure)
        full, rest = divmod(ni, m)
        out[i] = float(np.max(full * vals.sum(axis=1) + vals[:, :rest].sum(axis=1)))
    return out


@dataclass(frozen=True, slots=True)
class _Scan:
    """Every exposure time a strategy may take, with what one visit of each holds."""

    name: str
    t: F64
    n: NDArray[np.int64]
    step: F64
    info: F64  # per visit [(km/s)⁻²]
    sig: F64
    note: str = ""

    def wall(self, shape: VisitShape) -> F64:
        """Wall time of one full visit of each exposure time [s]."""
        return shape.acquisition_s + (self.n - 1) * self.step + self.t + shape.readout_s

    def result(self, shape: VisitShape, i: int | None) -> StrategyResult:
        """The result of exposure time number ``i`` (None: not possible)."""
        if i is None:
            return StrategyResult(
                self.name, math.nan, math.nan, 0, math.nan, math.nan, 0.0, 0.0, self.note
            )
        return StrategyResult(
            self.name,
            float(self.t[i]),
            float(lambda_k(self.t[i], shape.n_bar)),
            int(self.n[i]),
            float(self.step[i]),
            float(self.sig[i]),
            float(self.info[i]),
            float(self.wall(shape)[i]),
        )

    def most_info(self, shape: VisitShape) -> StrategyResult:
        """The exposure time with the most information per visit (ties: the shorter wall
        time, then the shorter exposure)."""
        if self.t.size == 0 or not np.any(self.info > 0):
            return self.result(shape, None)
        order = np.lexsort((self.t, self.wall(shape), -np.round(self.info, 12)))
        return self.result(shape, int(order[0]))


def _none(name: str, note: str) -> _Scan:
    empty = np.zeros(0)
    return _Scan(name, empty, np.zeros(0, np.int64), empty, empty, empty, note)


def _targeted_scan(name: str, shape: VisitShape, sigma: SigmaOfT, t: F64) -> _Scan:
    step, n = _targeted_counts(shape, t)
    sig = sigma(t)
    info = _pattern_sum(shape, step, n) * lambda_k(t, shape.n_bar) ** 2 / sig**2
    return _Scan(name, t, n, step, info, sig)


def targeted(shape: VisitShape, sigma: SigmaOfT) -> _Scan:
    """Every ``targeted`` exposure time (module notes)."""
    t = shape.exptimes()
    if t.size == 0:
        return _none("targeted", "no exposure fits the visit within the smearing floor")
    return _targeted_scan("targeted", shape, sigma, t)


def phase_locked(shape: VisitShape, sigma: SigmaOfT) -> _Scan:
    """``phase-locked``: T = kΔ − r − margin for the smallest whole k with T ≥ the minimum."""
    d = shape.spacing_s
    short = d * (1.0 - 2.0 * shape.eccentricity) - LOCK_MARGIN_S
    g = shape.granularity_s
    k = max(1, math.ceil((shape.readout_s + max(shape.min_exptime_s, g)) / short * (1 - 1e-12)))
    t_lock = math.floor((k * short - shape.readout_s) / g + 1e-9) * g
    lam = float(lambda_k(t_lock, shape.n_bar))
    if shape.min_lambda_k > 0 and lam < shape.min_lambda_k:
        return _none(
            "phase-locked",
            f"{t_lock:.0f}-s exposures give Lambda_K = {lam:.2f} < {shape.min_lambda_k:g}",
        )
    if t_lock + shape.readout_s > shape.science_s:
        return _none("phase-locked", "one exposure does not fit the visit")
    return _targeted_scan("phase-locked", shape, sigma, np.array([t_lock]))


def untargeted(shape: VisitShape, sigma: SigmaOfT) -> _Scan:
    """Every ``untargeted`` exposure time: back-to-back, ⟨cos² u⟩ = ½ (module notes)."""
    t = shape.exptimes()
    if t.size == 0:
        return _none("untargeted", "no exposure fits the visit within the smearing floor")
    step = t + shape.readout_s
    n = np.floor(shape.science_s / step + 1e-9).astype(np.int64)  # the last readout included
    g2 = UNTARGETED_COS2 if constrains_k(shape.pattern_u) else 1.0  # γ: every phase counts
    sig = sigma(t)
    info = n * g2 * lambda_k(t, shape.n_bar) ** 2 / sig**2
    return _Scan("untargeted", t, n, step, info, sig)


_SCANS = {"targeted": targeted, "phase-locked": phase_locked, "untargeted": untargeted}


def compare_strategies(
    shape: VisitShape, sigma: SigmaOfT, names: Sequence[str] = STRATEGIES
) -> list[StrategyResult]:
    """The best exposure time of every strategy in ``names`` for one visit of ``shape``.

    Parameters
    ----------
    shape : VisitShape
        Period, anchors, overheads, visit length and limits.
    sigma : callable
        σ_v [km/s] of exposures of the given lengths [s] (vectorised), e.g.
        ``lambda t: model.sigma(t, airmass, mag)``.
    """
    _check_shape(shape)
    return [_SCANS[name](shape, sigma).most_info(shape) for name in names]


def best_strategy(results: Sequence[StrategyResult]) -> StrategyResult:
    """The result with the most information per visit (ties: the first named).

    Raises
    ------
    InputError
        No strategy plans an exposure.
    """
    possible = [r for r in results if r.possible]
    if not possible:
        why = "; ".join(f"{r.name}: {r.note}" for r in results if r.note)
        raise InputError(f"no exposure strategy fits the visit ({why}); lengthen `visit`")
    return max(possible, key=lambda r: r.info_per_visit)


def session_result(shape: VisitShape, sigma: SigmaOfT, n_blocks: int) -> StrategyResult:
    """The targeted exposure time with the most information per hour of a session: one
    acquisition, then ``n_blocks`` exposures on consecutive reachable anchors (``shape.visit_s``
    only bounds the exposure time)."""
    _check_shape(shape)
    t = shape.exptimes()
    if t.size == 0:
        return _none("targeted", "no exposure keeps the smearing floor").result(shape, None)
    step, _ = _targeted_counts(shape, t)
    n = np.full(t.shape, n_blocks, dtype=np.int64)
    sig = sigma(t)
    info = _pattern_sum(shape, step, n) * lambda_k(t, shape.n_bar) ** 2 / sig**2
    return _best_rate(_Scan("targeted", t, n, step, info, sig), shape)


def _best_rate(scan: _Scan, shape: VisitShape) -> StrategyResult:
    """The exposure time of ``scan`` with the most information per hour of its wall time."""
    rate = np.round(scan.info / scan.wall(shape), 15)
    return scan.result(shape, int(np.lexsort((scan.t, -rate))[0]))


def _check_shape(shape: VisitShape) -> None:
    for name, value in (
        ("period", shape.period_s),
        ("readout", shape.readout_s),
        ("acquisition", shape.acquisition_s),
        ("visit", shape.visit_s),
    ):
        if not math.isfinite(value) or value < 0:
            raise InputError(f"{name}: expected non-negative seconds, got {value:g}")
    if not shape.pattern_u:
        raise InputError("anchors: expected at least one anchor phase")


@dataclass(frozen=True, slots=True)
class GoalTime:
    """Spectra, balanced visits and wall time that reach an information goal with one strategy.

    Attributes
    ----------
    strategy : StrategyResult
        The strategy at the exposure time with the fewest hours (its full-visit numbers).
    info_needed : float
        Information on K the goal needs [(km/s)⁻²].
    n_spectra, n_visits : int
        Spectra and visits (0 and inf hours when the strategy is not possible).
    per_visit : tuple of int
        Spectra of each visit, as even as whole anchor patterns allow.
    hours : float
        Wall time: Σ over visits of acquisition + (n − 1)·step + T + r [h].
    """

    strategy: StrategyResult
    info_needed: float
    n_spectra: int
    n_visits: int
    per_visit: tuple[int, ...]
    hours: float


def _goal_counts(
    info_needed: float, per_spectrum: F64, n_max: NDArray[np.int64], unit: F64
) -> tuple[F64, F64]:
    """(spectra, visits) of a goal, vectorised: ⌈I/w⌉ spectra in whole ``unit`` groups, in the
    fewest visits of at most ``n_max`` (the arithmetic of :func:`balanced_counts`)."""
    n = np.maximum(1.0, np.ceil(info_needed / per_spectrum * (1.0 - 1e-12)))
    unit = np.where(n_max >= unit, unit, 1.0)
    groups = np.ceil(n / unit)
    per_max = np.maximum(1.0, np.floor(n_max / unit))
    return groups * unit, np.ceil(groups / per_max)


def balanced_counts(n: int, n_max: int, pattern: int) -> tuple[int, ...]:
    """``n`` spectra in the fewest visits of at most ``n_max``, in whole anchor patterns when a
    visit holds one, split as evenly as whole patterns allow (the fuller visits first)."""
    unit = pattern if n_max >= pattern else 1
    groups, per_max = math.ceil(n / unit), max(1, n_max // unit)
    visits = math.ceil(groups / per_max)
    base, extra = divmod(groups, visits)
    return tuple(unit * (base + (1 if v < extra else 0)) for v in range(visits))


def goal_times(info_needed: float, shape: VisitShape, sigma: SigmaOfT, goal: str) -> list[GoalTime]:
    """:func:`goal_time` of every strategy (:data:`STRATEGIES`) for the goal ``goal`` (its text).

    Raises
    ------
    InputError
        Every strategy needs more than ``MAX_SPECTRA`` spectra at every exposure time: the one
        goal-magnitude check, :func:`~ucbplan.observing.precision.goals.check_goal_spectra`.
    """
    times = [goal_time(info_needed, shape, sigma, name) for name in STRATEGIES]
    counts = [g.n_spectra for g in times if g.n_visits or g.n_spectra > MAX_SPECTRA]
    if counts:
        check_goal_spectra(goal, min(counts))
    return times


def goal_time(
    info_needed: float, shape: VisitShape, sigma: SigmaOfT, name: str = "targeted"
) -> GoalTime:
    """The exposure time of strategy ``name`` that reaches ``info_needed`` in the fewest hours,
    in the fewest balanced visits of at most ``shape.visit_s`` (an exhaustive scan).

    N = ⌈I/w⌉ spectra of w = info per visit / exposures per visit each (whole anchor patterns
    for the targeted strategies), in V = ⌈N/n_max⌉ visits split as evenly as possible; the
    hours are V·(A + T + r − step) + N·step. A goal needing more than ``MAX_SPECTRA`` spectra
    at every exposure time is not possible (no visit is counted); its ``n_spectra`` is then the
    fewest needed, for :func:`goal_times`'s refusal.
    """
    _check_shape(shape)
    scan = _SCANS[name](shape, sigma)
    ok = (scan.n > 0) & (scan.info > 0)
    if not np.any(ok):
        return GoalTime(scan.result(shape, None), info_needed, 0, 0, (), math.inf)
    w = np.where(ok, scan.info / np.maximum(scan.n, 1), np.nan)
    unit = np.full(w.shape, 1.0 if name == "untargeted" else float(len(shape.pattern_u)))
    n, visits = _goal_counts(info_needed, w, scan.n, unit)
    fewest = float(np.min(np.where(ok, n, np.inf)))
    if not fewest <= MAX_SPECTRA:  # a typo goal: never build 10¹² visits
        too_many = int(min(fewest, MAX_SPECTRA + 1))
        return GoalTime(scan.result(shape, None), info_needed, too_many, 0, (), math.inf)
    wall = visits * (shape.acquisition_s + scan.t + shape.readout_s - scan.step) + n * scan.step
    wall = np.where(ok, wall, np.inf)
    i = int(np.lexsort((scan.t, np.round(wall, 6)))[0])
    counts = balanced_counts(int(n[i]), int(scan.n[i]), int(unit[i]))
    return GoalTime(
        scan.result(shape, i), info_needed, int(n[i]), len(counts), counts, float(wall[i]) / HOUR_S
    )


def information(lambda_k_rows: ArrayLike, u_rad: ArrayLike, sigma_v_kms: ArrayLike) -> float:
    """Σ (Λ_K,i cos u_i)² / σ_v,i² [(km/s)⁻²]: the information on K of planned spectra (γ
    known); NaN rows (unknown σ_v) count nothing."""
    g = np.asarray(lambda_k_rows, dtype=np.float64) * np.cos(np.asarray(u_rad, dtype=np.float64))
    w = (g / np.asarray(sigma_v_kms, dtype=np.float64)) ** 2
    return float(np.nansum(w))


def sigma_k_from_rows(lambda_k_rows: ArrayLike, u_rad: ArrayLike, sigma_v_kms: ArrayLike) -> float:
    """σ_K [km/s] of planned spectra with γ free: √[(F⁻¹)_KK] of the (γ, K) Fisher matrix
    F = Σ_i (1, Λ_i cos u_i)ᵀ(1, Λ_i cos u_i)/σ_i² (inf when K is not constrained)."""
    g = np.asarray(lambda_k_rows, dtype=np.float64) * np.cos(np.asarray(u_rad, dtype=np.float64))
    w = 1.0 / np.asarray(sigma_v_kms, dtype=np.float64) ** 2
    ok = np.isfinite(g) & np.isfinite(w)
    g, w = g[ok], w[ok]
    s0, s1, s2 = float(np.sum(w)), float(np.sum(w * g)), float(np.sum(w * g * g))
    det = s0 * s2 - s1 * s1
    if s0 <= 0 or det <= 1e-12 * max(s0 * s2, 1e-300):
        return math.inf
    return math.sqrt(s0 / det)
