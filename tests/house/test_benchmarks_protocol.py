"""Every benchmark takes part in the one table (issue 14): ``python -m benchmarks`` finds a
``rows(quick)`` function in each benchmark module and none is left unadapted."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

BENCH = Path(__file__).resolve().parents[2] / "benchmarks"


def test_every_benchmark_module_is_in_the_table() -> None:
    spec = importlib.util.spec_from_file_location("bench_main", BENCH / "__main__.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    found, unadapted = module.discover()
    assert not unadapted, unadapted
    for name in ("bench_core", "bench_plan", "horizon", "startup", "waveform", "posterior"):
        assert name in found


def test_every_benchmark_module_imports() -> None:
    """Each benchmark module imports as ``python -m benchmarks`` imports it (``benchmarks.NAME``).

    A helper renamed in the package or in ``tests/support`` breaks a benchmark only when it runs;
    this catches it in the default suite instead of in CI's quick benchmarks. One subprocess, so
    the modules' ``sys.path`` edits and imports stay out of the test process.
    """
    names = sorted(p.stem for p in BENCH.glob("*.py") if p.stem != "__main__")
    code = (
        "import importlib, sys, warnings\n"
        "warnings.simplefilter('ignore')\n"
        "bad = []\n"
        f"for name in {names!r}:\n"
        "    try:\n"
        "        importlib.import_module('benchmarks.' + name)\n"
        "    except Exception as exc:\n"
        "        bad.append(f'{name}: {type(exc).__name__}: {exc}')\n"
        "print('\\n'.join(bad))\n"
        "sys.exit(1 if bad else 0)\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], cwd=BENCH.parent, capture_output=True, text=True, check=False
    )
    assert done.returncode == 0, done.stdout + done.stderr
