"""Eccentric four-line waveform throughput (N = 512, three bands, TDI A and E) against the
kernel as it was before issue 14 (``benchmarks/waveform_before.py``), measured side by side.

Parameters are walkers drawn from the fiducial source's Fisher ball (what the sampler asks
for), the same sets for both kernels; the two are timed back to back in each round, the ratio
is the median of the per-round ratios and the rates are the best rounds (the machine may be
shared). Our kernel is timed on both of its paths when numba is installed (numpy + BLAS, the
default, and the optional compiled loops of ``ucbplan.lisa._fused``); the row names say which.
Goal (issue 14): ≥ 3× today.
Usage: ``python -m benchmarks --only waveform [--quick]``.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ucbplan.offline import offline

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


@offline()  # the offline astropy scope for the whole measurement
def setup(n_walkers: int, seed: int = 7) -> tuple[Any, Any, np.ndarray, dict[str, np.ndarray], Any]:
    """Today's model, ours, W walkers from the Fisher ball (sampled coordinates and physical
    parameters) and the zero-noise likelihood."""
    from benchmarks.waveform_before import FourLineModel as Before
    from ucbplan.core.mvnormal import sample_normal
    from ucbplan.lisa.likelihood import physical_from_theta, simulate_data
    from ucbplan.lisa.noise import SANGRIA
    from ucbplan.lisa.pipeline import build_model, fisher_forecast
    from ucbplan.targets import load_target

    lisa = build_model(load_target(INJECTION), n_bins=N_BINS)
    ours = lisa.model
    before = Before(ours.grid, ours.f_center_hz, ours.harmonics)
    fc = fisher_forecast(lisa)
    theta = sample_normal(fc.theta0, fc.cov_theta, n_walkers, np.random.default_rng(seed))
    params = physical_from_theta(theta, lisa.t_obs_s)
    like = lisa.likelihood(simulate_data(ours, lisa.truth, SANGRIA, None))
    return before, ours, theta, params, like


def _paths(ours: Any, quick_params: dict[str, np.ndarray]) -> dict[str, Callable[..., Any]]:
    """Our kernel on each available path: 'numpy', and 'numba' when numba is installed (its
    loops compiled here, outside the timing). Each callable takes the parameter dict."""
    from ucbplan.lisa import _fused

    def on(path: str) -> Callable[..., Any]:
        def call(p: dict[str, np.ndarray]) -> Any:
            if path == "numba":
                os.environ[_fused.ENV] = "1"
            else:
                os.environ.pop(_fused.ENV, None)
            return ours.bands(**p)

        return call

    paths = {"numpy": on("numpy")}
    try:
        import numba  # noqa: F401
    except ImportError:
        return paths
    paths["numba"] = on("numba")
    return paths


def _compile_seconds(ours: Any, params: dict[str, np.ndarray]) -> float | None:
    """Import and compilation time of the numba loops (first call), or None without numba."""
    from ucbplan.lisa import _fused

    try:
        import numba  # noqa: F401
    except ImportError:
        return None
    os.environ[_fused.ENV] = "1"
    t0 = time.perf_counter()
    ours.bands(**params)
    return time.perf_counter() - t0


def rows(quick: bool) -> list[dict[str, object]]:
    """Waveforms/s (batch 64 and 1) vs today on each path, the cost relative to the FFT,
    likelihood/s."""
    window, rounds = (0.3, 5) if quick else (1.0, 9)
    before, ours, theta, params, like = setup(64)
    compile_s = _compile_seconds(ours, {k: v[:2] for k, v in params.items()})
    paths = _paths(ours, params)
    out: list[dict[str, object]] = []
    for w in (64, 1):
        p = {k: v[:w] for k, v in params.items()}
        fns = {"before": lambda p=p: before.bands(**p)}
        fns |= {name: (lambda p=p, f=f: f(p)) for name, f in paths.items()}
        per_round = _round_rates(fns, w, window, rounds)
        base = max(x["before"] for x in per_round)
        for name in paths:
            out.append(_row(w, name, per_round, base, compile_s))
    best = max((r for r in out if "batch 64" in str(r["name"])), key=lambda r: r["value"])
    spec = np.zeros((64, ours.n_bands, 2, N_BINS), dtype=complex)
    fft = _best_rates({"fft": lambda: np.fft.fft(spec, axis=-1)}, 64, window, rounds)["fft"]
    out.append(
        {
            "name": f"waveform cost / its FFT cost (batch 64, {_path_of(best)} path)",
            "value": fft / best["value"],  # type: ignore[operator]
            "unit": "×",
            "note": "the FFT of the 3 bands x 2 channels alone is the floor of this design",
        }
    )
    from ucbplan.lisa import _fused

    os.environ.pop(_fused.ENV, None)  # the likelihood as a default run computes it (numpy)
    th = theta[:16]
    lk = _best_rates({"like": lambda: like.log_prob(th)}, 16, window, rounds)["like"]
    out.append(
        {
            "name": "log-likelihood (9 parameters), batch 16",
            "value": lk,
            "unit": "evals/s",
            "note": f"waveform path: {_fused.describe()}",
        }
    )
    return out


def _path_of(row: dict[str, object]) -> str:
    return "numba" if "numba" in str(row["name"]) else "numpy"


def _row(
    w: int,
    path: str,
    per_round: list[dict[str, float]],
    base: float,
    compile_s: float | None,
) -> dict[str, object]:
    """One throughput row: best rate on ``path``, ratio = median of the per-round ratios."""
    rate = max(x[path] for x in per_round)
    ratio = float(np.median([x[path] / x["before"] for x in per_round]))
    if path == "numba":
        note = (
            f"optional numba loops (pip install ucbplan[fast]); import + compilation "
            f"{compile_s:.1f} s once per process; on with UCBPLAN_NUMBA=1"
        )
    else:
        note = "numpy + BLAS (default; no compiled code)"
    return {
        "name": f"eccentric waveform, N=512, 3 bands, batch {w}, {path} path",
        "value": rate,
        "unit": "waveforms/s",
        "ratio": ratio,
        "peer": f"pre-issue-14 kernel ({base:,.0f}/s)",
        "goal": f"≥ {GOAL:g}× today" if w == 64 else None,
        "met": bool(ratio >= GOAL) if w == 64 else None,
        "note": note if w == 64 else None,
    }
