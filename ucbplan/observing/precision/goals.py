"""Goal-driven exposure plans: how many spectra, visits and hours reach a precision goal.

A goal names a precision on one quantity (:func:`parse_goal`): ``sigma_K=2km/s``, ``K1=1%``,
``K2=3km/s``, ``q=1%``, ``M1=0.01Msun``, ``M2=2%``. :func:`spectra_for_goal` turns it into a
number of spectra from the Fisher matrix of the regression ``reduce`` fits to each star
(docs/method.md, "Smearing": slopes on the window-averaged F̄ = Λ_K cos u + …):

    v_i = γ + K Λ_K cos u_i + noise(σ_v),   F = Σ_i (1, Λ_K cos u_i)ᵀ (1, Λ_K cos u_i) / σ_v².

The spectra repeat a pattern of anchors (one u★ each, e.g. u = 0 and π for ``quadrature``); one
pattern of m spectra has Fisher matrix F₁ and c patterns c F₁, so σ_K(c) = σ_K(1)/√c. For
quadratures in equal numbers F = diag(N, N Λ_K²)/σ_v², hence

    σ_K² = σ_v² / (N Λ_K²),   N = ⌈σ_v² / (σ_K² Λ_K²)⌉ rounded up to an even number.

The Λ_κ (eccentricity) terms of F̄ are O(e) and left out here. Double-lined (SB2) spectra measure
both stars from the same exposures, with independent velocity errors (σ_v for star 1,
``sigma_v2_kms`` for star 2, the same by default), so σ_K1 and σ_K2 follow from the same N.

Derived quantities (docs/method.md; Eqs. semimajor_axis_j, Kepler_mtot, M1M2_cir_and_ecc with P_b
and ι from LISA taken as exact):

    q = K1/K2 = M2/M1,                       (σ_q/q)² = (σ_K1/K1)² + (σ_K2/K2)²
    M1 sin³ι = (1 − e²)^{3/2} P_b K2 (K1 + K2)² / (2πG),   M2: K1 ↔ K2 in the first factor
    (σ_M1/M1)² = (2σ_K1/(K1+K2))² + ((1/K2 + 2/(K1+K2)) σ_K2)²
    (σ_M2/M2)² = ((1/K1 + 2/(K1+K2)) σ_K1)² + (2σ_K2/(K1+K2))²
(the inclination's own uncertainty, 3 σ_sin ι / sin ι on the masses, is not included).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ucbplan.core.binary import a_total_m, kepler_total_mass
from ucbplan.core.constants import HOUR_S, MSUN_KG
from ucbplan.core.mvnormal import inverse_scaled
from ucbplan.errors import InputError, shorten

if TYPE_CHECKING:
    from ucbplan.targets import Target

#: Goal quantities and the units their absolute form takes.
GOAL_QUANTITIES = {
    "sigma_K": "km/s",
    "K1": "km/s",
    "K2": "km/s",
    "q": "",
    "M1": "Msun",
    "M2": "Msun",
}
_UNITS = {"km/s": "km/s", "kms": "km/s", "km s-1": "km/s", "msun": "Msun", "m_sun": "Msun"}
_GOAL_RE = re.compile(
    r"^\s*([A-Za-z_0-9]+)\s*=\s*([+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)\s*([^\s].*?)?\s*$"
)
#: Most spectra a goal may ask for (beyond, the goal is not a plan but a typo).
MAX_SPECTRA = 10**7


@dataclass(frozen=True)
class Goal:
    """A precision goal: σ of ``quantity`` ≤ ``value`` (a fraction of it when ``relative``)."""

    quantity: str
    value: float
    relative: bool
    text: str

    def describe(self) -> str:
        """The goal as a short text, e.g. ``σ(q) ≤ 1 %`` or ``σ(K1) ≤ 2 km/s``."""
        if self.relative:
            return f"σ({self.quantity}) ≤ {100 * self.value:g} %"
        unit = GOAL_QUANTITIES[self.quantity]
        name = "K" if self.quantity == "sigma_K" else self.quantity
        return f"σ({name}) ≤ {self.value:g}{' ' + unit if unit else ''}"


@dataclass(frozen=True)
class TimeBudget:
    """Wall time of a goal's spectra in visits (all durations in hours except ``step_s``)."""

    n_visits: int
    spectra_per_visit: int
    step_s: float
    shutter_h: float
    overhead_h: float
    idle_h: float
    total_h: float

    @property
    def efficiency(self) -> float:
        """Shutter / (shutter + overheads + idle)."""
        return self.shutter_h / self.total_h if self.total_h > 0 else 0.0


@dataclass(frozen=True)
class GoalPlan:
    """Spectra, anchors, σ reached and time of a goal; ``collected_fisher``: ObservedFisher's."""

    goal: Goal
    n_spectra: int
    per_anchor: tuple[tuple[str, int], ...]
    expected: float
    sigma_K1_kms: float
    sigma_K2_kms: float | None
    time: TimeBudget | None
    cycles: int = 1
    info_needed: float | None = None
    visit_s: float | None = None
    collected_info: float = 0.0
    collected_spectra: int = 0
    collected_fisher: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)


@dataclass(frozen=True)
class Shortfall:
    """A goal the available time does not reach: what is needed, what fits, what that gives."""

    goal: Goal
    needed_spectra: int
    available_spectra: int
    reachable: float

    def message(self) -> str:
        """One line for the terminal / error."""
        reach = Goal(self.goal.quantity, self.reachable, self.goal.relative, "").describe()
        return (
            f"`goal` {self.goal.text}: needs {self.needed_spectra} spectra, the nights given allow "
            f"{self.available_spectra} (reaching {reach}); add nights or relax the goal"
        )


def parse_goal(text: str) -> Goal:
    """Parse ``QUANTITY=VALUE[UNIT]``: ``sigma_K=2km/s``, ``K1=1%``, ``q=1%``, ``M1=0.01Msun``.

    A ``%`` makes the goal relative (σ/value). ``sigma_K`` is absolute only (km/s; a bare
    number is km/s); ``q`` is relative or a bare number; masses take ``Msun`` or ``%``.

    Raises
    ------
    InputError
        One line naming the accepted forms.
    """
    forms = "expected QUANTITY=VALUE such as sigma_K=2km/s, K1=1%, q=1%, M1=0.01Msun"
    if str(text).count("=") > 1:  # 'q=1%,M1=2%': name the list, not a unit '%,M1=2%'
        raise InputError(
            f"goal: one QUANTITY=VALUE per goal, got several in {shorten(text, 60)}; "
            "keep the goal that decides the plan"
        )
    match = _GOAL_RE.match(str(text))
    if not match:
        raise InputError(f"goal: {forms}, got {shorten(text, 60)}")
    name, number, unit = match.group(1), float(match.group(2)), (match.group(3) or "").strip()
    canon = {k.lower(): k for k in GOAL_QUANTITIES}
    quantity = canon.get(name.lower())
    if quantity is None:
        raise InputError(
            f"goal: quantity expected one of {', '.join(GOAL_QUANTITIES)}, got {shorten(name, 40)}"
        )
    if not math.isfinite(number) or number <= 0:
        raise InputError(f"goal: {quantity}: expected a positive precision, got {number:g}")
    relative = unit == "%"
    if relative:
        if quantity == "sigma_K":
            raise InputError("goal: sigma_K is absolute (sigma_K=2km/s); for K1 to 1 % use K1=1%")
        if number >= 100:
            raise InputError(f"goal: {quantity}: expected a percentage below 100, got {number:g}")
        return Goal(quantity, number / 100.0, True, str(text).strip())
    want = GOAL_QUANTITIES[quantity]
    got = _UNITS.get(unit.lower(), unit)
    if got != want and not (unit == "" and quantity in ("sigma_K", "q")):
        need = f"{want} or %" if quantity != "sigma_K" else "km/s"
        if quantity == "q":
            need = "% or a bare number"
        raise InputError(
            f"goal: {quantity}: expected a unit {need}, got {shorten(unit or 'none', 40)}"
        )
    return Goal(quantity, number, False, str(text).strip())


def anchor_phases(anchors: tuple[str, ...] | list[str]) -> list[tuple[str, float]]:
    """The pattern of (anchor name, u★ [rad]) one cycle of the anchors visits.

    ``quadrature`` → u = 0, π; ``conjunction`` and ``zero-crossing`` → π/2, 3π/2 (cos u ≈ 0:
    they constrain γ, not K); ``u=VALUE`` → that u★.

    Raises
    ------
    InputError
        Unknown anchor name.
    """
    out: list[tuple[str, float]] = []
    for name in dict.fromkeys(str(a).strip().lower() for a in anchors):  # each anchor once
        key = str(name).strip().lower()
        if key == "quadrature":
            out += [("quadrature", 0.0), ("quadrature", math.pi)]
        elif key in ("conjunction", "zero-crossing"):
            out += [(key, 0.5 * math.pi), (key, 1.5 * math.pi)]
        elif key.startswith("u="):
            try:
                u = float(key[2:])
            except ValueError:
                u = math.nan
            if not math.isfinite(u):
                raise InputError(f"anchor: expected u=RADIANS, got {shorten(name, 40)}")
            out.append((key, u))
        else:
            raise InputError(
                "anchor: expected quadrature, conjunction, zero-crossing or u=VALUE, "
                f"got {shorten(name, 40)}"
            )
    if not out:
        raise InputError("anchor: expected at least one anchor, got none")
    return out


def sigma_k_per_pattern(phases: list[float], lambda_k: float, sigma_v: float = 1.0) -> float:
    """σ_K from ONE pattern of spectra at ``phases``: √[(F⁻¹)_KK] of the (γ, K) Fisher matrix.

    F = Σ_i (1, Λ_K cos u_i)ᵀ (1, Λ_K cos u_i) / σ_v² (module notes); c repetitions give σ/√c.

    Raises
    ------
    InputError
        If the anchors do not constrain K (all at cos u = 0, or all at the same cos u).
    """
    design = np.column_stack([np.ones(len(phases)), lambda_k * np.cos(np.asarray(phases))])
    fisher = design.T @ design / sigma_v**2
    try:
        cov = inverse_scaled(fisher)
    except np.linalg.LinAlgError:
        cov = None
    # A pattern with no spread in cos u leaves (γ, K) degenerate.
    spread = float(np.ptp(design[:, 1])) if len(phases) > 1 else 0.0
    if cov is None or spread < 1e-6 * lambda_k or not np.isfinite(cov[1, 1]):
        raise InputError(
            "goal: the anchors chosen do not constrain K (no spread in cos u); "
            "add quadrature to the anchors"
        )
    return float(math.sqrt(cov[1, 1]))


#: Smallest smearing factor Λ_K a goal is computed for: below it the exposure has averaged the
#: velocity curve away and no number of spectra measures K.
LAMBDA_K_MIN = 0.01


def _positive(name: str, value: float | None, high: float = math.inf) -> float:
    if value is None or not isinstance(value, int | float) or not math.isfinite(value):
        raise InputError(f"{name}: expected a positive number, got {shorten(value, 40)}")
    if not 0 < value <= high:
        raise InputError(f"{name}: expected a number in (0, {high:g}], got {value:g}")
    return float(value)


def goal_sigma(
    goal: Goal,
    s1: float,
    s2: float | None,
    k1: float,
    k2: float | None,
    period_s: float | None,
    sin_i: float | None,
    e: float,
) -> float:
    """σ of the goal quantity (absolute or relative as the goal) for per-star σ_K1, σ_K2 [km/s]
    (module notes)."""
    q = goal.quantity
    if q in ("q", "M1", "M2", "K2") and (k2 is None or s2 is None):
        raise InputError(
            f"goal: {q} needs a double-lined (SB2) target with K2; "
            "for a single-lined target use sigma_K or K1"
        )
    if q == "sigma_K":
        return max(s1, s2) if s2 is not None else s1
    if q == "K1":
        return s1 / k1 if goal.relative else s1
    assert k2 is not None and s2 is not None
    if q == "K2":
        return s2 / k2 if goal.relative else s2
    r1, r2 = s1 / k1, s2 / k2
    if q == "q":
        rel = math.hypot(r1, r2)
        return rel if goal.relative else rel * k1 / k2
    ksum = k1 + k2
    if q == "M1":
        rel = math.hypot(2 * s1 / ksum, (1 / k2 + 2 / ksum) * s2)
    else:
        rel = math.hypot((1 / k1 + 2 / ksum) * s1, 2 * s2 / ksum)
    if goal.relative:
        return rel
    if period_s is None or sin_i is None:
        raise InputError(
            f"goal: {goal.text}: an absolute mass goal needs P_b and sin i; give it in % instead"
        )
    a = a_total_m(k1 * 1e3, k2 * 1e3, e, period_s, sin_i)
    mtot = float(kepler_total_mass(a, period_s)) / MSUN_KG
    mass = mtot * (k2 if q == "M1" else k1) / ksum  # M1 = M_tot/(1 + q), M2 = q M1
    return rel * mass


def spectra_for_goal(
    goal: Goal,
    *,
    K1: float,
    K2: float | None,
    sigma_v_kms: float,
    lambda_k: float,
    anchors: tuple[str, ...] = ("quadrature",),
    sigma_v2_kms: float | None = None,
    period_s: float | None = None,
    sin_i: float | None = None,
    e: float = 0.0,
    exptime_s: float | None = None,
    readout_s: float = 0.0,
    acquisition_s: float = 0.0,
    visit_s: float | None = None,
) -> GoalPlan:
    """Spectra (and, given ``exptime_s`` and ``period_s``, wall time) that reach ``goal``.

    ``goal`` comes from :func:`parse_goal` (``sigma_K`` bounds σ_K of every star measured).
    ``K1``, ``K2``: semi-amplitudes [km/s] (``K2=None``: single-lined); ``sigma_v_kms``,
    ``sigma_v2_kms``: σ_v per exposure of star 1 and 2 [km/s] (star 2's defaults to star 1's);
    ``lambda_k``: the smearing attenuation Λ_K of one exposure, in (0, 1]; ``anchors``: one
    pattern (:func:`anchor_phases`), over which spectra are split in equal numbers; ``period_s``,
    ``sin_i``, ``e``: P_b [s], sin ι and e, for absolute mass goals and (P_b) the time budget;
    ``exptime_s``, ``readout_s``, ``acquisition_s``, ``visit_s``: the costs of
    :func:`time_budget`.

    Returns N = m·c spectra, c = ⌈(σ_goal(1 pattern)/goal)²⌉ patterns of m, and ``expected``,
    σ of the goal quantity with N spectra (a fraction for a relative goal). Raises
    :class:`InputError` for bad numbers, a goal needing K2 of a single-lined target, anchors
    that do not constrain K, or a goal needing more than ``MAX_SPECTRA`` spectra.
    """
    k1, k2, sv1, sv2, lam = _goal_inputs(K1, K2, sigma_v_kms, sigma_v2_kms, lambda_k)
    if period_s is not None:
        _positive("P_b", period_s)
    if sin_i is not None:
        _positive("sin i", sin_i, 1.0)
    pattern = anchor_phases(anchors)
    unit = sigma_k_per_pattern([u for _, u in pattern], lam)  # σ_K per pattern for σ_v = 1
    s1, s2 = sv1 * unit, (sv2 * unit if k2 is not None else None)
    per_pattern = goal_sigma(goal, s1, s2, k1, k2, period_s, sin_i, e)
    cycles = _cycles_to_goal(goal, per_pattern, len(pattern))
    time = None
    if exptime_s is not None and period_s is not None:
        time = time_budget(
            cycles * len(pattern),
            period_s=period_s,
            exptime_s=exptime_s,
            readout_s=readout_s,
            acquisition_s=acquisition_s,
            visit_s=visit_s,
            anchors_per_orbit=len(pattern),
        )
    return _cycle_plan(goal, [name for name, _ in pattern], cycles, per_pattern, s1, s2, time)


def _cycle_plan(
    goal: Goal,
    pattern: list[str],
    cycles: int,
    per_pattern: float,
    s1: float,
    s2: float | None,
    time: TimeBudget | None,
) -> GoalPlan:
    """``cycles`` whole patterns of spectra, and the σ's they reach (σ per pattern / √cycles)."""
    counts: dict[str, int] = {}
    for name in pattern:
        counts[name] = counts.get(name, 0) + cycles
    root = math.sqrt(cycles)
    return GoalPlan(
        goal=goal,
        n_spectra=cycles * len(pattern),
        per_anchor=tuple(counts.items()),
        expected=per_pattern / root,
        sigma_K1_kms=s1 / root,
        sigma_K2_kms=s2 / root if s2 is not None else None,
        time=time,
        cycles=cycles,
    )


def _goal_inputs(
    K1: float, K2: float | None, sv: float, sv2: float | None, lambda_k: float
) -> tuple[float, float | None, float, float, float]:
    """K1, K2, σ_v of star 1 and star 2 [km/s] and Λ_K, checked (star 2's σ_v: star 1's)."""
    k1 = _positive("K1", K1)
    k2 = _positive("K2", K2) if K2 is not None else None
    sv1 = _positive("sigma_v", sv)
    sv2_ = _positive("sigma_v (star 2)", sv2) if sv2 is not None else sv1
    lam = _positive("lambda_k", lambda_k, 1.0)
    if lam < LAMBDA_K_MIN:
        raise InputError(
            f"lambda_k: {lam:.3g} is below {LAMBDA_K_MIN}: the exposure averages the orbit away "
            "(shorten the exposures)"
        )
    return k1, k2, sv1, sv2_, lam


def check_goal_spectra(goal_text: str, n_spectra: float) -> None:
    """The one goal-magnitude check (plan, feasibility, API, population rank): a goal needing
    over :data:`MAX_SPECTRA` spectra, or infinitely many, is a typo (InputError, one line)."""
    if not n_spectra <= MAX_SPECTRA:  # nan and inf too
        raise InputError(
            f"goal {goal_text}: would need more than {MAX_SPECTRA} spectra; relax the goal"
        )


def _cycles_to_goal(goal: Goal, per_pattern: float, pattern_len: int) -> int:
    """Whole patterns c = ⌈(σ_goal(1 pattern)/goal)²⌉ that reach ``goal`` (at least one)."""
    ratio = (per_pattern / goal.value) * (per_pattern / goal.value)  # inf, not OverflowError
    check_goal_spectra(goal.text, ratio * pattern_len)
    return max(1, math.ceil(ratio * (1.0 - 1e-12)))


def time_budget(
    n_spectra: int,
    *,
    period_s: float,
    exptime_s: float,
    readout_s: float = 0.0,
    acquisition_s: float = 0.0,
    visit_s: float | None = None,
    anchors_per_orbit: int = 2,
) -> TimeBudget:
    """Wall time of ``n_spectra`` exposures centred on anchors, in visits.

    Anchors are P_b/m apart (m = ``anchors_per_orbit``: 2 for quadratures, P_b/2 apart). An
    exposure costs exptime + readout; the next one starts at the next anchor it can reach, so
    the step is ⌈cost/(P_b/m)⌉·P_b/m and each step idles step − cost waiting for phase. A visit
    is one acquisition followed by as many steps as fit in ``visit_s`` (acquisition included;
    ``None``: all spectra in one visit). Shutter = N·exptime; overheads = visits·acquisition +
    N·readout; idle = Σ_visits (n_v − 1)(step − cost). The wait for the first anchor of a visit
    is not counted (the acquisition is started so that it ends on one). When the step is an even
    number of quadrature spacings, one visit sees one quadrature only: the equal split is then
    made across visits.

    Raises
    ------
    InputError
        A visit shorter than acquisition + one exposure + readout; non-positive numbers.
    """
    pb = _positive("P_b", period_s)
    t = _positive("exptime", exptime_s)
    if readout_s < 0 or acquisition_s < 0 or not math.isfinite(readout_s + acquisition_s):
        raise InputError("readout/acquisition: expected non-negative seconds")
    if n_spectra < 0:
        raise InputError(f"n_spectra: expected >= 0, got {n_spectra}")
    cost = t + readout_s
    spacing = pb / max(1, anchors_per_orbit)
    step = math.ceil(cost / spacing * (1.0 - 1e-12)) * spacing
    per_visit = _spectra_per_visit(n_spectra, cost, step, acquisition_s, visit_s)
    n_visits = math.ceil(n_spectra / per_visit) if n_spectra else 0
    full, last = divmod(n_spectra, per_visit)
    gaps = full * (per_visit - 1) + (last - 1 if last else 0)
    shutter = n_spectra * t
    overhead = n_visits * acquisition_s + n_spectra * readout_s
    idle = gaps * (step - cost)
    return TimeBudget(
        n_visits=n_visits,
        spectra_per_visit=per_visit,
        step_s=step,
        shutter_h=shutter / HOUR_S,
        overhead_h=overhead / HOUR_S,
        idle_h=idle / HOUR_S,
        total_h=(shutter + overhead + idle) / HOUR_S,
    )


def _spectra_per_visit(
    n_spectra: int, cost: float, step: float, acquisition_s: float, visit_s: float | None
) -> int:
    """Exposures one visit holds: the first after the acquisition, then one per ``step``."""
    if visit_s is None:
        return max(1, n_spectra)
    usable = _positive("visit", visit_s) - acquisition_s
    if usable < cost:
        raise InputError(
            f"visit: expected at least acquisition + one exposure + readout = "
            f"{(acquisition_s + cost) / 60:.1f} min, got {visit_s / 60:.1f} min; "
            "lengthen `visit` or shorten the exposure"
        )
    return int((usable - cost) // step) + 1


def shortfall(
    plan: GoalPlan,
    *,
    available_spectra: int | None = None,
    available_hours: float | None = None,
    period_s: float | None = None,
    exptime_s: float | None = None,
    readout_s: float = 0.0,
    acquisition_s: float = 0.0,
    visit_s: float | None = None,
) -> Shortfall | None:
    """``None`` if the nights allow the goal's spectra, else what is missing and what is reached.

    Give ``available_spectra`` (anchor epochs the scheduler could place), or ``available_hours``
    with the time-budget arguments (the largest whole number of anchor patterns whose
    :func:`time_budget` fits). The σ reachable scales as √(N_goal/N_available) (whole patterns).
    """
    cycles_needed = plan.cycles
    m = plan.n_spectra // cycles_needed
    if available_spectra is None:
        if available_hours is None or period_s is None or exptime_s is None:
            raise InputError("shortfall: give available_spectra, or available_hours with timing")
        budget = available_hours

        def fits(c: int) -> bool:
            return (
                time_budget(
                    c * m,
                    period_s=period_s,
                    exptime_s=exptime_s,
                    readout_s=readout_s,
                    acquisition_s=acquisition_s,
                    visit_s=visit_s,
                    anchors_per_orbit=m,
                ).total_h
                <= budget
            )

        lo, hi = 0, cycles_needed
        while lo < hi:  # largest c in [0, needed] that fits (time grows with c)
            mid = (lo + hi + 1) // 2
            lo, hi = (mid, hi) if fits(mid) else (lo, mid - 1)
        available_spectra = lo * m
    if available_spectra >= plan.n_spectra:
        return None
    cycles = available_spectra // m
    reach = plan.expected * math.sqrt(cycles_needed / cycles) if cycles else math.inf
    return Shortfall(plan.goal, plan.n_spectra, available_spectra, reach)


def target_k(target: Target) -> tuple[float, float | None, float | None]:
    """(K1, K2 or None, sin i or None) of a goal's target [km/s].

    Raises
    ------
    InputError
        The target file has no K1 (or K_eff).
    """
    spec = target.spectroscopy
    k1 = (spec.K1_kms or spec.K_eff_kms) if spec is not None else None
    if k1 is None:
        raise InputError(
            f"goal: {target.name}: expected spectroscopy.K1 (or K_eff) in the target file, "
            "got none; add it or plan without `goal`"
        )
    k2 = spec.K2_kms if spec is not None and spec.lines == "SB2" else None
    sin_i = None
    cos_i = target.cos_inclination
    if cos_i is not None and math.isfinite(cos_i):
        sin_i = math.sqrt(max(0.0, 1.0 - cos_i**2)) or None
    return float(k1), k2, sin_i


def goal_info_needed(goal: Goal, target: Target) -> float:
    """Information on K [(km/s)⁻²] that reaches ``goal`` for ``target``.

    Every goal quantity's σ scales as I^{-½} with the information I = Σ w_i of the spectra
    (σ_K1 = I^{-½}; star 2's lines, measured in the same spectra, with the same σ_v), so the
    goal needs I = (σ_goal(I = 1)/goal)².

    Raises
    ------
    InputError
        No K1, or no K2 for a goal on K2, q or a mass.
    """
    k1, k2, sin_i = target_k(target)
    unit = goal_sigma(
        goal, 1.0, 1.0 if k2 is not None else None, k1, k2, target.period_s, sin_i,
        target.params.eccentricity,
    )  # fmt: skip
    return (unit / goal.value) * (unit / goal.value)  # inf, not OverflowError, for 1e-300
