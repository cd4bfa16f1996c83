"""Proposal technical-section table from a blocks table (docs/exports.md, "Proposal table").

One row per target: coordinates, magnitude, P_orb, the ephemeris file, σ_T at the semester
midpoint, the anchor phases and their tolerance, windows per month, visits and exposures, shutter,
overheads and idle time (from the plan's own time accounting, else from the blocks:
:mod:`ucbplan.observing.blocks.accounting`), efficiency, the time-critical flag and the constraints.
The LaTeX form is written by :mod:`.proposal_latex`.

Decisions where the issue is silent: the semester is the observatory's own (``--semester 2041A``
or ``P147``; default: the one containing the plan's first night, an ESO period for a plan made
for an ESO site); σ_T at the semester midpoint (its middle date, 00:00 UTC) is linearly
interpolated between the target's blocks (held at the first/last block outside them); windows per
month = visits divided by the calendar months the table spans; the phase tolerance is the
``tol_rad`` column, else the timing window as a phase, 2π·half-width/P_b; every phase-targeted
target is time critical.
"""

from __future__ import annotations

import datetime as dt
import io
import math
from collections import Counter
from collections.abc import Mapping
from dataclasses import dataclass
from datetime import UTC, datetime, timedelta
from typing import Any
from zoneinfo import ZoneInfo

import numpy as np
from astropy.table import MaskedColumn, Table

from ucbplan.core.constants import HOUR_S
from ucbplan.errors import InputFileError, shorten
from ucbplan.observing.blocks.accounting import BlockRows, TimeAccount, accounts_from_blocks
from ucbplan.observing.blocks.cells import sexagesimal
from ucbplan.observing.blocks.write import csv_safe_table
from ucbplan.observing.exports.columns import (
    acquisition_s,
    coordinates,
    floats,
    period_s,
    readout_total_s,
    required_times,
    strings,
    vmags,
)
from ucbplan.observing.exports.format_sites import serves_site
from ucbplan.observing.exports.interface import ExportOptions, ExportResult
from ucbplan.observing.exports.proposal_latex import proposal_latex
from ucbplan.observing.exports.provenance import clean_meta, created_utc, meta, version
from ucbplan.observing.exports.text import iso_ms
from ucbplan.observing.observatory.semesters import semester_dates, semester_label

#: Proposal table formats (``--format``) and the file suffix of each.
PROPOSAL_SUFFIXES = {"ecsv": ".ecsv", "csv": ".csv", "latex": ".tex"}
PROPOSAL_FORMATS = tuple(PROPOSAL_SUFFIXES)

_UNITS = {
    "p_orb_min": "min",
    "sigma_t_mid_s": "s",
    "tolerance_rad": "rad",
    "window_half_width_s": "s",
    "exposure_per_visit_s": "s",
    "overhead_per_visit_s": "s",
    "idle_per_visit_s": "s",
    "integration_h": "h",
    "overhead_h": "h",
    "idle_h": "h",
    "total_h": "h",
    "vmag": "mag",
}
#: Columns written blank (masked) where the number is not known, never as NaN.
_MAY_BE_BLANK = ("vmag", "p_orb_min", "tolerance_rad")


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
    period: np.ndarray
    ra: np.ndarray
    dec: np.ndarray
    vmag: np.ndarray
    tol: np.ndarray
    starts: list[datetime]
    mids: np.ndarray


def _columns(table: Table, notes: list[str]) -> _Columns:
    sessions, blocks = strings(table, "session_id"), strings(table, "block_id")
    ra, dec = coordinates(table)
    return _Columns(
        names=strings(table, "target"),
        anchors=strings(table, "anchor"),
        visit=[s or f"block {b}" for s, b in zip(sessions, blocks, strict=True)],
        u_star=floats(table, "u_star_rad", unit="rad"),
        sigma=floats(table, "sigma_t_s", unit="s"),
        period=period_s(table, notes),
        ra=ra,
        dec=dec,
        vmag=vmags(table, notes),
        tol=floats(table, "tol_rad", default=math.nan),
        starts=required_times(table, "t_start_utc"),
        mids=_seconds(required_times(table, "t_mid_utc")),
    )


def _tolerance_rad(tol: np.ndarray, half_width_s: float, period: float) -> float:
    """The ``tol_rad`` column's median, else the timing window as a phase, 2π·h/P_b."""
    given = _nanmedian(tol)
    return given if math.isfinite(given) else 2.0 * math.pi * half_width_s / period


def _target_row(
    c: _Columns,
    idx: np.ndarray,
    t_mid_sem: float,
    months: int,
    account: TimeAccount,
    options: ExportOptions,
) -> dict[str, Any]:
    """One proposal row; visits, exposures and times come from ``account``."""
    srt = idx[np.argsort(c.mids[idx], kind="stable")]
    first_of_visit = {c.visit[i]: int(i) for i in srt[::-1]}  # earliest block of each visit
    by_month = Counter(c.starts[i].strftime("%Y-%m") for i in first_of_visit.values())
    sigma_mid = float(np.interp(t_mid_sem, c.mids[srt], c.sigma[srt]))
    half = max(options.tolerance_sigma * sigma_mid, options.tolerance_floor_s)
    period = _nanmedian(c.period[idx])
    visits = max(account.visits, 1)
    return {
        "target": c.names[idx[0]],
        "ra_hms": sexagesimal(c.ra[idx[0]] / 15.0, 2, ":", False),
        "dec_dms": sexagesimal(c.dec[idx[0]], 1, ":", True),
        "vmag": float(c.vmag[idx[0]]),
        "p_orb_min": period / 60.0,
        "sigma_t_mid_s": sigma_mid,
        "anchors": _anchor_text([c.anchors[i] for i in srt], c.u_star[srt]),
        "tolerance_rad": _tolerance_rad(c.tol[idx], half, period),
        "window_half_width_s": half,
        "n_blocks": len(idx),
        "n_visits": account.visits,
        "n_exposures": account.exposures,
        "windows_per_month": account.visits / months,
        "windows_by_month": " ".join(f"{k}:{v}" for k, v in sorted(by_month.items())),
        "exposure_per_visit_s": account.shutter_s / visits,
        "overhead_per_visit_s": account.overhead_s / visits,
        "idle_per_visit_s": account.idle_s / visits,
        "integration_h": account.shutter_s / HOUR_S,
        "overhead_h": account.overhead_s / HOUR_S,
        "idle_h": account.idle_s / HOUR_S,
        "total_h": account.total_s / HOUR_S,
        "efficiency": account.efficiency,
        "time_critical": True,
    }


def _night_date(t: datetime, site: Any) -> dt.date:
    """Local date of the evening of the night holding ``t``: (local time − 12 h).date(), in the
    site's time zone (else the longitude's mean solar time, else UTC)."""
    site = site if isinstance(site, dict) else {}
    try:
        local = t.astimezone(ZoneInfo(str(site["timezone"])))
    except (KeyError, ValueError, OSError):
        lon = site.get("lon_deg")
        hours = float(lon) / 15.0 if isinstance(lon, int | float) and math.isfinite(lon) else 0.0
        local = t + timedelta(hours=hours)
    return (local - timedelta(hours=12)).date()


def _semester(
    table: Table, starts: list[datetime], options: ExportOptions, notes: list[str]
) -> tuple[str, dt.date, dt.date]:
    """The semester (label, first date, end date): ``options.semester``, else the one of the
    plan's first night (an ESO period for a plan made for an ESO site)."""
    site = meta(table).get("site")
    nights = [_night_date(t, site) for t in starts]
    label = options.semester or semester_label(min(nights), serves_site(site, "eso-p2"))
    first, end = semester_dates(label)
    outside = sum(not first <= n < end for n in nights)
    if outside:
        notes.append(
            f"proposal: {outside} of {len(nights)} blocks fall outside semester {label} "
            f"({first} to {end - timedelta(days=1)}); pass --semester to choose another"
        )
    return label.strip().upper(), first, end


def _blank_unknown(out: Table) -> None:
    """Unknown numbers (NaN) become blank cells, so that every number written is finite."""
    for col in _MAY_BE_BLANK:
        values = np.asarray(out[col], dtype=float)
        if not np.all(np.isfinite(values)):
            out[col] = MaskedColumn(values, mask=~np.isfinite(values), unit=out[col].unit)


def proposal_table(table: Table, options: ExportOptions, notes: list[str]) -> Table:
    """Summarise a blocks table per target for a proposal's technical section.

    Parameters
    ----------
    table : astropy.table.Table
        Master blocks table (``ucbplan plan -o``).
    options : ExportOptions
        Acquisition overhead, tolerance rule (k·σ_t) and ``semester``.
    notes : list of str
        Receives one note per default taken.

    Returns
    -------
    astropy.table.Table
        One row per target in order of first appearance; semester, totals and rules in ``meta``.
        Every number is finite; an unknown magnitude, period or tolerance is blank (masked).
    """
    c = _columns(table, notes)
    accounts, source = _plan_accounting(table, options, notes)
    label, first, end = _semester(table, c.starts, options, notes)
    sem_mid = datetime.combine(first + (end - first) / 2, dt.time(), tzinfo=UTC)
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
        row = _target_row(c, idx, t_mid_sem, months, accounts[name], options)
        row["ephemeris"] = " ".join(str(clean_meta(meta_t.get(name, {}).get("file") or "")).split())
        row["constraints"] = constraints
        rows.append(row)
    if any(not math.isfinite(r["vmag"]) for r in rows):
        notes.append("no vmag for some targets: magnitude left blank (add vmag to the target file)")
    out = Table(rows=rows, names=list(rows[0]))
    for col, unit in _UNITS.items():
        out[col].unit = unit
    _blank_unknown(out)
    total = sum(accounts.values(), TimeAccount(0, 0, 0.0, 0.0, 0.0))
    out.meta = _summary_meta(table, total, source, (label, first, end, sem_mid), options)
    return out


def _summary_meta(
    table: Table,
    total: TimeAccount,
    source: str,
    semester: tuple[str, dt.date, dt.date, datetime],
    options: ExportOptions,
) -> dict[str, Any]:
    """Provenance, the semester, the rules applied and the totals [h]."""
    label, first, end, sem_mid = semester
    return {
        "ucbplan_version": version(),
        "source_created_utc": created_utc(table),
        "site": clean_meta(meta(table).get("site", "")),
        "semester": label,
        "semester_first_night": first.isoformat(),
        "semester_last_night": (end - timedelta(days=1)).isoformat(),
        "semester_mid_utc": iso_ms(sem_mid, 0),
        "sigma_t_mid_rule": (
            "sigma_T linearly interpolated between the target's blocks at the semester midpoint "
            "(held at the first/last block outside them)"
        ),
        "time_source": (
            "the plan's time_accounting"
            if source == "plan"
            else "the blocks: a visit is a planner session (one acquisition) or a lone block; "
            "overheads = acquisition per visit + readout of every exposure; idle = waits "
            "between the blocks of a visit"
        ),
        "window_rule": (
            f"window_half_width_s = max({options.tolerance_sigma:g} sigma_T, "
            f"{options.tolerance_floor_s:g} s) at the semester midpoint; tolerance_rad from "
            "a tol_rad column, else 2 pi window_half_width_s / P_b"
        ),
        "n_visits": total.visits,
        "n_exposures": total.exposures,
        "total_integration_h": total.shutter_s / HOUR_S,
        "total_overhead_h": total.overhead_s / HOUR_S,
        "total_idle_h": total.idle_s / HOUR_S,
        "total_h": total.total_s / HOUR_S,
        "efficiency": total.efficiency,
        "time_scale": "UTC at the site",
    }


def write_proposal(summary: Table, fmt: str) -> str:
    """Serialise the proposal table as ``ecsv``, ``csv`` or ``latex``.

    Raises
    ------
    InputFileError
        For an unknown format.
    """
    if fmt not in PROPOSAL_FORMATS:
        raise InputFileError(f"format: got {fmt!r}, expected one of {', '.join(PROPOSAL_FORMATS)}")
    if fmt == "latex":
        return proposal_latex(summary)
    buf = io.StringIO()
    if fmt == "ecsv":
        summary.write(buf, format="ascii.ecsv")
    else:
        plain = csv_safe_table(summary)  # no formula cells (issue 33)
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


def _block_rows(table: Table, options: ExportOptions, notes: list[str]) -> BlockRows:
    """The columns the accounting from the blocks reads (documented defaults noted)."""
    n_exp = floats(table, "n_exp")
    return BlockRows(
        strings(table, "target"),
        strings(table, "session_id"),
        strings(table, "block_id"),
        required_times(table, "t_start_utc"),
        required_times(table, "t_end_utc"),
        n_exp,
        n_exp * floats(table, "exptime_s", unit="s"),
        readout_total_s(table, notes),
        acquisition_s(table, options, notes),
    )


def _plan_accounting(
    table: Table, options: ExportOptions, notes: list[str]
) -> tuple[dict[str, TimeAccount], str]:
    """Per-target accounts and where they come from (``"plan"`` or ``"blocks"``).

    The plan's own ``meta['time_accounting']`` when it covers every target of the table, else
    :func:`~ucbplan.observing.blocks.accounting.accounts_from_blocks` (with a note). A plan account
    whose shutter time differs from the blocks' by more than 1 % gets a note (the table was edited
    after planning).

    Raises
    ------
    InputFileError
        A ``time_accounting`` entry that is not a mapping of non-negative numbers.
    """
    from_blocks = accounts_from_blocks(_block_rows(table, options, notes))
    given = meta(table).get("time_accounting")
    targets = given.get("targets") if isinstance(given, Mapping) else None
    if not isinstance(targets, Mapping) or not set(from_blocks) <= set(map(str, targets)):
        notes.append(
            "proposal: no time_accounting for every target in the plan's metadata: time "
            "computed from the blocks (idle gaps within a visit included; docs/exports.md)"
        )
        return from_blocks, "blocks"
    out = {
        name: TimeAccount.from_meta(f"targets.{shorten(name, 40)}", targets[name])
        for name in from_blocks
    }
    for name, account in out.items():
        ref = from_blocks[name].shutter_s
        if abs(account.shutter_s - ref) > 0.01 * max(ref, 1.0):
            notes.append(
                f"proposal: {shorten(name, 40)}: the plan accounts {account.shutter_s:.0f} s "
                f"shutter time but its blocks hold {ref:.0f} s (table edited after planning?)"
            )
    return out, "plan"
