"""Horizon throughput: the analytic σ_u² roots against the sampled-grid search, side by side.

Both methods run in this process on the same random targets (circular and ω̇ = 0 eccentric,
correlated covariances, 30 % timing ephemerides with horizons both before and after T0), so the
ratio is fair on a shared machine. Apsidally oscillating rows use the grid in both methods and
are left out of the ratio. Also: the full horizon table (2 anchors × 2 α) of 10⁴ targets through
the API (goal ≤ 50 µs per target) and the peak resident memory.

Usage: python benchmarks/horizon.py [--quick]
"""

from __future__ import annotations

import argparse
import math
import resource
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from test_horizon_poly import _random_targets

from ucbplan.core.forecast import AFTER, BEFORE, t_valid_batch
from ucbplan.core.horizon_batch import horizon_columns


def _timed(fn, *args, **kw):  # type: ignore[no-untyped-def]
    t0 = time.perf_counter()
    out = fn(*args, **kw)
    return out, time.perf_counter() - t0


def bench_methods(n: int) -> None:
    pars, covs, t_obs, thr = _random_targets(n, seed=2026)
    worst, t_an, t_gr = 0.0, 0.0, 0.0
    for anchor in ((0.0, math.pi), (math.pi / 2,)):
        for direction in (AFTER, BEFORE):
            a, ta = _timed(t_valid_batch, pars, covs, t_obs, thr, anchor, 1, direction)
            g, tg = _timed(
                t_valid_batch, pars, covs, t_obs, thr, anchor, 1, direction, method="grid"
            )
            t_an, t_gr = t_an + ta, t_gr + tg
            worst = max(worst, float(np.max(np.abs(a - g) / np.maximum(g, 86400.0))))
    calls = 4 * n
    print(
        f"horizon T_valid, {n} targets x 4 (quadrature/conjunction, after/before): analytic "
        f"{1e6 * t_an / calls:.1f} us/target, grid {1e6 * t_gr / calls:.1f} us/target, ratio "
        f"{t_gr / t_an:.1f}x (goal >= 10x); max |dT|/T {worst:.1e} (goal <= 1e-3)"
    )


def bench_oscillating(n: int) -> None:
    """Eccentric rows with apsidal precession: σ_u oscillates, both methods sample the grid."""
    pars, covs, t_obs, thr = _random_targets(n, seed=3)
    ecc = pars[:, 4] != 0
    pars, covs, t_obs, thr = pars[ecc], covs[ecc], t_obs[ecc], thr[ecc]
    pars[:, 6] = 1.5e-6  # ω̇ [rad/s], P_aps ≈ 48 d
    _, wall = _timed(t_valid_batch, pars, covs, t_obs, thr, (0.0, math.pi))
    print(
        f"horizon T_valid, {len(pars)} apsidally precessing targets (grid search, no analytic "
        f"form): {1e6 * wall / len(pars):.0f} us/target"
    )


def bench_table(n: int) -> None:
    pars, covs, t_obs, _ = _random_targets(n, seed=7)
    horizon_columns(pars[:10], covs[:10], t_obs[:10], 15.0, 1000.0)  # warm-up
    _, wall = _timed(horizon_columns, pars, covs, t_obs, 15.0, 1000.0, two_sided=t_obs == 0)
    print(
        f"horizon table (2 anchors x 2 alpha, timing rows both sides), {n} targets via the API: "
        f"{wall:.2f} s, {1e6 * wall / n:.0f} us/target (goal <= 50 us, 1e4 in <= 0.5 s)"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quick", action="store_true", help="10x smaller, for CI")
    args = ap.parse_args()
    bench_methods(1000 if args.quick else 3000)  # small batches measure call overhead
    bench_oscillating(100 if args.quick else 400)
    bench_table(1000 if args.quick else 10_000)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"peak resident memory {peak:.0f} MB (machine shared: times are noisy, ratios are not)")


if __name__ == "__main__":
    main()
