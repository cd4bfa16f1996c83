"""Every benchmark takes part in the one table (issue 14): ``python -m benchmarks`` finds a
``rows(quick)`` function in each benchmark module and none is left unadapted."""

from __future__ import annotations

import importlib.util
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
