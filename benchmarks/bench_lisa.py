"""LISA simulation throughput: eccentric 4-line waveforms/s, likelihood evaluations/s, and (with
--full) wall time to a converged 9-parameter posterior of the paper's fiducial source.

Peers, run in the same invocation:
- GBGPU's circular ``run_wave`` (CPU backend, N = 512) when ``gbgpu`` is importable here, or in the
  interpreter given by ``--gbgpu-python`` (e.g. a throwaway venv: ``python -m venv /tmp/gbvenv &&
  /tmp/gbvenv/bin/pip install gbgpu``); it is never a dependency of ucbplan;
- otherwise our own circular (n = 2 only) model, the same code path with one band.

Goals (issue 5): >= 4000 eccentric waveforms/s batched on one core; converged 9-parameter
posterior <= 5 min on 2 cores.
Usage: python benchmarks/bench_lisa.py [--quick] [--full] [--gbgpu-python PATH]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from ucbplan.lisa.likelihood import (
    Likelihood,
    Prior,
    model_for_target,
    simulate_data,
    source_from_target,
    theta_from_source,
)
from ucbplan.lisa.noise import SANGRIA
from ucbplan.offline import configure_offline
from ucbplan.target import Target, load_target

INJECTION = Path(__file__).resolve().parents[1] / "catalogs" / "fiducial-injection.yaml"
N_BINS = 512

_GBGPU_SNIPPET = """
import json, sys, time
import numpy as np
from gbgpu.gbgpu import GBGPU
gb = GBGPU(force_backend="cpu")
T, N, window = float(sys.argv[1]), int(sys.argv[2]), float(sys.argv[3])
vals = (4.909e-22, 8.406186457145e-3, 1.6405e-15, 0.0, 4.61, 1.4777, 0.339, 2.398, -1.327)
out = {}
for w in (1, 32, 64):
    args = [np.full(w, v) for v in vals]
    gb.run_wave(*args, N=N, T=T, dt=10.0)
    n, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < window:
        gb.run_wave(*args, N=N, T=T, dt=10.0)
        n += 1
    out[w] = n * w / (time.perf_counter() - t0)
print(json.dumps(out))
"""


def _rate(fn, batch: int, window: float) -> float:  # type: ignore[no-untyped-def]
    fn()
    n, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < window:
        fn()
        n += 1
    return n * batch / (time.perf_counter() - t0)


def _gbgpu_rates(python: str | None, t_obs: float, window: float) -> dict[int, float] | None:
    try:
        import gbgpu  # noqa: F401
    except ImportError:
        if python is None:
            return None
        cmd = [python, "-c", _GBGPU_SNIPPET, repr(t_obs), str(N_BINS), repr(window)]
    else:
        cmd = [sys.executable, "-c", _GBGPU_SNIPPET, repr(t_obs), str(N_BINS), repr(window)]
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=300, check=False)
    if res.returncode != 0:
        print(f"GBGPU peer failed: {res.stderr.strip().splitlines()[-1:]}")
        return None
    return {int(k): v for k, v in json.loads(res.stdout.strip().splitlines()[-1]).items()}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="short timing windows (< 60 s)")
    ap.add_argument("--full", action="store_true", help="also run a converged posterior")
    ap.add_argument("--gbgpu-python", default=None, help="interpreter with gbgpu installed")
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    window = 1.0 if args.quick else 3.0
    configure_offline()
    target = load_target(INJECTION)
    truth = source_from_target(target)
    t_obs = target.t_obs_s
    ecc = model_for_target(target, t_obs, N_BINS, True, truth.f_gw)
    circ = model_for_target(target, t_obs, N_BINS, False, truth.f_gw)
    names = ("amplitude", "f_gw", "fdot", "cos_inclination", "psi", "phase")
    print(f"fiducial source, T = {t_obs:.6f} s, N = {N_BINS} bins per band")
    rates: dict[str, dict[int, float]] = {"eccentric": {}, "circular": {}}
    for label, model, keys in (
        ("eccentric", ecc, (*names, "eta", "kappa", "omega_dot")),
        ("circular", circ, names),
    ):
        for w in (1, 32, 64):
            kw = {k: np.full(w, getattr(truth, k)) for k in keys}
            rates[label][w] = _rate(lambda kw=kw, model=model: model.bands(**kw), w, window)
        print(
            f"{label:9s} waveform ({model.n_bands} band(s)): "
            + ", ".join(f"W={w}: {r:,.0f}/s" for w, r in rates[label].items())
        )
    like = Likelihood(
        ecc, simulate_data(ecc, truth, SANGRIA, None), Prior.paper(truth, t_obs), SANGRIA
    )
    theta0 = theta_from_source(truth, t_obs)
    for w in (1, 32):
        th = np.repeat(theta0[None], w, axis=0)
        r = _rate(lambda th=th: like.log_prob(th), w, window)
        print(f"likelihood (9 parameters, A+E, 3 bands) W={w}: {r:,.0f} evaluations/s")
    goal = rates["eccentric"][64]
    print(
        f"goal >= 4000 eccentric waveforms/s batched: {goal:,.0f}/s -> "
        f"{'met' if goal >= 4000 else 'NOT met'}"
    )
    peer = _gbgpu_rates(args.gbgpu_python, t_obs, window)
    if peer is not None:
        print(
            "GBGPU circular run_wave (CPU): "
            + ", ".join(f"W={w}: {r:,.0f}/s" for w, r in peer.items())
        )
        for w in (1, 64):
            print(
                f"ratio ours eccentric (4 lines, 3 bands) / GBGPU circular, W={w}: "
                f"{rates['eccentric'][w] / peer[w]:.2f}x; ours circular / GBGPU circular: "
                f"{rates['circular'][w] / peer[w]:.2f}x"
            )
    else:
        print("GBGPU not importable (pass --gbgpu-python PATH); peer = our circular model")
        for w in (1, 64):
            print(
                f"ratio eccentric / circular (cost of the sidebands), W={w}: "
                f"{rates['eccentric'][w] / rates['circular'][w]:.2f}"
            )
    if args.full:
        _full(args.seed)


def _full(seed: int) -> None:
    """Converged posterior through the library pipeline (as ``ucbplan simulate``)."""
    from ucbplan.lisa.pipeline import SimulateOptions, build_model, simulate

    t0 = time.perf_counter()
    model = build_model(load_target(INJECTION), n_bins=N_BINS)
    opts = SimulateOptions(seed=seed, walkers=32, steps=2000, until_converged=True)
    res = simulate(model, opts)
    wall = time.perf_counter() - t0
    print(
        f"posterior: {res.n_steps} steps x 32 walkers, tau_max {res.tau_max:.0f}, "
        f"converged={res.chain.converged}, acceptance {res.chain.acceptance:.2f}, "
        f"wall {wall:.0f} s (goal <= 300 s)"
    )
    table3 = {
        "phase": 0.001978,
        "f_gw": 5.5e-12,
        "fdot": 3.41e-19,
        "eta": 5.38244e-4,
        "kappa": 5.41031e-4,
        "omega_dot": 1.505e-9,
    }
    print(f"{'param':10s} {'post sigma':>11s} {'Fisher':>11s} {'ratio':>6s} {'Table 3':>10s}")
    s_post, s_fis = res.posterior_sigma, res.fisher_sigma
    for n in res.names:
        print(
            f"{n:10s} {s_post[n]:11.4g} {s_fis[n]:11.4g} {s_post[n] / s_fis[n]:6.3f} "
            f"{table3.get(n, float('nan')):10.4g}"
        )
    _horizons(res.posterior())


def _horizons(ptarget: Target) -> None:
    """Horizons of the posterior target against the paper's Table 4."""
    from ucbplan.core.forecast import horizon_table

    paper = {
        ("conjunction", 0.5): 390,
        ("conjunction", 1.0): 920,
        ("quadrature", 0.5): 3194,
        ("quadrature", 1.0): 4844,
    }
    for r in horizon_table(ptarget, 15.0, 1297.9):
        ref = paper[(r.anchor, r.alpha)]
        print(
            f"horizon {r.anchor:11s} alpha={r.alpha}: {r.t_valid_days:7.0f} d "
            f"(Table 4: {ref} d, {100 * (r.t_valid_days / ref - 1):+.1f} %)"
        )


if __name__ == "__main__":
    main()
