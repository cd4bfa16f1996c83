"""Phase-constraint table for facilities that schedule on orbital phase (HST/JWST APT-style
``PERIOD … ZERO-PHASE … PHASE a TO b``, Phase I tools): one row per target (docs/exports.md).

Each row is a linear ephemeris at the planning epoch: the period P_b (the median of the target's
blocks), a zero-phase epoch T0 (BJD_TDB at the barycentre) placed at the target's middle block,
and the phase ranges of the planned anchors, φ★ = u★/2π ± h/P_b with h = max(k·σ_t, floor) (the
timing window as a phase). Phase 0 is u = 0 of star 1 (ascending node, maximum recession of star
1). How well that linear ephemeris holds over the planned window is stated, not assumed: the
largest difference between the linear prediction and any planned block's barycentric mid-time
(a chirping binary drifts quadratically), against h, and the plan's own ephemeris validity
(``valid_until_tdb`` in the table metadata).
"""

from __future__ import annotations

import io
import math
from typing import Any

import numpy as np
from astropy.table import Table
from astropy.time import Time, TimeDelta

from ucbplan.errors import InputFileError, shorten
from ucbplan.observing.exports.columns import floats, strings
from ucbplan.observing.exports.interface import ExportOptions, ExportResult
from ucbplan.observing.exports.provenance import clean_meta, created_utc, meta, site_name, version

_UNITS = {
    "period_s": "s",
    "t0_bjd_tdb": "d",
    "phase_half_width": "",
    "window_half_width_s": "s",
    "linear_max_error_s": "s",
}


def _phase_ranges(u_star: np.ndarray, half_phase: float) -> str:
    """``a-b`` ranges (phase in [0, 1), wrapping through 1 → 0) of the distinct anchors."""
    centres = sorted({round(float(u) / (2 * math.pi) % 1.0, 9) for u in u_star})
    return "; ".join(f"{(c - half_phase) % 1.0:.4f}-{(c + half_phase) % 1.0:.4f}" for c in centres)


def _rows(idx: np.ndarray) -> str:
    """Row numbers (1 = first data row) for a message, at most five."""
    rows = [str(int(i) + 1) for i in idx[:5]]
    return ", ".join(rows) + (", …" if len(idx) > 5 else "")


def _target_row(
    name: str, idx: np.ndarray, c: dict[str, Any], options: ExportOptions
) -> dict[str, Any]:
    tdb: Time = c["tdb"][idx]
    order = np.argsort(tdb.jd, kind="stable")
    idx, tdb = idx[order], tdb[order]
    period = float(np.nanmedian(c["period"][idx]))
    mid = len(idx) // 2
    phase = (c["u_star"][idx] / (2 * math.pi)) % 1.0
    t0 = tdb[mid] - TimeDelta(phase[mid] * period, format="sec")
    elapsed = (tdb - t0).sec
    cycles = np.round(elapsed / period - phase)
    error = elapsed - (cycles + phase) * period
    half = max(
        options.tolerance_sigma * float(np.median(c["sigma"][idx])), options.tolerance_floor_s
    )
    valid = c["valid_until"].get(name, "")
    return {
        "target": name,
        "period_s": period,
        "t0_bjd_tdb": float(t0.jd1) + float(t0.jd2),
        "t0_tdb": t0.isot,
        "phase_ranges": _phase_ranges(c["u_star"][idx], half / period),
        "phase_half_width": half / period,
        "window_half_width_s": half,
        "first_block_tdb": tdb[0].isot,
        "last_block_tdb": tdb[-1].isot,
        "linear_max_error_s": float(np.max(np.abs(error))),
        "linear_valid_over_window": bool(np.max(np.abs(error)) <= half),
        "plan_ephemeris_valid_until_tdb": str(clean_meta(valid)) if valid else "",
    }


def phase_table(table: Table, options: ExportOptions, notes: list[str]) -> Table:
    """Per-target linear phase ephemeris at the planning epoch (see the module docstring)."""
    tdb = Time(strings(table, "t_mid_tdb_bary"), scale="tdb", precision=3)
    valid = meta(table).get("valid_until_tdb")
    c = {
        "tdb": tdb,
        "period": floats(table, "period_s", unit="s"),
        "u_star": floats(table, "u_star_rad", unit="rad"),
        "sigma": floats(table, "sigma_t_s", unit="s"),
        "valid_until": valid if isinstance(valid, dict) else {},
    }
    names = strings(table, "target")
    rows = []
    for name in dict.fromkeys(names):
        idx = np.array([i for i, n in enumerate(names) if n == name])
        if not np.any(np.isfinite(c["period"][idx])):
            raise InputFileError(
                f"blocks table: column period_s: empty (NaN) in every row of target "
                f"{shorten(name, 60)} (rows {_rows(idx)}); a phase table needs the orbital "
                "period: regenerate the table with `ucbplan plan`"
            )
        row = _target_row(name, idx, c, options)
        if not row["linear_valid_over_window"]:
            notes.append(
                f"phase table: {name}: the linear ephemeris misses a planned block by "
                f"{row['linear_max_error_s']:.1f} s > the {row['window_half_width_s']:.1f} s "
                "window: split the window or use the UTC exports"
            )
        rows.append(row)
    out = Table(rows=rows, names=list(rows[0])) if rows else Table()
    for col, unit in _UNITS.items():
        if col in out.colnames and unit:
            out[col].unit = unit
    out.meta = _meta(table, options)
    return out


def _meta(table: Table, options: ExportOptions) -> dict[str, Any]:
    return {
        "ucbplan_version": version(),
        "source_created_utc": created_utc(table),
        "site": site_name(table),
        "time_scale": "t0: BJD_TDB (barycentric); ranges are orbital phase in [0, 1)",
        "phase_convention": (
            "phase = u/(2 pi) of star 1: 0 at the ascending node (maximum recession of star 1)"
        ),
        "ephemeris": (
            "linear: t(phase, n) = t0 + (n + phase) period_s; linear_max_error_s = largest "
            "difference from a planned block's barycentric mid-time"
        ),
        "window_rule": (
            f"phase_half_width = max({options.tolerance_sigma:g} sigma_t, "
            f"{options.tolerance_floor_s:g} s) / period_s"
        ),
    }


def export_phase_table(table: Table, options: ExportOptions) -> ExportResult:
    """The phase-constraint table as ECSV (read by astropy; units and rules in the header)."""
    notes: list[str] = []
    out = phase_table(table, options, notes)
    buf = io.StringIO()
    out.write(buf, format="ascii.ecsv")
    return ExportResult(buf.getvalue().encode(), ".ecsv", tuple(dict.fromkeys(notes)))
