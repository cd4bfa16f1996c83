"""Reduce scaling: wall time and peak memory against the number of spectra and of samples.

(a) :func:`ucbplan.reduce.reduce` on N exact-Kepler spectra (contiguous P_b/8 exposures, one
session per 60 orbits, σ_v = 15 km/s) for growing N — O(N) means the time per spectrum stays
flat (goal: 10⁶ spectra ≤ 5 s); (b) the mass Monte Carlo alone for growing numbers of posterior
samples with its peak traced memory (goal: 10⁷ samples ≤ 1 GB). The machine may be shared: the
per-spectrum and per-sample columns are the comparable numbers.

Usage: ``python benchmarks/reduce_scaling.py [--quick]`` or
``python -m benchmarks --only reduce_scaling``.
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

from support.reduce_synth import exposure_factor, session_times  # noqa: E402

from ucbplan.offline import offline  # noqa: E402
from ucbplan.reduce.pipeline import ReduceOptions, reduce  # noqa: E402
from ucbplan.reduce.velocities import VelocityTable  # noqa: E402
from ucbplan.targets import Target, load_target  # noqa: E402

GOAL_SPECTRA, GOAL_SPECTRA_S = 1_000_000, 5.0
GOAL_SAMPLES, GOAL_SAMPLES_MB = 10_000_000, 1024.0  # judged in full mode only


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


def measure_spectra(t: Target, sizes: list[int]) -> list[dict[str, object]]:
    """Reduce wall time per spectrum for growing N; the goal is judged at (or scaled to) 10⁶."""
    out: list[dict[str, object]] = []
    for n in sizes:
        tab = make_table(t, n)
        t0 = time.perf_counter()
        reduce(t, tab, ReduceOptions(n_samples=1000, seed=5))
        wall = time.perf_counter() - t0
        at_goal = wall * GOAL_SPECTRA / n  # O(N): scaled to the goal's size
        last = n == sizes[-1]
        out.append(
            {
                "name": f"reduce, {n:,} spectra (10³ samples)",
                "value": wall,
                "unit": "s",
                "goal": f"10⁶ spectra ≤ {GOAL_SPECTRA_S:g} s" if last else None,
                "met": bool(at_goal <= GOAL_SPECTRA_S) if last else None,
                "note": f"{1e6 * wall / n:.1f} µs/spectrum"
                + ("" if n == GOAL_SPECTRA else f"; scaled linearly to 10⁶: {at_goal:.1f} s"),
            }
        )
    return out


def measure_samples(t: Target, sizes: list[int]) -> list[dict[str, object]]:
    """Reduce of 480 spectra for growing numbers of posterior samples, with peak traced memory."""
    tab = make_table(t, 480)
    out: list[dict[str, object]] = []
    for n in sizes:
        tracemalloc.start()
        t0 = time.perf_counter()
        red = reduce(t, tab, ReduceOptions(n_samples=n, seed=5))
        wall = time.perf_counter() - t0
        peak = tracemalloc.get_traced_memory()[1] / 2**20
        tracemalloc.stop()
        m1 = red.summaries["M1"]
        at_goal = n == GOAL_SAMPLES
        out.append(
            {
                "name": f"reduce, 480 spectra, {n:,} posterior samples",
                "value": wall,
                "unit": "s",
                "goal": f"10⁷ samples ≤ {GOAL_SAMPLES_MB:g} MB" if at_goal else None,
                "met": bool(peak <= GOAL_SAMPLES_MB) if at_goal else None,
                "peak_mb": peak,
                "note": f"peak MB traced by tracemalloc during the call "
                f"({peak * 2**20 / n:.0f} B/sample; chunked: does not grow with N); "
                f"M1 = {m1.value:.5f} ± {m1.sigma:.5f} Msun",
            }
        )
    return out


@offline()  # the offline astropy scope for the whole measurement
def rows(quick: bool) -> list[dict[str, object]]:
    """O(N) in spectra and bounded memory in samples (quick: 10x-100x smaller sizes)."""
    t = load_target(ROOT / "catalogs" / "fiducial-eccentric.yaml")
    if quick:
        return measure_spectra(t, [10_000, 100_000]) + measure_samples(t, [100_000, 1_000_000])
    return measure_spectra(t, [10_000, 100_000, 1_000_000]) + measure_samples(
        t, [100_000, 1_000_000, 10_000_000]
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="small sizes, for CI")
    args = ap.parse_args()
    for r in rows(args.quick):
        print(f"{r['name']:45s} {r['value']:7.2f} s  {r['note']}")
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"peak resident memory of the process {rss:.0f} MB (machine shared)")


if __name__ == "__main__":
    main()
