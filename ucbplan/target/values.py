"""Scalar values of a target file: quantities with units, plain numbers, angles and epochs.

Each reader takes the schema :class:`~ucbplan.target.schema.Field` it reads (unit, example,
allowed range) and fails with a one-line :class:`~ucbplan.errors.TargetFileError`
``file: field: expected …, got …``.
"""

from __future__ import annotations

import datetime as _dt
import math
import re
import warnings
from pathlib import Path
from typing import Any

from astropy import units as u
from astropy.coordinates import Angle
from astropy.time import Time
from erfa import ErfaWarning

from ucbplan.errors import TargetFileError
from ucbplan.target.schema import Field, field

__all__ = [
    "Ctx",
    "check_range",
    "parse_angle",
    "parse_epoch",
    "parse_number",
    "parse_quantity",
    "to_float",
]

#: A plain decimal number (PyYAML leaves exponents without a decimal point, 1e-6, as strings).
NUM_RE = re.compile(r"^\s*[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?\s*$")
_SCALE_LABEL_RE = re.compile(r"^(.*?)\s*\(?\b(TDB|TCB|TT|UTC|TAI)\b\)?$", flags=re.IGNORECASE)


class Ctx:
    """Error context: the file name that starts every message."""

    def __init__(self, path: Path | None) -> None:
        self.label = path.name if path is not None else "<target>"

    def fail(self, fieldname: str, msg: str) -> TargetFileError:
        """A one-line error ``label: fieldname: msg`` (to raise)."""
        return TargetFileError(f"{self.label}: {fieldname}: {msg}")


def to_float(x: Any) -> float:
    """A YAML number or numeric string as float (``ValueError`` otherwise, booleans included)."""
    if isinstance(x, bool):
        raise ValueError("boolean")
    if isinstance(x, int | float):
        return float(x)
    if isinstance(x, str) and NUM_RE.match(x):
        return float(x)
    raise ValueError(f"not a number: {x!r}")


def check_range(ctx: Ctx, f: Field, value: float, raw: Any, where: str | None = None) -> None:
    """Fail with the field's range message if ``value`` lies outside ``f.bounds``."""
    if f.bounds is not None and not f.bounds.contains(value):
        raise ctx.fail(where or f.path, f.bounds.error.format(raw=raw, value=value))


def parse_number(ctx: Ctx, f: Field, value: Any) -> float:
    """A plain finite number (no unit), e.g. ``priority`` or ``vmag``."""
    try:
        x = to_float(value)
    except ValueError:
        raise ctx.fail(f.path, f"expected a number, got {value!r}") from None
    if not math.isfinite(x):
        raise ctx.fail(f.path, f"expected a finite number, got {value!r}")
    return x


def parse_quantity(ctx: Ctx, f: Field, value: Any, where: str | None = None) -> float:
    """A bare number (in ``f.unit``) or an astropy quantity string, as a float in ``f.unit``.

    ``where`` replaces ``f.path`` in messages (a covariance σ is read with its parameter's field).
    Ranges are not checked here (:func:`check_range`).
    """
    path = where or f.path
    expect = f"expected {f.what} like {f.example}"
    if isinstance(value, bool) or value is None:
        raise ctx.fail(path, f"{expect}, got {value!r}")
    if isinstance(value, int | float):
        x = float(value)
    elif isinstance(value, str):
        x = _quantity_text(ctx, path, expect, value, u.Unit(f.unit))
    else:
        raise ctx.fail(path, f"{expect}, got {type(value).__name__} {value!r}")
    if not math.isfinite(x):
        raise ctx.fail(path, f"{expect}, got non-finite value {value!r}")
    return x


def _quantity_text(ctx: Ctx, path: str, expect: str, value: str, unit: u.UnitBase) -> float:
    """A number string (bare, or YAML ``.nan``/``.inf``) or a quantity string in ``unit``."""
    text = value.strip()
    if NUM_RE.match(text) or text.lower().lstrip("+-.") in ("nan", "inf"):
        return float(text.replace(".nan", "nan").replace(".inf", "inf"))
    try:
        q = u.Quantity(text)
    except (TypeError, ValueError):
        raise ctx.fail(path, f"{expect}, got {value!r} (not a number with a unit)") from None
    try:
        return float(q.to_value(unit, equivalencies=u.dimensionless_angles()))
    except u.UnitConversionError:
        raise ctx.fail(path, f"{expect}, got {value!r}") from None


def parse_angle(ctx: Ctx, f: Field, value: Any, hours: bool = False) -> float:
    """An angle in degrees: bare degrees, sexagesimal (hours if ``hours``) or with a unit.

    The range of ``f.bounds`` is checked.
    """
    try:
        deg = float(_angle(value, hours).to_value(u.deg))
    except (ValueError, TypeError, u.UnitsError):
        raise ctx.fail(f.path, f"expected an angle like {f.example}, got {value!r}") from None
    if not math.isfinite(deg):
        raise ctx.fail(f.path, f"expected a finite angle like {f.example}, got {value!r}")
    check_range(ctx, f, deg, value)
    return deg


def _angle(value: Any, hours: bool) -> Angle:
    if isinstance(value, int | float) and not isinstance(value, bool):
        return Angle(float(value), unit=u.deg)
    if not isinstance(value, str):
        raise ValueError
    text = value.strip()
    if NUM_RE.match(text):
        return Angle(float(text), unit=u.deg)
    if ":" in text or (" " in text and not re.search(r"[a-zA-Z]", text)):
        return Angle(text, unit=u.hourangle if hours else u.deg)
    return Angle(text)


def parse_epoch(ctx: Ctx, f: Field, value: Any, scale_field: Any) -> tuple[Time, str | None]:
    """An epoch as TDB, and the scale it was converted from (None if it was TDB).

    ``scale_field`` is the raw ``t_ref_scale`` (None if absent). An epoch labelled with another
    scale ("… UTC") is refused unless that scale is stated, so nothing converts silently.
    """
    scale_given = _scale_given(ctx, scale_field)
    text = _epoch_text(ctx, f, value)
    label: str | None = None
    m = _SCALE_LABEL_RE.match(text)
    if m:
        text, label = m.group(1).strip(), m.group(2).lower()
    if label is not None and scale_given is None and label != "tdb":
        raise ctx.fail(
            f.path,
            f"epochs must be TDB at the barycentre, got a {label.upper()}-labelled epoch "
            f"{value!r}; if it really is {label.upper()}, add 't_ref_scale: {label}' and "
            "ucbplan converts it explicitly",
        )
    if label is not None and scale_given is not None and label != scale_given:
        raise ctx.fail(f.path, f"label {label.upper()} contradicts t_ref_scale: {scale_given}")
    scale = scale_given or label or "tdb"
    try:
        tdb = _to_tdb(text, scale)
    except (ValueError, TypeError):
        raise ctx.fail(
            f.path, f"expected an ISO epoch like {f.example} (TDB), got {value!r}"
        ) from None
    return tdb, (None if scale == "tdb" else scale)


def _scale_given(ctx: Ctx, scale_field: Any) -> str | None:
    """The stated time scale (lower case), or None if ``t_ref_scale`` is absent."""
    if scale_field is None:
        return None
    scale = str(scale_field).strip().lower()
    f = field("lisa.t_ref_scale")
    if scale not in f.choices:
        raise ctx.fail(f.path, f"expected one of {'|'.join(f.choices)}, got {scale_field!r}")
    return scale


def _epoch_text(ctx: Ctx, f: Field, value: Any) -> str:
    """The epoch as text (YAML may hand over a date/datetime; time zones are refused)."""
    if isinstance(value, _dt.datetime | _dt.date):
        if isinstance(value, _dt.datetime) and value.tzinfo is not None:
            raise ctx.fail(
                f.path,
                f"expected a TDB epoch without time zone, got {value!r}; quote the epoch and "
                "drop the offset",
            )
        return value.isoformat()
    if isinstance(value, str):
        return value.strip()
    raise ctx.fail(f.path, f"expected an ISO epoch like {f.example}, got {value!r}")


def _to_tdb(text: str, scale: str) -> Time:
    """Epoch text (ISO, "MJD …" or "JD …") in ``scale``, converted to TDB."""
    with warnings.catch_warnings():
        # future UTC: leap seconds after the bundled table are unknown (TDB − UTC kept at the
        # last value); the user stated the scale, so convert with that caveat
        warnings.simplefilter("ignore", ErfaWarning)
        if text.upper().startswith("MJD"):
            t = Time(float(text[3:]), format="mjd", scale=scale)
        elif text.upper().startswith("JD"):
            t = Time(float(text[2:]), format="jd", scale=scale)
        else:
            t = Time(text, scale=scale, format="isot" if "T" in text else None)
        return t.tdb
