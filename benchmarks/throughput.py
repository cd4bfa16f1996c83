"""Issue 23's throughput rows, each in CPU seconds against the fixed numpy workload.

- population forecast, serial, per source (300 LDC-style sources minus the face-on first one):
  goal ≤ 4 ms per source at the reference machine (``_workload.REFERENCE_S``), i.e. ≤ 0.0136 ×
  the workload; 10⁴ sources then take ≤ 40 s there;
- ``ucbplan horizon`` of many target files with ``--format json``: the cost per target above
  reading and parsing its YAML with libyaml (``yaml.load(text, Loader=yaml.CSafeLoader)``, timed
  in this process), as a user compares it; goal ≤ 50 µs at the reference machine;
- a notebook user's first ``load_target`` in a fresh process, imports included (no goal);
- ``ucbplan reduce`` of 10⁶ spectra (CSV in, JSON out) through the CLI in a fresh process: goal
  ≤ 12 × the workload in CPU seconds, and ≤ 1 GB peak resident memory.

CPU seconds, not wall time: the machine is shared by other sessions, and time slices lost to
them count in neither the path nor the workload (see ``benchmarks/_workload.py``). Wall times
are in the notes. Usage: ``python benchmarks/throughput.py [--quick]`` or
``python -m benchmarks --only throughput``.
"""

from __future__ import annotations

import argparse
import gc
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(ROOT))

from _workload import REFERENCE_S, bracketed, children_cpu_s, compile_package, workload_s  # noqa: E402

from ucbplan.offline import offline  # noqa: E402

GOAL_SOURCE_S = 0.004
GOAL_TARGET_S = 50e-6
GOAL_REDUCE_X, GOAL_REDUCE_MB = 12.0, 1024.0


def _peak_mb() -> float:
    """Peak resident memory of this process so far [MB]."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _at_reference(cpu_s: float, work_s: float) -> float:
    """A CPU time here as the time it takes on the reference machine [s]."""
    return cpu_s / work_s * REFERENCE_S


@offline()  # the offline astropy scope for the whole measurement
def population_row(tmp: Path) -> dict[str, object]:
    """Serial population forecast of 299 sources (the face-on first row left out)."""
    from make_population_catalog import make

    from ucbplan.population.catalog import read_catalog
    from ucbplan.population.catalog_forecast import ForecastOptions, forecast_chunk

    path = tmp / "cat300.ecsv"
    make(300, 13).write(path, format="ascii.ecsv")
    sources = read_catalog(path).sources[1:]
    opts = ForecastOptions(sigma_v_kms=15.0)
    forecast_chunk(opts, sources[:3])  # imports and caches
    cpu, wall, work, rows = bracketed(lambda: forecast_chunk(opts, sources), 2)
    n = len(sources)
    per = _at_reference(cpu / n, work)
    ok = sum(r["status"] == "ok" for r in rows)
    return {
        "name": f"population forecast, serial, per source ({n} LDC-style sources)",
        "value": 1e3 * per,
        "unit": "ms/source at the reference",
        "ratio": work / (cpu / n),
        "peer": f"numpy workload ({work:.3f} CPU s here; ratio = sources per workload)",
        "goal": f"≤ {1e3 * GOAL_SOURCE_S:g} ms (10⁴ sources ≤ 40 s)",
        "met": bool(per <= GOAL_SOURCE_S),
        "peak_mb": _peak_mb(),
        "note": f"{1e3 * cpu / n:.2f} CPU ms/source here ({1e3 * wall / n:.2f} ms wall), "
        f"{ok} ok; 10⁴ sources ≈ {1e4 * per:.0f} s at the reference",
    }


def _target_files(folder: Path, n: int) -> list[Path]:
    """``n`` LISA target files, each its own binary: HM Cnc with the name, ḟ and K_eff varied
    (distinct values, so no horizon, tolerance or JSON text is shared between targets)."""
    text = (ROOT / "catalogs" / "hm-cnc-simulated.yaml").read_text(encoding="utf-8")
    swaps = ("name: HM Cnc (simulated)", 'fdot: "4.662e-19 Hz / s"', 'K_eff: "390 km/s"')
    assert all(s in text for s in swaps), "the HM Cnc example changed: update _target_files"
    folder.mkdir()
    out = []
    for i in range(n):
        p = folder / f"t{i:05d}.yaml"
        own = (f"name: T{i:05d}", f'fdot: "{4.0 + i / n:.6f}e-19 Hz / s"',
               f'K_eff: "{300 + 200 * i / n:.4f} km/s"')  # fmt: skip
        body = text
        for old, new in zip(swaps, own, strict=True):
            body = body.replace(old, new)
        p.write_text(body, "utf-8")
        out.append(p)
    return out


#: Runs ``ucbplan`` as ``python -m ucbplan`` does and prints its own peak resident memory last:
#: VmHWM of its address space, new at exec (ru_maxrss survives exec on Linux, so it would count
#: the forked copy of this benchmark process).
_PEAK = (
    "import runpy, sys\n"
    "sys.argv = ['ucbplan', *sys.argv[1:]]\n"
    "try:\n"
    "    runpy.run_module('ucbplan', run_name='__main__')\n"
    "finally:\n"
    "    hwm = [ln for ln in open('/proc/self/status') if ln.startswith('VmHWM')]\n"
    "    print('PEAK-KB', hwm[0].split()[1], file=sys.stderr)\n"
)


def _cli_cpu(args: list[str]) -> tuple[float, float, float]:
    """(CPU s, wall s, peak resident MB) of ``python -m ucbplan ARGS`` in a fresh process."""
    compile_package()
    c0, w0 = children_cpu_s(), time.perf_counter()
    res = subprocess.run(
        [sys.executable, "-c", _PEAK, *args],
        capture_output=True,
        text=True,
        cwd=ROOT,
        env=os.environ | {"PYTHONPATH": str(ROOT)},
        check=False,
    )
    if res.returncode != 0:
        raise RuntimeError(f"ucbplan {args[0]} failed: {res.stderr.strip()[-300:]}")
    peak = [ln for ln in res.stderr.splitlines() if ln.startswith("PEAK-KB ")]
    return children_cpu_s() - c0, time.perf_counter() - w0, float(peak[-1].split()[1]) / 1024.0


def _horizon_cli(files: list[Path], out: Path) -> tuple[float, float]:
    """(CPU s, wall s) of ``ucbplan horizon FILES… --format json -o OUT`` run in this process,
    from a collected heap: the cyclic collector stays on, but a full collection of the earlier
    runs' garbage (~50 ms here, 25 µs per target) is not charged to one run and not another."""
    from ucbplan.cli.app import app

    gc.collect()
    c0, w0 = time.process_time(), time.perf_counter()
    app(["horizon", *map(str, files), "--format", "json", "-o", str(out)], standalone_mode=False)
    return time.process_time() - c0, time.perf_counter() - w0


def _raw_yaml_cpu(files: list[Path]) -> float:
    """CPU s of reading the files and parsing their YAML with libyaml, nothing else: the peer
    a user compares with (``yaml.load(text, Loader=yaml.CSafeLoader)``)."""
    import yaml

    c0 = time.process_time()
    for path in files:
        yaml.load(path.read_text(encoding="utf-8"), Loader=yaml.CSafeLoader)
    return time.process_time() - c0


@offline()
def horizon_row(tmp: Path, n: int) -> dict[str, object]:
    """CPU per target of ``horizon FILES… --format json`` above parsing the files' YAML."""
    files = _target_files(tmp / "targets", n)
    _horizon_cli(files[:4], tmp / "warm.json")  # imports
    work = workload_s()
    runs = [_horizon_cli(files, tmp / f"h{k}.json") for k in range(2)]
    raw = min(_raw_yaml_cpu(files) for _ in range(2))
    work = min(work, workload_s())
    total, wall = min(runs)
    per = (total - raw) / n
    ref = _at_reference(per, work)
    return {
        "name": f"horizon, {n:,} target files, --format json: per target above its YAML parse",
        "value": 1e6 * ref,
        "unit": "µs/target at the reference",
        "ratio": (raw / n) / per,
        "peer": f"libyaml parse of one target file ({1e6 * raw / n:.0f} CPU µs here)",
        "goal": f"≤ {1e6 * GOAL_TARGET_S:g} µs/target",
        "met": bool(ref <= GOAL_TARGET_S),
        "peak_mb": _peak_mb(),
        "note": f"the CLI command in this process: {total:.2f} CPU s ({wall:.1f} s wall); "
        f"reading and parsing the files with yaml.CSafeLoader alone {raw:.2f} CPU s; "
        f"{1e6 * per:.0f} CPU µs/target here above it; workload {work:.3f} CPU s",
    }


def first_load_s() -> float:
    """Wall s of a notebook user's first ``load_target`` in a fresh process (imports included),
    the median of 5."""
    code = (
        "import time; t = time.perf_counter(); from ucbplan.targets import load_target; "
        "load_target('catalogs/hm-cnc-simulated.yaml'); print(time.perf_counter() - t)"
    )
    compile_package()
    runs = []
    for _ in range(5):
        res = subprocess.run(
            [sys.executable, "-c", code],
            capture_output=True,
            text=True,
            cwd=ROOT,
            env=os.environ | {"PYTHONPATH": str(ROOT)},
            check=True,
        )
        runs.append(float(res.stdout.strip()))
    return sorted(runs)[2]


def first_load_row() -> dict[str, object]:
    """A notebook user's first ``load_target`` (fresh process, imports included)."""
    wall = first_load_s()
    return {
        "name": "first load_target in a fresh process (imports included, median of 5)",
        "value": wall,
        "unit": "s wall",
        "ratio": None,
        "peer": "",
        "goal": "",
        "met": None,
        "peak_mb": _peak_mb(),
        "note": "python -c 'from ucbplan.targets import load_target; load_target(HM Cnc)'",
    }


def _velocity_csv(path: Path, n: int) -> None:
    """``n`` exact-Kepler SB2 spectra of the fiducial eccentric target as a CSV file."""
    import numpy as np
    from reduce_scaling import make_table

    from ucbplan.targets import load_target

    tab = make_table(load_target(ROOT / "catalogs" / "fiducial-eccentric.yaml"), n)
    jd = tab.time.tdb.jd1 + tab.time.tdb.jd2
    cols = np.column_stack([jd, tab.window_s, tab.v[0], tab.sigma[0], tab.v[1], tab.sigma[1]])
    with path.open("w", encoding="utf-8") as fh:
        fh.write("bjd_tdb,exptime_s,v1,sigma_v1,v2,sigma_v2\n")
        fmt = ["%.10f", "%.3f", "%.4f", "%.2f", "%.4f", "%.2f"]
        np.savetxt(fh, cols, fmt=fmt, delimiter=",")


@offline()
def reduce_row(tmp: Path, n: int) -> dict[str, object]:
    """``ucbplan reduce TARGET CSV --format json -o OUT`` in a fresh process: CPU and peak."""
    csv = tmp / "velocities.csv"
    _velocity_csv(csv, n)
    target = str(ROOT / "catalogs" / "fiducial-eccentric.yaml")
    args = ["reduce", target, str(csv), "--format", "json", "--seed", "1"]
    work = workload_s()
    cpu, wall, peak = min(_cli_cpu([*args, "-o", str(tmp / f"r{k}.json")]) for k in range(2))
    work = min(work, workload_s())
    x = cpu / work
    scaled = "" if n == 1_000_000 else "; the goal is judged at 10⁶ spectra (full mode)"
    return {
        "name": f"reduce through the CLI, {n:,} spectra (CSV in, JSON out)",
        "value": x,
        "unit": "× the workload (CPU)",
        "ratio": 1.0 / x,
        "peer": f"numpy workload ({work:.3f} CPU s here)",
        "goal": f"≤ {GOAL_REDUCE_X:g}× the workload (≈ 3.5 s at the reference), "
        f"≤ {GOAL_REDUCE_MB / 1024:g} GB",
        "met": bool(x <= GOAL_REDUCE_X and peak <= GOAL_REDUCE_MB) if n == 1_000_000 else None,
        "peak_mb": peak,
        "note": f"{cpu:.2f} CPU s ({wall:.1f} s wall), ≈ {_at_reference(cpu, work):.1f} s at "
        f"the reference, peak resident memory {peak:.0f} MB (of the CLI process){scaled}",
    }


def rows(quick: bool) -> list[dict[str, object]]:
    """Population per source, horizons per target, reduce of 10⁶ spectra (10⁵ quick)."""
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        return [
            population_row(tmp),
            horizon_row(tmp, 800 if quick else 2000),
            first_load_row(),
            reduce_row(tmp, 100_000 if quick else 1_000_000),
        ]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="smaller runs, for CI")
    ap.add_argument("--only", default="population,horizon,first_load,reduce", help="rows to run")
    ap.add_argument(
        "--markdown", action="store_true", help="the rows as the README's table has them"
    )
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        out = []
        if "population" in args.only:
            out.append(population_row(tmp))
        if "horizon" in args.only:
            out.append(horizon_row(tmp, 800 if args.quick else 2000))
        if "first_load" in args.only:
            out.append(first_load_row())
        if "reduce" in args.only:
            out.append(reduce_row(tmp, 100_000 if args.quick else 1_000_000))
    for r in out:
        print(f"{r['name']}: {r['value']:.4g} {r['unit']}; goal {r['goal']}; met {r['met']}")
        print(f"    {r['note']}")
    if args.markdown:
        print(_table().render([r | {"module": "throughput"} for r in out], True))


def _table() -> Any:
    """``benchmarks/__main__.py`` (its ``render`` writes the README's table), loaded by path."""
    from importlib.util import module_from_spec, spec_from_file_location

    spec = spec_from_file_location("benchmarks_table", Path(__file__).with_name("__main__.py"))
    assert spec is not None and spec.loader is not None
    module = module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


if __name__ == "__main__":
    main()
