"""Helpers shared by the sections of a target file, and the validated ephemeris record.

Each reader takes the :class:`~ucbplan.targets.values.Ctx` of its file and fails with a one-line
:class:`~ucbplan.errors.TargetFileError` naming the field (``file: field: expected …, got …``).
"""

from __future__ import annotations

import functools
import math
import unicodedata
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from astropy.time import Time
from numpy.typing import NDArray

from ucbplan.core.constants import E_MAX
from ucbplan.core.params import PhaseParams
from ucbplan.errors import shorten
from ucbplan.targets.fieldtypes import Field
from ucbplan.targets.model import TimingSection
from ucbplan.targets.schema import field, section_fields
from ucbplan.targets.values import (
    Ctx,
    check_keys,
    check_range,
    parse_number,
    parse_quantity,
)

FloatArray = NDArray[np.float64]
#: Unicode categories refused in a name or text: control characters, surrogates, line separators.
CONTROL = frozenset(("Cc", "Cs", "Zl", "Zp"))
#: Longest free text (a source, a citation) [characters].
MAX_TEXT_CHARS = 500


@functools.cache  # one tuple per section of the schema
def names(section: str) -> tuple[str, ...]:
    """Names of the fields directly inside ``section`` (``""``: the top level)."""
    return tuple(f.name for f in section_fields(section))


def mapping(ctx: Ctx, f: Field, value: Any) -> Mapping[Any, Any]:
    """``value`` as a mapping of the fields of section ``f`` (unknown keys refused)."""
    if not isinstance(value, Mapping):
        raise ctx.fail(f.path, f"expected a mapping like {f.example}, got {shorten(value)}")
    check_keys(ctx, f.path, value, names(f.path))
    return value


def quantities(ctx: Ctx, mapping: Mapping[str, Any], fields: Iterable[Field]) -> dict[str, Any]:
    """Fields of ``mapping`` as floats (absent: the schema default), ranges checked after all
    of them are read."""
    fields = tuple(fields)
    got = {f.name: parse_quantity(ctx, f, mapping[f.name]) for f in fields if f.name in mapping}
    for f in fields:
        if f.name in got:
            check_range(ctx, f, got[f.name], mapping[f.name])
    return {f.name: got.get(f.name, f.default) for f in fields}


def each_quantity(ctx: Ctx, mapping: Mapping[str, Any], fields: Iterable[Field]) -> dict[str, Any]:
    """Fields of ``mapping`` as floats (absent: the schema default), each read and range-checked
    in turn: :func:`quantities` of one field at a time."""
    out: dict[str, Any] = {}
    for f in fields:
        if f.name in mapping:
            raw = mapping[f.name]
            out[f.name] = x = parse_quantity(ctx, f, raw)
            check_range(ctx, f, x, raw)
        else:
            out[f.name] = f.default
    return out


def number(ctx: Ctx, doc: Mapping[str, Any], f: Field) -> Any:
    """A plain number at the top level (absent: the schema default), range checked."""
    if f.name not in doc:
        return f.default
    x = parse_number(ctx, f, doc[f.name])
    check_range(ctx, f, x, doc[f.name])
    return x


def check_section(ctx: Ctx, section: str, value: Any) -> None:
    """``value`` is a mapping of the known fields of ``section`` with every required one."""
    f = field(section)
    if value is None:
        raise ctx.fail(f.path, f"missing; add {section}: {f.example}")
    mapping(ctx, f, value)
    for f in section_fields(section):
        if f.required and f.name not in value:
            if f.kind == "mapping":
                raise ctx.fail(f.path, f"missing; add {f.name}: {f.example}")
            shown = f.example if f.kind == "quantity" else f.what
            raise ctx.fail(f.path, f"missing; expected {shown}")


def check_eccentricity(ctx: Ctx, eta: float, kappa: float, where: str = "lisa") -> None:
    """e = |η + iκ| must stay inside the first-order small-e model."""
    ecc = math.hypot(eta, kappa)
    if ecc >= E_MAX:
        raise ctx.fail(
            f"{where}.eta/kappa",
            f"e = |η + iκ| = {ecc:.4g} ≥ {E_MAX}: outside the small-e (first-order) model of the "
            "paper; ucbplan cannot schedule such orbits",
        )


def expect(f: Field) -> str:
    """``expected <what> like <example>`` of a field, for messages."""
    return f"expected {f.what} like {f.example}"


def parse_text(ctx: Ctx, path: str, value: Any, expect: str) -> str:
    """A non-empty one-line text of at most :data:`MAX_TEXT_CHARS` characters."""
    if not isinstance(value, str) or not value.strip():
        raise ctx.fail(path, f"{expect}, got {shorten(value)}")
    if len(value) > MAX_TEXT_CHARS:
        raise ctx.fail(
            path, f"{expect} of at most {MAX_TEXT_CHARS} characters, got {shorten(value)}"
        )
    if any(unicodedata.category(c) in CONTROL for c in value):
        raise ctx.fail(path, f"{expect} on one line without control characters")
    return " ".join(value.split())


@dataclass(frozen=True, slots=True)
class Ephemeris:
    """A validated ephemeris section as the phase model: ``lisa`` moved to the observation
    midpoint and to TDB, or ``timing`` at its epoch T0."""

    t_ref: Time
    t_obs_s: float
    params: PhaseParams
    cov_names: tuple[str, ...]
    cov_matrix: FloatArray
    extras: dict[str, float | None]
    samples: Path | None = None
    ref_shift_s: float = 0.0
    converted: str | None = None
    timing: TimingSection | None = None
