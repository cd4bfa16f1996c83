"""Timing ephemerides (T0, P, Ṗ, P̈) as a second parameterisation of the one phase model.

Optical and X-ray ephemerides of ultracompact binaries are fitted as a polynomial in the cycle
number n (Burdge et al. 2019; Hermes et al. 2012):

    t(n) = T0 + P n + ½ P Ṗ n² + ⅙ P² P̈ n³,

n integer at the event T0 marks (half-integer at the other conjunction). Its inversion is the
orbital phase; with n̄_b = πf it is the GW phase model of :mod:`ucbplan.core.phase` referenced to
t_ref = T0:

    f = 2/P,  ḟ = −2Ṗ/P²,  f̈ = 2(3Ṗ²/P³ − P̈/P²),  φ_ref such that u₁(T0) = the mark.

(Series inversion: n(τ) = τ/P − (Ṗ/2)τ²/P² + (Ṗ²/2 − PP̈/6)τ³/P³ + O(τ⁴), and f = 2 dn/dτ.)
The phase model is a cubic in τ where the ephemeris is a cubic in n, so the two differ at fourth
order: about 5|Ṗ/2|³(τ/P)⁴·P seconds (1.2 µs at 10 yr for ZTF J1539+5027, Ṗ = −2.4e-11), see
:func:`truncation_s`. Nothing else is approximated: every command reads the resulting
:class:`~ucbplan.core.params.PhaseParams` and its covariance, so timing and LISA targets share one
code path.

Marks (star 1 is the star eclipsed at primary eclipse, i.e. behind its companion at u₁ = π/2):
primary eclipse u₁ = π/2, secondary eclipse u₁ = 3π/2, ascending node and maximum recession of
star 1 u₁ = 0. Since Φ_asc = Φ_GW/2, φ_ref is kept modulo 4π (φ_ref = 3π for a secondary
eclipse; reduced modulo 2π it would be π, the primary).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Protocol

import numpy as np
from astropy.time import Time, TimeDelta
from numpy.typing import ArrayLike, NDArray

from ucbplan.core.constants import TWO_PI, YEAR_S
from ucbplan.core.params import PhaseParams
from ucbplan.core.phase import arg_latitude_rate, sigma_u_from_jacobian, u_cycles, u_jacobian

FloatArray = NDArray[np.float64]

#: Event at T0 → star 1's argument of latitude u₁ there [rad].
MARKS: dict[str, float] = {
    "primary_eclipse": math.pi / 2,
    "secondary_eclipse": 3 * math.pi / 2,
    "ascending_node": 0.0,
    "max_recession_star1": 0.0,
}
#: Order of the timing parameters (covariance rows); ``t0`` is the offset from the nominal T0.
TIMING_NAMES: tuple[str, ...] = ("t0", "period", "pdot", "pddot", "eta", "kappa", "omega_dot")
#: SI unit of each timing parameter (astropy unit strings).
TIMING_UNITS: dict[str, str] = {
    "t0": "s",
    "period": "s",
    "pdot": "",
    "pddot": "1 / s",
    "eta": "",
    "kappa": "",
    "omega_dot": "rad / s",
}
#: The period must keep its sign within this span either side of T0 [s] (100 Julian years).
SIGN_SPAN_S = 100.0 * YEAR_S


@dataclass(frozen=True, slots=True)
class TimingEphemeris:
    """A timing ephemeris at its epoch T0 (SI floats; T0 itself is the target's ``t_ref``).

    Attributes
    ----------
    mark : str
        The event at T0, a key of :data:`MARKS`.
    period_s : float
        P, the orbital period at T0 (from node to node: f = 2/P) [s].
    pdot : float
        Ṗ = dP/dt at T0 [s/s].
    pddot : float
        P̈ = d²P/dt² at T0 [1/s].
    eta, kappa : float
        η = e sin ω, κ = e cos ω of star 1 at T0 [1].
    omega_dot : float
        Apsidal advance rate ω̇ [rad/s].
    """

    mark: str
    period_s: float
    pdot: float
    pddot: float = 0.0
    eta: float = 0.0
    kappa: float = 0.0
    omega_dot: float = 0.0

    @property
    def mark_u(self) -> float:
        """u₁ at T0 [rad]."""
        return MARKS[self.mark]


def mark_phase_asc(u_mark: float, eta: float, kappa: float) -> float:
    """Φ_asc at the epoch where star 1's u = ``u_mark`` (solved exactly in the first-order model).

    Solves Φ + 2κ sin Φ − 2η cos Φ = u★ by Newton from Φ = u★ (contraction 2e < 0.2) [rad].

    Notes
    -----
    Eq. u_precessing_app at τ = 0; circular orbits give Φ = u★.
    """
    phi = u_mark
    for _ in range(50):
        g = phi + 2 * kappa * math.sin(phi) - 2 * eta * math.cos(phi) - u_mark
        d = 1 + 2 * kappa * math.cos(phi) + 2 * eta * math.sin(phi)
        step = g / d
        phi -= step
        if abs(step) < 1e-16:
            break
    return phi


def to_phase_params(eph: TimingEphemeris) -> PhaseParams:
    """The phase-model parameters at t_ref = T0 of a timing ephemeris (SI).

    Notes
    -----
    f = 2/P, ḟ = −2Ṗ/P², f̈ = 2(3Ṗ²/P³ − P̈/P²) from the series inversion of t(n) (module
    docstring); φ_ref = 2Φ_asc(T0) with u₁(T0) = the mark (kept modulo 4π, not 2π).
    """
    p, pd, pdd = eph.period_s, eph.pdot, eph.pddot
    return PhaseParams(
        phase=2.0 * mark_phase_asc(eph.mark_u, eph.eta, eph.kappa),
        f_gw=2.0 / p,
        fdot=-2.0 * pd / p**2,
        fddot=2.0 * (3.0 * pd**2 / p**3 - pdd / p**2),
        eta=eph.eta,
        kappa=eph.kappa,
        omega_dot=eph.omega_dot,
    )


def phase_jacobian(eph: TimingEphemeris) -> FloatArray:
    """∂(φ_ref, f, ḟ, f̈, η, κ, ω̇)/∂(T0, P, Ṗ, P̈, η, κ, ω̇), shape (7, 7), at fixed t_ref.

    Moving T0 by δ with t_ref held at the nominal T0 moves the mark to τ = δ: u₁(δ) = mark gives
    ∂φ_ref/∂T0 = −2u̇₁/(∂u₁/∂Φ_asc); the mark condition also gives ∂φ_ref/∂(η, κ).
    """
    p, pd, pdd = eph.period_s, eph.pdot, eph.pddot
    pp = to_phase_params(eph)
    phi = 0.5 * pp.phase
    s, c = math.sin(phi), math.cos(phi)
    d = 1.0 + 2.0 * eph.kappa * c + 2.0 * eph.eta * s  # ∂u/∂Φ_asc at T0
    rate = float(arg_latitude_rate(pp, np.array([0.0]))[0])
    j = np.eye(7)
    j[0, 0] = -2.0 * rate / d
    j[0, 4] = 4.0 * c / d
    j[0, 5] = -4.0 * s / d
    j[1, 1] = -2.0 / p**2
    j[2, 1] = 4.0 * pd / p**3
    j[2, 2] = -2.0 / p**2
    j[3, 1] = 2.0 * (-9.0 * pd**2 / p**4 + 2.0 * pdd / p**3)
    j[3, 2] = 12.0 * pd / p**3
    j[3, 3] = -2.0 / p**2
    return j


def phase_covariance(eph: TimingEphemeris, cov: ArrayLike) -> FloatArray:
    """Covariance of the phase-model parameters from that of the timing parameters (7×7 each).

    ``cov`` is in :data:`TIMING_NAMES` order and :data:`TIMING_UNITS`; the result is in
    :data:`~ucbplan.core.params.PARAM_NAMES` order and SI units. J C Jᵀ is formed on the
    correlation matrix (J scaled by the σ's), so entries 40 orders of magnitude apart keep their
    precision.
    """
    c = np.asarray(cov, dtype=np.float64)
    sig = np.sqrt(np.clip(np.diag(c), 0.0, None))
    safe = np.where(sig > 0, sig, 1.0)
    corr = c / np.outer(safe, safe)
    js = phase_jacobian(eph) * sig[None, :]
    out = js @ corr @ js.T
    return 0.5 * (out + out.T)


def cycle_time_s(eph: TimingEphemeris, n: ArrayLike) -> FloatArray:
    """t(n) − T0 = P n + ½PṖn² + ⅙P²P̈n³ [s] (the ephemeris polynomial itself, float64)."""
    nn = np.asarray(n, dtype=np.float64)
    p = eph.period_s
    out: FloatArray = p * nn + 0.5 * p * eph.pdot * nn**2 + p * p * eph.pddot * nn**3 / 6.0
    return out


def truncation_s(eph: TimingEphemeris, tau_s: ArrayLike) -> FloatArray:
    """Leading difference t_model − t(n) between the phase model and the polynomial [s].

    The cubic-in-τ phase model drops the fourth-order term of the inverse series n(τ): with
    b = Ṗ/2, c = PP̈/6 and x = τ/P it is (5b³ − 5bc)x⁴ cycles, so an event of the polynomial
    comes (5bc − 5b³)x⁴·P seconds later in the model (+1.2 µs at +10 yr for Ṗ = −2.4e-11,
    P = 415 s; higher orders are smaller by ~bx).
    """
    x = np.asarray(tau_s, dtype=np.float64) / eph.period_s
    b = 0.5 * eph.pdot
    c = eph.period_s * eph.pddot / 6.0
    out: FloatArray = (5.0 * b * c - 5.0 * b**3) * x**4 * eph.period_s
    return out


def period_sign_change(eph: TimingEphemeris, span_s: float = SIGN_SPAN_S) -> tuple[str, float]:
    """Where the period or the model frequency reaches zero within ±``span_s`` of T0.

    Returns
    -------
    (str, float)
        ``("", nan)`` if neither does; else the field to blame (``"pdot"`` when P + Ṗτ alone
        reaches zero or there is no P̈, ``"pddot"`` otherwise) and the signed time of the first
        zero [s].

    Notes
    -----
    P(τ) = P + Ṗτ + ½P̈τ² (Taylor series of the ephemeris' local period) and the phase model's
    f(τ) = f + ḟτ + ½f̈τ² must both stay positive on [−span, +span].
    """
    p = eph.period_s
    pp = to_phase_params(eph)
    quad = _first_root(p, eph.pdot, 0.5 * eph.pddot, span_s)
    freq = _first_root(pp.f_gw, pp.fdot, 0.5 * pp.fddot, span_s)
    first = min((x for x in (quad, freq) if math.isfinite(x)), key=abs, default=math.nan)
    if not math.isfinite(first):
        return "", math.nan
    linear = _first_root(p, eph.pdot, 0.0, span_s)
    return ("pdot" if eph.pddot == 0.0 or math.isfinite(linear) else "pddot"), first


def _first_root(a: float, b: float, c: float, span: float) -> float:
    """The root of a + bτ + cτ² (a > 0) nearest τ = 0 within |τ| ≤ span, else nan."""
    roots: list[float] = []
    if c == 0.0:
        if b != 0.0:
            roots.append(-a / b)
    else:
        disc = b * b - 4.0 * a * c
        if disc >= 0.0:
            q = -0.5 * (b + math.copysign(math.sqrt(disc), b))
            roots += [q / c] + ([a / q] if q != 0.0 else [])
    inside = [r for r in roots if math.isfinite(r) and abs(r) <= span]
    return min(inside, key=abs) if inside else math.nan


# ---------------------------------------------------------------------------------------------
# two ephemerides of one system
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class Comparison:
    """Phase and time offset of two ephemerides (A − B) of one system at an epoch.

    Attributes
    ----------
    du_rad : float
        u₁,A − u₁,B at the epoch, wrapped to (−π, π] [rad].
    sigma_du_rad : float
        σ of that offset from both covariances (independent ephemerides) [rad].
    dt_s : float
        t_A − t_B of the same orbital phase near the epoch (= −Δu/u̇) [s].
    sigma_dt_s : float
        Its σ [s].
    significance : float
        |Δu|/σ_Δu (inf when σ = 0 and Δu ≠ 0, 0 when both are 0).
    cycles_a, cycles_b : float
        Orbits of star 1 from A's reference epoch to B's, counted by A and by B.
    cycle_difference : float
        cycles_a − cycles_b: a whole-cycle disagreement the wrapped Δu cannot show.
    sigma_cycle_difference : float
        Its σ [cycles].
    rate_rad_s : float
        u̇₁ at the epoch (mean of the two) [rad/s].
    """

    du_rad: float
    sigma_du_rad: float
    dt_s: float
    sigma_dt_s: float
    significance: float
    cycles_a: float
    cycles_b: float
    cycle_difference: float
    sigma_cycle_difference: float
    rate_rad_s: float

    def offsets(self) -> dict[str, float | None]:
        """The offset as JSON-ready numbers (significance None when σ = 0)."""
        return {
            "phase_offset_rad": self.du_rad,
            "sigma_phase_offset_rad": self.sigma_du_rad,
            "time_offset_s": self.dt_s,
            "sigma_time_offset_s": self.sigma_dt_s,
            "significance": self.significance if math.isfinite(self.significance) else None,
        }


def compare(
    pa: PhaseParams,
    cov_a: FloatArray,
    pb: PhaseParams,
    cov_b: FloatArray,
    tau_a_s: float,
    tau_b_s: float,
    ref_b_from_a_s: float,
) -> Comparison:
    """Offset of ephemeris A from ephemeris B at one epoch (star 1, first-order model).

    Parameters
    ----------
    pa, cov_a, pb, cov_b : PhaseParams, ndarray (7, 7)
        Each ephemeris at its own reference epoch, with its covariance (PARAM_NAMES order).
    tau_a_s, tau_b_s : float
        The epoch in seconds after A's and after B's reference epoch (TDB) [s].
    ref_b_from_a_s : float
        B's reference epoch minus A's [s].

    Returns
    -------
    Comparison

    Notes
    -----
    σ_Δu² = J_A C_A J_Aᵀ + J_B C_B J_Bᵀ with the full ∂u/∂θ at the epoch (Sec. 4.1); the cycle
    count from A's reference to B's uses J(τ) − J(0) so each ephemeris' own correlations count.
    """
    ta, tb = np.array([tau_a_s]), np.array([tau_b_s])
    _, ga = u_cycles(pa, ta)
    _, gb = u_cycles(pb, tb)
    frac = float(ga[0] - gb[0]) % 1.0  # whole orbits since each reference do not matter
    du = TWO_PI * (frac - 1.0 if frac > 0.5 else frac)
    var = float(sigma_u_from_jacobian(u_jacobian(pa, ta), cov_a)[0]) ** 2
    var += float(sigma_u_from_jacobian(u_jacobian(pb, tb), cov_b)[0]) ** 2
    sig = math.sqrt(var)
    rate = 0.5 * float(arg_latitude_rate(pa, ta)[0] + arg_latitude_rate(pb, tb)[0])
    cyc_a, var_a = _cycles_between(pa, cov_a, 0.0, ref_b_from_a_s)
    cyc_b, var_b = _cycles_between(pb, cov_b, -ref_b_from_a_s, 0.0)
    if sig > 0:
        significance = abs(du) / sig
    else:
        significance = math.inf if du != 0 else 0.0
    return Comparison(
        du_rad=du,
        sigma_du_rad=sig,
        dt_s=-du / rate,
        sigma_dt_s=sig / abs(rate),
        significance=significance,
        cycles_a=cyc_a,
        cycles_b=cyc_b,
        cycle_difference=cyc_a - cyc_b,
        sigma_cycle_difference=math.sqrt(var_a + var_b) / TWO_PI,
        rate_rad_s=rate,
    )


def _cycles_between(p: PhaseParams, cov: FloatArray, t0: float, t1: float) -> tuple[float, float]:
    """(u(t1) − u(t0))/2π of star 1 and the variance of u(t1) − u(t0) [cycles, rad²]."""
    tau = np.array([t0, t1])
    m, g = u_cycles(p, tau)
    cycles = float((m[1] - m[0]) + (g[1] - g[0]))
    jac = u_jacobian(p, tau)
    diff = jac[1] - jac[0]
    return cycles, float(max(diff @ cov @ diff, 0.0))


class ReferencedSource(Protocol):
    """An ephemeris with its reference epoch (a :class:`~ucbplan.targets.Target` is one)."""

    @property
    def params(self) -> PhaseParams:
        """Phase-model parameters at ``t_ref``."""
        ...

    @property
    def covariance(self) -> FloatArray:
        """Their covariance (7, 7)."""
        ...

    @property
    def t_ref(self) -> Time:
        """Reference epoch (TDB at the barycentre)."""
        ...


@dataclass(frozen=True, slots=True)
class ComparisonReport:
    """:func:`compare_sources`: the offset at an epoch, and under each φ_ref π-mode alternative.

    Attributes
    ----------
    epoch : Time
        The epoch of the comparison (TDB).
    result : Comparison
        A − B as given.
    alternatives : tuple of (str, Comparison)
        ``("a", …)`` / ``("b", …)``: the same with that side's φ_ref + π (LISA posteriors only).
    """

    epoch: Time
    result: Comparison
    alternatives: tuple[tuple[str, Comparison], ...]


def midway(t_a: Time, t_b: Time) -> Time:
    """The epoch halfway between two TDB epochs (two-part arithmetic)."""
    half = 0.5 * float((t_b - t_a).to_value("s"))
    return t_a + TimeDelta(half, format="sec")


def compare_sources(
    a: ReferencedSource, b: ReferencedSource, at: Time | None = None
) -> ComparisonReport:
    """Phase and time offset of two ephemerides of one system (A − B) at ``at``.

    Parameters
    ----------
    a, b : ReferencedSource
        The two ephemerides (targets); ``has_pi_mode`` (default True) adds the alternatives.
    at : Time, optional
        Epoch (TDB); default midway between the two reference epochs.

    Returns
    -------
    ComparisonReport
    """
    epoch = midway(a.t_ref, b.t_ref) if at is None else at
    tau_a = float((epoch - a.t_ref).to_value("s"))
    tau_b = float((epoch - b.t_ref).to_value("s"))
    ref_b = float((b.t_ref - a.t_ref).to_value("s"))

    def run(pa: PhaseParams, pb: PhaseParams) -> Comparison:
        return compare(pa, a.covariance, pb, b.covariance, tau_a, tau_b, ref_b)

    alts: list[tuple[str, Comparison]] = []
    for side, src in (("a", a), ("b", b)):
        if _has_pi_mode(src):
            flipped = replace(src.params, phase=src.params.phase + math.pi)
            alts.append((side, run(flipped, b.params) if side == "a" else run(a.params, flipped)))
    return ComparisonReport(epoch=epoch, result=run(a.params, b.params), alternatives=tuple(alts))


def _has_pi_mode(src: Any) -> bool:
    return bool(getattr(src, "has_pi_mode", True))
