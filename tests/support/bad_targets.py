"""The target-file bad-input corpus: each way a target file can be wrong, with the words its
one-line error must hold. Run by tests/targets/test_target_bad_input.py (and reused by the
timing-target mutation tests)."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import pytest

from support.targets import BASE, ztf_j1539_doc
from ucbplan.errors import TargetFileError
from ucbplan.targets import Target, target_from_dict

#: Fields of the ``lisa:`` block given a bad value (merged into BASE's), and a phrase of the error.
LISA_FIELDS: list[tuple[dict[str, Any], str]] = [
    (
        {"fdot": "7.07e-16 Hz"},
        'lisa.fdot: expected a frequency derivative like "7.07e-16 Hz / s"',
    ),
    ({"f_gw": "6.2e-3 km"}, "lisa.f_gw: expected a frequency"),
    ({"phase": ".nan"}, "lisa.phase"),
    ({"phase": float("nan")}, "non-finite"),
    ({"fdot": float("inf")}, "non-finite"),
    ({"eta": 0.08, "kappa": 0.08}, "outside the small-e"),
    ({"t_ref": "2037-01-01T00:00:00 UTC"}, "t_ref_scale: utc"),
    ({"t_ref": "2037-01-01T00:00:00 TCB"}, "TCB-labelled"),
    ({"t_ref": "yesterday"}, "lisa.t_ref: expected an ISO epoch"),
    ({"t_ref_is": "end"}, "lisa.t_ref_is"),
    ({"frequency": 1.0}, "lisa.frequency: unknown field"),
    ({"t_obs": "-4 yr"}, "lisa.t_obs: must be positive"),
    ({"covariance": {"sigma": {"phse": 0.1}}}, "unknown parameter"),
    (
        {"covariance": {"parameters": ["phase", "f_gw"], "matrix": [[1.0, 2.0], [2.0, 1.0]]}},
        "not positive semi-definite",
    ),
    (
        {"covariance": {"parameters": ["phase", "f_gw"], "matrix": [[1.0, 0.5], [0.1, 1.0]]}},
        "not symmetric",
    ),
    ({"covariance": {"parameters": ["phase", "bogus"], "matrix": [[1, 0], [0, 1]]}}, "bogus"),
    ({"covariance": {"parameters": ["phase"], "matrix": [[1, 0], [0, 1]]}}, "1×1 matrix"),
    (
        {
            "covariance": {
                "sigma": {"phase": 0.1, "f_gw": 1e-12},
                "correlation": {"phase,f_gw": 1.5},
            }
        },
        "ρ in [-1, 1]",
    ),
    ({"cos_inclination": 1.5}, "lisa.cos_inclination"),
]

#: Whole documents wrong at the top level, and a phrase of the error.
DOCUMENTS: list[tuple[object, str]] = [
    ({"name": "x"}, "sky: missing"),
    ({**BASE, "sky": {"ra": "25h", "dec": 0}}, "sky.ra"),
    ({**BASE, "sky": {"ra": 10, "dec": 95}}, "declination"),
    ({**BASE, "spectroscopy": {"lines": "SB3"}}, "spectroscopy.lines"),
    (
        {**BASE, "spectroscopy": {"sigma_v": "15 km"}},
        "spectroscopy.sigma_v: expected a velocity",
    ),
    ({**BASE, "extra": 1}, "extra: unknown field"),
    ([1, 2], "expected a YAML mapping"),
]

#: In place of a value: delete the field.
DELETE = object()

#: (dotted field of the ZTF J1539+5027 timing document, its bad value or DELETE, the words of the
#: error).
TIMING_FIELDS: list[tuple[str, Any, list[str]]] = [
    ("timing.t0_marks", "primary", ["timing.t0_marks", "did you mean 'primary_eclipse'"]),
    ("timing.t0_marks", "periastron", ["timing.t0_marks", "expected one of"]),
    ("timing.t0", "BJD_XYZ 2458305.68", ["timing.t0", "unknown time-scale word"]),
    ("timing.t0", "HJD 2458305.6827886", ["timing.t0", "HJD", "convert"]),
    ("timing.t0", "2018-07-06T04:23:12 UTC", ["timing.t0", "UTC", "convert"]),
    ("timing.t0", 2458305.6827886, ["timing.t0", "quote it"]),
    ("timing.t0", "2458305.6827886", ["timing.t0", "state the time scale"]),
    ("timing.period", "0 s", ["timing.period", "must be positive"]),
    ("timing.period", "-414.79 s", ["timing.period", "must be positive"]),
    ("timing.period", 414.79, ["timing.period", "bare number", "unit"]),
    ("timing.period", "414.79 Hz", ["timing.period", "give a time"]),
    ("timing.pdot", -4e-6, ["timing.pdot", "reach zero", "100 yr"]),
    ("timing.pdot", 1e-5, ["timing.pdot", "before T0"]),
    ("timing.pdot", "1e-11 Hz", ["timing.pdot", "dimensionless"]),
    ("timing.pddot", "-1e-15 1 / s", ["timing.pddot", "reach zero"]),
    ("timing.pddot", "1e-15 s", ["timing.pddot", "1/s"]),
    ("timing.perod", "414 s", ["timing.perod", "did you mean 'period'"]),
    ("timing.covariance", DELETE, ["timing.covariance", "missing"]),
    ("timing.source", DELETE, ["timing.source", "missing"]),
    ("timing.source", "", ["timing.source", "citation"]),
    ("timing.source", "two\nlines", ["timing.source", "one line"]),
    ("timing.t0_marks", DELETE, ["timing.t0_marks", "missing"]),
    ("timing.covariance.sigma", {"t0": 8.4e-6}, ["sigma.t0", "bare number", "unit"]),
    ("timing.covariance.sigma", {"perod": "1 s"}, ["sigma.perod", "did you mean 'period'"]),
    ("timing.covariance.sigma", {"phase": 0.1}, ["sigma.phase", "unknown parameter"]),
    ("timing.covariance.sigma", {"pdot": -1e-14}, ["sigma.pdot", "must be > 0"]),
    ("timing.covariance.correlaton", {}, ["correlaton", "did you mean 'correlation'"]),
    ("timing.eccentricity", {"eta": 0.09, "kappa": 0.09}, ["timing.eccentricity", "small-e"]),
    ("timing.eccentricity", {"e": 0.01}, ["timing.eccentricity.e", "unknown field"]),
    ("timing.inclination", "95 rad", ["timing.inclination", "[0, 180]"]),
    ("timing", "BJD_TDB 1", ["timing", "mapping"]),
    ("magnitudes", {"V": "bright"}, ["magnitudes.V", "magnitude"]),
    ("magnitudes", {"not a band!": 20.0}, ["magnitudes", "band name"]),
    ("magnitudes", {"g": 99.0}, ["magnitudes.g", "[-30, 40]"]),
    ("references", {"timing.perod": "x"}, ["references.timing.perod", "did you mean"]),
    ("references", {"masses.m1": "x"}, ["references.masses.m1", "not a field of this file"]),
    ("references", {"timing": ""}, ["references.timing", "citation"]),
    ("lisa", {"t_ref": "2037-01-01T00:00:00"}, ["lisa/timing", "exactly one"]),
    ("timing", DELETE, ["lisa", "missing", "timing:"]),
]


def load_doc(doc: Any, tmp_path: Path | None = None) -> Target:
    """A target read from a document, as if from ``t.yaml`` (in ``tmp_path`` if given)."""
    return target_from_dict(doc, (tmp_path or Path(".")) / "t.yaml")


def refused(doc: Any) -> str:
    """The one-line error a document is refused with (at most 400 characters, naming t.yaml)."""
    with pytest.raises(TargetFileError) as exc:
        load_doc(doc)
    msg = str(exc.value)
    assert "\n" not in msg and len(msg) < 400, msg
    assert msg.startswith("t.yaml: ")
    return msg


def timing_with(path: str, value: Any) -> dict[str, Any]:
    """The ZTF J1539+5027 timing document with one dotted field set to ``value`` (or deleted)."""
    doc = copy.deepcopy(ztf_j1539_doc())
    *parents, key = path.split(".")
    node = doc
    for p in parents:
        node = node[p]
    if value is DELETE:
        del node[key]
    else:
        node[key] = value
    return doc
