"""ESO p2: absolute time windows on the OB start, one OB per visit (docs/exports.md).

p2 takes absolute time constraints as ``YYYY-MM-DDTHH:MM`` UTC (whole minutes), so each window
on the OB start is rounded outward to whole minutes; windows must not overlap.
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass
from datetime import datetime
from typing import Any

import numpy as np
from astropy.table import Table

from ucbplan.errors import InputFileError, UcbplanError, shorten
from ucbplan.io import dumps_json
from ucbplan.observing.blocks.cells import sexagesimal
from ucbplan.observing.exports.columns import (
    acquisition_s,
    coordinates,
    floats,
    period_s,
    required_times,
    strings,
)
from ucbplan.observing.exports.eso_ob import (
    USER_COMMENTS_MAX,
    eso_constraints,
    instrument_for,
    ob_body,
    user_comments,
)
from ucbplan.observing.exports.eso_templates import EsoTemplates, load_eso_templates
from ucbplan.observing.exports.interface import ExportOptions, ExportResult
from ucbplan.observing.exports.provenance import created_utc, meta, site_name, version
from ucbplan.observing.exports.queue import queue_note, untargeted
from ucbplan.observing.exports.text import ascii_names, iso_minute, iso_ms
from ucbplan.observing.exports.visitgroups import ExportUnit, export_units, exposure_runs
from ucbplan.observing.exports.windows import (
    ROUNDING_REMEDY,
    ceil_minute,
    floor_minute,
    ob_start_window,
)

#: Longest OB name p2 accepts.
ESO_NAME_MAX = 32


@dataclass(frozen=True, slots=True)
class _Member:
    """One block of an OB (an OB executes one or more blocks after one acquisition)."""

    block_id: str
    t_mid_utc: str
    sigma_t_s: float
    mid: datetime


@dataclass(slots=True)
class _Ob:
    """An OB being built: its JSON fields (in output order) and the bookkeeping beside them."""

    doc: dict[str, Any]
    lo: datetime  # window on the OB start, rounded outward to whole minutes (UTC)
    hi: datetime
    ob_start: datetime
    period_s: float
    session: str
    members: list[_Member]
    units: list[ExportUnit]
    position: tuple[float, float] = (0.0, 0.0)  # ICRS RA, Dec [deg]


@dataclass(frozen=True, slots=True)
class _Columns:
    """The blocks-table columns the ESO export reads (defaults applied, notes taken)."""

    mids: list[datetime]
    starts: list[datetime]
    sigma: np.ndarray
    acq: np.ndarray
    period: np.ndarray
    names: list[str]
    blocks: list[str]
    anchors: list[str]
    u_star: np.ndarray
    exptime: np.ndarray
    n_exp: np.ndarray
    sessions: list[str]
    ra: np.ndarray
    dec: np.ndarray


def _columns(table: Table, options: ExportOptions, notes: list[str]) -> _Columns:
    return _Columns(
        mids=required_times(table, "t_mid_utc"),
        starts=required_times(table, "t_start_utc"),
        sigma=floats(table, "sigma_t_s", unit="s"),
        acq=acquisition_s(table, options, notes),
        period=period_s(table, notes),
        names=strings(table, "target"),
        blocks=strings(table, "block_id"),
        anchors=strings(table, "anchor"),
        u_star=floats(table, "u_star_rad", unit="rad"),
        exptime=floats(table, "exptime_s", unit="s"),
        n_exp=floats(table, "n_exp"),
        sessions=strings(table, "session_id"),
        ra=coordinates(table)[0],
        dec=coordinates(table)[1],
    )


def _unit_ob(c: _Columns, unit: ExportUnit, options: ExportOptions, name: str) -> _Ob:
    """The OB of one visit (:class:`~.visitgroups.ExportUnit`): window on its start, rounded
    outward to whole minutes; its blocks as members."""
    i = unit.rows[0]
    mid, sigma = c.mids[i], float(c.sigma[i])
    w = ob_start_window(unit.start, float(c.acq[i]), sigma, options)
    lo_min, hi_min = floor_minute(w.lo), ceil_minute(w.hi)
    widening = (w.lo - lo_min).total_seconds() + (hi_min - w.hi).total_seconds()
    doc = {
        "name": name,
        "target": c.names[i],
        "block_ids": [c.blocks[j] for j in unit.rows],
        "anchor": c.anchors[i],
        "u_star_rad": float(c.u_star[i]),
        "t_mid_utc": iso_ms(mid),
        "sigma_t_s": sigma,
        "ob_start_utc": iso_ms(w.ob_start),
        "acquisition_s": float(c.acq[i]),
        "exptime_s": float(c.exptime[i]),
        "n_exp": unit.n_exposures,
        "window_half_width_s": w.half_width_s,
        "window_exact_utc": {"from": iso_ms(w.lo), "to": iso_ms(w.hi)},
        "rounding_widening_s": widening,
    }
    members = [
        _Member(c.blocks[j], iso_ms(c.mids[j]), float(c.sigma[j]), c.mids[j]) for j in unit.rows
    ]
    ob = _Ob(doc, lo_min, hi_min, w.ob_start, float(c.period[i]), c.sessions[i], members, [unit])
    ob.position = (float(c.ra[i]), float(c.dec[i]))
    return ob


def _ob_names(blocks: list[str], notes: list[str]) -> dict[str, str]:
    """OB name of each block id: ASCII, at most :data:`ESO_NAME_MAX` characters; a longer id is
    cut and given a stable 6-character hash suffix so that names stay unique.

    Raises
    ------
    InputFileError
        Two block ids that still give the same name (both named).
    """
    names = ascii_names(blocks, "ESO p2 OB name", notes, what="block")
    cut = 0
    for block, name in names.items():
        if len(name) > ESO_NAME_MAX:
            digest = hashlib.sha256(block.encode("utf-8")).hexdigest()[:6]
            names[block] = f"{name[: ESO_NAME_MAX - 7]}-{digest}"
            cut += 1
    if cut:
        notes.append(
            f"ESO p2: {cut} OB names longer than {ESO_NAME_MAX} characters cut and given a "
            "hash suffix of their block id (block_ids keeps the full ids)"
        )
    owner: dict[str, str] = {}
    for block, name in names.items():
        if owner.setdefault(name, block) != block:
            raise InputFileError(
                f"ESO p2: blocks {shorten(owner[name], 60)} and {shorten(block, 60)} both "
                f"become OB name {name!r}; rename one"
            )
    return names


def _eso_obs(table: Table, options: ExportOptions, notes: list[str]) -> list[_Ob]:
    """Time-ordered OBs: one per visit (:func:`~.visitgroups.export_units`: a visit, a session
    or a lone block), overlaps merged or refused."""
    c = _columns(table, options, notes)
    units = export_units(table, options)
    notes += queue_note(table, units, "ESO p2", options)
    ob_names = _ob_names([u.unit_id for u in units], notes)
    obs = [_unit_ob(c, u, options, ob_names[u.unit_id]) for u in units]
    for ob in obs:
        if not untargeted(table, ob.doc["target"]):
            _note_rounding(ob, options, notes)
    return _resolve_overlaps(obs, options)


def _note_rounding(ob: _Ob, options: ExportOptions, notes: list[str]) -> None:
    """Warn when minute rounding widens the window by a large fraction of the period."""
    per_s, widening = ob.period_s, ob.doc["rounding_widening_s"]
    if math.isfinite(per_s) and widening > options.rounding_warn_fraction * per_s:
        notes.append(
            f"ESO p2 {ob.doc['name']}: minute rounding widens the OB start window by "
            f"{widening:.0f} s = {widening / per_s:.2f} P_b; the OB start no longer fixes "
            f"the orbital phase: {ROUNDING_REMEDY}"
        )


def _merge(lead: _Ob, ob: _Ob) -> None:
    lead.doc["block_ids"] = [*lead.doc["block_ids"], *ob.doc["block_ids"]]
    lead.members = [*lead.members, *ob.members]
    lead.units = [*lead.units, *ob.units]
    lead.doc["n_exp"] = sum(u.n_exposures for u in lead.units)


def _resolve_overlaps(obs: list[_Ob], options: ExportOptions) -> list[_Ob]:
    obs = sorted(obs, key=lambda o: (o.lo, o.ob_start))
    out: list[_Ob] = []
    for ob in obs:
        prev = out[-1] if out else None
        if prev is None or ob.lo >= prev.hi:
            out.append(ob)
            continue
        if not options.merge_overlaps or prev.doc["target"] != ob.doc["target"]:
            raise _overlap_error(prev, ob)
        _merge(prev, ob)
    return out


def _overlap_error(prev: _Ob, ob: _Ob) -> UcbplanError:
    pair = f"{prev.doc['block_ids'][-1]} and {ob.doc['block_ids'][0]}"
    how = (
        "pass `merge_overlaps` to execute them as one OB"
        if prev.doc["target"] == ob.doc["target"]
        else "drop one of them from the blocks table (different targets)"
    )
    return UcbplanError(
        f"ESO p2: OB start windows of blocks {pair} overlap "
        f"({iso_minute(prev.lo)}-{iso_minute(prev.hi)} and "
        f"{iso_minute(ob.lo)}-{iso_minute(ob.hi)} UTC); {how}, "
        "or lower `tolerance_sigma`"
    )


def _visits(ob: _Ob) -> list[dict[str, Any]]:
    """Every block of a merged OB with its mid-exposure offset from the nominal OB start."""
    return [
        {
            "block_id": m.block_id,
            "t_mid_utc": m.t_mid_utc,
            "sigma_t_s": m.sigma_t_s,
            "mid_offset_from_ob_start_s": round((m.mid - ob.ob_start).total_seconds(), 3),
        }
        for m in ob.members
    ]


@dataclass(frozen=True, slots=True)
class _BodyContext:
    """What every OB body shares: target-list names, constraint set, instrument."""

    short_names: dict[str, str]
    constraints: dict[str, Any]
    instrument: Any
    templates: EsoTemplates | None
    rows: list[tuple[float, int]]  # (exposure time [s], n_exp) of every table row


def _ob_doc(ob: _Ob, ctx: _BodyContext, notes: list[str]) -> dict[str, Any]:
    """The OB's JSON: its fields, merged visits, the p2api constraint list, the OBX line and the
    OB body (:func:`~ucbplan.observing.exports.eso_ob.ob_body`)."""
    doc = ob.doc
    if len(ob.members) > 1:
        doc["merged_visits"] = _visits(ob)
    doc["absoluteTimeConstraints"] = [{"from": iso_minute(ob.lo), "to": iso_minute(ob.hi)}]
    doc["obx_absolute_times_list"] = (
        f'absolute_times_list "{{{ob.lo:%Y-%m-%dT%H:%M:%S} {ob.hi:%Y-%m-%dT%H:%M:%S} 0}} "'
    )
    comment, listed = user_comments([(m.block_id, m.t_mid_utc, m.sigma_t_s) for m in ob.members])
    if listed < len(ob.members):
        notes.append(
            f"ESO p2 {doc['name']}: userComments lists {listed} of {len(ob.members)} blocks "
            f"(p2 keeps {USER_COMMENTS_MAX} characters), cut with a mark; every block is in the "
            "OB's merged_visits in this file"
        )
    doc["ob"] = ob_body(
        ob_name=doc["name"],
        target_name=ctx.short_names[doc["target"]],
        ra_deg=ob.position[0],
        dec_deg=ob.position[1],
        constraints=ctx.constraints,
        comment=comment,
        runs=_science_runs(ob, ctx.rows),
        instrument=ctx.instrument,
        eso_templates=ctx.templates,
    )
    return doc


def _science_runs(ob: _Ob, rows: list[tuple[float, int]]) -> list[tuple[float, int]]:
    """The OB's science templates as (exposure time [s], count): a visit run back to back
    repeats each exposure time; otherwise one template per block (``rows``: per table row),
    each started at its planned time in visitor mode."""
    if len(ob.units) == 1 and ob.units[0].back_to_back:
        return exposure_runs(ob.units[0])
    return [rows[j] for unit in ob.units for j in unit.rows]


def _row_exposures(table: Table) -> list[tuple[float, int]]:
    """(exposure time [s], n_exp) of every table row."""
    exptime, n_exp = floats(table, "exptime_s", unit="s"), floats(table, "n_exp")
    return [(float(t), int(n)) for t, n in zip(exptime, n_exp, strict=True)]


def _target_names(table: Table, notes: list[str]) -> dict[str, str]:
    """ASCII p2 target name of each target (no commas or quotes)."""
    return ascii_names(strings(table, "target"), "ESO p2 target list", notes, drop=',"')


def _target_list(table: Table, short: dict[str, str]) -> list[str]:
    """p2 target-list CSV lines ``name,HH:MM:SS.SSS,±DD:MM:SS.SSS,J2000``, one per target."""
    ra, dec = coordinates(table)
    names = strings(table, "target")
    targets: dict[str, str] = {}
    for name, r, d in zip(names, ra, dec, strict=True):
        targets.setdefault(
            name,
            f"{short[name]},{sexagesimal(r / 15.0, 3, ':', False)},"
            f"{sexagesimal(d, 3, ':', True)},J2000",
        )
    return list(targets.values())


def export_eso_p2(table: Table, options: ExportOptions) -> ExportResult:
    """ESO p2 JSON: one OB per visit with its body and its absolute window on the OB start.

    A visit is a planner session (blocks sharing ``session_id``, e.g. a u = 0 / π pair observed
    after one acquisition) or a single block; a merged OB lists each block's mid-exposure offset
    from the nominal OB start in ``merged_visits``.

    The window is t_mid − (acquisition + exposure/2) ± max(k·σ_t, floor), i.e. the block start
    minus the acquisition overhead, rounded outward to whole minutes (p2 drops seconds). Each OB
    carries the p2api ``absoluteTimeConstraints`` list, the OBX ``absolute_times_list`` line, and
    the document carries the p2 target-list CSV lines. Each OB's ``ob`` holds its p2 body
    (target, constraint set, description, templates: :mod:`.eso_ob`), which ``--create`` sends
    with p2api (:mod:`.eso_create`).

    Raises
    ------
    UcbplanError
        When windows overlap (different targets, or the same target without ``merge_overlaps``).
    """
    notes: list[str] = []
    obs = _eso_obs(table, options, notes)
    short = _target_names(table, notes)
    ctx = _BodyContext(
        short,
        eso_constraints(
            meta(table).get("constraints"), options.seeing_arcsec, "ucbplan constraints", notes
        ),
        instrument_for(options.instrument),
        load_eso_templates(options.eso_templates) if options.eso_templates else None,
        _row_exposures(table),
    )
    notes.append(
        "ESO p2: OB bodies carry no proper motion (target files have none)"
        + (
            ""
            if ctx.templates
            else "; no template names: pass --eso-templates FILE or pick them in p2"
        )
    )
    doc = {
        "format": "ucbplan eso-p2 OBs with absolute time windows, version 2",
        "ucbplan_version": version(),
        "source_created_utc": created_utc(table),
        "site": site_name(table),
        "time_scale": "UTC at the site; windows constrain the OB start (acquisition included)",
        "window_rule": (
            "OB start = t_start_utc - acquisition_s; window = OB start +/- "
            f"max({options.tolerance_sigma:g} sigma_t, {options.tolerance_floor_s:g} s), "
            "rounded outward to whole minutes"
        ),
        "p2api_usage": "api.saveAbsoluteTimeConstraints(obId, ob['absoluteTimeConstraints'], v)",
        "target_list_csv": _target_list(table, short),
        "obs": [_ob_doc(ob, ctx, notes) for ob in obs],
    }
    text = dumps_json(doc) + "\n"
    return ExportResult(text.encode(), ".json", tuple(dict.fromkeys(notes)))
