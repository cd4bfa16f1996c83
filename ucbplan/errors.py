"""Exception hierarchy: every user-facing failure is a ``UcbplanError``.

Four kinds, each also inheriting the matching built-in so callers can catch either:

- :class:`InputError` (``ValueError``): an option value or an input is wrong; its subclass
  :class:`SchemaError` is a file that does not follow its documented format
  (:class:`TargetFileError`, :class:`InputFileError`, :class:`VelocityFileError`);
- :class:`OutputError` (``OSError``): an output cannot be written (:class:`OutputExistsError`);
- :class:`NumericalError` (``ArithmeticError``): a computation cannot give a trustworthy answer
  (:class:`ConvergenceError`).

Messages are one line: ``FILE: field: expected …, got …`` and how to fix it. Quote input values
with :func:`shorten` so a huge value never makes a huge message.
"""

from __future__ import annotations

__all__ = [
    "ConvergenceError",
    "InputError",
    "InputFileError",
    "NumericalError",
    "OutputError",
    "OutputExistsError",
    "SchemaError",
    "SiteError",
    "TargetFileError",
    "UcbplanError",
    "VelocityFileError",
    "shorten",
]

#: Longest quoted input value in an error message [characters].
MAX_VALUE_CHARS = 200


def shorten(value: object, limit: int = MAX_VALUE_CHARS) -> str:
    """``repr(value)`` cut to ``limit`` characters (with an ellipsis and the full length).

    A numpy scalar is shown as the number or text a user writes (``-1.0``, ``'abc'``), not as
    numpy's ``np.float64(-1.0)``.
    """
    if type(value).__module__ == "numpy" and getattr(value, "ndim", None) == 0:
        value = value.item()  # type: ignore[attr-defined]
    text = repr(value)
    if len(text) <= limit:
        return text
    return f"{text[: limit - 1]}… ({len(text)} characters)"


class UcbplanError(Exception):
    """Base class of all ucbplan errors shown to users as one line."""


class InputError(UcbplanError, ValueError):
    """An option value or input value is invalid."""


class SchemaError(InputError):
    """A file does not follow its documented format (unknown field, wrong unit, bad row)."""


class TargetFileError(SchemaError):
    """A target YAML file is malformed or physically out of range."""


class InputFileError(SchemaError):
    """A generic input file (table, config) is malformed."""


class VelocityFileError(InputFileError):
    """A velocity table has a malformed row or column."""


class SiteError(InputError):
    """An observatory site is unknown or malformed."""


class OutputError(UcbplanError, OSError):
    """An output file cannot be written (folder missing or read-only, disk full, not a file)."""


class OutputExistsError(OutputError, FileExistsError):
    """An output file exists and ``--overwrite`` was not given."""


class NumericalError(UcbplanError, ArithmeticError):
    """A computation cannot give a trustworthy answer."""


class ConvergenceError(NumericalError, RuntimeError):
    """A numerical solver did not converge."""
