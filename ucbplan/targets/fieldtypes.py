"""The records of the target-file schema: :class:`Field` and its bounds, :class:`Range`.

:mod:`ucbplan.targets.schema` declares every field of a target file with them;
:mod:`ucbplan.targets.fieldgroups` builds the families of fields that share a shape.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Literal

#: How a field's value is read: a number with a unit, a plain number, an angle, an epoch, one of
#: ``choices``, free text, a file name, a nested mapping (a section), a list, or anything.
Kind = Literal[
    "quantity", "number", "angle", "epoch", "choice", "text", "file", "mapping", "list", "any"
]


@dataclass(frozen=True, slots=True)
class Range:
    """Allowed interval of a value (in the field's unit) and why.

    Attributes
    ----------
    low, high : float
        Interval ends (±inf when unbounded).
    low_open, high_open : bool
        Whether the end itself is excluded.
    reason : str
        The physical reason for the bound (for the docs).
    error : str
        Message after ``file: field:`` when a value falls outside; ``{raw}`` is the value as
        written (quoted and shortened), ``{value}`` the parsed number. The parser appends the
        reason in parentheses.
    """

    low: float = -math.inf
    high: float = math.inf
    low_open: bool = False
    high_open: bool = False
    reason: str = ""
    error: str = "must be positive, got {raw}"

    def contains(self, x: float) -> bool:
        """Whether ``x`` lies inside the interval."""
        above = x > self.low if self.low_open else x >= self.low
        below = x < self.high if self.high_open else x <= self.high
        return above and below

    def __str__(self) -> str:
        """Interval notation, e.g. ``(0, inf)`` or ``[-1, 1]`` (infinite ends are open)."""
        left = "(" if self.low_open or math.isinf(self.low) else "["
        right = ")" if self.high_open or math.isinf(self.high) else "]"
        return f"{left}{self.low:g}, {self.high:g}{right}"


@dataclass(frozen=True, slots=True)
class Field:
    """One field of a target file.

    Attributes
    ----------
    path : str
        Dotted path in the document, e.g. ``"lisa.f_gw"`` (also the path in error messages).
    kind : Kind
        How the value is read.
    what : str
        What the value is, as in "expected a frequency like …".
    example : str
        A valid value as written in a target file (with its unit where it has one).
    unit : str or None
        Astropy unit string of the value inside ucbplan; a bare number in the file is taken in
        this unit (``""`` dimensionless; None for values without a unit).
    required : bool
        Whether the field must be present (inside its section, if that section is given).
    default : object
        Value used when the field is absent (None: stays unset).
    bounds : Range or None
        Allowed interval after conversion to ``unit``.
    choices : tuple of str
        Allowed values of a ``choice`` field.
    doc : str
        One line for the target-file reference.
    dimension_hint : str
        How to fix a quantity given with the wrong dimension (e.g. ``give Hz (f = ω/2π)``);
        empty: "give <unit>".
    cosine_of : str
        For a cosine (dimensionless): the angle it is the cosine of; an angle given instead is
        refused with the cosine to write.
    unit_required : bool
        A bare number is refused: the value must carry its unit (a period or a σ of T0 is
        published in seconds or in days; guessing would be off by 86400).
    """

    path: str
    kind: Kind
    what: str
    example: str
    unit: str | None = None
    required: bool = False
    default: Any = None
    bounds: Range | None = None
    choices: tuple[str, ...] = ()
    doc: str = ""
    dimension_hint: str = ""
    cosine_of: str = ""
    unit_required: bool = False

    #: Last component of the path (the key in its mapping); derived from ``path``.
    name: str = dataclasses.field(init=False, repr=False, compare=False)
    #: Path of the mapping that holds the field (``""`` for the top level); derived.
    section: str = dataclasses.field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        # kept, not recomputed: every value of every target file looks them up
        section, _, name = self.path.rpartition(".")
        object.__setattr__(self, "name", name)
        object.__setattr__(self, "section", section)
