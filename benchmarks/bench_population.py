"""Population forecast throughput: serial vs process pool vs Dask LocalCluster (issue 13).

Goals (issue 13): wall time ≤ 1.3 × (serial / workers) on 2 workers; Dask LocalCluster ≤ 1.2 ×
the process pool at the default chunk size. Also: peak RSS per worker (bounded: chunks are
streamed), and the cost of Dask's nanny setting MALLOC_TRIM_THRESHOLD_=65536 with and without
ucbplan's worker malloc tuning (ucbplan.population.execute.tune_malloc).

Every run also checks that the three tables are byte-identical.
Usage: python benchmarks/bench_population.py [--quick] [-n N]
"""

from __future__ import annotations

import argparse
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
from ucbplan.population.execute import ExecutorSpec
from ucbplan.population.forecast import ForecastOptions
from ucbplan.population.run import run_forecast

OPTS = ForecastOptions(sigma_v_kms=15.0)


def _maxrss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _timed(cat, spec: ExecutorSpec, tmp: Path, name: str) -> tuple[float, bytes, int]:
    t0 = time.perf_counter()
    run = run_forecast(cat, OPTS, spec=spec, parts=tmp / f"{name}.parts")
    dt = time.perf_counter() - t0
    out = tmp / f"{name}.ecsv"
    run.table.write(out, format="ascii.ecsv")
    return dt, out.read_bytes(), run.chunk


def _pool_worker_rss(cat, chunk: int) -> float:
    """Peak RSS [MB] of the busiest worker of a 2-process pool after a full forecast."""
    import functools

    from ucbplan.population.execute import open_executor
    from ucbplan.population.forecast import forecast_chunk

    task = functools.partial(forecast_chunk, OPTS)
    with open_executor(ExecutorSpec(workers=2)) as (pool, _):
        srcs = cat.sources
        list(pool.map(task, [srcs[i : i + chunk] for i in range(0, len(srcs), chunk)]))
        return max(pool.map(_maxrss_slow, range(8)))


def _maxrss_slow(_: int) -> float:
    time.sleep(0.05)  # spread the probes over both workers
    return _maxrss_mb()


def _dask(cat, tmp: Path, name: str, tune: bool) -> tuple[float, bytes, list[float]]:
    import distributed

    os.environ["UCBPLAN_MALLOC_TUNE"] = "1" if tune else "0"
    try:
        with (
            distributed.LocalCluster(
                n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
            ) as cluster,
            distributed.Client(cluster) as client,
        ):
            env = client.run(lambda: os.environ.get("MALLOC_TRIM_THRESHOLD_"))
            dt, data, _ = _timed(cat, ExecutorSpec(scheduler=cluster.scheduler_address), tmp, name)
            rss = client.run(_maxrss_mb)
    finally:
        os.environ.pop("UCBPLAN_MALLOC_TUNE", None)
    print(f"  dask workers' MALLOC_TRIM_THRESHOLD_: {sorted(set(env.values()))}")
    return dt, data, sorted(rss.values())


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="200 sources (CI)")
    ap.add_argument("-n", type=int, default=None, help="sources (default 2000; --quick 200)")
    args = ap.parse_args()
    n = args.n or (200 if args.quick else 2000)
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        path = tmp / "cat.ecsv"
        make(n, 13).write(path, format="ascii.ecsv")
        cat = read_catalog(path)
        print(f"population forecast, {n} sources, os.cpu_count() = {os.cpu_count()}")
        t_ser, ref, chunk = _timed(cat, ExecutorSpec(), tmp, "serial")
        print(
            f"serial:            {t_ser:8.2f} s  ({1e3 * t_ser / n:.1f} ms/source, chunk {chunk})"
        )
        t_pool, pool, chunk = _timed(cat, ExecutorSpec(workers=2), tmp, "pool")
        child_rss = _pool_worker_rss(cat, chunk)
        ratio = t_pool / (t_ser / 2)
        print(
            f"2-process pool:    {t_pool:8.2f} s  ratio to serial/2 = {ratio:.2f} (goal <= 1.3), "
            f"chunk {chunk}, peak RSS per worker {child_rss:.0f} MB"
        )
        same = pool == ref
        try:
            import distributed  # noqa: F401
        except ImportError:
            print("Dask: distributed not installed (pip install 'ucbplan[dask]'); skipped")
        else:
            t_raw, d_raw, rss_raw = _dask(cat, tmp, "dask_raw", tune=False)
            print(
                f"Dask, nanny malloc default: {t_raw:8.2f} s  ratio to pool = {t_raw / t_pool:.2f}"
                f", peak RSS per worker {rss_raw[-1]:.0f} MB"
            )
            t_dask, d_dask, rss = _dask(cat, tmp, "dask", tune=True)
            print(
                f"Dask, ucbplan malloc tuning: {t_dask:8.2f} s  ratio to pool = "
                f"{t_dask / t_pool:.2f} (goal <= 1.2), peak RSS per worker {rss[-1]:.0f} MB; "
                f"untuned/tuned = {t_raw / t_dask:.2f}"
            )
            same = same and d_raw == ref and d_dask == ref
        print(f"tables byte-identical across executors: {same}")
        return 0 if same else 1


if __name__ == "__main__":
    raise SystemExit(main())
