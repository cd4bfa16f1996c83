"""Write a :class:`~ucbplan.targets.model.Target` back as a target file (schema order and units).

LISA parameters are written at the midpoint (``t_ref_is: midpoint``); a timing ephemeris is
written as given (T0 as its full-precision text, the timing covariance as a matrix).
Quantities carry the unit the schema declares (:mod:`ucbplan.targets.schema`), so
:func:`~ucbplan.targets.parse.load_target` reads back the same numbers.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from pathlib import Path
from typing import IO, Any

import yaml
from astropy.time import Time

from ucbplan.core.params import PARAM_NAMES
from ucbplan.inputs import EXPONENT_FLOAT
from ucbplan.io import write_output
from ucbplan.targets.model import Spectroscopy, Target, TimingSection
from ucbplan.targets.schema import field
from ucbplan.targets.timing_section import sigmas_needed


class _Dumper(yaml.SafeDumper):
    """SafeDumper that quotes text :func:`ucbplan.inputs.load_yaml` would read as a number.

    load_yaml reads ``5e-14`` (an exponent without a decimal point) as a float, plain YAML as a
    string; without this a target named ``1e3`` would be written unquoted and read back as a
    number.
    """


_Dumper.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    EXPONENT_FLOAT,
    list("-+0123456789"),
)


def _value(path: str, value: float) -> float | str:
    """A number as the schema writes it: bare in rad or dimensionless, else ``"<repr> <unit>"``."""
    unit = field(path).unit
    if not unit or unit == "rad":
        return float(value)
    return f"{float(value)!r} {unit}"


def _given(section: str, pairs: Iterable[tuple[str, float | None]]) -> dict[str, float | str]:
    """``{name: written value}`` of the fields of ``section`` whose value is not None."""
    return {name: _value(f"{section}.{name}", v) for name, v in pairs if v is not None}


def target_to_dict(t: Target) -> dict[str, Any]:
    """YAML-ready dict in the documented schema (parameters at the midpoint, bare SI numbers).

    A samples path is written relative to the target's source directory when it lies below it.
    """
    doc: dict[str, Any] = {
        "name": t.name,
        "sky": _given("sky", (("ra", t.ra_deg), ("dec", t.dec_deg))),
    }
    if t.kind == "timing" and t.timing is not None:
        doc["timing"] = _timing_dict(t, t.timing)
    else:
        doc["lisa"] = _lisa_dict(t)
    if t.priority != field("priority").default:
        doc["priority"] = t.priority
    mags = dict(t.magnitudes)
    if t.vmag is not None:
        mags.setdefault("V", t.vmag)
    if set(mags) == {"V"}:
        doc["vmag"] = mags["V"]
    elif mags:
        doc["magnitudes"] = mags
    if t.references:
        doc["references"] = dict(t.references)
    if t.m1_msun is not None or t.m2_msun is not None:
        doc["masses"] = _given("masses", (("m1", t.m1_msun), ("m2", t.m2_msun)))
    if t.spectroscopy is not None:
        doc["spectroscopy"] = _spectroscopy_dict(t.spectroscopy)
    return doc


def _lisa_dict(t: Target) -> dict[str, Any]:
    lisa: dict[str, Any] = {
        "t_ref": _epoch_text(t.t_ref),
        "t_obs": _value("lisa.t_obs", t.t_obs_s),
        "t_ref_is": "midpoint",
    }
    lisa |= _given("lisa", ((n, getattr(t.params, n)) for n in PARAM_NAMES))
    lisa |= _given(
        "lisa",
        (
            ("cos_inclination", t.cos_inclination),
            ("amplitude", t.amplitude),
            ("psi", t.psi),
            ("distance", t.distance_kpc),
        ),
    )
    if t.cov_names:
        lisa["covariance"] = {
            "parameters": list(t.cov_names),
            "matrix": [[float(x) for x in row] for row in t.cov_matrix],
        }
    if t.samples is not None:
        base = t.source.parent if t.source is not None else Path(".")
        lisa["samples"] = _relative(t.samples, base.resolve())
    return lisa


def _timing_dict(t: Target, s: TimingSection) -> dict[str, Any]:
    """The ``timing`` section as given (T0 text, values at T0, the timing covariance)."""
    e = s.ephemeris
    out: dict[str, Any] = {"t0": s.t0_text, "t0_marks": e.mark}
    out["period"] = _value("timing.period", e.period_s)
    out["pdot"] = float(e.pdot)
    if e.pddot != 0.0:
        out["pddot"] = _value("timing.pddot", e.pddot)
    if s.eccentricity_given:
        out["eccentricity"] = _given(
            "timing.eccentricity",
            (("eta", e.eta), ("kappa", e.kappa), ("omega_dot", e.omega_dot)),
        )
    if t.cos_inclination is not None:
        out["inclination"] = f"{math.degrees(math.acos(t.cos_inclination))!r} deg"
    if t.distance_kpc is not None:
        out["distance"] = _value("timing.distance", t.distance_kpc)
    cov: dict[str, Any] = {}
    if s.cov_names:
        cov["parameters"] = list(s.cov_names)
        cov["matrix"] = [[float(x) for x in row] for row in s.cov_matrix]
    exact = [n for n in sigmas_needed(e) if n not in s.cov_names]
    if exact:  # declared exact when read (the reader refuses a σ left out silently)
        cov["exact"] = exact
    if cov:
        out["covariance"] = cov
    out["source"] = s.source
    return out


def _epoch_text(t: Time) -> str:
    """ISO TDB text of ``t`` to 1 µs: milliseconds when they are that close, else microseconds.

    A start-referenced or converted epoch moved to the midpoint has sub-millisecond digits;
    cutting them to 1 ms would shift the phase reference by up to 3e-4 rad at f = 0.1 Hz.
    """
    tdb = t.tdb
    text: str = Time(tdb, precision=3).isot
    if abs((Time(text, scale="tdb") - tdb).to_value("s")) > 1e-6:
        text = Time(tdb, precision=6).isot
    return text


def _spectroscopy_dict(s: Spectroscopy) -> dict[str, Any]:
    spec: dict[str, Any] = {"lines": s.lines}
    spec |= _given(
        "spectroscopy",
        (("K1", s.K1_kms), ("K2", s.K2_kms), ("K_eff", s.K_eff_kms), ("sigma_v", s.sigma_v_kms)),
    )
    return spec


def _relative(path: Path, base: Path) -> str:
    """``path`` relative to ``base`` if it lies below it, else as given."""
    try:
        return str(path.relative_to(base))
    except ValueError:
        return str(path)


def write_target(t: Target, path: Path, overwrite: bool = False, header: str = "") -> None:
    """Write ``t`` as YAML atomically.

    Parameters
    ----------
    t : Target
        The target to write.
    path : Path
        Output file; the samples path is written relative to its directory when possible.
    overwrite : bool
        Replace an existing file.
    header : str
        Comment lines written first (each prefixed with ``# ``).

    Raises
    ------
    OutputExistsError
        ``path`` exists and ``overwrite`` is false.
    """
    doc = target_to_dict(t)
    if t.samples is not None:
        doc["lisa"]["samples"] = _relative(t.samples.resolve(), path.parent.resolve())

    def _write(handle: IO[Any]) -> None:
        for line in header.splitlines():
            handle.write(f"# {line}\n")
        yaml.dump(doc, handle, Dumper=_Dumper, sort_keys=False, allow_unicode=True, width=100)

    write_output(path, _write, overwrite=overwrite)
