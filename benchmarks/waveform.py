"""Eccentric four-line waveform throughput (N = 512, three bands, TDI A and E) against the
kernel as it was before issue 14 (``benchmarks/waveform_before.py``), measured side by side.

Parameters are walkers drawn from the fiducial source's Fisher ball (what the sampler asks
for), the same sets for both kernels; the two are timed back to back in each round, the ratio
is the median of the per-round ratios and the rates are the best rounds (the machine may be
shared). Goal (issue 14): ≥ 3× today.
Usage: ``python -m benchmarks --only waveform [--quick]``.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

INJECTION = Path(__file__).resolve().parents[1] / "catalogs" / "fiducial-injection.yaml"
N_BINS = 512
GOAL = 3.0


def _best_rates(fns: dict[str, Callable[[], Any]], batch: int, window: float, rounds: int) -> dict:
    """Calls per second × batch for each function, best of ``rounds`` alternating windows."""
    per_round = _round_rates(fns, batch, window, rounds)
    return {key: max(r[key] for r in per_round) for key in fns}


def _round_rates(
    fns: dict[str, Callable[[], Any]], batch: int, window: float, rounds: int
) -> list[dict[str, float]]:
    """Rates of each function per round; within a round they run back to back, so a ratio
    taken per round sees the same machine load on both sides."""
    for fn in fns.values():
        fn()
    out = []
    for _ in range(rounds):
        rates = {}
        for key, fn in fns.items():
            n, t0 = 0, time.perf_counter()
            while time.perf_counter() - t0 < window:
                fn()
                n += 1
            rates[key] = n * batch / (time.perf_counter() - t0)
        out.append(rates)
    return out


def setup(n_walkers: int, seed: int = 7) -> tuple[Any, Any, np.ndarray, dict[str, np.ndarray], Any]:
    """Today's model, ours, W walkers from the Fisher ball (sampled coordinates and physical
    parameters) and the zero-noise likelihood."""
    from benchmarks.waveform_before import FourLineModel as Before
    from ucbplan.core.mvnormal import sample_normal
    from ucbplan.lisa.likelihood import physical_from_theta, simulate_data
    from ucbplan.lisa.noise import SANGRIA
    from ucbplan.lisa.pipeline import build_model, fisher_forecast
    from ucbplan.offline import configure_offline
    from ucbplan.target import load_target

    configure_offline()
    lisa = build_model(load_target(INJECTION), n_bins=N_BINS)
    ours = lisa.model
    before = Before(ours.grid, ours.f_center_hz, ours.harmonics)
    fc = fisher_forecast(lisa)
    theta = sample_normal(fc.theta0, fc.cov_theta, n_walkers, np.random.default_rng(seed))
    params = physical_from_theta(theta, lisa.t_obs_s)
    like = lisa.likelihood(simulate_data(ours, lisa.truth, SANGRIA, None))
    return before, ours, theta, params, like


def rows(quick: bool) -> list[dict[str, object]]:
    """Waveforms/s (batch 64 and 1) vs today, the cost relative to the FFT, likelihood/s."""
    window, rounds = (0.3, 5) if quick else (1.0, 9)
    before, ours, theta, params, like = setup(64)
    out: list[dict[str, object]] = []
    for w in (64, 1):
        p = {k: v[:w] for k, v in params.items()}
        per_round = _round_rates(
            {"before": lambda p=p: before.bands(**p), "ours": lambda p=p: ours.bands(**p)},
            w,
            window,
            rounds,
        )
        r = {k: max(x[k] for x in per_round) for k in ("before", "ours")}
        ratio = float(np.median([x["ours"] / x["before"] for x in per_round]))
        out.append(
            {
                "name": f"eccentric waveform, N=512, 3 bands, batch {w}",
                "value": r["ours"],
                "unit": "waveforms/s",
                "ratio": ratio,
                "peer": f"pre-issue-14 kernel ({r['before']:,.0f}/s)",
                "goal": f"≥ {GOAL:g}× today" if w == 64 else None,
                "met": bool(ratio >= GOAL) if w == 64 else None,
                "note": None
                if ratio >= GOAL or w != 64
                else "numpy-bound: every remaining pass over the (walker, band, channel, sample) "
                "array (link sum, carrier, FFT weights) costs about one FFT; fusing them needs a "
                "compiled kernel (numba/C), a new dependency",
            }
        )
    spec = np.zeros((64, ours.n_bands, 2, N_BINS), dtype=complex)
    fft = _best_rates({"fft": lambda: np.fft.fft(spec, axis=-1)}, 64, window, rounds)["fft"]
    out.append(
        {
            "name": "waveform cost / its FFT cost (batch 64)",
            "value": fft / out[0]["value"],  # type: ignore[operator]
            "unit": "×",
            "note": "the FFT of the 3 bands x 2 channels alone is the floor of this design",
        }
    )
    th = theta[:16]
    lk = _best_rates({"like": lambda: like.log_prob(th)}, 16, window, rounds)["like"]
    out.append({"name": "log-likelihood (9 parameters), batch 16", "value": lk, "unit": "evals/s"})
    return out
