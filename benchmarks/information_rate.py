"""Information per telescope hour (issue 20): the chosen exposure plan against the 60-s default.

For the README's targets (the simulated HM Cnc, P_b = 321 s, with X-shooter VIS's 45-s readout and
409-s acquisition; the synthetic eclipsing binary, P_b = 400 s, J1539-like) one 1-h visit is
planned twice with the same photon-limited σ_v law (30 km/s in 300 s): once with the exposure
time and strategy ucbplan chooses, once with the 60-s default exposure on the same anchors. The
value is the information on K the chosen plan's rows collect, Σ(Λ_K cos u)²/σ_v² [(km/s)⁻²]; the
ratio is chosen / default (> 1: the choice buys more per hour). A second row per target gives the
phase model's gain in hours to σ_K = 2 km/s (untargeted / best targeted strategy).
"""

from __future__ import annotations

from typing import Any

#: (label, target file, site, first night, readout [s], acquisition [s]).
CASES = (
    ("HM Cnc (simulated)", "catalogs/hm-cnc-simulated.yaml", "paranal", "2040-02-15", 45.0, 409.0),
    ("synthetic eclipsing", "catalogs/examples/synthetic-eclipsing.yaml", "paranal", "2026-02-15",
     45.0, 409.0),
)  # fmt: skip
SIGMA = "30km/s@300s"


def _info(run: Any) -> float:
    from ucbplan.observing.precision.strategy import information

    rows = run.result.blocks
    return information(
        [b.lambda_k for b in rows], [b.u_star_rad for b in rows], [b.sigma_v_kms for b in rows]
    )


def _plan(path: str, site: str, night: str, readout: float, acq: float, **kw: Any) -> Any:
    from ucbplan.observing.schedule import plan_files
    from ucbplan.observing.schedule.options import plan_settings

    settings = plan_settings(visit="1h", readout_s=readout, overhead_s=acq, sigma_v_kms=SIGMA, **kw)
    return plan_files([path], first_night=night, site=site, settings=settings)


def rows(quick: bool) -> list[dict[str, object]]:
    """Two rows per README target (see the module notes); quick and full are the same size."""
    from ucbplan.observing.schedule.compare import compare_target_strategies
    from ucbplan.observing.schedule.options import plan_settings
    from ucbplan.offline import offline
    from ucbplan.targets import load_target

    out: list[dict[str, object]] = []
    with offline():
        for label, path, site, night, readout, acq in CASES:
            chosen = _plan(path, site, night, readout, acq)
            default = _plan(path, site, night, readout, acq, exptime_s=60.0, cadence="targeted")
            te = chosen.result.exposures[chosen.targets[0].name]
            got, base = _info(chosen), _info(default)
            out.append(
                {
                    "name": f"information per 1-h visit, {label}",
                    "value": got,
                    "unit": "(km/s)^-2",
                    "peer": "the 60-s default exposure, same σ_v law and anchors",
                    "ratio": got / base if base > 0 else float("nan"),
                    "goal": "> 1 (the choice buys more per hour)",
                    "met": got > base,
                    "note": f"{te.strategy}, {te.plan.exptime_s:.0f}-s exposures; σ_v {SIGMA}, "
                    f"readout {readout:g} s, acquisition {acq:g} s",
                }
            )
            settings = plan_settings(readout_s=readout, overhead_s=acq, sigma_v_kms=SIGMA,
                                     goal="sigma_K=2km/s")  # fmt: skip
            cmp = compare_target_strategies(load_target(path), settings)
            ratio = cmp.ratio()
            out.append(
                {
                    "name": f"hours to σ_K = 2 km/s, {label}",
                    "value": cmp.best.hours or float("nan"),
                    "unit": "h",
                    "peer": "untargeted (no phase model), its best exposure time",
                    "ratio": ratio if ratio is not None else float("nan"),
                    "goal": "> 1 (the phase model saves time)",
                    "met": ratio is not None and ratio > 1,
                    "note": f"best: {cmp.best.name}, {cmp.best.exptime_s:.0f}-s exposures, "
                    "visits ≤ 2 h",
                }
            )
    return out
