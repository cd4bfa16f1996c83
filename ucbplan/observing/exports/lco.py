"""LCO/SOAR OCS request group JSON, TIME_CRITICAL, one request per block (docs/exports.md)."""

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
from ucbplan.observing.exports.text import iso_ms, safe_name
from ucbplan.observing.exports.windows import ob_start_window

__all__ = ["export_lco", "lco_json", "lco_requests", "request_window"]


@dataclass(frozen=True, slots=True)
class _Settings:
    """Request fields the blocks table does not know (see :func:`lco_requests`)."""

    proposal: str
    instrument_type: str
    telescope_class: str
    max_airmass: float
    min_lunar_distance: float


def _configuration(
    name: str, ra_deg: float, dec_deg: float, exptime_s: float, n_exp: int, s: _Settings
) -> dict[str, Any]:
    """One SPECTRUM configuration: ICRS target, constraints, exposures, acquisition, guiding."""
    return {
        "type": "SPECTRUM",
        "instrument_type": s.instrument_type,
        "target": {"name": name, "type": "ICRS", "ra": ra_deg, "dec": dec_deg, "epoch": 2000},
        "constraints": {
            "max_airmass": s.max_airmass,
            "min_lunar_distance": s.min_lunar_distance,
        },
        "instrument_configs": [{"exposure_time": exptime_s, "exposure_count": n_exp}],
        "acquisition_config": {"mode": "WCS"},
        "guiding_config": {"mode": "ON", "optional": True},
    }


def _floor_second(t: datetime) -> datetime:
    return t.replace(microsecond=0)


def _ceil_second(t: datetime) -> datetime:
    base = t.replace(microsecond=0)
    return base if base == t else base + timedelta(seconds=1)


def request_window(
    start: datetime, end: datetime, acquisition: float, sigma_s: float, options: ExportOptions
) -> tuple[datetime, datetime]:
    """The OCS window of one request: it holds the whole request, whose start may slide ±half.

    The request is the acquisition followed by the block: it starts at t_start − acquisition
    and ends at t_end. The OCS schedules a request anywhere its full duration fits inside the
    window, so the window is [t_start − acquisition − half, t_end + half] with half =
    max(k·σ_t, floor), rounded outward to whole seconds: the request then starts within ±half
    (+ < 1 s of rounding) of its nominal start, exactly the OB-start window of the ESO export.
    """
    w = ob_start_window(start, acquisition, sigma_s, options)
    return _floor_second(w.lo), _ceil_second(end + timedelta(seconds=w.half_width_s))


def _requests(
    table: Table, options: ExportOptions, s: _Settings, notes: list[str]
) -> list[dict[str, Any]]:
    """One request per block in start order; its window holds the whole request (to the second)."""
    acq = acquisition_s(table, options, notes)
    names = strings(table, "target")
    ra, dec = coordinates(table)
    sigma = floats(table, "sigma_t_s", unit="s")
    exptime, n_exp = floats(table, "exptime_s", unit="s"), floats(table, "n_exp")
    starts, ends = required_times(table, "t_start_utc"), required_times(table, "t_end_utc")
    requests = []
    for i in sorted(range(len(table)), key=lambda j: starts[j]):
        lo, hi = request_window(starts[i], ends[i], float(acq[i]), float(sigma[i]), options)
        config = _configuration(
            names[i], float(ra[i]), float(dec[i]), float(exptime[i]), int(n_exp[i]), s
        )
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
    """LCO/SOAR OCS request group: one TIME_CRITICAL request per block.

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
    return {
        "name": safe_name(f"ucbplan {strings(table, 'target')[0]}", 50),
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
    """LCO/SOAR OCS request-group JSON, TIME_CRITICAL (see :func:`lco_requests`)."""
    notes: list[str] = []
    acquisition_s(table, options, notes)  # the defaults taken, for the user's stderr
    return ExportResult(lco_json(table, options).encode(), ".json", tuple(notes))
