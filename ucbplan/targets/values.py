"""Scalar values of a target file: quantities with units, plain numbers, angles and epochs.

Each reader takes the schema :class:`~ucbplan.targets.fieldtypes.Field` it reads (unit, example,
allowed range) and fails with a one-line :class:`~ucbplan.errors.TargetFileError`
``file: field: expected …, got …``. Values are quoted with :func:`~ucbplan.errors.shorten`, text
longer than any valid value is refused before it is parsed, and a unit of the wrong dimension is
refused saying which dimension was given and which unit to write (no angle is dropped silently:
ω in rad/s is not f in Hz).
"""

from __future__ import annotations

import datetime as _dt
import difflib
import math
import re
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

from astropy import units as u
from astropy.time import Time

from ucbplan.core.epochs import MAX_EPOCH_CHARS, epoch_in_scale, split_scale_label
from ucbplan.errors import EpochRangeError, TargetFileError, shorten
from ucbplan.targets.fastvalues import cached_epoch, quantity_in, sexagesimal_deg
from ucbplan.targets.fieldtypes import Field
from ucbplan.targets.schema import field

#: A plain decimal number (PyYAML leaves exponents without a decimal point, 1e-6, as strings).
NUM_RE = re.compile(r"^\s*[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?\s*$")
#: Longest number, quantity or angle text [characters] ("-1.0650000000000001e-26 Hz / s2" is 31).
MAX_VALUE_CHARS = 100
#: Longest message [characters] (the issue's bound; values are shortened well below it).
MAX_MESSAGE_CHARS = 399
#: Exceptions a malformed value can raise inside numpy/astropy/the standard library.
MALFORMED = (
    TypeError,
    ValueError,
    OverflowError,
    ArithmeticError,
    UnicodeError,
    KeyError,
    IndexError,
    AttributeError,
    RecursionError,
)


def one_line(text: str) -> str:
    """``text`` on one line, at most 399 characters, printable on any UTF-8 terminal (a lone
    surrogate from an undecodable file name is escaped)."""
    text = " ".join(text.splitlines())
    text = text.encode("utf-8", "backslashreplace").decode("utf-8")
    if len(text) > MAX_MESSAGE_CHARS:
        text = f"{text[: MAX_MESSAGE_CHARS - 1]}…"
    return text


class Ctx:
    """Error context: the file name that starts every message."""

    def __init__(self, path: Path | None) -> None:
        name = path.name if path is not None else "<target>"
        self.label = name if len(name) <= 80 else f"{name[:79]}…"

    def fail(self, fieldname: str, msg: str) -> TargetFileError:
        """A one-line error ``label: fieldname: msg`` (to raise), at most 399 characters."""
        return TargetFileError(one_line(f"{self.label}: {fieldname}: {msg}"))

    @staticmethod
    def key(key: Any) -> str:
        """A mapping key as it appears in a field path (quoted and shortened unless plain)."""
        if isinstance(key, str) and 0 < len(key) <= 60 and key.isprintable():
            return key
        return shorten(key, 60)

    def reading(self, where: str, what: str = "a value") -> _Reading:
        """Turn a stray exception of a malformed value into a one-line error at ``where``."""
        return _Reading(self, where, what)


class _Reading:
    """The context of :meth:`Ctx.reading` (a class: entered for every value of every file)."""

    __slots__ = ("ctx", "what", "where")

    def __init__(self, ctx: Ctx, where: str, what: str) -> None:
        self.ctx, self.where, self.what = ctx, where, what

    def __enter__(self) -> None:
        return None

    def __exit__(
        self, kind: type[BaseException] | None, exc: BaseException | None, tb: Any
    ) -> None:
        if kind is None or issubclass(kind, TargetFileError) or not issubclass(kind, MALFORMED):
            return
        raise self.ctx.fail(
            self.where,
            f"expected {self.what}, got a value that cannot be read ({kind.__name__})",
        ) from None


def did_you_mean(name: Any, options: Iterable[str]) -> str:
    """``"did you mean 'x'? "`` for the option closest to ``name`` (empty when none is close)."""
    if not isinstance(name, str) or len(name) > 60:
        return ""
    close = difflib.get_close_matches(name, list(options), n=1, cutoff=0.6)
    if not close:
        close = [o for o in options if o.lower() == name.lower()]
    return f"did you mean {close[0]!r}? " if close else ""


def check_keys(ctx: Ctx, section: str, mapping: Mapping[Any, Any], allowed: Sequence[str]) -> None:
    """Fail on the first key of ``mapping`` (document order) that is not in ``allowed``, naming
    the closest allowed key."""
    for key in mapping:
        if isinstance(key, str) and key in allowed:
            continue
        path = f"{section}.{ctx.key(key)}" if section else ctx.key(key)
        hint = did_you_mean(key, allowed)
        if hint:
            raise ctx.fail(path, f"unknown field; {hint.strip()}")
        raise ctx.fail(path, f"unknown field; expected some of {', '.join(allowed)}")


def to_float(x: Any) -> float:
    """A YAML number or numeric string as float (``ValueError`` otherwise, booleans included)."""
    if isinstance(x, bool):
        raise ValueError("boolean")
    if isinstance(x, int | float):
        try:
            return float(x)
        except OverflowError:
            raise ValueError("too large for a float") from None
    if isinstance(x, str) and len(x) <= MAX_VALUE_CHARS and NUM_RE.match(x):
        return float(x)
    raise ValueError("not a number")


def check_range(ctx: Ctx, f: Field, value: float, raw: Any, where: str | None = None) -> None:
    """Fail with the field's range message (and its reason) if ``value`` is outside
    ``f.bounds``."""
    b = f.bounds
    if b is not None and not b.contains(value):
        msg = b.error.format(raw=shorten(raw), value=value)
        raise ctx.fail(where or f.path, f"{msg} ({b.reason})" if b.reason else msg)


def parse_number(ctx: Ctx, f: Field, value: Any) -> float:
    """A plain finite number (no unit), e.g. ``priority`` or ``vmag``."""
    try:
        x = to_float(value)
    except ValueError:
        raise ctx.fail(
            f.path, f"expected a number like {f.example}, got {shorten(value)}"
        ) from None
    if not math.isfinite(x):
        raise ctx.fail(f.path, f"expected a finite number, got {shorten(value)}")
    return x


def parse_choice(ctx: Ctx, f: Field, value: Any) -> str:
    """One of ``f.choices`` (any case), returned as the schema spells it."""
    options = ", ".join(f.choices)
    if isinstance(value, str) and len(value) <= MAX_VALUE_CHARS:
        text = value.strip().lower()
        for choice in f.choices:
            if choice.lower() == text:
                return choice
        hint = did_you_mean(value.strip(), f.choices)
        raise ctx.fail(f.path, f"{hint}expected one of {options}, got {shorten(value)}")
    raise ctx.fail(f.path, f"expected one of {options}, got {shorten(value)}")


def parse_quantity(ctx: Ctx, f: Field, value: Any, where: str | None = None) -> float:
    """A bare number (in ``f.unit``) or an astropy quantity string, as a float in ``f.unit``.

    ``where`` replaces ``f.path`` in messages (a covariance σ is read with its parameter's field).
    Ranges are not checked here (:func:`check_range`).
    """
    if type(value) is str and len(value) <= MAX_VALUE_CHARS and f.unit is not None:
        fast = quantity_in(value, f.unit)  # "<number> <unit>", the usual spelling
        if fast is not None and math.isfinite(fast):
            return fast
    path = where or f.path
    expect = f"expected {f.what} like {f.example}"
    if isinstance(value, bool) or value is None:
        raise ctx.fail(path, f"{expect}, got {shorten(value)}")
    if f.unit_required and _bare_number(value):
        raise ctx.fail(
            path,
            f"{expect}, got the bare number {shorten(value)}; write its unit (it could be "
            "seconds or days)",
        )
    if isinstance(value, int | float):
        try:
            x = to_float(value)
        except ValueError:
            raise ctx.fail(path, f"{expect}, got a number too large for a float") from None
    elif isinstance(value, str):
        if len(value) > MAX_VALUE_CHARS:
            raise ctx.fail(path, f"{expect}, got {shorten(value)} (too long for a value)")
        with ctx.reading(path, f"{f.what} like {f.example}"):
            x = _quantity_text(ctx, path, f, value)
    else:
        raise ctx.fail(path, f"{expect}, got {_kind(value)} {shorten(value)}")
    if not math.isfinite(x):
        raise ctx.fail(path, f"{expect}, got non-finite value {shorten(value)}")
    return x


def _bare_number(value: Any) -> bool:
    """Whether ``value`` is a number without a unit (a YAML number or a numeric string)."""
    if isinstance(value, int | float):
        return True
    return isinstance(value, str) and len(value) <= MAX_VALUE_CHARS and bool(NUM_RE.match(value))


def _kind(value: Any) -> str:
    """``a list``, ``a mapping``, … for messages."""
    if isinstance(value, list | tuple):
        return "a list"
    if isinstance(value, dict):
        return "a mapping"
    return f"a {type(value).__name__}"


def _quantity_text(ctx: Ctx, path: str, f: Field, value: str) -> float:
    """A number string (bare, or YAML ``.nan``/``.inf``) or a quantity string in ``f.unit``."""
    expect = f"expected {f.what} like {f.example}"
    text = value.strip()
    if NUM_RE.match(text) or text.lower().lstrip("+-.") in ("nan", "inf"):
        return float(text.replace(".nan", "nan").replace(".inf", "inf"))
    assert f.unit is not None, f.path  # a quantity field has a unit ("" when dimensionless)
    fast = quantity_in(text, f.unit)
    if fast is not None:
        return fast
    try:
        q = u.Quantity(text)
    except MALFORMED:
        raise ctx.fail(path, f"{expect}, got {shorten(value)} (not a number with a unit)") from None
    if not q.isscalar:
        raise ctx.fail(path, f"{expect}, got {shorten(value)} (not a number with a unit)")
    unit = u.Unit(f.unit)
    try:
        return float(q.to_value(unit))
    except u.UnitConversionError:
        raise ctx.fail(
            path, f"{expect}, got {shorten(value)}{_dimension_help(f, q, path == f.path)}"
        ) from None


def _physical(unit: u.UnitBase) -> str:
    """What a unit measures, for messages: ``an angular frequency``, ``a length``, …"""
    if unit.physical_type == "dimensionless":
        return "a plain number"
    kind = str(unit.physical_type).split("/")[0].replace("_", " ")
    if kind == "unknown":
        return f"a quantity in {unit}"
    return f"{'an' if kind[0] in 'aeiou' else 'a'} {kind}"


def _dimension_help(f: Field, q: u.Quantity, own_field: bool) -> str:
    """`` (a length); give s`` — what the given unit measures and the unit to write.

    ``own_field``: the value is the field itself (not a σ read in its unit), so an angle given
    for a cosine can be answered with the cosine to write.
    """
    given = q.unit
    unit = u.Unit(f.unit)
    label = str(unit) if str(unit) else "a plain number"
    what = f" ({_physical(given)})"
    if given.physical_type == "angle":
        if f.cosine_of and own_field:
            deg = float(q.to_value(u.deg))
            return (
                f"{what}; {f.name} is a cosine, dimensionless: for an {f.cosine_of} of {deg:g} "
                f"deg write {f.name}: {math.cos(math.radians(deg)):.3g}"
            )
    elif (given / u.rad).is_equivalent(unit):
        what = f" ({_physical(given)}, with an angle)"
    elif (given * u.rad).is_equivalent(unit):
        what = f" ({_physical(given)}, no angle)"
    return f"{what}; {f.dimension_hint or f'give {label}'}"


def parse_angle(ctx: Ctx, f: Field, value: Any, hours: bool = False) -> float:
    """An angle in degrees: bare degrees, sexagesimal (hours if ``hours``) or with a unit.

    The range of ``f.bounds`` is checked.
    """
    expect = f"expected an angle like {f.example}"
    if isinstance(value, str) and len(value) > MAX_VALUE_CHARS:
        raise ctx.fail(f.path, f"{expect}, got {shorten(value)} (too long for an angle)")
    try:
        deg = _angle_deg(value, hours)
    except (*MALFORMED, u.UnitsError):
        raise ctx.fail(f.path, f"{expect}, got {shorten(value)}") from None
    if not math.isfinite(deg):
        raise ctx.fail(f.path, f"expected a finite angle like {f.example}, got {shorten(value)}")
    check_range(ctx, f, deg, value)
    return deg


def fast_angle_deg(value: Any, hours: bool) -> float | None:
    """Degrees of an angle value's common spellings (:mod:`~ucbplan.targets.fastvalues`, the
    same floats as astropy's); None: astropy reads it (:func:`parse_angle`)."""
    if isinstance(value, int | float) and not isinstance(value, bool):
        return to_float(value)
    if not isinstance(value, str):
        raise ValueError
    text = value.strip()
    if NUM_RE.match(text):
        return float(text)
    fast = sexagesimal_deg(text, hours)
    if fast is not None:
        return fast
    if _spaced(text):
        return None
    return quantity_in(text, "deg")  # a number with an angle unit


def _spaced(text: str) -> bool:
    """Sexagesimal fields separated by colons or spaces (astropy's Angle reads them)."""
    return ":" in text or (" " in text and not re.search(r"[a-zA-Z]", text))


def _angle_deg(value: Any, hours: bool) -> float:
    """Degrees of an angle value: the common spellings read directly (:func:`fast_angle_deg`),
    the rest by astropy."""
    fast = fast_angle_deg(value, hours)
    if fast is not None:
        return fast
    text = value.strip()
    spaced = _spaced(text)
    from astropy.coordinates import Angle  # the other spellings (imported only for them)

    if spaced:
        return float(Angle(text, unit=u.hourangle if hours else u.deg).to_value(u.deg))
    try:  # "1.5e-05 deg": astropy's angle parser refuses exponents, its quantity parser not
        q = u.Quantity(text)
    except MALFORMED:
        pass
    else:
        if q.isscalar and q.unit.physical_type == "angle":
            return float(Angle(q).to_value(u.deg))
    angle = Angle(text)
    if not angle.isscalar:
        raise ValueError
    return float(angle.to_value(u.deg))


def parse_epoch(ctx: Ctx, f: Field, value: Any, scale_field: Any) -> tuple[Time, str | None]:
    """An epoch as TDB, and the scale it was converted from (None if it was TDB).

    ``scale_field`` is the raw ``t_ref_scale`` (None if absent). An epoch labelled with another
    scale ("… UTC") is refused unless that scale is stated, so nothing converts silently.
    """
    scale_given = _scale_given(ctx, scale_field)
    raw_text = _epoch_text(ctx, f, value)
    text, label = split_scale_label(raw_text)
    if label is not None and scale_given is None and label != "tdb":
        raise ctx.fail(
            f.path,
            f"epochs must be TDB at the barycentre, got a {label.upper()}-labelled epoch "
            f"{shorten(value)}; if it really is {label.upper()}, add 't_ref_scale: {label}' and "
            "ucbplan converts it explicitly",
        )
    if label is not None and scale_given is not None and label != scale_given:
        raise ctx.fail(f.path, f"label {label.upper()} contradicts t_ref_scale: {scale_given}")
    scale = scale_given or label or "tdb"
    try:
        tdb = cached_epoch(text, scale, True, lambda: epoch_in_scale(text, scale, isot_if_t=True))
    except EpochRangeError as exc:
        raise ctx.fail(f.path, f"{shorten(value)} {exc}") from None
    except ValueError:
        raise ctx.fail(
            f.path, f"expected an ISO epoch like {f.example} (TDB), got {shorten(value)}"
        ) from None
    return tdb, (None if scale == "tdb" else scale)


def _scale_given(ctx: Ctx, scale_field: Any) -> str | None:
    """The stated time scale (lower case), or None if ``t_ref_scale`` is absent."""
    if scale_field is None:
        return None
    return parse_choice(ctx, field("lisa.t_ref_scale"), scale_field)


def _epoch_text(ctx: Ctx, f: Field, value: Any) -> str:
    """The epoch as text (YAML may hand over a date/datetime; time zones are refused)."""
    if isinstance(value, _dt.datetime | _dt.date):
        if isinstance(value, _dt.datetime) and value.tzinfo is not None:
            raise ctx.fail(
                f.path,
                f"expected a TDB epoch without time zone, got {shorten(value)}; quote the epoch "
                "and drop the offset",
            )
        return value.isoformat()
    if isinstance(value, str) and len(value.strip()) <= MAX_EPOCH_CHARS + 8:
        return value.strip()
    raise ctx.fail(f.path, f"expected an ISO epoch like {f.example}, got {shorten(value)}")
