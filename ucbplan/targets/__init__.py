"""Target files: the YAML contract, its validation, and the :class:`Target` record.

Modules: ``model`` (the :class:`Target` / :class:`Spectroscopy` / :class:`TimingSection`
records), ``schema`` (every field of a target file declared once: unit, range, example, default),
``fieldtypes`` (the schema's :class:`Field` and :class:`Range` records), ``fieldgroups`` (families
of fields that share a shape: phase parameters, velocities, eccentricity, covariance),
``values`` (scalar readers), ``fastvalues`` (their common spellings read without astropy's
parsers, the same floats), ``sections`` (helpers shared by the sections), ``parse``
(:func:`load_target`), ``columnwise`` (:func:`load_target_files`: many files validated column
by column), ``timing_section`` (``timing``, ``magnitudes``, ``references``),
``covariance`` (``lisa.covariance``, ``timing.covariance``), ``samples`` (posterior samples
files), ``write`` (:func:`write_target`).
"""

from ucbplan.targets.columnwise import load_target_files
from ucbplan.targets.model import Spectroscopy, Target, TimingSection
from ucbplan.targets.parse import (
    check_distinct_files,
    load_target,
    load_target_documents,
    load_targets,
    target_from_dict,
)
from ucbplan.targets.samples import load_samples, read_samples_file
from ucbplan.targets.write import target_to_dict, write_target

__all__ = [
    "Spectroscopy",
    "Target",
    "TimingSection",
    "check_distinct_files",
    "load_samples",
    "load_target",
    "load_target_documents",
    "load_target_files",
    "load_targets",
    "read_samples_file",
    "target_from_dict",
    "target_to_dict",
    "write_target",
]
