"""Reduce measured velocities to K_j, γ_j, masses, Δκ and Δv_CM (paper Secs. 3–5).

The pipeline lives in :mod:`ucbplan.reduce.pipeline`; this package is the public entry point
(:func:`reduce`, its options and record, and the velocity reader).
Its steps: :mod:`~ucbplan.reduce.velocities` (read, validate), :mod:`~ucbplan.reduce.design`
(ephemeris → design variable), :mod:`~ucbplan.reduce.regression` (fits),
:mod:`~ucbplan.reduce.montecarlo` and :mod:`~ucbplan.reduce.masses` (masses),
:mod:`~ucbplan.reduce.groups` and :mod:`~ucbplan.reduce.drifts` (inter-session differences),
:mod:`~ucbplan.reduce.report` and :mod:`~ucbplan.reduce.plots` (output).
"""

from ucbplan.reduce.pipeline import ReduceOptions, Reduction, reduce
from ucbplan.reduce.velocities import read_velocities

__all__ = ["ReduceOptions", "Reduction", "read_velocities", "reduce"]
