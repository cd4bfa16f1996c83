"""One table of every benchmark: ``python -m benchmarks [--quick] [--markdown] [--only NAMES]``.

Protocol: a module ``benchmarks/NAME.py`` takes part when it defines ::

    def rows(quick: bool) -> list[dict[str, object]]:
        '''One dict per measured quantity (keys below); quick: a CI-sized run (< ~1 min).'''

with keys ``name`` (str, required), ``value`` (float, required), ``unit`` (str), ``peer`` (what
the ratio compares against, str), ``ratio`` (ours relative to the peer measured side by side in
the same run, > 1 = ours faster/better, float), ``goal`` (str, e.g. "≥ 3× today"), ``met``
(bool: the goal is met), ``note`` (str: conditions, or why a goal cannot be met) and
``peak_mb`` (float; default: the module's peak resident memory). No import from this file is
needed. Each module runs in its own interpreter (a fresh process: its peak memory is its own
and one failure does not stop the others); its rows come back as JSON on the last stdout line.
Modules without ``rows`` are listed as not adapted.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import signal
import subprocess
import sys
import time
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
#: Prefix of the child's result line on stdout.
MARK = "BENCHMARK-ROWS "
#: Columns of the table: (header, row key).
COLUMNS = (
    ("benchmark", "name"),
    ("value", "value"),
    ("unit", "unit"),
    ("ratio", "ratio"),
    ("peer (ratio against)", "peer"),
    ("goal", "goal"),
    ("met", "met"),
    ("peak MB", "peak_mb"),
    ("module", "module"),
)


def discover(only: list[str] | None = None) -> tuple[list[str], list[str]]:
    """(modules defining ``rows``, modules without it), by name, sorted."""
    found, other = [], []
    for path in sorted(HERE.glob("*.py")):
        name = path.stem
        if name.startswith("_") or (only and not any(o in name for o in only)):
            continue
        if "\ndef rows(" in path.read_text(encoding="utf-8"):
            found.append(name)
        elif name.startswith("bench_"):  # a benchmark script not (yet) adapted
            other.append(name)
    return found, other


def run_one(name: str, quick: bool) -> None:
    """Child side: import ``benchmarks.NAME``, call ``rows(quick)``, print them as JSON."""
    import importlib

    mod = importlib.import_module(f"benchmarks.{name}")
    out = mod.rows(quick)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # Linux: KiB
    for r in out:
        r.setdefault("peak_mb", peak)
        r["module"] = name
    sys.stdout.flush()
    print(MARK + json.dumps(out, default=float), flush=True)


def collect(name: str, quick: bool, timeout: float) -> list[dict[str, Any]]:
    """Parent side: run one module in a fresh interpreter and return its rows."""
    cmd = [sys.executable, "-m", "benchmarks", "--one", name] + (["--quick"] if quick else [])
    t0 = time.perf_counter()
    try:
        res = subprocess.run(
            cmd, capture_output=True, text=True, timeout=timeout, check=False, cwd=HERE.parent
        )
    except subprocess.TimeoutExpired:
        return [{"name": f"{name}: timed out after {timeout:.0f} s", "module": name}]
    lines = [ln for ln in res.stdout.splitlines() if ln.startswith(MARK)]
    if res.returncode != 0 or not lines:
        err = (res.stderr.strip().splitlines() or ["no output"])[-1]
        if res.returncode < 0:  # killed by a signal, e.g. SIGILL: a wheel built for another CPU
            err = f"killed by {signal.Signals(-res.returncode).name}; {err}"
        return [{"name": f"{name}: FAILED ({err[:120]})", "module": name}]
    rows: list[dict[str, Any]] = json.loads(lines[-1][len(MARK) :])
    print(f"  {name}: {len(rows)} rows in {time.perf_counter() - t0:.0f} s", file=sys.stderr)
    return rows


def _fmt(key: str, value: Any) -> str:
    if value is None:
        return ""
    if key == "met":
        return "yes" if value else "NO"
    if key == "ratio":
        return f"{value:.3g}×"
    if key == "peak_mb":
        return f"{value:.0f}"
    if isinstance(value, float):
        return f"{value:.4g}"
    return str(value)


def machine() -> str:
    """CPU model, core count, Python and numpy versions (no host name)."""
    model = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    import numpy

    return (
        f"{model}, {os.cpu_count()} cores, {platform.system()}, Python "
        f"{platform.python_version()}, numpy {numpy.__version__}"
    )


def render(rows: list[dict[str, Any]], markdown: bool) -> str:
    """The table as aligned text or as Markdown."""
    cells = [[_fmt(k, r.get(k)) for _, k in COLUMNS] for r in rows]
    heads = [h for h, _ in COLUMNS]
    if markdown:
        out = ["| " + " | ".join(heads) + " |", "|" + "---|" * len(heads)]
        out += ["| " + " | ".join(c) + " |" for c in cells]
    else:
        width = [max(len(x) for x in col) for col in zip(heads, *cells, strict=False)]
        out = ["  ".join(h.ljust(w) for h, w in zip(heads, width, strict=True))]
        out += ["  ".join(x.ljust(w) for x, w in zip(c, width, strict=True)) for c in cells]
    notes = [f"- {r['name']}: {r['note']}" for r in rows if r.get("note")]
    return "\n".join(out + (["", *notes] if notes else []))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks", description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="CI-sized runs")
    ap.add_argument("--markdown", action="store_true", help="a Markdown table (for the README)")
    ap.add_argument("--only", default=None, help="comma-separated parts of module names")
    ap.add_argument("--timeout", type=float, default=1800.0, help="per module [s]")
    ap.add_argument("--one", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.one:
        run_one(args.one, args.quick)
        return 0
    found, other = discover(args.only.split(",") if args.only else None)
    stamp = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
    print(f"running {len(found)} benchmark modules ({stamp})", file=sys.stderr, flush=True)
    rows = [r for name in found for r in collect(name, args.quick, args.timeout)]
    rows += [{"name": f"{n} (no rows(); not in the table)", "module": n} for n in other]
    mode = "quick" if args.quick else "full"
    print(f"Benchmarks ({mode} mode), {stamp}, on {machine()}")
    print("Ratios are measured side by side in one process; peak MB is per module.\n")
    print(render(rows, args.markdown))
    return 1 if any("FAILED" in r["name"] or "timed out" in r["name"] for r in rows) else 0


if __name__ == "__main__":
    sys.exit(main())
