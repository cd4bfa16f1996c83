"""CLI start-up: `ucbplan --help` and a one-night plan, as ratios to `python -c "import numpy"`.

Each command runs as a fresh process (median wall time of several runs, interleaved so that load
on a shared machine hits all of them alike; the notes add the least CPU time, user + system, the
number to compare on a shared machine). Goals (issue 14): --help ≤ 0.3 s and a one-night plan
≤ 1.5 s. The second part lists the heaviest imports behind each (``python -X importtime``), the
ones to make lazy.

Usage: ``python benchmarks/startup.py [--quick]`` (also lists the imports) or
``python -m benchmarks --only startup``.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _workload import compile_package

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
BASE = "python -c 'import numpy'"
GOALS = {"ucbplan --help": 0.3, "ucbplan plan (1 night)": 1.5}


def _wall(cmd: list[str]) -> tuple[float, float, float]:
    """(wall time [s], peak resident memory [MB], CPU time [s]) of one fresh process."""
    compile_package()
    t0 = time.perf_counter()
    proc = subprocess.Popen(
        cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, cwd=ROOT, env=os.environ.copy()
    )
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t0
    proc.returncode = os.waitstatus_to_exitcode(status)
    if proc.returncode:
        raise subprocess.CalledProcessError(proc.returncode, cmd)
    return wall, usage.ru_maxrss / 1024.0, usage.ru_utime + usage.ru_stime  # Linux: KiB


def measure_wall(repeats: int) -> dict[str, tuple[float, float, float]]:
    """(median wall [s], peak RSS [MB], least CPU [s]) per command, interleaved runs after one
    warm-up each. CPU seconds (user + system) are the comparable number on a shared machine."""
    for cmd in COMMANDS.values():  # warm the file cache and the parsed IERS cache
        _wall(cmd)
    runs: dict[str, list[tuple[float, float, float]]] = {k: [] for k in COMMANDS}
    for _ in range(repeats):
        for name, cmd in COMMANDS.items():
            runs[name].append(_wall(cmd))
    return {
        name: (
            statistics.median(w for w, _, _ in r),
            max(m for _, m, _ in r),
            min(c for _, _, c in r),
        )
        for name, r in runs.items()
    }


def rows(quick: bool) -> list[dict[str, object]]:
    """Median wall time of --help and of a one-night plan, with their ratio to numpy's import."""
    repeats = 3 if quick else 9
    res = measure_wall(repeats)
    med = {k: w for k, (w, _, _) in res.items()}
    base = med[BASE]
    return [
        {
            "name": f"{name} (fresh process, median of {repeats})",
            "value": med[name],
            "unit": "s wall",
            "ratio": base / med[name],
            "peer": f"{BASE} ({base:.3f} s)",
            "goal": f"≤ {GOALS[name]:g} s",
            "met": bool(med[name] <= GOALS[name]),
            "note": f"{med[name] / base:.1f}× the time of {BASE}; least CPU {res[name][2]:.3f} s "
            f"(numpy's import: {res[BASE][2]:.3f} s)",
            "peak_mb": res[name][1],
        }
        for name in GOALS
    ]


def heaviest_imports(name: str, top: int) -> None:
    """Cumulative import time of top-level packages and ucbplan modules behind ``name``."""
    res = subprocess.run(
        [PY, "-X", "importtime", *COMMANDS[name][1:]],
        capture_output=True,
        text=True,
        cwd=ROOT,
        check=True,
    )
    rows = []
    for line in res.stderr.splitlines():
        if not line.startswith("import time:") or "|" not in line:
            continue
        _, cum, module = (x.strip() for x in line[len("import time:") :].split("|"))
        if not cum.isdigit():
            continue
        if module.startswith("ucbplan.") or "." not in module:
            rows.append((int(cum), module))
    print(f"heaviest imports behind {name} (cumulative, us; {top} shown):")
    for cum, module in sorted(rows, reverse=True)[:top]:
        print(f"  {cum / 1e3:8.1f} ms  {module}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="3 runs each, for CI")
    args = ap.parse_args()
    for r in rows(args.quick):
        print(f"{r['name']:45s} {r['value']:6.3f} s  ({r['note']}; goal {r['goal']})")
    for name in GOALS:
        heaviest_imports(name, 12)
    print("(machine may be shared: compare the ratios)")


if __name__ == "__main__":
    main()
