"""ERFA's "dubious year" warnings are silenced once, at the edges (issue 25).

Every conversion of a date past the bundled leap-second table makes ERFA warn "dubious year";
ucbplan reports the tables' coverage itself, once per run. The filter lives in the offline scope
(:func:`ucbplan.offline.offline`), which the public API, the command line and each population
task enter; no inner function handles the warning (tests/house/test_architecture.py checks that).
Here: the filter works at each edge, is scoped (the caller's filters come back), and without
it the same conversion does warn (so the tests below can fail).
"""

from __future__ import annotations

import os
import subprocess
import sys
import warnings
from pathlib import Path

import pytest
from astropy.time import Time
from astropy.utils.exceptions import AstropyWarning
from erfa import ErfaWarning

import ucbplan
from ucbplan.offline import offline

ROOT = Path(__file__).resolve().parents[2]
HM = ROOT / "catalogs" / "hm-cnc-simulated.yaml"


def _future_utc() -> Time:
    return Time("2045-01-01T00:00:00", scale="tdb").utc  # past the leap-second table: dubious


def test_the_conversion_warns_outside_the_scope() -> None:
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        _future_utc()
    assert any(issubclass(w.category, ErfaWarning) for w in seen)


def test_the_offline_scope_silences_it_and_restores_the_filters() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error", ErfaWarning)
        before = list(warnings.filters)
        with offline():
            _future_utc()
        assert warnings.filters == before
        with pytest.raises(ErfaWarning):
            _future_utc()


def test_the_api_raises_no_erfa_or_astropy_warning() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error", ErfaWarning)
        warnings.simplefilter("error", AstropyWarning)
        warnings.simplefilter("ignore", ucbplan.UcbplanWarning)  # the plan's own coverage note
        plan = ucbplan.plan(str(HM), "paranal", "2040-02-15")
        rows = len(plan.table)
    assert rows > 0


def test_the_cli_raises_no_erfa_warning(tmp_path: Path) -> None:
    env = {**os.environ, "PYTHONPATH": str(ROOT), "COLUMNS": "100"}
    args = ["plan", str(HM), "--site", "paranal", "--night", "2040-02-15"]
    out = subprocess.run(
        [sys.executable, "-W", "error::erfa.ErfaWarning", "-m", "ucbplan", *args],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        env=env,
        timeout=300,
    )
    assert out.returncode == 0, out.stderr[-800:]
    assert "ErfaWarning" not in out.stderr and "dubious year" not in out.stderr
