"""Population forecast scaling: serial vs 2-process pool vs 2-worker Dask LocalCluster, one run.

Issue 13's goals, measured side by side in one process (ratios, not absolute times, matter on a
shared machine):

- 2-process pool wall time ≤ 1.3 × serial / 2;
- Dask LocalCluster (2 workers × 1 thread, default chunk) ≤ 1.2 × the pool;
- peak memory (max RSS) per worker bounded: chunks are streamed, so it does not grow with the
  catalog (compare ``-n 1000`` with the default 10⁴);
- the cost of Dask's nanny setting ``MALLOC_TRIM_THRESHOLD_`` low: Dask run once with ucbplan's
  worker malloc tuning (the default) and once without (``UCBPLAN_MALLOC_TUNE=0``).

The three tables are checked byte-identical. Usage::

    python benchmarks/population_scaling.py            # 10⁴ sources (minutes)
    python benchmarks/population_scaling.py --quick    # 10³ sources (CI)
    python -m benchmarks --only population_scaling [--quick]
"""

from __future__ import annotations

import argparse
import functools
import os
import resource
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from make_population_catalog import make

from ucbplan.population.catalog import read_catalog
from ucbplan.population.catalog_forecast import ForecastOptions, forecast_chunk
from ucbplan.population.execute import ExecutorSpec, default_chunk, open_executor, run_chunks
from ucbplan.population.runner import FORECAST_SECONDS_PER_SOURCE, forecast_table

OPTS = ForecastOptions(sigma_v_kms=15.0)
GOAL_POOL, GOAL_DASK = 1.3, 1.2


def _maxrss_mb() -> float:
    """Peak resident memory of this process [MB] (Linux ru_maxrss is in KiB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _probe(_: int) -> tuple[int, float]:
    time.sleep(0.05)  # keep each worker busy long enough that every worker answers
    return os.getpid(), _maxrss_mb()


def _forecast(cat, spec: ExecutorSpec, tmp: Path, name: str) -> tuple[float, bytes, int, dict]:
    """(wall s, table bytes, chunk, {worker: peak RSS MB}) of one forecast on ``spec``."""
    ids = [s.source_id for s in cat.sources]
    parts = tmp / f"{name}.parts"
    parts.mkdir()
    t0 = time.perf_counter()
    with open_executor(spec) as (executor, slots):
        chunk = default_chunk(len(ids), slots, FORECAST_SECONDS_PER_SOURCE)
        rows, _ = run_chunks(
            functools.partial(forecast_chunk, OPTS),
            cat.sources,
            ids,
            chunk=chunk,
            executor=executor,
            slots=slots,
            parts=parts,
            kind="forecast",
            options=OPTS.as_dict(),
            catalog_sha256=cat.sha256,
        )
        wall = time.perf_counter() - t0
        if spec.scheduler:
            rss = {"dask": 0.0}
        elif slots > 1:
            rss = dict(executor.map(_probe, range(8 * slots)))
        else:
            rss = {"serial (this process)": _maxrss_mb()}
    out = tmp / f"{name}.ecsv"
    forecast_table(rows, cat, OPTS).write(out, format="ascii.ecsv")
    return wall, out.read_bytes(), chunk, rss


def _dask(cat, tmp: Path, name: str, tune: bool = True) -> tuple[float, bytes, int, dict, list]:
    """One forecast on a 2-worker LocalCluster; ``tune=False`` leaves the nanny's malloc setting."""
    import distributed

    os.environ["UCBPLAN_MALLOC_TUNE"] = "1" if tune else "0"  # inherited by the workers
    try:
        with (
            distributed.LocalCluster(
                n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
            ) as cluster,
            distributed.Client(cluster) as client,
        ):
            wall, data, chunk, _ = _forecast(
                cat, ExecutorSpec(scheduler=cluster.scheduler_address), tmp, name
            )
            rss = client.run(_maxrss_mb)
            env = client.run(lambda: os.environ.get("MALLOC_TRIM_THRESHOLD_"))
    finally:
        os.environ.pop("UCBPLAN_MALLOC_TUNE", None)
    return wall, data, chunk, rss, sorted(set(env.values()))


def _row(name: str, wall: float, n: int, chunk: int, rss: dict, **kw: object) -> dict:
    return {
        "name": f"population forecast, {n:,} sources, {name}",
        "value": wall,
        "unit": "s wall",
        "peak_mb": max(rss.values()),
        "note": f"{1e3 * wall / n:.2f} ms/source, chunk {chunk}, peak RSS per worker "
        f"{_rss_text(rss)}",
    } | kw


def _rss_text(rss: dict) -> str:
    return ", ".join(f"{v:.0f}" for v in sorted(rss.values())) + " MB"


def measure(n: int, tmp: Path) -> list[dict[str, object]]:
    """Serial, 2-process pool and 2-worker Dask (tuned and untuned malloc) on one catalog."""
    path = tmp / "cat.ecsv"
    make(n, 13).write(path, format="ascii.ecsv")
    cat = read_catalog(path)
    t_ser, ref, c_ser, rss_ser = _forecast(cat, ExecutorSpec(), tmp, "serial")
    out = [_row("serial", t_ser, n, c_ser, rss_ser)]
    t_pool, pool, c_pool, rss_pool = _forecast(cat, ExecutorSpec(workers=2), tmp, "pool")
    rel = t_pool / (t_ser / 2)
    out.append(
        _row("2-process pool", t_pool, n, c_pool, rss_pool)
        | {
            "ratio": t_ser / t_pool,
            "peer": f"serial ({t_ser:.2f} s)",
            "goal": f"≤ {GOAL_POOL:g} × serial/2",
            "met": bool(rel <= GOAL_POOL),
        }
    )
    out[-1]["note"] = f"pool / (serial/2) = {rel:.2f}; " + str(out[-1]["note"])
    same = {"pool": pool == ref}
    try:
        import distributed  # noqa: F401
    except ImportError:
        out.append(
            {
                "name": f"population forecast, {n:,} sources, Dask LocalCluster",
                "value": float("nan"),
                "note": "distributed is not installed (pip install 'ucbplan[dask]'): not measured",
            }
        )
    else:
        t_dask, dask, c_dask, rss_dask, _ = _dask(cat, tmp, "dask")
        t_raw, raw, _, rss_raw, trim = _dask(cat, tmp, "dask_raw", tune=False)
        same |= {"Dask": dask == ref, "Dask untuned": raw == ref}
        out.append(
            _row("Dask 2 workers × 1 thread", t_dask, n, c_dask, rss_dask)
            | {
                "ratio": t_pool / t_dask,
                "peer": f"2-process pool ({t_pool:.2f} s)",
                "goal": f"≤ {GOAL_DASK:g} × the pool",
                "met": bool(t_dask / t_pool <= GOAL_DASK),
            }
        )
        out.append(
            _row("Dask, nanny's malloc setting kept", t_raw, n, c_dask, rss_raw)
            | {
                "ratio": t_raw / t_dask,
                "peer": "the tuned Dask run (ratio > 1: the tuning pays)",
            }
        )
        out[-1]["note"] = f"MALLOC_TRIM_THRESHOLD_ {trim} (UCBPLAN_MALLOC_TUNE=0); " + str(
            out[-1]["note"]
        )
    ok = all(same.values())
    out.append(
        {
            "name": "population tables byte-identical across executors",
            "value": float(ok),
            "unit": "1 = yes",
            "goal": "identical",
            "met": ok,
            "note": ", ".join(f"{k} {'=' if v else '≠'} serial" for k, v in same.items()),
        }
    )
    return out


def rows(quick: bool) -> list[dict[str, object]]:
    """Issue 13's scaling goals on 10³ (quick) or 10⁴ sources."""
    with tempfile.TemporaryDirectory() as d:
        return measure(1000 if quick else 10_000, Path(d))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="10^3 sources (CI)")
    ap.add_argument("-n", type=int, default=None, help="sources (default 10^4; --quick 10^3)")
    args = ap.parse_args()
    n = args.n or (1000 if args.quick else 10_000)
    print(f"population forecast of {n} sources; os.cpu_count() = {os.cpu_count()}")
    with tempfile.TemporaryDirectory() as d:
        out = measure(n, Path(d))
    for r in out:
        ratio = f"  {r['ratio']:.2f}x {r['peer']}" if r.get("ratio") else ""
        print(f"{r['name']}: {r['value']:.2f} {r.get('unit', '')}{ratio}; {r.get('note', '')}")
    return 0 if out[-1]["met"] else 1


if __name__ == "__main__":
    raise SystemExit(main())
