"""Like-for-like against GBGPU (Katz et al.; ``pip install gbgpu``, CPU backend), never a
dependency of ucbplan.

The same work on both sides, in one process, timed in alternating windows: 100 eccentric
sources × 4 lines = 400 lines at N = 512 over the fiducial's T and sky. GBGPU computes each
line as a circular source (its ``run_wave``, one batched call of 400); ours computes the 100
four-line sources in one batched call (3 bands, TDI A and E). GBGPU's CPU backend is single
threaded here (its CPU time equals its wall time); ours uses one core. Goal (issue 14): ≥ 10×.
Usage: ``python -m benchmarks --only gbgpu [--quick]``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

GOAL = 10.0
N_SOURCES = 100


def _gbgpu_call(model: Any, params: dict[str, np.ndarray], lon: float, lat: float) -> Any:
    """GBGPU's batched run_wave over the 4 lines of every source, as circular sources."""
    from gbgpu.gbgpu import GBGPU

    from ucbplan.lisa.source import LINES, line_frequencies

    gb = GBGPU(force_backend="cpu")
    t_obs = model.grid.t_obs_s
    f_lines = line_frequencies(params["f_gw"], params["omega_dot"])  # (4, S)
    half = np.array([0.5 * line.harmonic for line in LINES])[:, None]
    n = f_lines.size
    args = [
        np.repeat(params["amplitude"][None], 4, axis=0).ravel(),
        f_lines.ravel(),
        (half * params["fdot"][None]).ravel(),
        np.zeros(n),
        (half * params["phase"][None]).ravel(),
        np.repeat(np.arccos(params["cos_inclination"])[None], 4, axis=0).ravel(),
        np.repeat(params["psi"][None], 4, axis=0).ravel(),
        np.full(n, lon),
        np.full(n, lat),
    ]

    def call() -> None:
        gb.run_wave(*args, N=model.grid.n, T=t_obs, dt=10.0)

    return call


def rows(quick: bool) -> list[dict[str, object]]:
    """Ratio of GBGPU's time for 400 lines to ours for the same 100 four-line sources."""
    from benchmarks.waveform import _best_rates, setup

    try:
        import gbgpu  # noqa: F401
    except ImportError:
        return [
            {
                "name": "GBGPU like-for-like (400 lines, N=512, batched)",
                "value": float("nan"),
                "note": "gbgpu is not installed here (pip install gbgpu): no ratio measured",
            }
        ]
    from benchmarks.posterior import INJECTION
    from ucbplan.lisa.response import ecliptic_from_icrs
    from ucbplan.targets import load_target

    _, ours, _, params, _ = setup(N_SOURCES)
    target = load_target(INJECTION)
    lon, lat = ecliptic_from_icrs(target.ra_deg, target.dec_deg)
    peer = _gbgpu_call(ours, params, lon, lat)
    window, rounds = (0.5, 3) if quick else (2.0, 5)
    r = _best_rates({"gbgpu": peer, "ours": lambda: ours.bands(**params)}, 1, window, rounds)
    ratio = r["ours"] / r["gbgpu"]
    return [
        {
            "name": "100 eccentric sources (400 lines), N=512, one batched call",
            "value": 1.0 / r["ours"],
            "unit": "s per call",
            "ratio": ratio,
            "peer": f"GBGPU run_wave CPU, 400 circular lines ({1.0 / r['gbgpu']:.3g} s)",
            "goal": f"≥ {GOAL:g}×",
            "met": bool(ratio >= GOAL),
            "note": "one core each; ours shares the fixed sky's response across sources and "
            "lines (a targeted search), GBGPU recomputes it per line (any sky)",
        }
    ]
