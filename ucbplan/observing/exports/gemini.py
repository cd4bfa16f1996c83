"""Gemini timing windows: one window on the observation start per block (docs/exports.md).

A Gemini timing window is a start (UTC), a duration and an optional repeat (count, period). As for
ESO p2, the window constrains the start of the observation, which includes the acquisition:
t_start − acquisition ± max(k·σ_t, floor), rounded outward to whole minutes (Gemini's tools take
minutes). Windows do not repeat: a repeat period of whole minutes cannot follow an orbit of a few
minutes for more than a few cycles.
"""

from __future__ import annotations

import math
from datetime import datetime
from typing import Any

from astropy.table import Table

from ucbplan.io import dumps_json
from ucbplan.observing.exports.columns import (
    acquisition_s,
    floats,
    period_s,
    required_times,
    strings,
    time_order,
)
from ucbplan.observing.exports.interface import ExportOptions, ExportResult
from ucbplan.observing.exports.provenance import created_utc, site_name, version
from ucbplan.observing.exports.text import iso_ms
from ucbplan.observing.exports.windows import ceil_minute, floor_minute, ob_start_window

__all__ = ["export_gemini", "gemini_windows"]


def _window(lo: datetime, hi: datetime) -> dict[str, Any]:
    minutes = round((hi - lo).total_seconds() / 60)
    return {
        "inclusion": "INCLUDE",
        "start_utc": lo.strftime("%Y-%m-%d %H:%M:%S"),
        "duration": f"{minutes // 60:02d}:{minutes % 60:02d}",
        "duration_minutes": minutes,
        "repeat": None,
    }


def gemini_windows(table: Table, options: ExportOptions, notes: list[str]) -> list[dict[str, Any]]:
    """One entry per block in time order: the block, its observation start and timing window."""
    starts, mids = required_times(table, "t_start_utc"), required_times(table, "t_mid_utc")
    sigma = floats(table, "sigma_t_s", unit="s")
    acq = acquisition_s(table, options, notes)
    period = period_s(table, notes)
    names, blocks = strings(table, "target"), strings(table, "block_id")
    out = []
    for i in time_order(table):
        w = ob_start_window(starts[i], float(acq[i]), float(sigma[i]), options)
        lo, hi = floor_minute(w.lo), ceil_minute(w.hi)
        widening = (hi - lo).total_seconds() - 2 * w.half_width_s
        if math.isfinite(period[i]) and widening > options.rounding_warn_fraction * period[i]:
            notes.append(
                f"Gemini {blocks[i]}: minute rounding widens the start window by {widening:.0f} s "
                f"= {widening / period[i]:.2f} P_b; plan exposures covering it and select in "
                "`reduce`"
            )
        out.append(
            {
                "target": names[i],
                "block_id": blocks[i],
                "t_mid_utc": iso_ms(mids[i]),
                "sigma_t_s": float(sigma[i]),
                "observation_start_utc": iso_ms(w.ob_start),
                "acquisition_s": float(acq[i]),
                "window_half_width_s": w.half_width_s,
                "timing_window": _window(lo, hi),
            }
        )
    return out


def export_gemini(table: Table, options: ExportOptions) -> ExportResult:
    """Gemini timing-window JSON (see :func:`gemini_windows`)."""
    notes: list[str] = []
    doc = {
        "format": "ucbplan gemini timing windows, version 1",
        "ucbplan_version": version(),
        "source_created_utc": created_utc(table),
        "site": site_name(table),
        "time_scale": "UTC at the site; each window constrains the observation start",
        "window_rule": (
            "observation start = t_start_utc - acquisition_s; window = start +/- "
            f"max({options.tolerance_sigma:g} sigma_t, {options.tolerance_floor_s:g} s), "
            "rounded outward to whole minutes; no repeats"
        ),
        "observations": gemini_windows(table, options, notes),
    }
    text = dumps_json(doc) + "\n"
    return ExportResult(text.encode(), ".json", tuple(dict.fromkeys(notes)))
