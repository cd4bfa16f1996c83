"""Read and validate a target file into a :class:`~ucbplan.target.model.Target`.

``load_target`` validates once, section by section, against the schema
(:mod:`ucbplan.target.schema`). A ``lisa`` section gives parameters referenced to the *midpoint*
of the LISA observation (paper Sec. 4.1; ``docs/method.md``, "Phase model"); a ``timing``
section (exactly one of the two) is converted to the same phase model at its epoch T0 by
:mod:`ucbplan.core.timing`. Every validation failure is a one-line
:class:`~ucbplan.errors.TargetFileError`: ``file: field: expected …, got …``.
"""

from __future__ import annotations

import math
import re
import unicodedata
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from astropy import units as u
from astropy.coordinates import SkyCoord
from astropy.time import Time, TimeDelta
from numpy.typing import NDArray

from ucbplan.core.constants import E_MAX, L_B, YEAR_S
from ucbplan.core.params import PARAM_NAMES, PhaseParams, shift_jacobian, shift_reference
from ucbplan.core.timescale import parse_timing_epoch
from ucbplan.core.timing import (
    SIGN_SPAN_S,
    TIMING_NAMES,
    TimingEphemeris,
    period_sign_change,
    phase_covariance,
    to_phase_params,
)
from ucbplan.errors import SchemaError, TargetFileError, shorten
from ucbplan.inputs import load_yaml
from ucbplan.target.covariance import parse_covariance
from ucbplan.target.model import Spectroscopy, Target, TimingSection
from ucbplan.target.schema import EPHEMERIS_KINDS, FIELDS, Field, field, section_fields
from ucbplan.target.values import (
    Ctx,
    check_keys,
    check_range,
    did_you_mean,
    one_line,
    parse_angle,
    parse_choice,
    parse_epoch,
    parse_number,
    parse_quantity,
    to_float,
)

__all__ = ["load_target", "target_from_dict"]

FloatArray = NDArray[np.float64]

_PHASE_MODEL = tuple(field(f"lisa.{n}") for n in PARAM_NAMES)
_LISA_EXTRAS = tuple(
    field(f"lisa.{n}") for n in ("cos_inclination", "amplitude", "psi", "distance")
)
#: Longest target name [characters] (names go into starlists, headers and file names).
MAX_NAME_CHARS = 200
#: Unicode categories refused in a name: control characters, surrogates, line separators.
_CONTROL = frozenset(("Cc", "Cs", "Zl", "Zp"))
#: Powers of 1/s in the unit of each rate that a TCB → TDB conversion rescales.
_TCB_POWER = {"f_gw": 1, "fdot": 2, "fddot": 3, "omega_dot": 1}


def load_target(path: Path | str) -> Target:
    """Read and validate a target YAML file (strictly, see :func:`ucbplan.inputs.load_yaml`).

    Raises
    ------
    TargetFileError
        One line naming the file, the field path, what was expected and how to fix it.
    """
    path = Path(path)
    label = Ctx(path).label
    try:
        doc = load_yaml(path, "target file")
    except SchemaError as exc:
        msg = str(exc)
        if len(msg) > 300 and msg.startswith(str(path)):  # a long path: its name is enough
            msg = label + msg[len(str(path)) :]
        raise TargetFileError(one_line(msg)) from None
    except RecursionError:
        raise TargetFileError(
            one_line(f"{label}: <top>: nested too deeply to be a target file; check the brackets")
        ) from None
    except (OSError, ValueError, UnicodeError):
        raise TargetFileError(
            one_line(f"{shorten(str(path))}: cannot open; check the path")
        ) from None
    return target_from_dict(doc, path)


def target_from_dict(doc: Any, path: Path | None = None) -> Target:
    """Validate a parsed target document (see :func:`load_target`).

    ``path`` names the file in messages and anchors a relative ``lisa.samples``.
    """
    ctx = Ctx(path)
    if not isinstance(doc, Mapping):
        raise ctx.fail(
            "<top>", f"expected a YAML mapping with name, sky and lisa, got {_kind(doc)}"
        )
    check_keys(ctx, "", doc, _TOP)
    with ctx.reading("name", "a name"):
        name = _parse_name(ctx, doc.get("name"))
    with ctx.reading("sky", "a sky position"):
        ra, dec = _parse_sky(ctx, doc)
    kind = _ephemeris_kind(ctx, doc)
    if kind == "lisa":
        with ctx.reading("lisa", "the LISA posterior summary"):
            eph = _parse_lisa(ctx, doc.get("lisa"), path)
    else:
        with ctx.reading("timing", "a timing ephemeris"):
            eph = _parse_timing(ctx, doc["timing"])
    with ctx.reading("spectroscopy", "spectroscopy defaults"):
        spectroscopy = _parse_spectroscopy(ctx, doc.get("spectroscopy"))
    priority = _number(ctx, doc, field("priority"))
    with ctx.reading("magnitudes", "magnitudes"):
        magnitudes = _parse_magnitudes(ctx, doc)
    with ctx.reading("references", "references"):
        references = _parse_references(ctx, doc)
    with ctx.reading("masses", "masses"):
        masses = _parse_masses(ctx, doc)
    return Target(
        name=name,
        source=path.resolve() if path is not None else None,
        ra_deg=ra,
        dec_deg=dec,
        t_ref=eph.t_ref,
        t_obs_s=eph.t_obs_s,
        params=eph.params,
        cov_names=eph.cov_names,
        cov_matrix=eph.cov_matrix,
        cos_inclination=eph.extras["cos_inclination"],
        amplitude=eph.extras["amplitude"],
        psi=eph.extras["psi"],
        distance_kpc=eph.extras["distance"],
        spectroscopy=spectroscopy,
        samples=eph.samples,
        priority=priority,
        vmag=magnitudes.get("V"),
        m1_msun=masses.get("m1"),
        m2_msun=masses.get("m2"),
        ref_shift_s=eph.ref_shift_s,
        notes={"t_ref_converted_from": eph.converted} if eph.converted else {},
        kind=kind,
        timing=eph.timing,
        magnitudes=magnitudes,
        references=references,
    )


def _ephemeris_kind(ctx: Ctx, doc: Mapping[str, Any]) -> str:
    """``"lisa"`` or ``"timing"``: exactly one of the two sections must be given."""
    given = [k for k in EPHEMERIS_KINDS if k in doc]
    if len(given) == 1:
        return given[0]
    if given:
        raise ctx.fail(
            "lisa/timing",
            "give exactly one of lisa (a LISA posterior) and timing (an optical/X-ray timing "
            "ephemeris), not both; keep the other in a second target file",
        )
    raise ctx.fail(
        "lisa",
        f"missing; add lisa: {field('lisa').example} (a LISA posterior) or timing: "
        f"{field('timing').example} (a timing ephemeris)",
    )


# ---------------------------------------------------------------------------------------------
# fields and sections
# ---------------------------------------------------------------------------------------------


def _names(section: str) -> tuple[str, ...]:
    return tuple(f.name for f in section_fields(section))


_TOP = _names("")


def _kind(value: Any) -> str:
    if isinstance(value, list):
        return "a list"
    if value is None:
        return "an empty document"
    return f"{type(value).__name__} {shorten(value)}"


def _mapping(ctx: Ctx, f: Field, value: Any) -> Mapping[Any, Any]:
    """``value`` as a mapping of the fields of section ``f`` (unknown keys refused)."""
    if not isinstance(value, Mapping):
        raise ctx.fail(f.path, f"expected a mapping like {f.example}, got {shorten(value)}")
    check_keys(ctx, f.path, value, _names(f.path))
    return value


def _quantities(ctx: Ctx, mapping: Mapping[str, Any], fields: Iterable[Field]) -> dict[str, Any]:
    """Fields of ``mapping`` as floats (absent: the schema default), ranges checked after all
    of them are read."""
    fields = tuple(fields)
    got = {f.name: parse_quantity(ctx, f, mapping[f.name]) for f in fields if f.name in mapping}
    for f in fields:
        if f.name in got:
            check_range(ctx, f, got[f.name], mapping[f.name])
    return {f.name: got.get(f.name, f.default) for f in fields}


def _number(ctx: Ctx, doc: Mapping[str, Any], f: Field) -> Any:
    """A plain number at the top level (absent: the schema default), range checked."""
    if f.name not in doc:
        return f.default
    x = parse_number(ctx, f, doc[f.name])
    check_range(ctx, f, x, doc[f.name])
    return x


def _parse_name(ctx: Ctx, name: Any) -> str:
    """A non-empty one-line name (no control characters), at most :data:`MAX_NAME_CHARS`."""
    f = field("name")
    expect = f"expected {f.what} like {f.example}"
    if name is None:
        raise ctx.fail(f.path, f"missing; {expect}")
    if not isinstance(name, str) or not name.strip():
        raise ctx.fail(f.path, f"{expect}, got {shorten(name)}")
    if len(name) > MAX_NAME_CHARS:
        raise ctx.fail(
            f.path, f"{expect} of at most {MAX_NAME_CHARS} characters, got {shorten(name)}"
        )
    if any(unicodedata.category(c) in _CONTROL for c in name):
        raise ctx.fail(
            f.path, f"{expect} on one line without control characters, got {shorten(name)}"
        )
    return name.strip()


def _parse_sky(ctx: Ctx, doc: Mapping[str, Any]) -> tuple[float, float]:
    """ICRS (ra, dec) in degrees from ``sky``: ICRS ra/dec, or galactic l/b converted."""
    f = field("sky")
    if "sky" not in doc:
        raise ctx.fail(f.path, f"missing; add sky: {f.example}")
    sky = _mapping(ctx, f, doc["sky"])
    keys = set(sky)
    if {"l", "b"} & keys:
        if {"ra", "dec", "frame"} & keys:
            raise ctx.fail(f.path, "give ICRS ra, dec (with frame) or galactic l, b, not both")
        for k in ("l", "b"):
            if k not in sky:
                raise ctx.fail(f"sky.{k}", "missing; give galactic l and b together")
        lon = parse_angle(ctx, field("sky.l"), sky["l"])
        lat = parse_angle(ctx, field("sky.b"), sky["b"])
        c = SkyCoord(l=lon * u.deg, b=lat * u.deg, frame="galactic").icrs
        return float(c.ra.deg), float(c.dec.deg)
    for k in ("ra", "dec"):
        if k not in sky:
            raise ctx.fail(f"sky.{k}", "missing; give ICRS ra and dec (or galactic l and b)")
    frame_field = field("sky.frame")
    parse_choice(ctx, frame_field, sky.get("frame", frame_field.default))
    ra = parse_angle(ctx, field("sky.ra"), sky["ra"], hours=True)
    return ra, parse_angle(ctx, field("sky.dec"), sky["dec"])


def _parse_spectroscopy(ctx: Ctx, spec: Any) -> Spectroscopy | None:
    if spec is None:
        return None
    spec = _mapping(ctx, field("spectroscopy"), spec)
    lines_field = field("spectroscopy.lines")
    lines = parse_choice(ctx, lines_field, spec.get("lines", lines_field.default))
    vals: dict[str, Any] = {}
    for f in section_fields("spectroscopy"):
        if f.kind == "quantity":  # each read and range-checked in turn
            vals |= _quantities(ctx, spec, (f,))
    return Spectroscopy(lines, vals["K1"], vals["K2"], vals["K_eff"], vals["sigma_v"])


def _parse_masses(ctx: Ctx, doc: Mapping[str, Any]) -> dict[str, float | None]:
    if "masses" not in doc:
        return {}
    masses = _mapping(ctx, field("masses"), doc["masses"])
    return _quantities(ctx, masses, section_fields("masses"))


# ---------------------------------------------------------------------------------------------
# the LISA section
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class _Ephemeris:
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


def _parse_lisa(ctx: Ctx, lisa: Any, path: Path | None) -> _Ephemeris:
    """The ``lisa`` section; TCB rates are rescaled and start-referenced ones moved."""
    _check_lisa_fields(ctx, lisa)
    t_ref, converted = parse_epoch(ctx, field("lisa.t_ref"), lisa["t_ref"], lisa.get("t_ref_scale"))
    t_obs = float(_quantities(ctx, lisa, (field("lisa.t_obs"),))["t_obs"])
    ref_is = _reference_point(ctx, lisa)
    vals = _quantities(ctx, lisa, _PHASE_MODEL)
    _check_eccentricity(ctx, vals["eta"], vals["kappa"])
    names, mat = parse_covariance(ctx, lisa.get("covariance"))
    if converted == "tcb":
        vals, mat = _tcb_to_tdb(vals, names, mat)
        t_obs *= 1.0 - L_B
    params = PhaseParams(**vals)
    shift = 0.0
    if ref_is == "start":
        shift = t_obs / 2.0
        params, mat = _moved_to_midpoint(ctx, params, names, mat, shift)
        t_ref = t_ref + TimeDelta(shift, format="sec")
    return _Ephemeris(
        t_ref=t_ref,
        t_obs_s=t_obs,
        params=params,
        cov_names=names,
        cov_matrix=mat,
        extras=_quantities(ctx, lisa, _LISA_EXTRAS),
        samples=_samples_path(ctx, lisa, path),
        ref_shift_s=shift,
        converted=converted,
    )


def _moved_to_midpoint(
    ctx: Ctx, params: PhaseParams, names: tuple[str, ...], mat: FloatArray, shift: float
) -> tuple[PhaseParams, FloatArray]:
    """Start-referenced values moved by T_obs/2; they must stay finite, and f positive."""
    why = (
        "from the start to the midpoint of the observation (t_ref_is: start); check the "
        "magnitudes and units of f_gw, fdot, fddot and omega_dot"
    )
    try:
        with np.errstate(all="ignore"):
            moved, moved_mat = _shift_named(params, names, mat, shift)
    except (ValueError, OverflowError, ArithmeticError):
        raise ctx.fail("lisa", f"values overflow when moved {why}") from None
    if not (np.all(np.isfinite(moved.as_array())) and np.all(np.isfinite(moved_mat))):
        raise ctx.fail("lisa", f"values overflow when moved {why}")
    if moved.f_gw <= 0.0:
        raise ctx.fail(
            "lisa.f_gw", f"f_gw at the midpoint is {moved.f_gw:.4g} Hz ≤ 0 when moved {why}"
        )
    return moved, moved_mat


def _check_lisa_fields(ctx: Ctx, lisa: Any) -> None:
    """``lisa`` is a mapping of known fields with every required one present."""
    _check_section(ctx, "lisa", lisa)


def _check_section(ctx: Ctx, section: str, value: Any) -> None:
    """``value`` is a mapping of the known fields of ``section`` with every required one."""
    f = field(section)
    if value is None:
        raise ctx.fail(f.path, f"missing; add {section}: {f.example}")
    _mapping(ctx, f, value)
    for f in section_fields(section):
        if f.required and f.name not in value:
            if f.kind == "mapping":
                raise ctx.fail(f.path, f"missing; add {f.name}: {f.example}")
            shown = f.example if f.kind == "quantity" else f.what
            raise ctx.fail(f.path, f"missing; expected {shown}")


def _reference_point(ctx: Ctx, lisa: Mapping[str, Any]) -> str:
    """``t_ref_is``: where in the observation t_ref lies (``midpoint`` or ``start``)."""
    f = field("lisa.t_ref_is")
    return parse_choice(ctx, f, lisa.get(f.name, f.default))


def _check_eccentricity(ctx: Ctx, eta: float, kappa: float, where: str = "lisa") -> None:
    """e = |η + iκ| must stay inside the first-order small-e model."""
    ecc = math.hypot(eta, kappa)
    if ecc >= E_MAX:
        raise ctx.fail(
            f"{where}.eta/kappa",
            f"e = |η + iκ| = {ecc:.4g} ≥ {E_MAX}: outside the small-e (first-order) model of the "
            "paper; ucbplan cannot schedule such orbits",
        )


def _samples_path(ctx: Ctx, lisa: Mapping[str, Any], path: Path | None) -> Path | None:
    """``lisa.samples`` resolved next to the target file (it must exist)."""
    f = field("lisa.samples")
    if f.name not in lisa:
        return None
    name = lisa[f.name]
    if not isinstance(name, str) or not name.strip() or len(name) > 1000:
        raise ctx.fail(f.path, f"expected {f.what} like {f.example}, got {shorten(name)}")
    base = path.parent if path is not None else Path(".")
    try:
        samples = (base / name).resolve()
        found = samples.is_file()
    except (OSError, ValueError, UnicodeError):
        found = False
    if not found:
        raise ctx.fail(
            f.path, f"file {shorten(name)} not found next to the target file (or not a file)"
        )
    return samples


# ---------------------------------------------------------------------------------------------
# the timing section
# ---------------------------------------------------------------------------------------------

_TIMING_VALUES = tuple(field(f"timing.{n}") for n in ("period", "pdot", "pddot"))
#: Longest free text (source, a citation) [characters].
MAX_TEXT_CHARS = 500


def _parse_timing(ctx: Ctx, timing: Any) -> _Ephemeris:
    """The ``timing`` section as the phase model at t_ref = T0 (:mod:`ucbplan.core.timing`)."""
    _check_section(ctx, "timing", timing)
    f_t0 = field("timing.t0")
    try:
        t0 = parse_timing_epoch(timing["t0"])
    except ValueError as exc:
        raise ctx.fail(f_t0.path, str(exc)) from None
    mark = parse_choice(ctx, field("timing.t0_marks"), timing["t0_marks"])
    vals = _quantities(ctx, timing, _TIMING_VALUES)
    ecc = _timing_eccentricity(ctx, timing)
    eph = TimingEphemeris(mark, vals["period"], vals["pdot"], vals["pddot"], **ecc)
    _check_period_sign(ctx, eph)
    names, mat = parse_covariance(ctx, timing["covariance"], "timing")
    cov_names, cov_matrix = _phase_model_covariance(ctx, eph, names, mat)
    extras: dict[str, float | None] = {"cos_inclination": None, "amplitude": None, "psi": None}
    if "inclination" in timing:
        incl = parse_angle(ctx, field("timing.inclination"), timing["inclination"])
        extras["cos_inclination"] = math.cos(math.radians(incl))
    extras |= _quantities(ctx, timing, (field("timing.distance"),))
    section = TimingSection(
        ephemeris=eph,
        t0_text=" ".join(str(timing["t0"]).split()),
        cov_names=names,
        cov_matrix=mat,
        source=_parse_text(ctx, "timing.source", timing["source"], _expect(field("timing.source"))),
        eccentricity_given="eccentricity" in timing,
    )
    return _Ephemeris(
        t_ref=t0,
        t_obs_s=0.0,
        params=to_phase_params(eph),
        cov_names=cov_names,
        cov_matrix=cov_matrix,
        extras=extras,
        timing=section,
    )


def _timing_eccentricity(ctx: Ctx, timing: Mapping[str, Any]) -> dict[str, float]:
    """η, κ, ω̇ of ``timing.eccentricity`` (0 when absent), e inside the small-e model."""
    if "eccentricity" not in timing:
        return {"eta": 0.0, "kappa": 0.0, "omega_dot": 0.0}
    ecc = _mapping(ctx, field("timing.eccentricity"), timing["eccentricity"])
    vals = _quantities(ctx, ecc, section_fields("timing.eccentricity"))
    _check_eccentricity(ctx, vals["eta"], vals["kappa"], "timing.eccentricity")
    return {k: float(v) for k, v in vals.items()}


def _check_period_sign(ctx: Ctx, eph: TimingEphemeris) -> None:
    """P (and the model frequency 2/P) must keep their sign within ±100 yr of T0."""
    which, when = period_sign_change(eph)
    if not which:
        return
    side = "after" if when > 0 else "before"
    raise ctx.fail(
        f"timing.{which}",
        f"the period (or the model frequency 2/P) would reach zero {abs(when) / YEAR_S:.3g} yr "
        f"{side} T0 (P = "
        f"{eph.period_s:.10g} s, Ṗ = {eph.pdot:.4g}, P̈ = {eph.pddot:.4g} 1/s); it must stay "
        f"positive within ±{SIGN_SPAN_S / YEAR_S:.0f} yr of T0: check the sign, value and unit "
        "(Ṗ in s/s, P̈ in 1/s)",
    )


def _phase_model_covariance(
    ctx: Ctx, eph: TimingEphemeris, names: tuple[str, ...], mat: FloatArray
) -> tuple[tuple[str, ...], FloatArray]:
    """The timing covariance moved to the phase-model parameters (those with σ > 0)."""
    full = np.zeros((7, 7))
    idx = [TIMING_NAMES.index(n) for n in names]
    full[np.ix_(idx, idx)] = mat
    with np.errstate(all="ignore"):
        pcov = phase_covariance(eph, full)
    if not np.all(np.isfinite(pcov)):
        raise ctx.fail(
            "timing.covariance", "overflows when moved to the phase model; check its units"
        )
    keep = [i for i in range(7) if pcov[i, i] > 0.0]
    return tuple(PARAM_NAMES[i] for i in keep), pcov[np.ix_(keep, keep)]


def _expect(f: Field) -> str:
    return f"expected {f.what} like {f.example}"


def _parse_text(ctx: Ctx, path: str, value: Any, expect: str) -> str:
    """A non-empty one-line text of at most :data:`MAX_TEXT_CHARS` characters."""
    if not isinstance(value, str) or not value.strip():
        raise ctx.fail(path, f"{expect}, got {shorten(value)}")
    if len(value) > MAX_TEXT_CHARS:
        raise ctx.fail(
            path, f"{expect} of at most {MAX_TEXT_CHARS} characters, got {shorten(value)}"
        )
    if any(unicodedata.category(c) in _CONTROL for c in value):
        raise ctx.fail(path, f"{expect} on one line without control characters")
    return " ".join(value.split())


# ---------------------------------------------------------------------------------------------
# magnitudes and references
# ---------------------------------------------------------------------------------------------

#: A photometric band name: V, g, G, G_BP, Ks, r', …
_BAND = re.compile(r"[A-Za-z][A-Za-z0-9_']{0,15}")


def _parse_magnitudes(ctx: Ctx, doc: Mapping[str, Any]) -> dict[str, float]:
    """``magnitudes`` by band, with ``vmag`` as V (both given: they must agree)."""
    f = field("magnitudes")
    out: dict[str, float] = {}
    if f.name in doc:
        mags = doc[f.name]
        if not isinstance(mags, Mapping) or not mags:
            raise ctx.fail(f.path, f"expected {f.what} like {f.example}, got {shorten(mags)}")
        for band, raw in mags.items():
            where = f"{f.path}.{ctx.key(band)}"
            if not isinstance(band, str) or not _BAND.fullmatch(band):
                raise ctx.fail(where, "expected a band name like V, g, G or G_BP")
            try:
                x = to_float(raw)
            except ValueError:
                raise ctx.fail(
                    where, f"expected a magnitude like 20.5, got {shorten(raw)}"
                ) from None
            check_range(ctx, f, x, raw, where=where)
            out[band] = x
    vmag = _number(ctx, doc, field("vmag"))
    if vmag is not None:
        if "V" in out and out["V"] != vmag:
            raise ctx.fail(
                "vmag", f"vmag {vmag:g} and magnitudes.V {out['V']:g} differ; give V once"
            )
        out = {"V": vmag, **out}
    return out


def _field_paths(doc: Mapping[str, Any]) -> list[str]:
    """Schema field paths present in ``doc``, and ``magnitudes.<band>`` of its bands."""
    paths = []
    for f in FIELDS:
        node: Any = doc
        for part in f.path.split("."):
            node = node.get(part) if isinstance(node, Mapping) else None
        if node is not None:
            paths.append(f.path)
    mags = doc.get("magnitudes")
    if isinstance(mags, Mapping):
        paths += [f"magnitudes.{b}" for b in mags if isinstance(b, str)]
    if "vmag" in doc:
        paths.append("magnitudes.V")
    return paths


def _parse_references(ctx: Ctx, doc: Mapping[str, Any]) -> dict[str, str]:
    """``references``: a citation for each field given in the file."""
    f = field("references")
    if f.name not in doc:
        return {}
    refs = doc[f.name]
    if not isinstance(refs, Mapping) or not refs:
        raise ctx.fail(f.path, f"expected {f.what} like {f.example}, got {shorten(refs)}")
    present = _field_paths(doc)
    out: dict[str, str] = {}
    for key, raw in refs.items():
        where = f"{f.path}.{ctx.key(key)}"
        if not isinstance(key, str) or key not in present:
            hint = did_you_mean(key, present)
            raise ctx.fail(
                where,
                f"not a field of this file; {hint}cite fields the file gives, e.g. "
                "timing.period, masses.m1 or magnitudes.V",
            )
        out[key] = _parse_text(
            ctx, where, raw, 'expected a citation like "2019Natur.571..528B" or a DOI'
        )
    return out


# ---------------------------------------------------------------------------------------------
# time scale and reference epoch
# ---------------------------------------------------------------------------------------------


def _tcb_to_tdb(
    vals: dict[str, float], names: tuple[str, ...], mat: FloatArray
) -> tuple[dict[str, float], FloatArray]:
    """Rescale rates from TCB to TDB seconds: a quantity per TCB second^n gains (1 − L_B)^−n."""
    out = dict(vals)
    scale = np.ones(len(names))
    for key, n in _TCB_POWER.items():
        out[key] = vals[key] / (1.0 - L_B) ** n
        if key in names:
            scale[names.index(key)] = 1.0 / (1.0 - L_B) ** n
    return out, mat * np.outer(scale, scale)


def _shift_named(
    p: PhaseParams, names: tuple[str, ...], mat: FloatArray, dt: float
) -> tuple[PhaseParams, FloatArray]:
    """Shift parameters and the named covariance by ``dt`` [s] (extras like cos ι unchanged)."""
    new_p, _ = shift_reference(p, np.zeros((7, 7)), dt)
    if not names:
        return new_p, mat
    j7 = shift_jacobian(p, dt)
    j = np.eye(len(names))
    for a, na in enumerate(names):
        for b, nb in enumerate(names):
            if na in PARAM_NAMES and nb in PARAM_NAMES:
                j[a, b] = j7[PARAM_NAMES.index(na), PARAM_NAMES.index(nb)]
    # parameters absent from the covariance are exact: their columns do not matter
    new = j @ mat @ j.T
    return new_p, 0.5 * (new + new.T)
