"""Regression tests of issue 22: the new surfaces (timing, population, plan options, exports,
several targets per horizon) refuse bad input with one line and exit 2, write nothing on failure
and never crash on values JSON cannot spell."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from ucbplan.cli.app import app
from ucbplan.io import dumps_json, json_plain

runner = CliRunner()
ROOT = Path(__file__).resolve().parents[1]
CAT = ROOT / "catalogs"
HM = CAT / "hm-cnc-simulated.yaml"
INJ = CAT / "fiducial-injection.yaml"


def _strict_json(text: str) -> object:
    """Parse JSON as a strict reader does: the bare tokens NaN/Infinity are errors."""

    def _refuse(token: str) -> None:
        raise AssertionError(f"non-standard JSON token {token}")

    return json.loads(text, parse_constant=_refuse)


def _one_error_line(output: str) -> str:
    lines = [ln for ln in output.splitlines() if ln.strip()]
    assert len(lines) == 1, output
    return lines[0]


def test_json_plain_spells_non_finite_as_null() -> None:
    doc = {"a": float("nan"), "b": [np.float64("inf"), np.int64(3)], 4: (np.nan, "x")}
    assert json_plain(doc) == {"a": None, "b": [None, 3], "4": [None, "x"]}
    assert _strict_json(dumps_json(doc)) == {"a": None, "b": [None, 3], "4": [None, "x"]}


def test_horizon_of_two_lisa_targets_is_valid_json(tmp_path: Path) -> None:
    res = runner.invoke(app, ["horizon", str(INJ), str(HM), "--format", "json"])
    assert res.exit_code == 0, res.output
    doc = _strict_json(res.stdout)
    text = json.dumps(doc)
    assert "null" in text  # the LISA targets' "before" horizons are NaN in the table
    out = tmp_path / "h.json"
    res = runner.invoke(app, ["horizon", str(INJ), str(HM), "-o", str(out)])
    assert res.exit_code == 0, res.output
    assert _strict_json(out.read_text()) == doc
