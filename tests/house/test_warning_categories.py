"""Each warning is raised with its cause's class, chosen where the line is made (never guessed
from its text), under the public parents a script already filters on."""

from __future__ import annotations

import inspect
import warnings
from pathlib import Path
from typing import Any

import pytest

import ucbplan
from ucbplan import errors

CATALOGS = Path(__file__).resolve().parents[2] / "catalogs"
HM = CATALOGS / "hm-cnc-simulated.yaml"

#: σ_v fixed (exposure not optimised) and a smear above σ_v/2, in 2040 (past the IERS tables).
SMEARED = {"sigma_v_kms": 5.0}


def _caught(call: Any) -> list[warnings.WarningMessage]:
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        call()
    return [w for w in got if issubclass(w.category, ucbplan.UcbplanWarning)]


def test_the_tree_keeps_the_public_parents() -> None:
    assert issubclass(ucbplan.SmearingWarning, ucbplan.PlanWarning)
    assert issubclass(ucbplan.ExposureWarning, ucbplan.PlanWarning)
    assert issubclass(ucbplan.EphemerisRangeWarning, ucbplan.PlanWarning)
    assert issubclass(ucbplan.SamplerConvergenceWarning, ucbplan.ReduceWarning)
    assert issubclass(ucbplan.EarthOrientationWarning, ucbplan.UcbplanWarning)
    assert not issubclass(ucbplan.EarthOrientationWarning, ucbplan.PlanWarning)


def test_no_category_is_guessed_from_the_text() -> None:
    assert not hasattr(errors, "warning_category")
    source = inspect.getsource(errors)
    assert 'IERS", ' not in source and "_EARTH_WORDS" not in source
    # a line that mentions IERS keeps the class it was emitted with
    got = _caught(lambda: errors.emit(["IERS and leap-second words"], ucbplan.ReduceWarning))
    assert [w.category for w in got] == [ucbplan.ReduceWarning]
    kinds = [ucbplan.SmearingWarning, ucbplan.EarthOrientationWarning]
    got = _caught(lambda: errors.emit(["a", "b"], kinds))
    assert [w.category for w in got] == kinds


def test_a_plan_raises_each_warning_with_its_cause() -> None:
    run: list[ucbplan.Plan] = []
    got = _caught(lambda: run.append(ucbplan.plan(HM, "paranal", "2040-02-15", **SMEARED)))
    by_class = {w.category: str(w.message) for w in got}
    assert "fixed per exposure" in by_class[ucbplan.ExposureWarning]
    assert "smears K" in by_class[ucbplan.SmearingWarning]
    earth = [str(w.message) for w in got if w.category is ucbplan.EarthOrientationWarning]
    assert len(earth) == 2 and "IERS-A" in earth[0] and "leap-second" in earth[1]
    assert [str(w.message) for w in got] == run[0].warnings  # the same lines, in order
    assert all(w.filename == __file__ for w in got)  # pointing at the caller's line


def test_epochs_past_the_horizon_are_an_ephemeris_range_warning() -> None:
    got = _caught(lambda: ucbplan.ephemeris(HM, "2060-01-01T00:00", "2060-01-01T00:20"))
    assert [w.category for w in got] == [ucbplan.EphemerisRangeWarning]
    assert "T_valid" in str(got[0].message)


def test_filters_by_class() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        warnings.simplefilter("error", ucbplan.SmearingWarning)
        with pytest.raises(ucbplan.SmearingWarning, match="smears K"):
            ucbplan.plan(HM, "paranal", "2040-02-15", **SMEARED)
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        warnings.simplefilter("ignore", ucbplan.PlanWarning)  # its subclasses too
        ucbplan.plan(HM, "paranal", "2040-02-15", **SMEARED)
    ours = {w.category for w in got if issubclass(w.category, ucbplan.UcbplanWarning)}
    assert ours == {ucbplan.EarthOrientationWarning}


@pytest.mark.slow
def test_a_short_chain_is_a_sampler_convergence_warning() -> None:
    injection = CATALOGS / "fiducial-injection.yaml"
    got = _caught(lambda: ucbplan.simulate(injection, seed=1, steps=20, n_bins=64))
    assert got and {w.category for w in got} == {ucbplan.SamplerConvergenceWarning}
