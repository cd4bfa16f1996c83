"""Dump the blocks tables (ECSV, CSV, JSON) of a fixed set of plans, to diff two versions.

Usage: ``python benchmarks/plan_outputs_dump.py OUT_DIR`` (run it before and after a change,
then ``diff -r BEFORE AFTER``). The ``created_utc`` stamp is blanked so that equal plans give
byte-identical files. The plans cover the modes the planner writes: every epoch at u = 0
(the exposure-dense benchmark case), quadrature pairs of several targets, visits with a
goal, untargeted exposures, fixed-u pairs, a timing-ephemeris target, and the semester of the
speed benchmarks (10 targets × 183 nights).
"""

from __future__ import annotations

import re
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
HM, FID = "hm-cnc-simulated", "fiducial-eccentric"
PARANAL = ["--site", "paranal"]

#: name -> (targets: a bundled catalog or "UCBnn" of benchmarks.bench_plan.make_targets, options)
PLANS: dict[str, tuple[list[str], list[str]]] = {
    "dense_u0": (["UCB03"], ["--night", "2040-01-01", "--nights", "4", "--mode", "u=0",
                             "--sessions", "1000", "--overhead", "0"]),
    "quadrature3": (["UCB00", "UCB04", "UCB07"], ["--night", "2040-01-01", "--nights", "6"]),
    "visits_goal": ([HM], ["--night", "2040-02-15", "--nights", "3", "--instrument",
                           "xshooter-vis", "--sigma-v", "5", "--visit", "1h"]),
    "goal": ([HM], ["--night", "2040-02-15", "--nights", "4", "--sigma-v", "30km/s@300s",
                    "--readout", "45", "--overhead", "480", "--goal", "sigma_K=5km/s"]),
    "untargeted": ([HM], ["--night", "2040-02-15", "--sigma-v", "30km/s@300s", "--readout",
                          "45", "--visit", "1h", "--cadence", "untargeted"]),
    "pairs": ([FID], ["--night", "2040-02-15", "--nights", "5", "--mode", "fixed-u-pairs",
                     "--exptime", "20", "--overhead", "0"]),
    "timing": ([FID], ["--night", "2040-02-15", "--nights", "2", "--mode", "conjunction"]),
    "semester": ([f"UCB{i:02d}" for i in range(10)], ["--night", "2040-01-01", "--nights", "183"]),
}  # fmt: skip


def targets(tmp: Path) -> dict[str, str]:
    """The benchmark's synthetic targets written as YAML files, by name."""
    sys.path.insert(0, str(REPO / "benchmarks"))
    from bench_plan import make_targets

    from ucbplan.targets.write import write_target

    out = {}
    for name in (HM, FID):  # copied: every dump names the same files
        path = tmp / f"{name}.yaml"
        path.write_bytes((REPO / "catalogs" / f"{name}.yaml").read_bytes())
        out[name] = str(path)
    for t in make_targets(10):
        path = tmp / f"{t.name}.yaml"
        write_target(t, path, overwrite=True)
        out[t.name] = str(path)
    return out


def dump(out: Path, name: str, paths: list[str], opts: list[str], fmt: str) -> None:
    """One plan written as ``out/NAME.FMT`` (stamp blanked) and its terminal output."""
    dest = out / f"{name}.{fmt}"
    cmd = [sys.executable, "-m", "ucbplan", "plan", *paths, *PARANAL, *opts]
    cmd += ["-o", str(dest), "--overwrite"]
    res = subprocess.run(cmd, capture_output=True, text=True, cwd=REPO, check=False)
    log = f"exit {res.returncode}\n{res.stderr}".replace(str(out), "OUT")
    (out / f"{name}.{fmt}.log").write_text(log, encoding="utf-8")
    if dest.exists():
        text = dest.read_text(encoding="utf-8")
        text = re.sub(r"(created_utc[\"']?: [\"']?)[0-9T:+-]+", r"\g<1>X", text)
        dest.write_text(text, encoding="utf-8")


def main() -> int:
    out = Path(sys.argv[1])
    out.mkdir(parents=True, exist_ok=True)
    fixed = Path(tempfile.gettempdir()) / "ucbplan-plan-dump"  # the same paths in every dump
    fixed.mkdir(exist_ok=True)
    files = targets(fixed)
    for name, (tgts, opts) in PLANS.items():
        for fmt in ("ecsv", "csv", "json"):
            dump(out, name, [files[t] for t in tgts], opts, fmt)
        print(name, file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
