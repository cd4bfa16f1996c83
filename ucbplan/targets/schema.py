"""The target file, declared once: every field's path, unit, allowed range, example and default.

:data:`FIELDS` is a plain tuple of frozen ``Field`` records in document order. The parser
(:mod:`ucbplan.targets.parse`), the writer (:mod:`ucbplan.targets.write`) and the target-file
reference in the docs all read it, so a field cannot be accepted, written or documented in one
place and forgotten in another. Look a field up with :func:`field`. The records (``Field``,
``Range``, ``Kind``) are declared in :mod:`ucbplan.targets.fieldtypes`; import them from there.
The families of fields that share a shape are built by :mod:`ucbplan.targets.fieldgroups`.
"""

from __future__ import annotations

from ucbplan.core.params import PARAM_NAMES
from ucbplan.core.timing import MARKS, TIMING_NAMES
from ucbplan.targets.fieldgroups import (
    TIME_SCALES,
    covariance_fields,
    eccentricity_fields,
    phase_field,
    positive,
    velocity_field,
)
from ucbplan.targets.fieldtypes import Field, Range

#: Kinds of ephemeris a target file gives: exactly one of these sections.
EPHEMERIS_KINDS: tuple[str, ...] = ("lisa", "timing")

#: The σ's of a timing covariance as messages and the reference show them: placeholders, so
#: that no real system's σ's are copied as defaults.
TIMING_SIGMA_PLACEHOLDERS = '{t0: "<σ(T0)> d", period: "<σ(P)> s", pdot: <σ(Ṗ)>}'

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
        doc="the LISA posterior summary; give exactly one of lisa and timing",
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
        choices=TIME_SCALES,
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
    phase_field(
        "phase",
        "a phase",
        '5.500397 (rad) or "5.5 rad"',
        "φ_ref, GW phase of the n=2 mode at t_ref",
        required=True,
        dimension_hint="give rad (or deg, cycle)",
    ),
    phase_field(
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
    phase_field(
        "fdot",
        "a frequency derivative",
        '"7.07e-16 Hz / s"',
        "df/dt at t_ref",
        required=True,
        dimension_hint="give Hz / s (ḟ = ω̇_GW/2π)",
    ),
    phase_field(
        "fddot",
        "a second frequency derivative",
        '"-1.07e-26 Hz / s2"',
        "d²f/dt² at t_ref",
        dimension_hint="give Hz / s2 (f̈ = ω̈_GW/2π)",
    ),
    *eccentricity_fields("lisa", "t_ref"),
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
        bounds=positive("a strain amplitude is positive"),
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
        bounds=positive("a distance is positive"),
        doc="distance to the binary",
    ),
    *covariance_fields(
        "lisa",
        "[phase, f_gw, fdot]",
        '{sigma: {phase: 0.023, f_gw: "7.7e-12 Hz"}}',
        '{phase: 0.022993, f_gw: "7.7e-12 Hz"}',
    ),
    Field(
        "lisa.samples",
        "file",
        "a file name",
        "posterior.ecsv",
        doc="posterior samples (ECSV, next to this file), columns named like the parameters",
    ),
    Field(
        "timing",
        "mapping",
        "a mapping",
        '{t0: "BJD_TDB 2458305.6827886", t0_marks: primary_eclipse, period: "414.7915404 s", '
        "pdot: -2.373e-11, covariance: …, source: …}",
        doc="a timing (optical/X-ray) ephemeris t(n) = T0 + P n + ½PṖn² (+ ⅙P²P̈n³), n the "
        "cycle number; give exactly one of lisa and timing",
    ),
    Field(
        "timing.t0",
        "epoch",
        "a barycentric TDB epoch",
        '"BJD_TDB 2458305.6827886"',
        required=True,
        doc='T0, TDB at the barycentre: "BJD_TDB …", "BMJD_TDB …", "MJD_TDB …" or an ISO epoch '
        "labelled TDB, kept to full precision (HJD and UTC-based epochs are refused)",
    ),
    Field(
        "timing.t0_marks",
        "choice",
        "an event",
        "primary_eclipse",
        required=True,
        choices=tuple(MARKS),
        doc="the event at T0; star 1 is the star eclipsed at primary eclipse (u₁ = π/2), the "
        "secondary eclipse is u₁ = 3π/2, the ascending node and star 1's maximum recession u₁ = 0",
    ),
    Field(
        "timing.period",
        "quantity",
        "a period",
        '"414.7915404 s"',
        unit="s",
        required=True,
        bounds=positive("an orbital period is positive"),
        doc="P at T0 (from node to node, f_gw = 2/P); the unit is required (s or d)",
        dimension_hint="give a time, e.g. s or d",
        unit_required=True,
    ),
    Field(
        "timing.pdot",
        "quantity",
        "a period derivative",
        "-2.373e-11 (s/s)",
        unit="",
        required=True,
        doc="Ṗ = dP/dt at T0, dimensionless (s/s); P must keep its sign within ±100 yr of T0",
        dimension_hint="Ṗ is dimensionless (s/s): give a plain number",
    ),
    Field(
        "timing.pddot",
        "quantity",
        "a second period derivative",
        '"1e-21 1 / s"',
        unit="1 / s",
        default=0.0,
        doc="P̈ = d²P/dt² at T0 (the ephemeris gains ⅙P²P̈n³)",
        dimension_hint='P̈ has the dimension 1/s: give e.g. "1e-21 1 / s"',
    ),
    Field(
        "timing.eccentricity",
        "mapping",
        "a mapping",
        '{eta: 0.0, kappa: 0.002, omega_dot: "1e-6 rad / s"}',
        doc="small eccentricity (first order, as in lisa): η, κ of star 1 at T0 and ω̇",
    ),
    *eccentricity_fields("timing.eccentricity", "T0"),
    Field(
        "timing.inclination",
        "angle",
        "an angle",
        '"84.15 deg"',
        unit="deg",
        bounds=Range(
            0.0,
            180.0,
            reason="an orbital inclination",
            error="expected an inclination in [0, 180] deg, got {raw}",
        ),
        doc="orbital inclination from the light-curve fit (feasibility, simulations)",
    ),
    Field(
        "timing.distance",
        "quantity",
        "a distance",
        '"2.34 kpc"',
        unit="kpc",
        bounds=positive("a distance is positive"),
        doc="distance to the binary",
    ),
    *covariance_fields(
        "timing",
        "[t0, period, pdot]",
        f"{{sigma: {TIMING_SIGMA_PLACEHOLDERS}}}",
        TIMING_SIGMA_PLACEHOLDERS,
        required=True,
    ),
    Field(
        "timing.covariance.exact",
        "list",
        "a list of timing parameters",
        "[pdot]",
        doc="timing parameters known exactly (no σ): T0 and P, and Ṗ, P̈, η, κ, ω̇ when not "
        "zero, need a σ or a place here",
    ),
    Field(
        "timing.source",
        "text",
        "a citation",
        '"Burdge et al. 2019, Nature 571, 528"',
        required=True,
        doc="where the ephemeris comes from (paper, bibcode or DOI)",
    ),
    Field(
        "priority",
        "number",
        "a number",
        "1.0",
        default=1.0,
        bounds=positive("a weight; higher is scheduled first"),
        doc="weight in night schedules",
    ),
    Field(
        "vmag",
        "number",
        "a number",
        "21.1",
        bounds=Range(
            -30.0,
            40.0,
            reason="an apparent magnitude",
            error="expected a magnitude in [-30, 40], got {raw}",
        ),
        doc="V magnitude, for starlists and proposals (the same as magnitudes: {V: …})",
    ),
    Field(
        "magnitudes",
        "mapping",
        "a mapping band: magnitude",
        "{V: 20.5, g: 20.3}",
        bounds=Range(
            -30.0,
            40.0,
            reason="an apparent magnitude",
            error="expected a magnitude in [-30, 40], got {raw}",
        ),
        doc="apparent magnitudes by band (V, g, G, …); V is the vmag of starlists",
    ),
    Field(
        "references",
        "mapping",
        "a mapping field: citation",
        '{timing.period: "2019Natur.571..528B", masses.m1: "doi:10.1038/s41586-019-1403-0"}',
        doc="where each number comes from: a field path (or magnitudes.BAND) and a bibcode, DOI "
        "or citation",
    ),
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
        bounds=positive("a mass is positive"),
        doc="mass of star 1",
    ),
    Field(
        "masses.m2",
        "quantity",
        "a mass",
        '"0.285 solMass"',
        unit="solMass",
        bounds=positive("a mass is positive"),
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
    velocity_field(
        "K1", '"585 km/s"', "velocity semi-amplitude of star 1", "a semi-amplitude is positive"
    ),
    velocity_field(
        "K2", '"713 km/s"', "velocity semi-amplitude of star 2", "a semi-amplitude is positive"
    ),
    velocity_field(
        "K_eff",
        '"390 km/s"',
        "K for tolerances; default K1 + K2 (SB2) or K1 (SB1)",
        "a semi-amplitude is positive",
    ),
    velocity_field(
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
#: Every parameter ``timing.covariance`` may name (``t0`` is the offset from the nominal T0).
TIMING_COVARIANCE_PARAMETERS: tuple[str, ...] = TIMING_NAMES

_BY_PATH = {f.path: f for f in FIELDS}
#: σ(T0) is a duration; it must carry its unit (published in days or in seconds).
_T0_SIGMA = Field(
    "timing.t0",
    "quantity",
    "a duration",
    '"<σ(T0)> d"',
    unit="s",
    doc="σ of T0",
    dimension_hint="give a time, e.g. s or d",
    unit_required=True,
)


def timing_parameter_field(name: str) -> Field:
    """The field whose unit and example read a timing parameter (its σ, its matrix row).

    ``t0`` → a duration in s (unit required); ``period``, ``pdot``, ``pddot`` → the
    ``timing.*`` fields; ``eta``, ``kappa``, ``omega_dot`` → ``timing.eccentricity.*``.
    """
    if name == "t0":
        return _T0_SIGMA
    if name in ("eta", "kappa", "omega_dot"):
        return _BY_PATH[f"timing.eccentricity.{name}"]
    return _BY_PATH[f"timing.{name}"]


def field(path: str) -> Field:
    """The field at dotted ``path`` (``KeyError`` if the schema has none)."""
    return _BY_PATH[path]


def _by_section() -> dict[str, tuple[Field, ...]]:
    """The fields of each section, in document order (built once: every target reads them)."""
    out: dict[str, list[Field]] = {}
    for f in FIELDS:
        out.setdefault(f.section, []).append(f)
    return {k: tuple(v) for k, v in out.items()}


_BY_SECTION = _by_section()


def section_fields(section: str) -> tuple[Field, ...]:
    """Fields directly inside the mapping at ``section`` (``""``: top level), document order."""
    return _BY_SECTION.get(section, ())
