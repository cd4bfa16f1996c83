"""Barycentric TDB <-> UTC at an observatory, and the coverage of astropy's time tables.

placeholder: filled in below.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterator
from contextlib import contextmanager

__all__ = ["quiet_erfa"]


@contextmanager
def quiet_erfa() -> Iterator[None]:
    """Silence ERFA's "dubious year" warnings for dates past the leap-second table.

    The planner reports table coverage itself (:func:`coverage_warnings`) in words a user can act
    on, once per run, instead of one ERFA warning per call.
    """
    from erfa import ErfaWarning

    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", category=ErfaWarning)
        yield
