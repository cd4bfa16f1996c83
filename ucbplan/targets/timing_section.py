"""The ``timing`` section of a target file, and the top-level ``magnitudes`` and ``references``.

:func:`parse_timing` reads a timing ephemeris (T0 as a full-precision BJD_TDB epoch, the mark,
P, Ṗ, P̈, a small eccentricity, the covariance of the timing parameters) and converts it with
:mod:`ucbplan.core.timing` into the phase model referenced to T0, the one every command reads.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ucbplan.core.constants import YEAR_S
from ucbplan.core.params import PARAM_NAMES
from ucbplan.core.timing import (
    SIGN_SPAN_S,
    TIMING_NAMES,
    TimingEphemeris,
    period_sign_change,
    phase_covariance,
    to_phase_params,
)
from ucbplan.core.timing_epochs import parse_timing_epoch
from ucbplan.errors import shorten
from ucbplan.targets.covariance import exact_parameters, parse_covariance
from ucbplan.targets.epoch_batch import take_epoch
from ucbplan.targets.model import TimingSection
from ucbplan.targets.schema import FIELDS, field, section_fields
from ucbplan.targets.sections import (
    Ephemeris,
    check_eccentricity,
    check_section,
    expect,
    mapping,
    number,
    parse_text,
    quantities,
)
from ucbplan.targets.values import (
    Ctx,
    check_range,
    did_you_mean,
    parse_angle,
    parse_choice,
    to_float,
)

FloatArray = NDArray[np.float64]
_TIMING_VALUES = tuple(field(f"timing.{n}") for n in ("period", "pdot", "pddot"))
#: A photometric band name: V, g, G, G_BP, Ks, r', …
_BAND = re.compile(r"[A-Za-z][A-Za-z0-9_']{0,15}")


def parse_timing(ctx: Ctx, timing: Any) -> Ephemeris:
    """The ``timing`` section as the phase model at t_ref = T0 (:mod:`ucbplan.core.timing`)."""
    check_section(ctx, "timing", timing)
    f_t0 = field("timing.t0")
    t0 = take_epoch(timing["t0"])  # read ahead with the other files' epochs
    try:
        t0 = parse_timing_epoch(timing["t0"]) if t0 is None else t0
    except ValueError as exc:
        raise ctx.fail(f_t0.path, str(exc)) from None
    mark = parse_choice(ctx, field("timing.t0_marks"), timing["t0_marks"])
    vals = quantities(ctx, timing, _TIMING_VALUES)
    ecc = _timing_eccentricity(ctx, timing)
    eph = TimingEphemeris(mark, vals["period"], vals["pdot"], vals["pddot"], **ecc)
    _check_period_sign(ctx, eph)
    names, mat = parse_covariance(ctx, timing["covariance"], "timing")
    exact = exact_parameters(ctx, timing["covariance"], names)
    _check_sigmas_known(ctx, eph, (*names, *exact))
    cov_names, cov_matrix = _phase_model_covariance(ctx, eph, names, mat)
    extras: dict[str, float | None] = {"cos_inclination": None, "amplitude": None, "psi": None}
    if "inclination" in timing:
        incl = parse_angle(ctx, field("timing.inclination"), timing["inclination"])
        extras["cos_inclination"] = math.cos(math.radians(incl))
    extras |= quantities(ctx, timing, (field("timing.distance"),))
    section = TimingSection(
        ephemeris=eph,
        t0_text=" ".join(str(timing["t0"]).split()),
        cov_names=names,
        cov_matrix=mat,
        source=parse_text(ctx, "timing.source", timing["source"], expect(field("timing.source"))),
        eccentricity_given="eccentricity" in timing,
    )
    return Ephemeris(
        t_ref=t0,
        t_obs_s=0.0,
        params=to_phase_params(eph),
        cov_names=cov_names,
        cov_matrix=cov_matrix,
        extras=extras,
        timing=section,
    )


#: How messages show a σ to give, per timing parameter: placeholders, no real system's values.
_SIGMA_PLACEHOLDER = {
    "t0": '"<σ(T0)> d"',
    "period": '"<σ(P)> s"',
    "pdot": "<σ(Ṗ)>",
    "pddot": '"<σ(P̈)> 1/s"',
    "eta": "<σ(η)>",
    "kappa": "<σ(κ)>",
    "omega_dot": '"<σ(ω̇)> rad/s"',
}


def sigmas_needed(eph: TimingEphemeris) -> tuple[str, ...]:
    """Timing parameters whose σ the covariance must give or declare exact: T0 and P always,
    Ṗ, P̈, η, κ and ω̇ when not zero (a zero value claims nothing to be uncertain about)."""
    values = {"pdot": eph.pdot, "pddot": eph.pddot, "eta": eph.eta, "kappa": eph.kappa}
    values["omega_dot"] = eph.omega_dot
    return tuple(n for n in TIMING_NAMES if n in ("t0", "period") or values[n] != 0.0)


def _check_sigmas_known(ctx: Ctx, eph: TimingEphemeris, known: tuple[str, ...]) -> None:
    """Every σ of :func:`sigmas_needed` is given or its parameter declared exact (issue 33:
    σ(T0) alone made P and Ṗ exact without a word, and the horizon 300 yr)."""
    missing = [n for n in sigmas_needed(eph) if n not in known]
    if missing:
        shown = ", ".join(f"{n}: {_SIGMA_PLACEHOLDER[n]}" for n in missing)
        raise ctx.fail(
            "timing.covariance",
            f"no σ for {', '.join(missing)}; give each in sigma ({shown}) or, for a parameter "
            f"known exactly, list it in exact: [{', '.join(missing)}]",
        )


def _timing_eccentricity(ctx: Ctx, timing: Mapping[str, Any]) -> dict[str, float]:
    """η, κ, ω̇ of ``timing.eccentricity`` (0 when absent), e inside the small-e model."""
    if "eccentricity" not in timing:
        return {"eta": 0.0, "kappa": 0.0, "omega_dot": 0.0}
    ecc = mapping(ctx, field("timing.eccentricity"), timing["eccentricity"])
    vals = quantities(ctx, ecc, section_fields("timing.eccentricity"))
    check_eccentricity(ctx, vals["eta"], vals["kappa"], "timing.eccentricity")
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


def parse_magnitudes(ctx: Ctx, doc: Mapping[str, Any]) -> dict[str, float]:
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
    vmag = number(ctx, doc, field("vmag"))
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


def parse_references(ctx: Ctx, doc: Mapping[str, Any]) -> dict[str, str]:
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
        out[key] = parse_text(
            ctx, where, raw, 'expected a citation like "2019Natur.571..528B" or a DOI'
        )
    return out
