"""Property tests of the whole command line: any option value gives a result or one clear line.

For every command, hypothesis draws option values (numbers of every kind, non-finite and huge
values, unicode, padding, unit strings, paths that are folders or devices) and runs the real entry
point in-process. Whatever the input: the exit code is 0, 2 or 130; no traceback is printed; an
error is one line shorter than 400 characters; a failed run leaves the output folder unchanged.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from support.cli import VALUES, check_outcome, run_cli

ROOT = Path(__file__).resolve().parents[2]
HM = str(ROOT / "catalogs" / "hm-cnc-simulated.yaml")
ECC = str(ROOT / "catalogs" / "fiducial-eccentric.yaml")
VEL = str(ROOT / "catalogs" / "fiducial-eccentric-velocities.csv")


# (command line without the option, option under test); the plan and reduce cases run a real
# plan or reduction per example (~1 s each) and are marked slow (CI runs them with -m slow).
CASES = [
    (["horizon", HM], "--sigma-v"),
    (["horizon", HM], "--k-eff"),
    (["horizon", HM], "--alpha"),
    (["horizon", HM], "--epochs"),
    (["horizon", HM], "--anchor"),
    (["horizon", HM], "--format"),
    (["ephemeris", HM, "--end", "2040-01-01T01:00"], "--start"),
    (["ephemeris", HM, "--start", "2040-01-01T00:00", "--end", "2040-01-01T01:00"], "--anchor"),
    (["ephemeris", HM, "--start", "2040-01-01T00:00", "--end", "2040-01-01T01:00"], "--star"),
    (["validate", HM], "--format"),
    (["plan", HM, "--site", "paranal"], "--night"),
    (["plan", HM, "--night", "2040-02-15"], "--site"),
    (["plan", HM, "--night", "2040-02-15"], "--site-lonlat"),
    (["plan", HM, "--site", "paranal", "--night", "2040-02-15"], "--exptime"),
    (["plan", HM, "--site", "paranal", "--night", "2040-02-15"], "--airmass-max"),
    (["plan", HM, "--site", "paranal", "--night", "2040-02-15"], "--mode"),
    (["plan", HM, "--site", "paranal", "--night", "2040-02-15"], "--nights"),
    (["plan", HM, "--site", "paranal", "--night", "2040-02-15"], "--max-smear"),
    (["plan", HM, "--site", "paranal", "--night", "2040-02-15"], "--priority"),
    (["feasibility", ECC], "--baseline"),
    (["feasibility", ECC], "--m1"),
    (["feasibility", ECC], "--n-spectra"),
    (["reduce", ECC, VEL, "--samples", "500"], "--seed"),
    (["reduce", ECC, VEL], "--samples"),
    (["reduce", ECC, VEL, "--samples", "500"], "--mass-radius"),
    (["reduce", ECC, VEL, "--samples", "500"], "--cos-i-sigma"),
]


SLOW_COMMANDS = ("plan", "reduce")
PARAMS = [
    pytest.param(b, o, id=f"{b[0]}{o}", marks=[pytest.mark.slow] if b[0] in SLOW_COMMANDS else [])
    for b, o in CASES
]


@pytest.mark.parametrize(("base", "option"), PARAMS)
@settings(
    max_examples=10,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(value=VALUES)
def test_any_option_value(tmp_path: Path, base: list[str], option: str, value: str) -> None:
    out_dir = tmp_path / "out"
    out_dir.mkdir(exist_ok=True)
    before = sorted(os.listdir(out_dir))
    target = out_dir / "result.json"
    args = [*base, option, value]
    if base[0] in ("horizon", "ephemeris", "plan", "reduce"):
        args += ["-o", str(target), "--overwrite"]
    code, err = run_cli(args)
    check_outcome(code, err)
    if code != 0:
        assert sorted(os.listdir(out_dir)) == before, "a failed run changed the output folder"
    elif target.exists():
        target.unlink()
