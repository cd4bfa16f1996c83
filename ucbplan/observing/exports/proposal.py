"""Proposal technical-section table, ING catalogue and LCO request JSON from a blocks table.

One row per target: coordinates, magnitude, P_orb, the ephemeris file, σ_T at the semester
midpoint, the anchor phases and their tolerance, usable windows per month, exposure and overheads
per visit, visits, hours (total = integration + overheads), the time-critical flag and the
constraints (docs/exports.md, "Proposal technical section").

Decisions where the issue is silent: the "semester" is the span of the blocks table (first block
start to last block end) and σ_T at its midpoint is linearly interpolated in time between the
target's blocks; windows per month = visits divided by the calendar months the table spans; every
phase-targeted target is time critical.
"""

from __future__ import annotations

import io
import math
from collections import Counter
from dataclasses import dataclass
from datetime import UTC, datetime
from typing import Any

import numpy as np
from astropy.table import Table

from ucbplan.errors import InputFileError
from ucbplan.observing.exports.base import (
    ExportOptions,
    ExportResult,
    acquisition_s,
    clean_meta,
    coordinates,
    created_utc,
    floats,
    fmt_sigma,
    iso_ms,
    meta,
    period_s,
    readout_total_s,
    required_times,
    sexagesimal,
    strings,
    version,
    vmags,
)

__all__ = [
    "PROPOSAL_FORMATS",
    "export_proposal",
    "proposal_table",
    "write_proposal",
]

#: Proposal table formats (``--format``) and the file suffix of each.
PROPOSAL_SUFFIXES = {"ecsv": ".ecsv", "csv": ".csv", "latex": ".tex"}
PROPOSAL_FORMATS = tuple(PROPOSAL_SUFFIXES)

#: LaTeX display names (astropy's LaTeX writer does not escape column names).
_LATEX_COLUMNS = {
    "target": "Target",
    "ra_hms": r"RA (J2000)",
    "dec_dms": r"Dec (J2000)",
    "vmag": r"$V$ [mag]",
    "p_orb_min": r"$P_\mathrm{orb}$ [min]",
    "sigma_t_mid_s": r"$\sigma_T$ [s]",
    "anchors": r"Phases $u_\star$ [rad]",
    "n_visits": "Visits",
    "windows_per_month": "Windows/month",
    "exposure_per_visit_s": r"$t_\mathrm{exp}$/visit [s]",
    "overhead_per_visit_s": "Overheads/visit [s]",
    "total_h": "Total [h]",
}

_UNITS = {
    "p_orb_min": "min",
    "sigma_t_mid_s": "s",
    "tolerance_rad": "rad",
    "window_half_width_s": "s",
    "exposure_per_visit_s": "s",
    "overhead_per_visit_s": "s",
    "integration_h": "h",
    "overhead_h": "h",
    "total_h": "h",
    "vmag": "mag",
}


def _seconds(ts: list[datetime]) -> np.ndarray:
    epoch = datetime(2000, 1, 1, tzinfo=UTC)
    return np.array([(t - epoch).total_seconds() for t in ts])


def _meta_targets(table: Table) -> dict[str, dict[str, Any]]:
    items = meta(table).get("targets", [])
    items = items if isinstance(items, list) else []
    return {str(clean_meta(t.get("name"))): dict(t) for t in items if isinstance(t, dict)}


def _months(ts: list[datetime]) -> int:
    first, last = min(ts), max(ts)
    return (last.year - first.year) * 12 + last.month - first.month + 1


def _nanmedian(values: np.ndarray) -> float:
    finite = values[np.isfinite(values)]
    return float(np.median(finite)) if finite.size else math.nan


def _anchor_text(anchors: list[str], u_star: np.ndarray) -> str:
    groups: dict[str, list[float]] = {}
    for a, u in zip(anchors, u_star, strict=True):
        values = groups.setdefault(a, [])
        if not any(abs(u - v) < 1e-9 for v in values):
            values.append(float(u))
    return "; ".join(f"{a} {','.join(f'{v:.4g}' for v in sorted(vs))}" for a, vs in groups.items())


@dataclass(frozen=True, slots=True)
class _Columns:
    """Per-block arrays the proposal summary needs (defaults already applied)."""

    names: list[str]
    anchors: list[str]
    visit: list[str]
    u_star: np.ndarray
    sigma: np.ndarray
    exposure: np.ndarray
    acquisition: np.ndarray
    readout: np.ndarray
    period: np.ndarray
    ra: np.ndarray
    dec: np.ndarray
    vmag: np.ndarray
    tol: np.ndarray
    starts: list[datetime]
    mids: np.ndarray


def _columns(table: Table, options: ExportOptions, notes: list[str]) -> _Columns:
    sessions, blocks = strings(table, "session_id"), strings(table, "block_id")
    ra, dec = coordinates(table)
    return _Columns(
        names=strings(table, "target"),
        anchors=strings(table, "anchor"),
        visit=[s or f"block {b}" for s, b in zip(sessions, blocks, strict=True)],
        u_star=floats(table, "u_star_rad", unit="rad"),
        sigma=floats(table, "sigma_t_s", unit="s"),
        exposure=floats(table, "n_exp") * floats(table, "exptime_s", unit="s"),
        acquisition=acquisition_s(table, options, notes),
        readout=readout_total_s(table, notes),
        period=period_s(table, notes),
        ra=ra,
        dec=dec,
        vmag=vmags(table, notes),
        tol=floats(table, "tol_rad", default=math.nan),
        starts=required_times(table, "t_start_utc"),
        mids=_seconds(required_times(table, "t_mid_utc")),
    )


def _target_row(
    c: _Columns, idx: np.ndarray, t_mid_sem: float, months: int, options: ExportOptions
) -> dict[str, Any]:
    """One proposal row; a visit is a planner session (one acquisition) or a lone block."""
    srt = idx[np.argsort(c.mids[idx], kind="stable")]
    first_of_visit = {c.visit[i]: int(i) for i in srt[::-1]}  # earliest block of each visit
    visits = sorted(first_of_visit.values(), key=lambda i: c.mids[i])
    n_visits = len(visits)
    by_month = Counter(c.starts[i].strftime("%Y-%m") for i in visits)
    overhead = float(np.sum(c.acquisition[visits])) + float(np.sum(c.readout[idx]))
    exposure = float(np.sum(c.exposure[idx]))
    sigma_mid = float(np.interp(t_mid_sem, c.mids[srt], c.sigma[srt]))
    return {
        "target": c.names[idx[0]],
        "ra_hms": sexagesimal(c.ra[idx[0]] / 15.0, 2, ":", False),
        "dec_dms": sexagesimal(c.dec[idx[0]], 1, ":", True),
        "vmag": float(c.vmag[idx[0]]),
        "p_orb_min": _nanmedian(c.period[idx]) / 60.0,
        "sigma_t_mid_s": sigma_mid,
        "anchors": _anchor_text([c.anchors[i] for i in srt], c.u_star[srt]),
        "tolerance_rad": _nanmedian(c.tol[idx]),
        "window_half_width_s": max(options.tolerance_sigma * sigma_mid, options.tolerance_floor_s),
        "n_blocks": len(idx),
        "n_visits": n_visits,
        "windows_per_month": n_visits / months,
        "windows_by_month": " ".join(f"{k}:{v}" for k, v in sorted(by_month.items())),
        "exposure_per_visit_s": exposure / n_visits,
        "overhead_per_visit_s": overhead / n_visits,
        "integration_h": exposure / 3600.0,
        "overhead_h": overhead / 3600.0,
        "total_h": (exposure + overhead) / 3600.0,
        "time_critical": True,
    }


def proposal_table(table: Table, options: ExportOptions, notes: list[str]) -> Table:
    """Summarise a blocks table per target for a proposal's technical section.

    Parameters
    ----------
    table : astropy.table.Table
        Master blocks table (``ucbplan plan -o``).
    options : ExportOptions
        Acquisition overhead and tolerance rule (k·σ_t) used for the timing tolerance column.
    notes : list of str
        Receives one note per default taken.

    Returns
    -------
    astropy.table.Table
        One row per target in order of first appearance; totals and rules in ``meta``. A visit
        is a planner session (blocks sharing ``session_id``: one acquisition) or a lone block;
        overheads = one acquisition per visit + the readout inside every block.
    """
    c = _columns(table, options, notes)
    ends = required_times(table, "t_end_utc")
    sem_start, sem_end = min(c.starts), max(ends)
    sem_mid = sem_start + (sem_end - sem_start) / 2
    t_mid_sem = float(_seconds([sem_mid])[0])
    months = _months(c.starts)
    meta_t = _meta_targets(table)
    listed = meta(table).get("constraints", [])
    constraints = "; ".join(
        " ".join(str(clean_meta(x)).split()) for x in (listed if isinstance(listed, list) else [])
    )
    rows: list[dict[str, Any]] = []
    for name in dict.fromkeys(c.names):
        idx = np.array([i for i, n in enumerate(c.names) if n == name])
        row = _target_row(c, idx, t_mid_sem, months, options)
        row["ephemeris"] = " ".join(str(clean_meta(meta_t.get(name, {}).get("file") or "")).split())
        row["constraints"] = constraints
        rows.append(row)
    if any(not math.isfinite(r["vmag"]) for r in rows):
        notes.append("no vmag for some targets: magnitude left blank (add vmag to the target file)")
    out = Table(rows=rows, names=list(rows[0]))
    for col, unit in _UNITS.items():
        out[col].unit = unit
    out.meta = _summary_meta(table, out, (sem_start, sem_mid, sem_end), options)
    return out


def _summary_meta(
    table: Table,
    summary: Table,
    semester: tuple[datetime, datetime, datetime],
    options: ExportOptions,
) -> dict[str, Any]:
    """Provenance, the semester (start, mid, end UTC), the rules applied and the totals [h]."""
    sem_start, sem_mid, sem_end = semester
    return {
        "ucbplan_version": version(),
        "source_created_utc": created_utc(table),
        "site": clean_meta(meta(table).get("site", "")),
        "semester_start_utc": iso_ms(sem_start, 0),
        "semester_end_utc": iso_ms(sem_end, 0),
        "semester_mid_utc": iso_ms(sem_mid, 0),
        "sigma_t_mid_rule": "sigma_T linearly interpolated between the target's blocks at mid",
        "overheads_rule": (
            "a visit is a planner session (one acquisition) or a lone block; overheads = one "
            "acquisition per visit + readout inside every block"
        ),
        "window_rule": (
            f"window_half_width_s = max({options.tolerance_sigma:g} sigma_T, "
            f"{options.tolerance_floor_s:g} s) at the semester midpoint; tolerance_rad from "
            "a tol_rad column when the planner writes one"
        ),
        "total_integration_h": float(np.sum(summary["integration_h"])),
        "total_overhead_h": float(np.sum(summary["overhead_h"])),
        "total_h": float(np.sum(summary["total_h"])),
        "time_scale": "UTC at the site",
    }


#: LaTeX's special characters in text and how to write them.
_LATEX_SPECIAL = {
    "\\": r"\textbackslash{}",
    "_": r"\_",
    "&": r"\&",
    "%": r"\%",
    "#": r"\#",
    "$": r"\$",
    "{": r"\{",
    "}": r"\}",
    "~": r"\textasciitilde{}",
    "^": r"\textasciicircum{}",
}


def _latex_escape(text: str) -> str:
    """Text for a LaTeX table cell: special characters escaped, line breaks and other control
    characters dropped (one pass, so an escape is never escaped again)."""
    return "".join(
        _LATEX_SPECIAL.get(ch, ch)
        for ch in " ".join(text.split())
        if ch.isprintable() and not 0xD800 <= ord(ch) <= 0xDFFF
    )


def _latex(summary: Table) -> str:
    def num(v: float, fmt: str) -> str:
        return "--" if not math.isfinite(v) else format(v, fmt)

    cols: dict[str, list[str]] = {k: [] for k in _LATEX_COLUMNS}
    for r in summary:
        cols["target"].append(_latex_escape(str(r["target"])))
        cols["ra_hms"].append(str(r["ra_hms"]))
        cols["dec_dms"].append(str(r["dec_dms"]).replace("-", "$-$"))
        cols["vmag"].append(num(float(r["vmag"]), ".1f"))
        cols["p_orb_min"].append(num(float(r["p_orb_min"]), ".3f"))
        cols["sigma_t_mid_s"].append(fmt_sigma(float(r["sigma_t_mid_s"])))
        cols["anchors"].append(_latex_escape(str(r["anchors"])))
        cols["n_visits"].append(str(int(r["n_visits"])))
        cols["windows_per_month"].append(num(float(r["windows_per_month"]), ".1f"))
        cols["exposure_per_visit_s"].append(num(float(r["exposure_per_visit_s"]), ".0f"))
        cols["overhead_per_visit_s"].append(num(float(r["overhead_per_visit_s"]), ".0f"))
        cols["total_h"].append(num(float(r["total_h"]), ".2f"))
    for key in cols:
        cols[key].append("")
    cols["target"][-1] = "Total"
    cols["n_visits"][-1] = str(int(np.sum(summary["n_visits"])))
    cols["total_h"][-1] = format(float(summary.meta["total_h"]), ".2f")
    latex = Table([cols[k] for k in _LATEX_COLUMNS], names=list(_LATEX_COLUMNS.values()))
    buf = io.StringIO()
    caption = (
        r"Phase-targeted visits (times UTC at the site; $\sigma_T$ at the semester midpoint "
        + summary.meta["semester_mid_utc"].replace("T", " ")
        + r" UTC; total = integration + overheads)."
    )
    latex.write(
        buf,
        format="ascii.latex",
        latexdict={"caption": caption, "tabletype": "table*", "col_align": "lllrrrlrrrrr"},
    )
    return buf.getvalue()


def write_proposal(summary: Table, fmt: str) -> str:
    """Serialise the proposal table as ``ecsv``, ``csv`` or ``latex``.

    Raises
    ------
    InputFileError
        For an unknown format.
    """
    if fmt not in PROPOSAL_FORMATS:
        raise InputFileError(
            f"--format: got {fmt!r}, expected one of {', '.join(PROPOSAL_FORMATS)}"
        )
    if fmt == "latex":
        return _latex(summary)
    buf = io.StringIO()
    if fmt == "ecsv":
        summary.write(buf, format="ascii.ecsv")
    else:
        plain = summary.copy()
        plain.meta = {}
        plain.write(buf, format="ascii.csv")
    return buf.getvalue()


def export_proposal(table: Table, options: ExportOptions) -> ExportResult:
    """Proposal technical-section table per target as ``options.proposal_format``.

    Raises
    ------
    InputFileError
        For an unknown proposal format.
    """
    notes: list[str] = []
    summary = proposal_table(table, options, notes)
    text = write_proposal(summary, options.proposal_format)
    suffix = PROPOSAL_SUFFIXES[options.proposal_format]
    return ExportResult(text.encode("utf-8"), suffix, tuple(dict.fromkeys(notes)))
