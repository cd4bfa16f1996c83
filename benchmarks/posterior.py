"""Wall time to a converged (≥ 50 τ) 9-parameter posterior of the paper's fiducial source.

The library pipeline as ``ucbplan simulate --until-converged`` runs it (seeded noise draw, Fisher
whitening, emcee with differential-evolution moves, 32 walkers, N = 512). Goal (issue 14):
≤ 30 s on 2 cores. The CPU time is printed beside the wall time: on a shared machine the wall
time is the one that varies.
Usage: ``python -m benchmarks --only posterior [--quick]``.
"""

from __future__ import annotations

import time
from pathlib import Path

from ucbplan.offline import offline

INJECTION = Path(__file__).resolve().parents[1] / "catalogs" / "fiducial-injection.yaml"
GOAL_S = 30.0


@offline()  # the offline astropy scope for the whole measurement
def rows(quick: bool) -> list[dict[str, object]]:
    """Converged posterior: wall time, and its σ's against the Fisher forecast."""
    from ucbplan.lisa.pipeline import build_model, simulate
    from ucbplan.lisa.simulation import SimulateOptions
    from ucbplan.targets import load_target

    seeds = (1,) if quick else (1, 2, 3)
    out: list[dict[str, object]] = []
    for seed in seeds:
        wall0, cpu0 = time.perf_counter(), time.process_time()
        model = build_model(load_target(INJECTION), n_bins=512)
        opts = SimulateOptions(seed=seed, walkers=32, steps=200, until_converged=True)
        res = simulate(model, opts)
        wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
        ratio = [res.posterior_sigma[n] / res.fisher_sigma[n] for n in res.names]
        out.append(
            {
                "name": f"converged posterior (50 τ), fiducial, seed {seed}",
                "value": wall,
                "unit": "s wall",
                "goal": f"≤ {GOAL_S:g} s on 2 cores",
                "met": bool(res.chain.converged and wall <= GOAL_S),
                "note": f"{res.n_steps} steps × 32 walkers, τ_max {res.tau_max:.0f} steps, "
                f"converged={res.chain.converged}, CPU {cpu:.1f} s (one core used); posterior/"
                f"Fisher σ {min(ratio):.2f}–{max(ratio):.2f}",
            }
        )
    return out
