"""Exception hierarchy: every user-facing failure is a ``UcbplanError``.

Each subclass also inherits the matching built-in so callers can catch either.
Messages say what, where (file/field), got vs expected, and how to fix it.
"""

from __future__ import annotations

__all__ = [
    "ConvergenceError",
    "InputFileError",
    "OutputExistsError",
    "SiteError",
    "TargetFileError",
    "UcbplanError",
    "VelocityFileError",
]


class UcbplanError(Exception):
    """Base class of all ucbplan errors shown to users as one line."""


class TargetFileError(UcbplanError, ValueError):
    """A target YAML file is malformed or physically out of range."""


class InputFileError(UcbplanError, ValueError):
    """A generic input file (table, config) is malformed."""


class VelocityFileError(InputFileError):
    """A velocity table has a malformed row or column."""


class SiteError(UcbplanError, ValueError):
    """An observatory site is unknown or malformed."""


class OutputExistsError(UcbplanError, FileExistsError):
    """An output file exists and ``--overwrite`` was not given."""


class ConvergenceError(UcbplanError, RuntimeError):
    """A numerical solver did not converge."""
