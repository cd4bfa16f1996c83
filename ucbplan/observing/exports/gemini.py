"""Gemini timing windows: one observation per visit, a window on its start (docs/exports.md).

Each observation is one acquisition and then the visit's exposures (a sequence step repeated
``repeat`` times per exposure time), with their count, shutter time and planned starts.

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
)
from ucbplan.observing.exports.interface import ExportOptions, ExportResult
from ucbplan.observing.exports.provenance import created_utc, site_name, version
from ucbplan.observing.exports.queue import queue_note, untargeted
from ucbplan.observing.exports.text import iso_ms
from ucbplan.observing.exports.visitgroups import ExportUnit, export_units, exposure_runs
from ucbplan.observing.exports.windows import (
    ROUNDING_REMEDY,
    ceil_minute,
    floor_minute,
    ob_start_window,
)


def _window(lo: datetime, hi: datetime) -> dict[str, Any]:
    minutes = round((hi - lo).total_seconds() / 60)
    return {
        "inclusion": "INCLUDE",
        "start_utc": lo.strftime("%Y-%m-%d %H:%M:%S"),
        "duration": f"{minutes // 60:02d}:{minutes % 60:02d}",
        "duration_minutes": minutes,
        "repeat": None,
    }


def _sequence(unit: ExportUnit) -> dict[str, Any]:
    """The unit's exposures: total count and time, the sequence steps and their repeats, and
    each exposure's planned start (UTC)."""
    runs = exposure_runs(unit)
    return {
        "exposure_time_s": runs[0][0] if len(runs) == 1 else None,
        "exposure_count": unit.n_exposures,
        "shutter_s": unit.shutter_s,
        "sequence": [{"exposure_time_s": t, "repeat": n} for t, n in runs],
        "exposure_starts_utc": [iso_ms(t) for t in unit.starts],
    }


def gemini_windows(table: Table, options: ExportOptions, notes: list[str]) -> list[dict[str, Any]]:
    """One observation per visit (:func:`~.visitgroups.export_units`) in time order: its
    blocks, its start, its exposures and the timing window on its start."""
    mids = required_times(table, "t_mid_utc")
    sigma = floats(table, "sigma_t_s", unit="s")
    acq = acquisition_s(table, options, notes)
    period = period_s(table, notes)
    blocks = strings(table, "block_id")
    units = export_units(table, options)
    notes += queue_note(table, units, "Gemini", options)
    out = []
    for unit in units:
        i = unit.rows[0]
        w = ob_start_window(unit.start, float(acq[i]), float(sigma[i]), options)
        lo, hi = floor_minute(w.lo), ceil_minute(w.hi)
        widening = (hi - lo).total_seconds() - 2 * w.half_width_s
        costly = widening > options.rounding_warn_fraction * period[i]
        if math.isfinite(period[i]) and costly and not untargeted(table, unit.target):
            notes.append(
                f"Gemini {blocks[i]}: minute rounding widens the start window by {widening:.0f} s "
                f"= {widening / period[i]:.2f} P_b; {ROUNDING_REMEDY}"
            )
        out.append(
            {
                "target": unit.target,
                "visit_id": unit.unit_id,
                "block_ids": [blocks[j] for j in unit.rows],
                "t_mid_utc": iso_ms(mids[i]),
                "sigma_t_s": float(sigma[i]),
                "observation_start_utc": iso_ms(w.ob_start),
                "acquisition_s": float(acq[i]),
                **_sequence(unit),
                "window_half_width_s": w.half_width_s,
                "timing_window": _window(lo, hi),
            }
        )
    return out


def export_gemini(table: Table, options: ExportOptions) -> ExportResult:
    """Gemini timing-window JSON (see :func:`gemini_windows`)."""
    notes: list[str] = []
    doc = {
        "format": "ucbplan gemini timing windows, version 2",
        "ucbplan_version": version(),
        "source_created_utc": created_utc(table),
        "site": site_name(table),
        "time_scale": "UTC at the site; each window constrains the observation start",
        "window_rule": (
            "observation start = t_start_utc - acquisition_s; window = start +/- "
            f"max({options.tolerance_sigma:g} sigma_t, {options.tolerance_floor_s:g} s), "
            "rounded outward to whole minutes; no repeats; one observation per visit"
        ),
        "observations": gemini_windows(table, options, notes),
    }
    text = dumps_json(doc) + "\n"
    return ExportResult(text.encode(), ".json", tuple(dict.fromkeys(notes)))
