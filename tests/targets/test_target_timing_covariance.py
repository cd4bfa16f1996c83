"""The timing covariance rule (issue 33, "Wrong acceptances"): every timing parameter the
ephemeris uses has a σ or is declared exact.

A timing target that gave only σ(T0) loaded silently, P and Ṗ then exact, and its horizon read
300 yr; and the message for a missing covariance offered ZTF J1539+5027's published σ's, which
users copied as defaults. Now T0 and P always, and Ṗ, P̈, η, κ, ω̇ when not zero, need a σ in
``sigma`` (or a row of the matrix) or a place in ``exact: [...]``; example values in messages
are placeholders.
"""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import pytest

from ucbplan.errors import TargetFileError
from ucbplan.targets import Target, load_target, target_from_dict, write_target

#: A synthetic timing target (round numbers, not a real system).
DOC: dict[str, Any] = {
    "name": "Synthetic (test)",
    "sky": {"ra": "08h00m00s", "dec": "-20d00m00s"},
    "timing": {
        "t0": "BJD_TDB 2461000.5000000",
        "t0_marks": "primary_eclipse",
        "period": "400.0 s",
        "pdot": -2.0e-11,
        "covariance": {"sigma": {"t0": "1.0 s", "period": "5e-6 s", "pdot": 1.0e-13}},
        "source": "synthetic test input",
    },
}


def _with_covariance(cov: Any, **timing: Any) -> dict[str, Any]:
    doc = copy.deepcopy(DOC)
    doc["timing"]["covariance"] = cov
    doc["timing"].update(timing)
    return doc


def _load(doc: dict[str, Any]) -> Target:
    return target_from_dict(doc, Path("t.yaml"))


def _refused(doc: dict[str, Any]) -> str:
    with pytest.raises(TargetFileError) as exc:
        _load(doc)
    msg = str(exc.value)
    assert "\n" not in msg and len(msg) < 400 and msg.startswith("t.yaml: "), msg
    return msg


def test_only_the_sigma_of_t0_is_refused_naming_the_unknown_sigmas() -> None:
    msg = _refused(_with_covariance({"sigma": {"t0": "1.0 s"}}))
    assert msg.startswith("t.yaml: timing.covariance: no σ for period, pdot;"), msg
    assert "exact: [period, pdot]" in msg, msg


def test_a_matrix_without_the_period_is_refused() -> None:
    cov = {"parameters": ["t0", "pdot"], "matrix": [[1.0, 0.0], [0.0, 1e-26]]}
    assert "no σ for period;" in _refused(_with_covariance(cov))


def test_parameters_declared_exact_are_accepted_and_have_no_uncertainty() -> None:
    t = _load(_with_covariance({"sigma": {"t0": "1.0 s"}, "exact": ["period", "pdot"]}))
    assert t.timing is not None
    assert t.timing.sigma("t0") == 1.0
    assert t.timing.sigma("period") is None and t.timing.sigma("pdot") is None


def test_everything_exact_is_an_explicit_choice() -> None:
    t = _load(_with_covariance({"exact": ["t0", "period", "pdot"]}))
    assert t.cov_names == () and t.covariance_source.startswith("none")


def test_a_zero_pdot_needs_no_sigma_but_a_given_eccentricity_does() -> None:
    assert isinstance(
        _load(_with_covariance({"sigma": {"t0": "1 s", "period": "1e-6 s"}}, pdot=0)), Target
    )
    ecc = {"eta": 0.01, "kappa": 0.0, "omega_dot": "1e-6 rad / s"}
    doc = _with_covariance({"sigma": {"t0": "1 s", "period": "1e-6 s", "pdot": 1e-13}})
    doc["timing"]["eccentricity"] = ecc
    assert "no σ for eta, omega_dot;" in _refused(doc)


@pytest.mark.parametrize(
    ("exact", "expected"),
    [
        ("period", "timing.covariance.exact: expected a list of timing parameters like [pdot]"),
        (["periods"], "unknown parameter 'periods'; did you mean 'period'?"),
        (["pdot", "pdot"], "parameter names repeat"),
        (["t0", "period", "pdot"], "t0 has a σ in the covariance and is listed as exact"),
    ],
)
def test_a_bad_exact_list_is_one_line(exact: Any, expected: str) -> None:
    msg = _refused(_with_covariance({"sigma": {"t0": "1.0 s"}, "exact": exact}))
    assert expected in msg, msg


def test_a_lisa_covariance_has_no_exact_list() -> None:
    doc = {
        "name": "L",
        "sky": {"ra": 120.0, "dec": 15.0},
        "lisa": {
            "t_ref": "2037-01-01T00:00:00",
            "t_obs": "126232599.05 s",
            "phase": 1.0,
            "f_gw": "6.2e-3 Hz",
            "fdot": "7e-16 Hz / s",
            "covariance": {"sigma": {"phase": 0.02}, "exact": ["f_gw"]},
        },
    }
    assert "lisa.covariance.exact: unknown field" in _refused(doc)


def test_messages_show_placeholders_not_a_real_systems_sigmas() -> None:
    doc = copy.deepcopy(DOC)
    del doc["timing"]["covariance"]
    msg = _refused(doc)
    assert msg.startswith("t.yaml: timing.covariance: missing; add covariance: "), msg
    assert "8.4e-6" not in msg and "2.9e-6" not in msg and "5.0e-14" not in msg, msg
    assert "<σ(T0)>" in msg, msg
    missing = _refused(_with_covariance({"sigma": {"t0": "1.0 s"}}))
    assert "8.4e-6" not in missing and "<σ(P)>" in missing, missing


def test_a_target_with_exact_parameters_is_written_and_read_back(tmp_path: Path) -> None:
    t = _load(_with_covariance({"sigma": {"t0": "1.0 s"}, "exact": ["period", "pdot"]}))
    path = tmp_path / "w.yaml"
    write_target(t, path)
    back = load_target(path)
    assert back.timing is not None and back.timing.cov_names == ("t0",)
    assert back.params == t.params
