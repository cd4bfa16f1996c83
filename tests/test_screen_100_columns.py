"""Screen test (issue 15): at 100 columns no command's default table is cut.

Rich marks a cell it had to cut with "…"; each command runs in a fresh process with
``COLUMNS=100`` (the terminal width rich reads), as a user's terminal would run it.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

CAT = Path(__file__).resolve().parents[1] / "catalogs"
HM, ECC = str(CAT / "hm-cnc-simulated.yaml"), str(CAT / "fiducial-eccentric.yaml")
SYN = str(CAT / "examples" / "synthetic-eclipsing.yaml")

COMMANDS = [
    ["validate", HM],
    ["horizon", HM],
    ["ephemeris", HM, "--start", "2040-02-16T03:00", "--end", "2040-02-16T03:10"],
    ["ephemeris", SYN, "--start", "2026-11-24", "--end", "2026-11-24T01:00", "--anchor", "eclipse"],
    ["feasibility", ECC],
    ["reduce", ECC, str(CAT / "fiducial-eccentric-velocities.csv"), "--samples", "2000"],
    ["plan", HM, "--site", "paranal", "--night", "2040-02-15"],
    [
        "plan",
        HM,
        ECC,
        "--site",
        "paranal",
        "--night",
        "2040-02-15",
        "--visit",
        "1h",
        "--sigma-v",
        "5",
        "--nights",
        "5",
    ],
]


@pytest.mark.parametrize("args", COMMANDS, ids=lambda a: " ".join(Path(x).name for x in a)[:60])
def test_default_output_fits_100_columns(args: list[str], tmp_path: Path) -> None:
    env = {**os.environ, "COLUMNS": "100", "LINES": "50"}
    cmd = [sys.executable, "-m", "ucbplan", *args]
    out = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=tmp_path, timeout=120)
    assert out.returncode == 0, out.stderr[-800:]
    cut = [line for line in out.stderr.splitlines() if "…" in line and "│" in line]
    assert not cut, "\n".join(cut[:5])
