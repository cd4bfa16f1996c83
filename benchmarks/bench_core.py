"""Core throughput: t★ inversion (epochs/s) against a peer run in the same process.

Peer: scipy.optimize.brentq per epoch on the same u(t) (bracketed a quarter orbit around the
mean-phase guess) — what one would write without a vectorised Newton. Horizons are measured in
``benchmarks/horizon.py`` (analytic roots against the grid search, and across processes).

Goal (issue 2): ≥ 10⁶ epochs/s.
Usage: ``python benchmarks/bench_core.py [--quick]`` or ``python -m benchmarks --only core``
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np
from scipy.optimize import brentq

from ucbplan.core.ephemeris import solve_u
from ucbplan.core.params import PhaseParams
from ucbplan.core.phase import u_cycles

T4 = 4 * 31558149.7635
ECC = PhaseParams(
    2.410235, 8.4062899940e-3, 1.640367e-15, 0.0, 8.249643e-3, 4.524585e-3, 1.496836e-6
)
CIRC = PhaseParams(5.500397, 6.2204944286e-3, 7.073958e-16, -1.06565e-26)
GOAL_EPOCHS_PER_S = 1e6


def measure_inversion(n_epochs: int) -> list[dict[str, object]]:
    """Epochs/s of the vectorised inversion and of a brentq-per-epoch peer, per orbit type."""
    out: list[dict[str, object]] = []
    for label, p in (("eccentric", ECC), ("circular", CIRC)):
        span = n_epochs / 2 * (2 / p.f_gw)  # quadrature: two epochs per orbit
        solve_u(p, 0.0, 1e4, 0.0)  # warm-up
        t0 = time.perf_counter()
        n = 0
        for u_star in (0.0, math.pi):
            k, _, _, _ = solve_u(p, 5e7, 5e7 + span, u_star)
            n += k.size
        ours = n / (time.perf_counter() - t0)
        peer = _brentq_rate(p, 2000)
        out.append(
            {
                "name": f"t★ inversion, {label} ({n:,} quadrature epochs)",
                "value": ours,
                "unit": "epochs/s",
                "ratio": ours / peer,
                "peer": f"scipy brentq per epoch ({peer:,.0f}/s)",
                "goal": f"≥ {GOAL_EPOCHS_PER_S:.0e} epochs/s",
                "met": bool(ours >= GOAL_EPOCHS_PER_S),
            }
        )
    return out


def _brentq_rate(p: PhaseParams, m: int) -> float:
    """Peer: brentq per epoch on the same u(t), given a good guess and a quarter-orbit bracket."""
    k, dt, _, origin = solve_u(p, 5e7, 5e7 + m / 2 * (2 / p.f_gw), 0.0)
    period = 2 / p.f_gw
    t0 = time.perf_counter()
    for kk, d in zip(k, dt, strict=True):
        guess = d + 1e-3 * period

        def f(x: float, kk: int = int(kk), p: PhaseParams = p, o: float = origin) -> float:
            mm, g = u_cycles(p, np.array([x]), o)
            return float((mm[0] - kk) + g[0])

        brentq(f, guess - period / 4, guess + period / 4, xtol=1e-12)
    return k.size / (time.perf_counter() - t0)


def rows(quick: bool) -> list[dict[str, object]]:
    """t★ inversion throughput against brentq (10⁵ epochs quick, 10⁶ full)."""
    return measure_inversion(100_000 if quick else 1_000_000)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quick", action="store_true", help="10x smaller, for CI")
    args = ap.parse_args()
    for r in rows(args.quick):
        print(f"{r['name']}: {r['value']:,.0f} {r['unit']}; {r['ratio']:,.0f}x {r['peer']}")


if __name__ == "__main__":
    main()
