"""Start-up (issue 34): each command imports only what it needs.

Checked structurally, never timed: a fresh interpreter runs one command through the CLI's entry
point and reports which of the heavy modules ended up in ``sys.modules``. A plan without observed
spectra has no use for the night tools (chart, countdown, observing log) or matplotlib, nor for
scipy (its cubic splines are ucbplan's own); horizons and reduce have no use for the planner's
sky model either.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
HM = str(ROOT / "catalogs" / "hm-cnc-simulated.yaml")
ECC = str(ROOT / "catalogs" / "fiducial-eccentric.yaml")
VEL = str(ROOT / "catalogs" / "fiducial-eccentric-velocities.csv")

NIGHT_TOOLS = (
    "ucbplan.observing.night.chart",
    "ucbplan.observing.night.countdown",
    "ucbplan.observing.night.observing_log",
    "ucbplan.plotting",
    "matplotlib",
)
SKY_MODEL = ("ucbplan.observing.observatory.sky",)

#: Runs ``ucbplan ARGS`` as the console script does, then prints the loaded modules it is asked
#: about (argv[1]: a JSON list of names; the rest: the command line).
_PROBE = """
import json, sys
from ucbplan.cli import main
names = json.loads(sys.argv[1])
sys.argv = ["ucbplan", *sys.argv[2:]]
try:
    main()
except SystemExit as exc:
    code = exc.code
print("LOADED", json.dumps([n for n in names if n in sys.modules]), code)
"""


def _loaded(names: tuple[str, ...], *args: str) -> list[str]:
    """Which of ``names`` a fresh ``ucbplan ARGS`` process imported (the command must succeed)."""
    done = subprocess.run(
        [sys.executable, "-c", _PROBE, json.dumps(names), *args],
        capture_output=True,
        text=True,
        cwd=ROOT,
        check=False,
    )
    line = [ln for ln in done.stdout.splitlines() if ln.startswith("LOADED ")]
    assert line, done.stderr[-500:]
    loaded, code = line[-1].removeprefix("LOADED ").rsplit(" ", 1)
    assert code in ("0", "None"), done.stderr[-500:]
    return list(json.loads(loaded))


def test_a_plan_does_not_import_the_night_tools(tmp_path: Path) -> None:
    out = str(tmp_path / "p.ecsv")
    args = ("plan", HM, "--site", "paranal", "--night", "2040-02-15", "-o", out)
    # the sky model is listed as a control: the probe sees what the plan does import
    assert _loaded(NIGHT_TOOLS + SKY_MODEL, *args) == list(SKY_MODEL)


def test_a_plan_does_not_import_scipy(tmp_path: Path) -> None:
    """``scipy.interpolate`` alone cost ~0.3 CPU s of every plan's start-up."""
    out = str(tmp_path / "p.ecsv")
    args = ("plan", HM, "--site", "paranal", "--night", "2040-02-15", "-o", out)
    assert _loaded(("scipy", *SKY_MODEL), *args) == list(SKY_MODEL)


def test_horizon_does_not_import_the_planner(tmp_path: Path) -> None:
    args = ("horizon", HM, "--format", "json", "-o", str(tmp_path / "h.json"))
    assert _loaded((*NIGHT_TOOLS, *SKY_MODEL, "astropy.units"), *args) == ["astropy.units"]


def test_reduce_does_not_import_the_planner(tmp_path: Path) -> None:
    args = ("reduce", ECC, VEL, "--seed", "1", "--format", "json", "-o", str(tmp_path / "r.json"))
    assert _loaded((*NIGHT_TOOLS, *SKY_MODEL, "astropy.units"), *args) == ["astropy.units"]
