"""A first period from the eclipse times alone, when there is no cycle column and no guess.

Eclipses of one night fix the period; the count then bridges the gaps between nights
(:func:`~ucbplan.timing.cycles.count_cycles`, which refuses an ambiguous gap):

1. the times are split into nights at gaps longer than :data:`NIGHT_GAP_S`; the night with most
   distinct eclipses (at least :data:`MIN_ECLIPSES`) is used;
2. its two closest distinct eclipses are ``d`` apart: ``d = k P`` (same kind) or
   ``d = (k − ½) P`` (a primary and a secondary) for some whole ``k ≥ 1``;
3. from ``k = 1`` up, the first candidate P that counts every eclipse of the night (no eclipse
   ambiguous or far from its prediction, and a straight line t = T + n P through them within
   5σ of every time) is taken: the longest period that puts every time of the night on an
   eclipse of its kind. A period ``P/j`` (every ``j``-th eclipse observed) fits
   the same times; that cannot be told from times alone, and the note says so;
4. the candidate's σ is that of a straight-line fit to the night's counted times.

When no night holds :data:`MIN_ECLIPSES` eclipses, or every candidate long enough to be told
from the timing noise fails, the error names the ambiguity and what to supply.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from numpy.typing import NDArray

from ucbplan.core.constants import HOUR_S
from ucbplan.errors import InputFileError
from ucbplan.timing.cycles import AMBIGUITY_FRACTION, count_cycles
from ucbplan.timing.eclipse_table import EclipseTimes
from ucbplan.timing.fit import solve_wls
from ucbplan.timing.initial import PeriodGuess

F64 = NDArray[np.float64]

#: A gap longer than this ends a night [s] (6 h: no night of eclipse timing has a longer one).
NIGHT_GAP_S = 6.0 * HOUR_S
#: Distinct eclipses a night needs to fix the period (two fit any period d/k alike).
MIN_ECLIPSES = 3
#: Two times closer than this many σ (combined) are the same eclipse measured twice.
SAME_ECLIPSE_SIGMA = 5.0


def _nights(times: EclipseTimes) -> list[NDArray[np.intp]]:
    """Indices of the times of each night, in time order."""
    breaks = np.flatnonzero(np.diff(times.t_s) > NIGHT_GAP_S) + 1
    return [np.asarray(part, dtype=np.intp) for part in np.split(np.arange(times.n), breaks)]


def _distinct(times: EclipseTimes, idx: NDArray[np.intp]) -> NDArray[np.intp]:
    """``idx`` without the repeats of an eclipse (a time within 5σ of the one before)."""
    keep = [int(idx[0])]
    for i in idx[1:]:
        j = keep[-1]
        if times.t_s[i] - times.t_s[j] > SAME_ECLIPSE_SIGMA * math.hypot(
            times.sigma_s[i], times.sigma_s[j]
        ):
            keep.append(int(i))
    return np.asarray(keep, dtype=np.intp)


def _subset(times: EclipseTimes, idx: NDArray[np.intp]) -> EclipseTimes:
    return dataclasses.replace(
        times,
        jd=tuple(times.jd[i] for i in idx),
        t_s=times.t_s[idx],
        sigma_s=times.sigma_s[idx],
        secondary=times.secondary[idx],
        cycle=None,
        rows=times.rows[idx],
    )


def _candidates(night: EclipseTimes) -> tuple[float, float, bool]:
    """Spacing ``d`` of the closest pair, its σ, and whether the pair mixes kinds."""
    gaps = np.diff(night.t_s)
    i = int(np.argmin(gaps))
    sigma = math.hypot(night.sigma_s[i], night.sigma_s[i + 1])
    return float(gaps[i]), sigma, bool(night.secondary[i] != night.secondary[i + 1])


def _line_fit(night: EclipseTimes, cycles: F64) -> tuple[float, float, float]:
    """Period, its σ [s] and the largest |residual|/σ of the straight line t = T + n P through
    the night's times."""
    a = np.stack([np.ones_like(cycles), cycles - cycles.mean()], axis=1)
    coef, cov = solve_wls(a, night.t_s, night.sigma_s)
    worst = float(np.max(np.abs(night.t_s - a @ coef) / night.sigma_s))
    return float(coef[1]), float(math.sqrt(cov[1, 1])), worst


def _night_period(night: EclipseTimes, origin: str) -> PeriodGuess | None:
    """The longest period that counts every eclipse of ``night`` (None: none long enough)."""
    d, sigma_d, mixed = _candidates(night)
    noise = float(np.max(night.sigma_s))
    for k in range(1, 10_000):
        step = (k - 0.5) if mixed else float(k)
        period = d / step
        if AMBIGUITY_FRACTION * period <= SAME_ECLIPSE_SIGMA * noise:
            return None  # shorter periods cannot be told from the timing noise
        guess = PeriodGuess(period_s=period, sigma_period_s=sigma_d / step, origin=origin)
        try:
            cycles = count_cycles(night, guess)
        except InputFileError:
            continue
        p, sigma_p, worst = _line_fit(night, cycles)
        if worst > SAME_ECLIPSE_SIGMA:
            continue  # counted, but a time is off its eclipse: not this period
        return PeriodGuess(period_s=p, sigma_period_s=sigma_p, origin=origin)
    return None


def period_from_times(times: EclipseTimes) -> PeriodGuess:
    """A first period from the eclipses of the best-covered night (see the module notes).

    Parameters
    ----------
    times : EclipseTimes
        The table, without a cycle column.

    Returns
    -------
    PeriodGuess
        P and σ_P [s] at that night; ``origin`` names the night for messages.

    Raises
    ------
    InputFileError
        No night with :data:`MIN_ECLIPSES` distinct eclipses, or one whose times fit no single
        period that the timing noise can tell: one line naming the ambiguity and the fixes.
    """
    fixes = "give `period` P, `initial` TARGET.yaml or a cycle column"
    nights = [_distinct(times, idx) for idx in _nights(times)]
    best = max(nights, key=len)  # the first of equally full nights
    if best.size < MIN_ECLIPSES:
        raise InputFileError(
            f"{times.label()}: column 'cycle': missing, and no night has {MIN_ECLIPSES} or more "
            f"eclipses to fix the period (at most {best.size} within "
            f"{NIGHT_GAP_S / HOUR_S:g} h of each other), so cycles cannot be counted from the "
            f"times alone; {fixes}"
        )
    night = _subset(times, best)
    first, last = times.jd[int(best[0])], times.jd[int(best[-1])]
    origin = f"the {best.size} eclipses of BJD_TDB {first:.4f}..{last:.4f}"
    guess = _night_period(night, origin)
    if guess is None:
        raise InputFileError(
            f"{times.label()}: counting cycles: {origin} (rows {times.rows[int(best[0])]}.."
            f"{times.rows[int(best[-1])]}) fit no single period long enough to tell from their "
            f"timing errors (every eclipse within P/8); {fixes}"
        )
    return guess
