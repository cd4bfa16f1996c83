"""Reduce measured velocities to K_j, γ_j, masses, Δκ and Δv_CM (paper Secs. 3–5).

The pipeline lives in :mod:`ucbplan.reduce.pipeline`; this package re-exports its public API.
"""

from ucbplan.reduce.pipeline import ReduceOptions, Reduction, read_samples, read_velocities, reduce

__all__ = ["ReduceOptions", "Reduction", "read_samples", "read_velocities", "reduce"]
