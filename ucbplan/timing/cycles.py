"""Counting cycles from the eclipse times themselves, starting from a first ephemeris.

Without a ``cycle`` column each time needs its cycle number before the ephemeris can be fitted.
Starting from a first guess (:class:`~ucbplan.timing.initial.PeriodGuess`: P, and T0 and Ṗ from
an earlier ephemeris), the count grows outward from the densest cluster of times:

1. without a T0, the seed is the time with most neighbours within the span over which the
   period guess alone predicts an eclipse to P/8; it is cycle 0 (0.5 if a secondary);
2. the current ephemeris (a quadratic fitted to the counted times plus the guess as priors on
   P and Ṗ, and T0 if given) predicts each uncounted time's cycle and that prediction's σ; every
   time whose prediction is good to P/8 (σ of prediction and measurement combined, so the
   neighbouring eclipse is ≥ 4σ away) gets the nearest cycle of its kind;
3. the fit is redone with them, and 2 repeats until all are counted.

If no uncounted time can be predicted to P/8, the count across that gap is ambiguous: an error
says where and what to supply (a ``cycle`` column, or ``--initial`` with a better ephemeris).
A time predicted well but lying more than P/4 from its eclipse is an error too (wrong kind or a
wrong period guess), never silently counted.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ucbplan.core.constants import DAY_S
from ucbplan.core.timing_epochs import jd_to_seconds
from ucbplan.errors import InputFileError
from ucbplan.timing.eclipse_table import EclipseTimes, check_monotonic
from ucbplan.timing.fit import solve_wls
from ucbplan.timing.initial import PeriodGuess

F64 = NDArray[np.float64]

#: A cycle is counted only when its predicted time is known to this fraction of P (1σ).
AMBIGUITY_FRACTION = 1.0 / 8.0
#: A counted time must lie within this fraction of P of its predicted eclipse.
MAX_OFFSET_FRACTION = 0.25
#: A prior from the guess that disagrees with the counted times by more than this many σ is an
#: error (a guess written with more digits than it holds, e.g. a P far from its epoch).
PRIOR_PULL = 5.0


def _seed(times: EclipseTimes, guess: PeriodGuess) -> int:
    """The time with most neighbours within the span the period guess alone can bridge."""
    p = guess.period_s
    reach = AMBIGUITY_FRACTION * p * p / max(guess.sigma_period_s, 1e-15 * p)
    t = times.t_s
    lo = np.searchsorted(t, t - reach, side="left")
    hi = np.searchsorted(t, t + reach, side="right")
    count = hi - lo
    order = np.lexsort((np.arange(t.size), times.sigma_s, -count))
    return int(order[0])


def _fit(
    times: EclipseTimes,
    cycles: F64,
    done: NDArray[np.bool_],
    guess: PeriodGuess,
    t0_s: float | None,
) -> tuple[float, F64, F64]:
    """Center, coefficients and covariance of the quadratic through the counted times + priors.

    Raises
    ------
    InputFileError
        If a prior (P, Ṗ or T0 of the guess) disagrees with the counted times by > 5σ.
    """
    p = guess.period_s
    center = float(np.mean(cycles[done])) if done.any() else 0.0
    nu = cycles[done] - center
    data = np.stack([np.ones_like(nu), nu, nu * nu], axis=1)
    nu0 = -center  # the guess refers to cycle 0
    priors = [
        ("period", [0.0, 1.0, 2.0 * nu0], p, max(guess.sigma_period_s, 1e-15 * p)),
        ("pdot", [0.0, 0.0, 1.0], 0.5 * p * guess.pdot, 0.5 * p * guess.sigma_pdot),
    ]
    if t0_s is not None:
        priors.append(("t0", [1.0, nu0, nu0 * nu0], t0_s, max(guess.sigma_t0_s, 1e-6)))
    a = np.vstack([data, np.array([row for _, row, _, _ in priors])])
    y = np.concatenate([times.t_s[done], [v for _, _, v, _ in priors]])
    s = np.concatenate([times.sigma_s[done], [e for _, _, _, e in priors]])
    coef, cov = solve_wls(a, y, s)
    for name, row, value, sig in priors:
        x = np.array(row)
        var = sig * sig - float(x @ cov @ x)  # variance of the prior's residual
        if var > 1e-6 * sig * sig:
            pull = (value - float(x @ coef)) / np.sqrt(var)
            if abs(pull) > PRIOR_PULL:
                raise _disagrees(times, guess, name, float(pull))
    return center, coef, cov


def _disagrees(times: EclipseTimes, guess: PeriodGuess, name: str, pull: float) -> InputFileError:
    what = {
        "period": f"period {guess.period_s:.10g} s (±{guess.sigma_period_s:.2g} s from its digits)",
        "pdot": f"pdot {guess.pdot:.4g} (±{guess.sigma_pdot:.2g})",
        "t0": f"t0 (±{guess.sigma_t0_s:.2g} s from its digits)",
    }[name]
    fix = (
        "write it with fewer digits (as many as hold over the times), or give `initial` "
        "TARGET.yaml with t0, period and pdot"
        if guess.origin == "--period"
        else "check that file's ephemeris, or add a cycle column"
    )
    return InputFileError(
        f"{times.label()}: counting cycles: the {what} of {guess.origin} disagrees with the times "
        f"counted so far by {abs(pull):.3g}σ; {fix}"
    )


def _predict(t_s: F64, half: F64, center: float, coef: F64, cov: F64) -> tuple[F64, F64, F64]:
    """Nearest cycle of each time's kind, its predicted time and that prediction's σ."""
    c0, c1, c2 = coef
    with np.errstate(all="ignore"):
        nu = (t_s - c0) / c1
        for _ in range(4):
            nu = nu - (c0 + c1 * nu + c2 * nu * nu - t_s) / (c1 + 2 * c2 * nu)
        n = np.round(nu + center - half) + half
        x = n - center
        jac = np.stack([np.ones_like(x), x, x * x], axis=1)
        pred = jac @ coef
        var = np.einsum("ij,jk,ik->i", jac, cov, jac)
    return n, pred, np.sqrt(np.clip(var, 0.0, None))


def count_cycles(times: EclipseTimes, guess: PeriodGuess) -> F64:
    """Cycle number of each time (sorted like ``times``), counted from ``guess``.

    Raises
    ------
    InputFileError
        An ambiguous count across a gap (with what to supply), or a time that is far from every
        predicted eclipse of its kind.
    """
    p = guess.period_s
    half = np.where(times.secondary, 0.5, 0.0)
    cycles = np.zeros(times.n)
    done = np.zeros(times.n, dtype=bool)
    t0_s = None if guess.t0_jd is None else jd_to_seconds(guess.t0_jd, times.ref_jd)
    if t0_s is None:
        seed = _seed(times, guess)
        cycles[seed], done[seed] = half[seed], True
    while not done.all():
        center, coef, cov = _fit(times, cycles, done, guess, t0_s)
        todo = np.flatnonzero(~done)
        n, pred, sig_pred = _predict(times.t_s[todo], half[todo], center, coef, cov)
        sig = np.hypot(sig_pred, times.sigma_s[todo])
        sig = np.where(np.isfinite(sig) & np.isfinite(n), sig, np.inf)
        ok = sig <= AMBIGUITY_FRACTION * p
        if not ok.any():
            k = int(np.argmin(sig))
            why = _limit(times, guess, todo[k], n[k] - center, cov)
            raise _ambiguous(times, guess, done, int(todo[k]), float(sig[k]), why)
        offset = np.abs(times.t_s[todo] - pred)
        far = ok & (offset > MAX_OFFSET_FRACTION * p) & (offset > 5 * sig)
        if far.any():
            k = int(np.flatnonzero(far)[0])
            i = int(todo[k])
            kind = "secondary" if times.secondary[i] else "primary"
            raise InputFileError(
                f"{times.label()}: row {times.rows[i]}, column 'bjd_tdb': {offset[k] / p:.2f} P "
                f"from the nearest predicted {kind} eclipse (counting from {guess.origin}); check "
                "its kind, or whether the guess holds over these times (fewer digits, or `initial` "
                "with t0, period, pdot), or remove the row"
            )
        cycles[todo[ok]] = n[ok]
        done[todo[ok]] = True
    check_monotonic(times, cycles)
    return cycles


def _limit(times: EclipseTimes, guess: PeriodGuess, i: int, x: float, cov: F64) -> str:
    """What limits the prediction of time ``i`` at ``x`` cycles from the fit's centre: ``"pdot"``
    when knowing the quadratic term (Ṗ) alone would predict it to P/8, else ``"period"``.

    The prediction's variance given the quadratic coefficient is the Schur complement of the
    coefficients' covariance (the linear part's variance conditional on c₂).
    """
    j = np.array([1.0, x])
    if not (np.all(np.isfinite(cov)) and cov[2, 2] > 0):
        return "period"
    cond = cov[:2, :2] - np.outer(cov[:2, 2], cov[2, :2]) / cov[2, 2]
    sig = float(np.hypot(np.sqrt(max(float(j @ cond @ j), 0.0)), times.sigma_s[i]))
    return "pdot" if sig <= AMBIGUITY_FRACTION * guess.period_s else "period"


def _ambiguous(
    times: EclipseTimes,
    guess: PeriodGuess,
    done: NDArray[np.bool_],
    i: int,
    sig: float,
    why: str = "period",
) -> InputFileError:
    """The error for an ambiguous count: which gap, how uncertain, what to supply."""
    counted = np.flatnonzero(done)
    where = f"at row {times.rows[i]} (BJD_TDB {times.jd[i]})"
    if counted.size:
        a = int(counted[np.argmin(np.abs(times.t_s[counted] - times.t_s[i]))])
        gap_d = abs(times.t_s[i] - times.t_s[a]) / DAY_S
        first, last = sorted((a, i))
        where = (
            f"across the {gap_d:.4g} d gap between rows {times.rows[first]} and "
            f"{times.rows[last]} (BJD_TDB {times.jd[first]} and {times.jd[last]})"
        )
    sig_text = f"{sig:.3g} s = {sig / guess.period_s:.2g} P" if np.isfinite(sig) else "unbounded"
    head = (
        f"{times.label()}: cycle count ambiguous {where}: the ephemeris so far (from "
        f"{guess.origin}) predicts that eclipse only to σ = {sig_text} (> P/8); "
    )
    if why == "period":
        return InputFileError(
            f"{head}add a cycle column, or give `initial` TARGET.yaml with a better ephemeris (or "
            "`period` with more digits)"
        )
    return InputFileError(
        f"{head}an unknown Ṗ limits it, not P (more digits in the period will not help): add a "
        "cycle column, eclipse times that bridge the gap in shorter steps, or `initial` "
        "TARGET.yaml whose timing block has pdot (a Ṗ prior)"
    )
