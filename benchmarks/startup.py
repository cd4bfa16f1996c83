"""CLI start-up: `ucbplan --help` and a one-night plan, as ratios to `python -c "import numpy"`.

Each command runs as a fresh process (median wall time of several runs, interleaved so that load
on a shared machine hits all of them alike). Goals (issue 14): --help ≤ 0.3 s and a one-night
plan ≤ 1.5 s. The second part lists the heaviest imports behind --help (``python -X importtime``),
the ones to make lazy.

Usage: python benchmarks/startup.py [--quick]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PY = sys.executable
COMMANDS = {
    "python -c 'import numpy'": [PY, "-c", "import numpy"],
    "ucbplan --help": [PY, "-m", "ucbplan", "--help"],
    "ucbplan plan (1 night)": [
        PY,
        "-m",
        "ucbplan",
        "plan",
        str(ROOT / "catalogs" / "hm-cnc-simulated.yaml"),
        "--site",
        "paranal",
        "--night",
        "2040-02-15",
    ],
}
GOALS = {"ucbplan --help": 0.3, "ucbplan plan (1 night)": 1.5}


def _wall(cmd: list[str]) -> float:
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, capture_output=True, cwd=ROOT, env=os.environ.copy())
    return time.perf_counter() - t0


def bench_wall(repeats: int) -> None:
    for cmd in COMMANDS.values():  # warm the file cache and the parsed IERS cache
        _wall(cmd)
    times: dict[str, list[float]] = {k: [] for k in COMMANDS}
    for _ in range(repeats):
        for name, cmd in COMMANDS.items():
            times[name].append(_wall(cmd))
    base = statistics.median(times["python -c 'import numpy'"])
    for name, ts in times.items():
        med = statistics.median(ts)
        goal = f"  (goal <= {GOALS[name]:.1f} s)" if name in GOALS else ""
        print(f"{name:28s} {med:6.3f} s median of {repeats}  = {med / base:5.1f}x numpy{goal}")


def heaviest_imports(top: int) -> None:
    """Cumulative import time of top-level packages and ucbplan modules behind --help."""
    res = subprocess.run(
        [PY, "-X", "importtime", "-m", "ucbplan", "--help"],
        capture_output=True,
        text=True,
        cwd=ROOT,
        check=True,
    )
    rows = []
    for line in res.stderr.splitlines():
        if not line.startswith("import time:") or "|" not in line:
            continue
        _, cum, name = (x.strip() for x in line[len("import time:") :].split("|"))
        if not cum.isdigit():
            continue
        if name.startswith("ucbplan.") or "." not in name:
            rows.append((int(cum), name))
    print(f"heaviest imports behind --help (cumulative, us; {top} shown):")
    for cum, name in sorted(rows, reverse=True)[:top]:
        print(f"  {cum / 1e3:8.1f} ms  {name}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="3 runs each, for CI")
    args = ap.parse_args()
    bench_wall(3 if args.quick else 9)
    heaviest_imports(12)
    print("(machine may be shared: compare the ratios)")


if __name__ == "__main__":
    main()
