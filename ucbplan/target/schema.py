"""The target file, declared once: every field's path, unit, allowed range, example and default.

:data:`FIELDS` is a plain tuple of frozen :class:`Field` records in document order. The parser
(:mod:`ucbplan.target.parse`), the writer (:mod:`ucbplan.target.write`) and the target-file
reference in the docs all read it, so a field cannot be accepted, written or documented in one
place and forgotten in another. Look a field up with :func:`field`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Literal

from ucbplan.core.constants import C_KM_S, E_MAX
from ucbplan.core.params import PARAM_NAMES, PARAM_UNITS

__all__ = [
    "COVARIANCE_EXTRAS",
    "COVARIANCE_PARAMETERS",
    "FIELDS",
    "SECTIONS",
    "Field",
    "Kind",
    "Range",
    "field",
    "section_fields",
]

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


def _positive(reason: str) -> Range:
    return Range(low=0.0, low_open=True, reason=reason)


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

    @property
    def name(self) -> str:
        """Last component of the path (the key in its mapping)."""
        return self.path.rpartition(".")[2]

    @property
    def section(self) -> str:
        """Path of the mapping that holds the field (``""`` for the top level)."""
        return self.path.rpartition(".")[0]


_TIME_SCALES = ("tdb", "tcb", "tt", "utc", "tai")
_ECC_NOTE = f"e = |η + iκ| < {E_MAX} (the paper's first-order small-e model)"


def _phase(
    name: str,
    what: str,
    example: str,
    doc: str,
    required: bool = False,
    bounds: Range | None = None,
    dimension_hint: str = "",
) -> Field:
    """A phase-model parameter ``lisa.<name>`` in its core unit; optional ones default to 0."""
    return Field(
        f"lisa.{name}",
        "quantity",
        what,
        example,
        unit=PARAM_UNITS[name],
        required=required,
        default=None if required else 0.0,
        bounds=bounds,
        doc=doc,
        dimension_hint=dimension_hint,
    )


def _velocity(name: str, example: str, doc: str, reason: str) -> Field:
    """A spectroscopy velocity ``spectroscopy.<name>`` in km/s, positive and below c."""
    return Field(
        f"spectroscopy.{name}",
        "quantity",
        "a velocity",
        example,
        unit="km / s",
        bounds=Range(
            0.0,
            C_KM_S,
            low_open=True,
            high_open=True,
            reason=f"{reason}, below the speed of light",
            error=f"must be in (0, {C_KM_S:g}) km/s, got {{raw}}",
        ),
        doc=doc,
    )


#: Every field of a target file, in document order (the order :func:`write_target` writes).
FIELDS: tuple[Field, ...] = (
    Field("name", "text", "a non-empty string", '"HM Cnc"', required=True, doc="target name"),
    Field(
        "sky",
        "mapping",
        "a mapping",
        '{ra: "08h06m23.2s", dec: "+15d27m30s"}',
        required=True,
        doc="ICRS position (ra, dec) or galactic (l, b)",
    ),
    Field(
        "sky.ra",
        "angle",
        "an angle",
        '"08h06m23.2s" or "121.5967 deg"',
        unit="deg",
        bounds=Range(
            0.0,
            360.0,
            high_open=True,
            reason="right ascension wraps at 24h",
            error="right ascension must be in [0h, 24h), got {raw}",
        ),
        doc="ICRS right ascension (sexagesimal hours, or degrees); required unless l, b are given",
    ),
    Field(
        "sky.dec",
        "angle",
        "an angle",
        '"+15d27m30s" or "15.458 deg"',
        unit="deg",
        bounds=Range(
            -90.0,
            90.0,
            reason="a latitude on the sky",
            error="declination must be in [-90, +90] deg, got {raw}",
        ),
        doc="ICRS declination; required unless l, b are given",
    ),
    Field(
        "sky.frame",
        "choice",
        "a frame",
        "icrs",
        default="icrs",
        choices=("icrs", "j2000", "fk5"),
        doc="frame of ra/dec; j2000 and fk5 are read as ICRS",
    ),
    Field(
        "sky.l",
        "angle",
        "an angle",
        '"+15d27m30s" or "15.458 deg"',
        unit="deg",
        doc="galactic longitude (instead of ra/dec, with b)",
    ),
    Field(
        "sky.b",
        "angle",
        "an angle",
        '"+15d27m30s" or "15.458 deg"',
        unit="deg",
        bounds=Range(
            -90.0,
            90.0,
            reason="a latitude on the sky",
            error="declination must be in [-90, +90] deg, got {raw}",
        ),
        doc="galactic latitude (with l)",
    ),
    Field(
        "lisa",
        "mapping",
        "a mapping",
        "{t_ref: …, t_obs: …, phase: …, f_gw: …, fdot: …}",
        required=True,
        doc="the LISA posterior summary",
    ),
    Field(
        "lisa.t_ref",
        "epoch",
        "an ISO TDB epoch",
        '"2039-01-01T00:00:00"',
        required=True,
        doc='reference epoch, TDB at the barycentre; "MJD …" and "JD …" also accepted',
    ),
    Field(
        "lisa.t_ref_scale",
        "choice",
        "a time scale",
        "utc",
        choices=_TIME_SCALES,
        doc="only if t_ref is not TDB: converted explicitly (TCB also rescales the rates)",
    ),
    Field(
        "lisa.t_obs",
        "quantity",
        "a duration",
        '"126232599.05 s" or "4 yr"',
        unit="s",
        required=True,
        bounds=Range(
            0.0,
            3.15576e9,
            low_open=True,
            reason="an observation lasts a positive time, at most 100 yr",
            error="must be positive and at most 100 yr (3.15576e9 s), got {raw}",
        ),
        doc="length of the LISA observation",
    ),
    Field(
        "lisa.t_ref_is",
        "choice",
        "a reference",
        "midpoint",
        default="midpoint",
        choices=("midpoint", "start"),
        doc="where t_ref lies in the observation; start-referenced inputs move to the midpoint",
    ),
    _phase(
        "phase",
        "a phase",
        '5.500397 (rad) or "5.5 rad"',
        "φ_ref, GW phase of the n=2 mode at t_ref",
        required=True,
        dimension_hint="give rad (or deg, cycle)",
    ),
    _phase(
        "f_gw",
        "a frequency",
        '"6.2204944286e-3 Hz"',
        "GW frequency at t_ref",
        required=True,
        bounds=Range(
            0.0,
            1.0,
            low_open=True,
            reason="a GW frequency (twice the orbital frequency) is positive, and LISA's band "
            "ends near 1 Hz",
            error="must be in (0, 1] Hz, got {raw}",
        ),
        dimension_hint="give Hz (f = ω/2π)",
    ),
    _phase(
        "fdot",
        "a frequency derivative",
        '"7.07e-16 Hz / s"',
        "df/dt at t_ref",
        required=True,
        dimension_hint="give Hz / s (ḟ = ω̇_GW/2π)",
    ),
    _phase(
        "fddot",
        "a second frequency derivative",
        '"-1.07e-26 Hz / s2"',
        "d²f/dt² at t_ref",
        dimension_hint="give Hz / s2 (f̈ = ω̈_GW/2π)",
    ),
    _phase(
        "eta",
        "a dimensionless number",
        "0.0068 (dimensionless)",
        f"η = e sin ω of star 1 at t_ref; {_ECC_NOTE}",
        dimension_hint="η = e sin ω is dimensionless: give a plain number",
    ),
    _phase(
        "kappa",
        "a dimensionless number",
        "0.0068 (dimensionless)",
        f"κ = e cos ω of star 1 at t_ref; {_ECC_NOTE}",
        dimension_hint="κ = e cos ω is dimensionless: give a plain number",
    ),
    _phase(
        "omega_dot",
        "an angular rate",
        '"1.498e-6 rad / s"',
        "apsidal advance rate ω̇",
        dimension_hint="give rad/s (ω̇ = 2π rad × the rate in Hz)",
    ),
    Field(
        "lisa.cos_inclination",
        "quantity",
        "a dimensionless number",
        "0.67 (dimensionless, in [-1, 1])",
        unit="",
        bounds=Range(
            -1.0,
            1.0,
            reason="cos ι is the cosine of an angle",
            error="expected a value in [-1, 1], got {value}",
        ),
        doc="cos ι of the orbit",
        dimension_hint="cos ι is a cosine, dimensionless: give a plain number",
        cosine_of="inclination",
    ),
    Field(
        "lisa.amplitude",
        "quantity",
        "a dimensionless strain",
        "4.9e-22 (dimensionless strain)",
        unit="",
        bounds=_positive("a strain amplitude is positive"),
        doc="GW strain amplitude",
        dimension_hint="a strain is dimensionless: give a plain number",
    ),
    Field(
        "lisa.psi",
        "quantity",
        "an angle",
        '0.339 (rad) or "19.4 deg"',
        unit="rad",
        doc="GW polarisation angle ψ",
    ),
    Field(
        "lisa.distance",
        "quantity",
        "a distance",
        '"2.0 kpc"',
        unit="kpc",
        bounds=_positive("a distance is positive"),
        doc="distance to the binary",
    ),
    Field(
        "lisa.covariance",
        "mapping",
        "a mapping",
        '{sigma: {phase: 0.023, f_gw: "7.7e-12 Hz"}}',
        doc="posterior covariance: parameters + matrix, or sigma (+ correlation)",
    ),
    Field(
        "lisa.covariance.parameters",
        "list",
        "a list of parameter names",
        "[phase, f_gw, fdot]",
        doc="names of the matrix rows, in the units of the parameters above",
    ),
    Field(
        "lisa.covariance.matrix",
        "list",
        "a square list of lists of numbers",
        "[[5.29e-4, 0, 0], [0, 5.93e-23, 0], [0, 0, 2.17e-37]]",
        doc="symmetric positive semi-definite covariance matrix",
    ),
    Field(
        "lisa.covariance.sigma",
        "mapping",
        "a mapping parameter: sigma",
        '{phase: 0.022993, f_gw: "7.7e-12 Hz"}',
        bounds=Range(
            0.0,
            low_open=True,
            reason="a standard deviation is positive; leave out a parameter known exactly",
            error="must be > 0, got {raw}",
        ),
        doc="marginal standard deviations, each in its parameter's unit",
    ),
    Field(
        "lisa.covariance.correlation",
        "mapping",
        "a mapping of parameter pairs to ρ",
        '{"phase,fdot": -0.7} or [[phase, fdot, -0.7]]',
        bounds=Range(
            -1.0,
            1.0,
            reason="a correlation coefficient",
            error="expected ρ in [-1, 1], got {raw}",
        ),
        doc="correlation coefficients between parameters of sigma (default 0)",
    ),
    Field(
        "lisa.samples",
        "file",
        "a file name",
        "posterior.ecsv",
        doc="posterior samples (ECSV, next to this file), columns named like the parameters",
    ),
    Field(
        "priority",
        "number",
        "a number",
        "1.0",
        default=1.0,
        bounds=_positive("a weight; higher is scheduled first"),
        doc="weight in night schedules",
    ),
    Field("vmag", "number", "a number", "21.1", doc="V magnitude, for starlists and proposals"),
    Field(
        "masses",
        "mapping",
        "a mapping",
        '{m1: "0.347 solMass", m2: "0.285 solMass"}',
        doc="component masses (feasibility, simulations)",
    ),
    Field(
        "masses.m1",
        "quantity",
        "a mass",
        '"0.347 solMass"',
        unit="solMass",
        bounds=_positive("a mass is positive"),
        doc="mass of star 1",
    ),
    Field(
        "masses.m2",
        "quantity",
        "a mass",
        '"0.285 solMass"',
        unit="solMass",
        bounds=_positive("a mass is positive"),
        doc="mass of star 2",
    ),
    Field(
        "spectroscopy",
        "mapping",
        "a mapping",
        '{lines: SB2, K1: "585 km/s", K2: "713 km/s", sigma_v: "15 km/s"}',
        doc="defaults for velocity tolerances; CLI flags override them",
    ),
    Field(
        "spectroscopy.lines",
        "choice",
        "a line set",
        "SB2",
        default="SB2",
        choices=("SB1", "SB2"),
        doc="one (SB1) or both (SB2) stars' lines are measured",
    ),
    _velocity(
        "K1", '"585 km/s"', "velocity semi-amplitude of star 1", "a semi-amplitude is positive"
    ),
    _velocity(
        "K2", '"713 km/s"', "velocity semi-amplitude of star 2", "a semi-amplitude is positive"
    ),
    _velocity(
        "K_eff",
        '"390 km/s"',
        "K for tolerances; default K1 + K2 (SB2) or K1 (SB1)",
        "a semi-amplitude is positive",
    ),
    _velocity(
        "sigma_v", '"15 km/s"', "velocity error of one spectrum", "a velocity error is positive"
    ),
    Field("notes", "any", "anything", '"free text"', doc="free-form notes; ucbplan ignores them"),
)

#: Paths of the mappings whose keys are fields (``""`` is the top level), document order.
SECTIONS: tuple[str, ...] = (
    "",
    *(f.path for f in FIELDS if f.kind == "mapping" and any(g.section == f.path for g in FIELDS)),
)

#: Parameters a covariance or a samples file may carry besides the phase model.
COVARIANCE_EXTRAS: tuple[str, ...] = ("cos_inclination", "amplitude", "psi")
#: Every parameter a covariance may name (rows of ``lisa.covariance``, samples columns).
COVARIANCE_PARAMETERS: tuple[str, ...] = (*PARAM_NAMES, *COVARIANCE_EXTRAS)

_BY_PATH = {f.path: f for f in FIELDS}


def field(path: str) -> Field:
    """The field at dotted ``path`` (``KeyError`` if the schema has none)."""
    return _BY_PATH[path]


def section_fields(section: str) -> tuple[Field, ...]:
    """Fields directly inside the mapping at ``section`` (``""``: top level), document order."""
    return tuple(f for f in FIELDS if f.section == section)
