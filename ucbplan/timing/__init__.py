"""Timing ephemerides from measured eclipse times: read, count cycles, fit, report, plot.

- :mod:`~ucbplan.timing.eclipse_table`: eclipse-time tables with full-precision epochs;
- :mod:`~ucbplan.timing.initial`: a first ephemeris (``--period``, ``--initial TARGET.yaml``);
- :mod:`~ucbplan.timing.cycles`: counting cycles from the times;
- :mod:`~ucbplan.timing.first_period`: a first period from one night's eclipses, when none is
  given;
- :mod:`~ucbplan.timing.fit`: the weighted least-squares fit of T0, P, Ṗ[, P̈];
- :mod:`~ucbplan.timing.document`: the JSON report and the timing target file;
- :mod:`~ucbplan.timing.plots`: the O − C figure.

:func:`fit_times` runs the whole chain.
"""

from __future__ import annotations

from pathlib import Path

from ucbplan.timing.cycles import count_cycles
from ucbplan.timing.eclipse_table import EclipseTimes, read_times
from ucbplan.timing.first_period import period_from_times
from ucbplan.timing.fit import EphemerisFit, fit_ephemeris
from ucbplan.timing.initial import PeriodGuess, period_guess, read_initial

__all__ = [
    "EclipseTimes",
    "EphemerisFit",
    "PeriodGuess",
    "count_cycles",
    "fit_ephemeris",
    "fit_times",
    "period_from_times",
    "period_guess",
    "read_initial",
    "read_times",
]


def fit_times(
    times: EclipseTimes,
    guess: PeriodGuess | None = None,
    terms: int = 3,
    clip: float | None = None,
) -> EphemerisFit:
    """Fit an ephemeris to ``times``: cycles from the table, else counted from ``guess``, else
    from the times alone (a first period from the best-covered night,
    :func:`~ucbplan.timing.first_period.period_from_times`).

    Raises
    ------
    InputError
        No cycle column, no guess and no night that fixes the period; an ambiguous count; too
        few times; see the parts.
    """
    if times.cycle is not None:
        return fit_ephemeris(times, times.cycle, terms, clip, "given in the table")
    if guess is None:
        guess = period_from_times(times)
    cycles = count_cycles(times, guess)
    return fit_ephemeris(times, cycles, terms, clip, f"counted from the times ({guess.origin})")


def load_and_fit(
    path: Path,
    guess: PeriodGuess | None = None,
    terms: int = 3,
    clip: float | None = None,
) -> tuple[EclipseTimes, EphemerisFit]:
    """Read a table and fit it (:func:`read_times` then :func:`fit_times`)."""
    times = read_times(path)
    return times, fit_times(times, guess, terms, clip)
