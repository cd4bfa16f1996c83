"""LCO/SOAR OCS request group JSON, TIME_CRITICAL, one request per visit (docs/exports.md)."""

from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime, timedelta
from typing import Any

from astropy.table import Table

from ucbplan.errors import InputFileError
from ucbplan.io import dumps_json
from ucbplan.observing.exports.columns import (
    acquisition_s,
    coordinates,
    floats,
    required_times,
    strings,
)
from ucbplan.observing.exports.interface import ExportOptions, ExportResult
from ucbplan.observing.exports.queue import queue_note
from ucbplan.observing.exports.text import iso_ms, safe_name
from ucbplan.observing.exports.visitgroups import export_units, exposure_runs

#: Longest request-group name written [characters].
LCO_NAME_MAX = 50


@dataclass(frozen=True, slots=True)
class _Settings:
    """Request fields the blocks table does not know (see :func:`lco_requests`)."""

    proposal: str
    instrument_type: str
    telescope_class: str
    max_airmass: float
    min_lunar_distance: float


def _configuration(
    name: str, ra_deg: float, dec_deg: float, runs: list[tuple[float, int]], s: _Settings
) -> dict[str, Any]:
    """One SPECTRUM configuration: ICRS target, constraints, exposures (one instrument
    configuration per run of equal exposure times), acquisition, guiding."""
    return {
        "type": "SPECTRUM",
        "instrument_type": s.instrument_type,
        "target": {"name": name, "type": "ICRS", "ra": ra_deg, "dec": dec_deg, "epoch": 2000},
        "constraints": {
            "max_airmass": s.max_airmass,
            "min_lunar_distance": s.min_lunar_distance,
        },
        "instrument_configs": [
            {"exposure_time": exptime_s, "exposure_count": count} for exptime_s, count in runs
        ],
        "acquisition_config": {"mode": "WCS"},
        "guiding_config": {"mode": "ON", "optional": True},
    }


def _floor_second(t: datetime) -> datetime:
    return t.replace(microsecond=0)


def _ceil_second(t: datetime) -> datetime:
    base = t.replace(microsecond=0)
    return base if base == t else base + timedelta(seconds=1)


def request_window(
    start: datetime, end: datetime, acquisition: float, half_s: float, options: ExportOptions
) -> tuple[datetime, datetime]:
    """The OCS window of one request: it holds the whole request, whose start may slide ±half.

    The request is the acquisition followed by the block: it starts at t_start − acquisition
    and ends at t_end. The OCS schedules a request anywhere its full duration fits inside the
    window, so the window is [t_start − acquisition − half, t_end + half] with half =
    max(k·σ_t, floor) (``half_s``), rounded outward to whole seconds: the request then starts
    within ±half (+ < 1 s of rounding) of its nominal start, exactly the OB-start window of the
    ESO export.
    """
    lo = start - timedelta(seconds=acquisition + half_s)
    return _floor_second(lo), _ceil_second(end + timedelta(seconds=half_s))


def _requests(
    table: Table, options: ExportOptions, s: _Settings, notes: list[str]
) -> list[dict[str, Any]]:
    """One request per visit (:func:`~.visitgroups.export_units`) in start order: one
    acquisition, then the visit's exposures; its window holds the whole request (to the
    second), so it contains every planned exposure start and no two requests of one plan
    collide."""
    acq = acquisition_s(table, options, notes)
    ra, dec = coordinates(table)
    units = export_units(table, options)
    notes += queue_note(table, units, "LCO", options)
    requests = []
    for unit in units:
        i = unit.rows[0]
        lo, hi = request_window(unit.start, unit.end, float(acq[i]), unit.half_width_s, options)
        config = _configuration(unit.target, float(ra[i]), float(dec[i]), exposure_runs(unit), s)
        requests.append(
            {
                "location": {"telescope_class": s.telescope_class},
                "windows": [{"start": iso_ms(lo, 0), "end": iso_ms(hi, 0)}],
                "configurations": [config],
            }
        )
    return requests


def lco_requests(
    table: Table,
    options: ExportOptions,
    *,
    proposal: str = "FILL-ME",
    instrument_type: str = "SOAR_GHTS_REDCAM",
    telescope_class: str = "4m0",
    max_airmass: float = 2.0,
    min_lunar_distance: float = 30.0,
) -> dict[str, Any]:
    """LCO/SOAR OCS request group: one TIME_CRITICAL request per visit (its exposures after one
    acquisition; a lone block is a visit of its ``n_exp`` exposures).

    Each window holds the whole request (acquisition + block) with its start free by
    ± max(k·σ_t, floor) (:func:`request_window`); the OCS refuses a window shorter than the
    request. Block mid-times and σ go in an ``ucbplan`` key the OCS API ignores.

    Parameters
    ----------
    table : astropy.table.Table
        Master blocks table.
    options : ExportOptions
        Acquisition overhead and window rule.
    proposal : str
        LCO proposal id (fill in before submitting).
    instrument_type, telescope_class : str
        OCS instrument type and telescope class.
    max_airmass : float
        Airmass limit of every request.
    min_lunar_distance : float
        Smallest Moon separation of every request [deg].

    Raises
    ------
    InputFileError
        For a table without rows.
    """
    s = _Settings(proposal, instrument_type, telescope_class, max_airmass, min_lunar_distance)
    notes: list[str] = []
    requests = _requests(table, options, s, notes)
    if not requests:
        raise InputFileError("blocks table has no rows: nothing to export")
    name = safe_name(f"ucbplan {strings(table, 'target')[0]}")
    if len(name) > LCO_NAME_MAX:
        notes.append(
            f"LCO: request group name cut to {LCO_NAME_MAX} characters: {name[:LCO_NAME_MAX]!r}"
        )
    return {
        "name": name[:LCO_NAME_MAX],
        "proposal": s.proposal,
        "ipp_value": 1.0,
        "operator": "MANY",
        "observation_type": "TIME_CRITICAL",
        "requests": requests,
        "ucbplan": {
            "note": "ignored by the OCS API; block mid-times are UTC at the site with 1-sigma",
            "blocks": _block_times(table),
            "notes": notes,
        },
    }


def _block_times(table: Table) -> list[dict[str, Any]]:
    """UTC mid-time and 1σ of every block, in the order of the requests (block start)."""
    sigma = floats(table, "sigma_t_s", unit="s")
    starts = required_times(table, "t_start_utc")
    mids = required_times(table, "t_mid_utc")
    return [
        {"t_mid_utc": iso_ms(mids[i]), "sigma_t_s": float(sigma[i])}
        for i in sorted(range(len(table)), key=lambda j: starts[j])
    ]


def lco_json(table: Table, options: ExportOptions) -> str:
    """:func:`lco_requests` as indented JSON text."""
    return dumps_json(lco_requests(table, options)) + "\n"


def export_lco(table: Table, options: ExportOptions) -> ExportResult:
    """LCO/SOAR OCS request-group JSON, TIME_CRITICAL (see :func:`lco_requests`); its notes
    (defaults taken, visits a queue cannot run as planned) also go to the user's stderr."""
    doc = lco_requests(table, options)
    text = dumps_json(doc) + "\n"
    return ExportResult(text.encode(), ".json", tuple(doc["ucbplan"]["notes"]))
