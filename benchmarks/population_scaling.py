"""Population forecast scaling: serial vs 2-process pool vs 2-worker Dask LocalCluster, one run.

Issue 13's goals, measured side by side in one process (ratios, not absolute times, matter on a
shared machine):

- 2-process pool wall time ≤ 1.3 × serial / 2;
- Dask LocalCluster (2 workers × 1 thread, default chunk) ≤ 1.2 × the pool;
- peak memory (max RSS) per worker bounded: chunks are streamed, so it does not grow with the
  catalog (compare ``-n 1000`` with the default 10⁴).

The three tables are checked byte-identical. Usage::

    python benchmarks/population_scaling.py            # 10⁴ sources (minutes)
    python benchmarks/population_scaling.py --quick    # 10³ sources (CI)
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
from ucbplan.population.execute import ExecutorSpec, default_chunk, open_executor, run_chunks
from ucbplan.population.forecast import ForecastOptions, forecast_chunk
from ucbplan.population.run import FORECAST_SECONDS_PER_SOURCE, forecast_table

OPTS = ForecastOptions(sigma_v_kms=15.0)


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


def _dask(cat, tmp: Path) -> tuple[float, bytes, int, dict] | None:
    try:
        import distributed
    except ImportError:
        print("Dask: distributed not installed (pip install 'ucbplan[dask]'); skipped")
        return None
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        wall, data, chunk, _ = _forecast(
            cat, ExecutorSpec(scheduler=cluster.scheduler_address), tmp, "dask"
        )
        rss = client.run(_maxrss_mb)
        trim = sorted(set(client.run(lambda: os.environ.get("MALLOC_TRIM_THRESHOLD_")).values()))
    print(f"  Dask workers' MALLOC_TRIM_THRESHOLD_ (set by the nanny): {trim}; ucbplan retunes")
    return wall, data, chunk, rss


def _rss_text(rss: dict) -> str:
    return ", ".join(f"{v:.0f}" for v in sorted(rss.values())) + " MB"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="10^3 sources (CI)")
    ap.add_argument("-n", type=int, default=None, help="sources (default 10^4; --quick 10^3)")
    args = ap.parse_args()
    n = args.n or (1000 if args.quick else 10_000)
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        path = tmp / "cat.ecsv"
        make(n, 13).write(path, format="ascii.ecsv")
        cat = read_catalog(path)
        print(f"population forecast of {n} sources; os.cpu_count() = {os.cpu_count()}")
        t_ser, ref, c_ser, rss_ser = _forecast(cat, ExecutorSpec(), tmp, "serial")
        print(
            f"serial          {t_ser:8.2f} s  {1e3 * t_ser / n:6.2f} ms/source  chunk {c_ser:4d}  "
            f"peak RSS {_rss_text(rss_ser)}"
        )
        t_pool, pool, c_pool, rss_pool = _forecast(cat, ExecutorSpec(workers=2), tmp, "pool")
        print(
            f"2-process pool  {t_pool:8.2f} s  pool / (serial/2) = {t_pool / (t_ser / 2):.2f} "
            f"(goal <= 1.3)  chunk {c_pool:4d}  peak RSS per worker {_rss_text(rss_pool)}"
        )
        same = pool == ref
        res = _dask(cat, tmp)
        if res is not None:
            t_dask, dask, c_dask, rss_dask = res
            print(
                f"Dask 2 workers  {t_dask:8.2f} s  dask / pool = {t_dask / t_pool:.2f} "
                f"(goal <= 1.2)  chunk {c_dask:4d}  peak RSS per worker {_rss_text(rss_dask)}"
            )
            same = same and dask == ref
        print(f"tables byte-identical (serial, pool, Dask): {same}")
        return 0 if same else 1


if __name__ == "__main__":
    raise SystemExit(main())
