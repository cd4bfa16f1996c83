"""Target files: the YAML contract, its validation, and the :class:`Target` record.

Public API: :func:`load_target`, :func:`write_target`, :class:`Target`, :class:`Spectroscopy`.
"""

from ucbplan.target.model import (
    Spectroscopy,
    Target,
    load_samples,
    load_target,
    target_from_dict,
    target_to_dict,
    write_target,
)

__all__ = [
    "Spectroscopy",
    "Target",
    "load_samples",
    "load_target",
    "target_from_dict",
    "target_to_dict",
    "write_target",
]
