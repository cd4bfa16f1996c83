"""The target-file schema and the parser cannot drift apart.

The documents below are written by hand (not generated from the schema): together they use every
field a target file may hold (a LISA posterior in two forms, a timing ephemeris in two forms).
The tests check that the parser accepts exactly the schema's fields, that the schema's required
flags, ranges, examples and choices are what the parser enforces.
"""

from __future__ import annotations

import copy
import math
import re
from pathlib import Path
from typing import Any

import pytest

from ucbplan.errors import TargetFileError
from ucbplan.targets import Target, target_from_dict, target_to_dict
from ucbplan.targets.fieldtypes import Field
from ucbplan.targets.schema import FIELDS, SECTIONS, field

FULL: dict[str, Any] = {
    "name": "Full",
    "sky": {"ra": "08h06m23.2s", "dec": "+15d27m30s", "frame": "icrs"},
    "lisa": {
        "t_ref": "2035-01-01T00:00:00",
        "t_ref_scale": "tdb",
        "t_obs": "126232599.05 s",
        "t_ref_is": "start",
        "phase": 4.61,
        "f_gw": "8.406e-3 Hz",
        "fdot": "1.64e-15 Hz / s",
        "fddot": "0 Hz / s2",
        "eta": 0.0068,
        "kappa": 0.0068,
        "omega_dot": "1.498e-6 rad / s",
        "cos_inclination": 0.093,
        "amplitude": 4.9e-22,
        "psi": 0.339,
        "distance": "0.577 kpc",
        "covariance": {
            "parameters": ["phase", "f_gw", "cos_inclination"],
            "matrix": [[4e-6, 0, 0], [0, 3e-23, 0], [0, 0, 1e-4]],
        },
        "samples": "post.ecsv",
    },
    "priority": 2.0,
    "vmag": 21.1,
    "masses": {"m1": "0.347 solMass", "m2": "0.285 solMass"},
    "spectroscopy": {
        "lines": "SB2",
        "K1": "585.3 km/s",
        "K2": "712.6 km/s",
        "K_eff": "390 km/s",
        "sigma_v": "15 km/s",
    },
    "notes": "anything at all",
}
#: The other forms: galactic sky position, marginal σ with correlations.
VARIANT: dict[str, Any] = {
    **FULL,
    "sky": {"l": -93.56, "b": "-19.19 deg"},
    "lisa": {
        **FULL["lisa"],
        "covariance": {
            "sigma": {"phase": 0.002, "f_gw": "5.5e-12 Hz", "fdot": "3.4e-19 Hz / s"},
            "correlation": {"phase,fdot": -0.7},
        },
    },
}
#: A timing ephemeris (test input with the issue's ZTF J1539+5027 numbers, not a catalog entry),
#: every timing field, matrix form; magnitudes and references at the top level.
TIMING: dict[str, Any] = {
    "name": "Timing",
    "sky": {"ra": "15h39m32.16s", "dec": "+50d27m38.8s"},
    "timing": {
        "t0": "BJD_TDB 2458305.6827886",
        "t0_marks": "primary_eclipse",
        "period": "414.7915404 s",
        "pdot": -2.373e-11,
        "pddot": "0 1 / s",
        "eccentricity": {"eta": 0.001, "kappa": 0.002, "omega_dot": "1e-7 rad / s"},
        "inclination": "84.15 deg",
        "distance": "2.34 kpc",
        "covariance": {  # every σ the ephemeris needs (issue 33); P̈ = 0 declared exact
            "parameters": ["t0", "period", "pdot", "eta", "kappa", "omega_dot"],
            "matrix": [
                [0.53, 0, 0, 0, 0, 0],
                [0, 8.4e-12, 0, 0, 0, 0],
                [0, 0, 2.5e-27, 0, 0, 0],
                [0, 0, 0, 1e-8, 0, 0],
                [0, 0, 0, 0, 1e-8, 0],
                [0, 0, 0, 0, 0, 1e-18],
            ],
            "exact": ["pddot"],
        },
        "source": "Burdge et al. 2019, Nature 571, 528",
    },
    "magnitudes": {"g": 20.5, "G": 20.4},
    "references": {"timing": "2019Natur.571..528B", "magnitudes.g": "Burdge et al. 2019"},
    "spectroscopy": {"lines": "SB2", "K1": "300 km/s", "K2": "870 km/s", "sigma_v": "20 km/s"},
}
#: The σ form of the timing covariance, with a correlation.
TIMING_VARIANT: dict[str, Any] = {
    **TIMING,
    "timing": {
        **TIMING["timing"],
        "covariance": {
            "sigma": {
                "t0": "8.4e-6 d",
                "period": "2.9e-6 s",
                "pdot": 5.0e-14,
                "eta": 1e-4,
                "kappa": 1e-4,
                "omega_dot": "1e-9 rad / s",
            },
            "correlation": {"period,pdot": -0.5},
            "exact": ["pddot"],
        },
    },
}
DOCS = (FULL, VARIANT, TIMING, TIMING_VARIANT)
#: Mappings whose keys are field names (σ and ρ are keyed by parameter names instead).
NESTED = {
    "sky",
    "lisa",
    "lisa.covariance",
    "timing",
    "timing.covariance",
    "timing.eccentricity",
    "masses",
    "spectroscopy",
}
#: Fields required within one of two forms (ra+dec or l+b; parameters+matrix or sigma; a LISA
#: posterior or a timing ephemeris).
ALTERNATIVES = {
    "sky.ra",
    "sky.dec",
    "sky.l",
    "sky.b",
    "lisa",
    "timing",
    "lisa.covariance.parameters",
    "lisa.covariance.matrix",
    "lisa.covariance.sigma",
    "timing.covariance.parameters",
    "timing.covariance.matrix",
    "timing.covariance.sigma",
}


def _path(f: Field) -> str:
    return f.path


def _paths(doc: dict[str, Any], prefix: str = "") -> set[str]:
    out = set()
    for key, value in doc.items():
        path = f"{prefix}{key}"
        out.add(path)
        if path in NESTED:
            out |= _paths(value, f"{path}.")
    return out


def _doc_with(f: Field) -> dict[str, Any]:
    """A deep copy of the first hand-written document that holds ``f``."""
    return copy.deepcopy(next(d for d in DOCS if f.path in _paths(d)))


def _set(doc: dict[str, Any], path: str, value: Any) -> None:
    *parents, key = path.split(".")
    for p in parents:
        doc = doc[p]
    doc[key] = value


def _delete(doc: dict[str, Any], path: str) -> None:
    *parents, key = path.split(".")
    for p in parents:
        doc = doc[p]
    del doc[key]


@pytest.fixture
def load(tmp_path: Path) -> Any:
    # a readable samples file: a target without lisa.covariance takes its covariance from it
    (tmp_path / "post.ecsv").write_text("# %ECSV 1.0\n# ---\nf_gw\n6.22e-3\n6.23e-3\n")

    def _load(doc: dict[str, Any]) -> Target:
        return target_from_dict(doc, tmp_path / "t.yaml")

    return _load


def test_every_schema_field_is_accepted_and_nothing_else(load: Any) -> None:
    """The hand-written documents load, and their fields are exactly the schema's."""
    for doc in DOCS:
        assert isinstance(load(doc), Target)
    assert set().union(*(_paths(d) for d in DOCS)) == {f.path for f in FIELDS}
    assert len({f.path for f in FIELDS}) == len(FIELDS)


@pytest.mark.parametrize("section", SECTIONS)
def test_a_field_outside_the_schema_is_rejected(load: Any, section: str) -> None:
    """Every section is strict (a misspelt lisa.covariance.correlation would drop the
    correlations), also beside galactic l, b."""
    for base in DOCS:
        if section and section not in _paths(base):
            continue
        doc = copy.deepcopy(base)
        path = f"{section}.not_a_field" if section else "not_a_field"
        _set(doc, path, 1)
        with pytest.raises(TargetFileError) as exc:
            load(doc)
        assert str(exc.value).startswith(f"t.yaml: {path}: unknown field")


def test_sections_are_the_nested_mappings() -> None:
    assert set(SECTIONS) == {"", *NESTED}


@pytest.mark.parametrize("f", [f for f in FIELDS if f.path not in ALTERNATIVES], ids=_path)
def test_required_flags_match_the_parser(load: Any, f: Field) -> None:
    doc = _doc_with(f)
    _delete(doc, f.path)
    for key in list(doc.get("references", {})):  # a citation of a field left out is refused
        if key == f.path or key.startswith(f"{f.path}."):
            del doc["references"][key]
    if f.required:
        with pytest.raises(TargetFileError, match=re.escape(f.path)):
            load(doc)
    else:
        assert isinstance(load(doc), Target)


@pytest.mark.parametrize("path", sorted(ALTERNATIVES))
def test_alternative_forms_need_all_their_fields(load: Any, path: str) -> None:
    doc = _doc_with(field(path))
    _delete(doc, path)
    with pytest.raises(TargetFileError, match=r"sky|covariance|lisa"):
        load(doc)


def test_lisa_and_timing_are_exclusive(load: Any) -> None:
    doc = copy.deepcopy(FULL)
    doc["timing"] = copy.deepcopy(TIMING["timing"])
    with pytest.raises(TargetFileError, match=r"t.yaml: lisa/timing: give exactly one of lisa"):
        load(doc)


def _outside(f: Field) -> float:
    assert f.bounds is not None
    b = f.bounds
    if math.isfinite(b.low):
        return b.low if b.low_open else b.low - 1.0
    return b.high if b.high_open else b.high + 1.0


@pytest.mark.parametrize("f", [f for f in FIELDS if f.bounds is not None], ids=_path)
def test_declared_ranges_are_enforced(load: Any, f: Field) -> None:
    """A value just outside the declared range fails with the declared message; the
    hand-written value inside it loads (test above)."""
    x = _outside(f)
    doc = _doc_with(f)
    where = f.path
    value: Any = f"{x} {f.unit}" if f.unit_required else x
    keyed = {
        "lisa.covariance.sigma": "phase",
        "lisa.covariance.correlation": "phase,fdot",
        "timing.covariance.sigma": "pdot",
        "timing.covariance.correlation": "period,pdot",
        "magnitudes": "g",
    }
    if f.path in keyed:
        where = f"{f.path}.{keyed[f.path]}"
        _set(doc, f.path, {keyed[f.path]: x})
    else:
        _set(doc, f.path, value)
    assert f.bounds is not None
    message = f.bounds.error.format(raw=repr(value) if f.unit_required else x, value=x)
    with pytest.raises(TargetFileError, match=re.escape(f"t.yaml: {where}: {message}")):
        load(doc)


def _example_values(f: Field) -> list[Any]:
    """The values an example string shows: each quoted one, else the leading bare number."""
    quoted = re.findall(r'"([^"]+)"', f.example)
    bare = re.match(r"^\s*([-+]?[0-9.]+(?:e[-+]?\d+)?)(?:\s|$)", f.example)
    return quoted + ([float(bare.group(1))] if bare else [])


@pytest.mark.parametrize(
    "f", [f for f in FIELDS if f.kind in ("quantity", "angle", "epoch")], ids=_path
)
def test_examples_are_valid_values(load: Any, f: Field) -> None:
    values = _example_values(f)
    assert values, f"{f.path}: example {f.example!r} shows no value"
    for value in values:
        doc = _doc_with(f)
        _set(doc, f.path, value)
        assert isinstance(load(doc), Target), value


@pytest.mark.parametrize("f", [f for f in FIELDS if f.kind == "choice"], ids=_path)
def test_choices_are_accepted_and_others_are_not(load: Any, f: Field) -> None:
    assert f.choices
    for choice in f.choices:
        doc = _doc_with(f)
        _set(doc, f.path, choice)
        assert isinstance(load(doc), Target), choice
    doc = _doc_with(f)
    _set(doc, f.path, "none-of-these")
    with pytest.raises(TargetFileError, match=re.escape(f.path)):
        load(doc)


def test_range_notation() -> None:
    assert str(field("lisa.cos_inclination").bounds) == "[-1, 1]"
    assert str(field("lisa.f_gw").bounds) == "(0, 1]"
    assert str(field("lisa.distance").bounds) == "(0, inf)"
    assert str(field("sky.ra").bounds) == "[0, 360)"


#: Two different valid values per kind (bare numbers are in the field's unit).
_PAIRS: dict[str, tuple[Any, Any]] = {
    "quantity": (0.01, 0.02),
    "angle": (10.0, 20.0),
    "number": (2.0, 3.0),
    "epoch": ("2035-01-01T00:00:00", "2036-01-01T00:00:00"),
}
#: Fields whose kind's pair is not valid for them.
_FIELD_PAIRS: dict[str, tuple[Any, Any]] = {
    "timing.t0": ("BJD_TDB 2458305.6827886", "BMJD_TDB 58306.1827886"),
    "timing.period": ("414.79 s", "0.0048 d"),
    "timing.pdot": (-2.373e-11, 1e-12),
    "timing.pddot": ("1e-21 1 / s", "-1e-21 1 / s"),
}
#: Accepted but without effect: free-form notes; j2000/fk5 are read as ICRS.
_NO_EFFECT = {"notes", "sky.frame"}


@pytest.mark.parametrize(
    "f",
    [f for f in FIELDS if f.kind in (*_PAIRS, "choice") and f.path not in _NO_EFFECT],
    ids=_path,
)
def test_every_value_reaches_the_target_and_the_written_file(load: Any, f: Field) -> None:
    """Two different values of a field give two different targets (so the parser reads the
    field) and two different written documents (so the writer writes what it depends on)."""
    a, b = _FIELD_PAIRS.get(f.path, _PAIRS.get(f.kind, f.choices[:2]))
    written = []
    for value in (a, b):
        doc = _doc_with(f)
        _set(doc, f.path, value)
        written.append(target_to_dict(load(doc)))
    assert written[0] != written[1]
