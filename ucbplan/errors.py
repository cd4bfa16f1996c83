"""Exception hierarchy: every user-facing failure is a ``UcbplanError``.

Four kinds, each also inheriting the matching built-in so callers can catch either:

- :class:`InputError` (``ValueError``): an option value or an input is wrong; its subclass
  :class:`SchemaError` is a file that does not follow its documented format
  (:class:`TargetFileError`, :class:`InputFileError`, :class:`VelocityFileError`);
- :class:`OutputError` (``OSError``): an output cannot be written (:class:`OutputExistsError`);
- :class:`NumericalError` (``ArithmeticError``): a computation cannot give a trustworthy answer
  (:class:`ConvergenceError`).

Messages are one line: ``FILE: field: expected …, got …`` and how to fix it. Quote input values
with :func:`shorten` so a huge value never makes a huge message. A library error about an
argument names the parameter (``airmass_max: expected …``) and may carry it in
:attr:`InputError.parameter`; the command line maps parameter names to its flags in one place
(``ucbplan.cli._flags``).

Warnings a user must act on are emitted through :func:`warnings.warn` with a category of the
:class:`UcbplanWarning` tree (so a script can filter or escalate them) as well as returned in
the results' ``warnings`` lists; :func:`emit` does both with one line. Each line's class is its
cause's, chosen where the line is made: :class:`EarthOrientationWarning` (past the bundled time
tables), :class:`PlanWarning` and under it :class:`SmearingWarning`, :class:`ExposureWarning`,
:class:`EphemerisRangeWarning`; :class:`ReduceWarning` and under it
:class:`SamplerConvergenceWarning`.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence

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
    if "\n" in text:  # a SkyCoord's repr spans lines; an error message has one
        text = " ".join(text.split())
    if len(text) <= limit:
        return text
    return f"{text[: limit - 1]}… ({len(text)} characters)"


class UcbplanError(Exception):
    """Base class of all ucbplan errors shown to users as one line.

    A control character in the message (a newline in a file name a user typed, say) is written
    as its escape (``\\n``), so that the message stays one line whatever value it quotes.
    """

    def __init__(self, *args: object) -> None:
        if args and isinstance(args[0], str) and not args[0].isprintable():
            args = (_escaped(args[0]), *args[1:])
        super().__init__(*args)


def _escaped(text: str) -> str:
    """``text`` with each non-printable character as its Python escape (``\\n``, ``\\x00``)."""
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)


class InputError(UcbplanError, ValueError):
    """An option value or input value is invalid.

    Parameters
    ----------
    message : str
        One line: what is wrong, what was expected and how to fix it.
    parameter : str, optional
        The library parameter at fault (``airmass_max``), when one is; the command line names
        its flag instead (``--airmass-max``).
    """

    def __init__(self, message: str = "", parameter: str | None = None) -> None:
        super().__init__(message)
        self.parameter = parameter


class EpochRangeError(InputError):
    """An epoch that parses but lies outside the supported years (``YEAR_RANGE``)."""


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


class UcbplanWarning(UserWarning):
    """Base class of the warnings ucbplan emits: something the user must act on.

    Silence all of them with ``warnings.simplefilter("ignore", ucbplan.UcbplanWarning)`` or
    turn them into errors with ``"error"``.
    """


class EarthOrientationWarning(UcbplanWarning):
    """Times past the bundled IERS Earth-orientation predictions or leap-second table."""


class PlanWarning(UcbplanWarning):
    """A plan was made but something in it needs attention (smearing, horizons, budgets)."""


class SmearingWarning(PlanWarning):
    """An exposure smears the radial-velocity curve past the plan's budget (Λ_K, K(1−Λ_K))."""


class ExposureWarning(PlanWarning):
    """The exposure time chosen needs attention (not optimised, capped, no readout given)."""


class EphemerisRangeWarning(PlanWarning):
    """Epochs past the ephemeris' validity horizon T_valid: σ_u above the phase tolerance."""


class ReduceWarning(UcbplanWarning):
    """A reduction finished but something in its input or result needs attention."""


class SamplerConvergenceWarning(ReduceWarning):
    """A posterior chain too short for its autocorrelation time: its σ's are not reliable."""


def emit(
    lines: list[str],
    category: type[UcbplanWarning] | Sequence[type[UcbplanWarning]],
    stacklevel: int = 3,
) -> list[str]:
    """Emit each warning line through :func:`warnings.warn` and return the lines unchanged
    (they also go into the result).

    ``category`` is the class of every line, or one class per line: the cause's class, chosen
    where the line was made (never guessed from its text).
    """
    kinds = [category] * len(lines) if isinstance(category, type) else list(category)
    for line, kind in zip(lines, kinds, strict=True):
        warnings.warn(line, kind, stacklevel=stacklevel)
    return lines
