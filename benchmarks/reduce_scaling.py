"""Reduce scaling: wall time and peak memory against the number of spectra and of samples.

(a) :func:`ucbplan.reduce.reduce` on N exact-Kepler spectra (contiguous P_b/8 exposures, one
session per 60 orbits, σ_v = 15 km/s) for growing N — O(N) means the time per spectrum stays
flat (goal: 10⁶ spectra ≤ 5 s); (b) the mass Monte Carlo alone for growing numbers of posterior
samples with its peak traced memory (goal: 10⁷ samples ≤ 1 GB). The machine may be shared: the
per-spectrum and per-sample columns are the comparable numbers.

Usage: python benchmarks/reduce_scaling.py [--quick]
"""

from __future__ import annotations

import argparse
import math
import resource
import sys
import time
import tracemalloc
from pathlib import Path

import numpy as np
from astropy.time import TimeDelta

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from test_reduce_synth import exposure_factor, session_times  # noqa: E402

from ucbplan.offline import configure_offline  # noqa: E402
from ucbplan.reduce.pipeline import ReduceOptions, reduce  # noqa: E402
from ucbplan.reduce.velocities import VelocityTable  # noqa: E402
from ucbplan.target import Target, load_target  # noqa: E402


def make_table(t: Target, n_spectra: int, seed: int = 1) -> VelocityTable:
    """``n_spectra`` spectra in sessions of 480 (60 orbits × 8), one session a day."""
    p = t.params
    per = 480
    n_sess = math.ceil(n_spectra / per)
    taus, dts = [], 0.0
    for k in range(n_sess):
        tau, dts = session_times(p, 0.5 * t.t_obs_s + (30 + k) * 86400.0)
        taus.append(tau)
    tau = np.concatenate(taus)[:n_spectra]
    F = exposure_factor(p, tau, dts)
    rng = np.random.default_rng(seed)
    n = tau.size
    labels = tuple(f"S{k // per}" for k in range(n))
    return VelocityTable(
        None,
        t.t_ref + TimeDelta(tau, format="sec"),
        np.full(n, dts),
        np.full(n, np.nan),
        (30 + 585.3 * F + rng.normal(0, 15, n), 10 - 712.6 * F + rng.normal(0, 15, n)),
        (np.full(n, 15.0), np.full(n, 15.0)),
        labels,
        None,
    )


def bench_spectra(t: Target, sizes: list[int]) -> None:
    for n in sizes:
        tab = make_table(t, n)
        t0 = time.perf_counter()
        reduce(t, tab, ReduceOptions(n_samples=1000, seed=5))
        wall = time.perf_counter() - t0
        print(f"reduce, {n:>9,} spectra: {wall:7.2f} s  ({1e6 * wall / n:6.1f} us/spectrum)")


def bench_samples(t: Target, sizes: list[int]) -> None:
    tab = make_table(t, 480)
    for n in sizes:
        tracemalloc.start()
        t0 = time.perf_counter()
        red = reduce(t, tab, ReduceOptions(n_samples=n, seed=5))
        wall = time.perf_counter() - t0
        peak = tracemalloc.get_traced_memory()[1] / 2**20
        tracemalloc.stop()
        m1 = red.summaries["M1"]
        print(
            f"reduce, {n:>11,} samples: {wall:7.2f} s, peak traced memory {peak:7.0f} MB "
            f"({peak * 2**20 / n:5.0f} B/sample); M1 = {m1.value:.5f} ± {m1.sigma:.5f} Msun"
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="small sizes, for CI")
    args = ap.parse_args()
    configure_offline()
    t = load_target(ROOT / "catalogs" / "fiducial-eccentric.yaml")
    if args.quick:
        bench_spectra(t, [1_000, 10_000])
        bench_samples(t, [10_000, 100_000])
    else:
        bench_spectra(t, [10_000, 100_000, 1_000_000])
        bench_samples(t, [100_000, 1_000_000, 10_000_000])
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"peak resident memory of the process {rss:.0f} MB (machine shared)")


if __name__ == "__main__":
    main()
