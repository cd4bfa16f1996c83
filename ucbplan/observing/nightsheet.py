"""The night sheet for the telescope: per night, the chart and what to tell the night assistant.

:func:`write_night_sheet` writes a PDF (one page per night; a night with many visits continues
on further pages) or a self-contained HTML file (charts embedded as base64 PNG, no links, no
scripts, no network). Each night lists its visits in time order with UTC start and end (date and
time, scale stated), the exposure sequence of every block and a plain instruction: target,
ICRS coordinates, when to be acquired, exposure time × number, and the anchor epochs.
"""

from __future__ import annotations

import base64
import html
import io
import math
from collections.abc import Sequence
from datetime import datetime, timedelta
from pathlib import Path
from typing import IO, Any

import numpy as np
from astropy import units as u
from astropy.coordinates import SkyCoord
from astropy.table import Table

from ucbplan.errors import InputError, shorten
from ucbplan.io import write_output
from ucbplan.observing.constraints import ConstraintSet
from ucbplan.observing.nightplot import (
    NightChart,
    Visit,
    chart_figure,
    hhmm,
    level_crossings,
    night_chart,
)
from ucbplan.observing.sites import Site
from ucbplan.observing.sky import SkyModel
from ucbplan.observing.timeaxis import TimeAxis
from ucbplan.observing.timeconv import quiet_erfa
from ucbplan.plotting import pyplot

__all__ = [
    "SHEET_FORMATS",
    "night_events",
    "plan_note",
    "sheet_format",
    "sky_line",
    "visit_instruction",
    "visit_lines",
    "write_night_sheet",
]

#: Formats of :func:`write_night_sheet`, by file suffix.
SHEET_FORMATS = ("pdf", "html")
#: Text lines of the visit list on one PDF page (below the chart).
_LINES_PER_PAGE = 19
#: Text lines on a continuation page (no chart).
_LINES_PER_CONTINUATION = 50
#: Characters per line and font size [pt] of the PDF visit list (fills an A4 landscape page).
_WIDTH, _FONT_PT = 140, 8.5


def _utc(iso: str) -> str:
    """``YYYY-MM-DD HH:MM:SS UTC`` of an ISO UTC string (rounded down to the second)."""
    return f"{iso[:10]} {iso[11:19]} UTC"


def _cell(row: Any, name: str) -> float | None:
    """A float cell, None when the column is absent, masked or NaN."""
    if name not in row.colnames or np.ma.is_masked(row[name]):
        return None
    value = float(row[name])
    return value if math.isfinite(value) else None


def _exposures(row: Any) -> str:
    readout = _cell(row, "readout_s")
    dead = f", {readout:g} s between" if readout else ""
    return f"{int(row['n_exp'])} × {float(row['exptime_s']):g} s{dead}"


def visit_lines(visit: Visit) -> list[str]:
    """The exposure sequence of a visit, one line per block: UTC start–end, exposures, anchor
    (u★ [rad]) and its epoch (block centre, UTC) ± σ_t [s], airmass at the centre."""
    out = []
    for row in visit.rows:
        start, end, mid = str(row["t_start_utc"]), str(row["t_end_utc"]), str(row["t_mid_utc"])
        out.append(
            f"{row['block_id']}: {_utc(start)} to {end[11:19]} UTC, {_exposures(row)}; anchor "
            f"{row['anchor']} (u★ = {float(row['u_star_rad']):.3f} rad) at {mid[11:23]} UTC "
            f"± {float(row['sigma_t_s']):.2g} s; airmass {float(row['airmass']):.2f}"
        )
    return out


def _local(row: Any, name: str) -> str:
    """`` (local HH:MM)`` from a ``t_*_local`` cell, empty when the table has none."""
    text = str(row[name]).strip() if name in row.colnames and not np.ma.is_masked(row[name]) else ""
    return f" (local {text[11:16]})" if len(text) >= 16 else ""


def _minus(iso: str, seconds: float) -> str:
    """``_utc`` of an ISO UTC string moved back by ``seconds``."""
    t = datetime.fromisoformat(iso[:19]) - timedelta(seconds=seconds)
    return _utc(t.isoformat())


def visit_instruction(visit: Visit) -> str:
    """What to tell the night assistant about a visit, in one paragraph: target, ICRS position,
    magnitude (if the table has ``vmag``), when to be on target, the exposures and the anchors."""
    row = visit.rows[0]
    names = visit.rows.colnames
    ra = str(row["ra_hms"]) if "ra_hms" in names else f"{float(row['ra_deg']):.5f}°"
    dec = str(row["dec_dms"]) if "dec_dms" in names else f"{float(row['dec_deg']):+.5f}°"
    vmag = _cell(row, "vmag")
    mag = f", V = {vmag:.1f} mag" if vmag is not None else ""
    acq = _cell(row, "acq_s")
    start = f"{_utc(visit.start_utc)}{_local(row, 't_start_local')}"
    ready = (
        f"Start acquiring at {_minus(visit.start_utc, acq)} ({acq / 60:.0f} min acquisition) so "
        f"that the first exposure starts at {start}"
        if acq
        else f"Be on target and guiding by {start}, when the first exposure starts"
    )
    n_blocks = len(visit.rows)
    seq = "; ".join(f"{_exposures(r)} from {str(r['t_start_utc'])[11:19]} UTC" for r in visit.rows)
    anchors = ", ".join(f"{r['anchor']} at {str(r['t_mid_utc'])[11:19]} UTC" for r in visit.rows)
    return (
        f"{visit.target}: RA {ra}, Dec {dec} (ICRS){mag}. {ready}. "
        f"{n_blocks} block{'s' if n_blocks > 1 else ''}: {seq}. The exposure start times are "
        f"fixed (phase-critical): the anchor epochs are {anchors}. Finished at "
        f"{_utc(visit.end_utc)}."
    )


#: Sun altitudes [deg] whose crossings the sheet lists, with the evening and morning names.
_SUN_EVENTS = (
    (0.0, "sunset", "sunrise"),
    (-6.0, "civil twilight ends", "civil twilight begins"),
    (-12.0, "nautical twilight ends", "nautical twilight begins"),
    (-18.0, "astronomical twilight ends", "astronomical twilight begins"),
)


def night_events(chart: NightChart, site: Site) -> tuple[list[tuple[str, str]], float]:
    """Sunset, twilights, sunrise, and any moonrise or moonset between sunset and sunrise
    (name, ISO UTC, in time order), found on a 1-min grid of geometric altitudes (no refraction);
    and the Moon's illuminated fraction at local midnight."""
    axis = TimeAxis.starting_at(chart.window.start, site.location)
    probe = SkyCoord([0.0] * u.deg, [0.0] * u.deg)
    sky = SkyModel.build(site.location, axis.origin, (0.0, 86400.0), probe)
    x = np.linspace(0.0, 86400.0, 1441)
    sun = sky.sun_alt_deg(x)
    found = [
        (xc, evening if falling else morning)
        for level, evening, morning in _SUN_EVENTS
        for xc, falling in level_crossings(x, sun - level)
    ]
    dark = [xc for xc, name in found if name in ("sunset", "sunrise")]
    lo, hi = (min(dark), max(dark)) if len(dark) == 2 else (0.0, 86400.0)
    moon = level_crossings(x, sky.moon_alt_deg(x))
    found += [(xc, "moonset" if down else "moonrise") for xc, down in moon if lo <= xc <= hi]
    found.sort()
    times = axis.utc([xc for xc, _ in found]) if found else []
    with quiet_erfa():
        events = [(name, t.isot) for (_, name), t in zip(found, times, strict=True)]
    return events, float(sky.moon_illum(np.array([43200.0]))[0])


def sky_line(chart: NightChart, site: Site) -> str:
    """The night's Sun and Moon events in one line (UTC, date stated once)."""
    events, illum = night_events(chart, site)
    if not events:
        return f"Sun and Moon: no rising or setting this night; Moon {illum:.0%} illuminated."
    text = ", ".join(f"{name} {hhmm(iso)}" for name, iso in events)
    return f"Sun and Moon (UTC, from {events[0][1][:10]}): {text}; Moon {illum:.0%} illuminated."


def plan_note(table: Table) -> str:
    """One line on the plan from the table's provenance: mode, constraints, ucbplan version."""
    meta = table.meta
    parts = ["All times UTC (date and time); exposure start times are phase-critical"]
    if meta.get("mode"):
        parts.append(f"mode {meta['mode']}")
    if meta.get("constraints"):
        parts.append("constraints: " + ", ".join(str(c) for c in meta["constraints"]))
    if meta.get("ucbplan_version"):
        parts.append(f"planned with ucbplan {meta['ucbplan_version']}")
    return "; ".join(parts) + "."


def _night_rows(chart: NightChart) -> list[tuple[str, Visit]]:
    return [(f"{k + 1}", v) for k, v in enumerate(chart.visits)]


# -- PDF ------------------------------------------------------------------------------------------


def _wrap(text: str, width: int = _WIDTH) -> list[str]:
    import textwrap

    return textwrap.wrap(text, width=width, subsequent_indent="      ") or [""]


def _text_lines(chart: NightChart) -> list[str]:
    lines: list[str] = []
    for number, v in _night_rows(chart):
        lines += _wrap(f"Visit {number} ({v.visit_id}): {_utc(v.start_utc)} to {_utc(v.end_utc)}")
        for line in visit_lines(v):
            lines += _wrap(f"   {line}")
        lines += _wrap(f"   Tell the night assistant: {visit_instruction(v)}")
    return lines


def _pdf_pages(
    chart: NightChart, site: Site, constraints: ConstraintSet | None, note: str = ""
) -> list[Any]:
    """The figures of one night: chart and first lines, then continuation pages."""
    plt = pyplot()
    lines = [*_wrap(note), ""] if note else []
    lines += [*_wrap(sky_line(chart, site)), ""]
    lines += _text_lines(chart)
    first = chart_figure([chart], site, constraints)
    first.set_size_inches(11.69, 8.27)
    engine: Any = first.get_layout_engine()
    engine.set(rect=(0.0, 0.42, 1.0, 0.58))
    pages = [first]
    chunk, rest = lines[:_LINES_PER_PAGE], lines[_LINES_PER_PAGE:]
    first.text(0.02, 0.40, "\n".join(chunk), family="monospace", fontsize=_FONT_PT, va="top")
    while rest:
        fig = plt.figure(figsize=(11.69, 8.27))
        head = f"{site.name}, night of {chart.window.label} (continued)"
        fig.text(0.02, 0.97, head, fontsize=10, va="top")
        body, rest = rest[:_LINES_PER_CONTINUATION], rest[_LINES_PER_CONTINUATION:]
        fig.text(0.02, 0.93, "\n".join(body), family="monospace", fontsize=_FONT_PT, va="top")
        pages.append(fig)
    return pages


def _write_pdf(
    handle: IO[Any], charts: Sequence[NightChart], site: Site, cs: Any, note: str
) -> None:
    from matplotlib.backends.backend_pdf import PdfPages

    plt = pyplot()
    with PdfPages(handle) as pdf:
        for chart in charts:
            for fig in _pdf_pages(chart, site, cs, note):
                pdf.savefig(fig)
                plt.close(fig)


# -- HTML -----------------------------------------------------------------------------------------

_STYLE = (
    "body{font-family:sans-serif;max-width:1100px;margin:1em auto}"
    "table{border-collapse:collapse;font-size:90%}td,th{border:1px solid #999;padding:2px 6px;"
    "vertical-align:top}section{page-break-after:always}img{max-width:100%}"
)


def _png(chart: NightChart, site: Site, constraints: ConstraintSet | None) -> str:
    fig = chart_figure([chart], site, constraints)
    buf = io.BytesIO()
    try:
        fig.savefig(buf, format="png", dpi=100)
    finally:
        pyplot().close(fig)
    return base64.b64encode(buf.getvalue()).decode("ascii")


def _html_night(chart: NightChart, site: Site, constraints: ConstraintSet | None) -> str:
    e = html.escape
    rows = []
    for number, v in _night_rows(chart):
        blocks = "<br>".join(e(line) for line in visit_lines(v))
        rows.append(
            f"<tr><td>{number}</td><td>{e(v.visit_id)}</td><td>{e(v.target)}</td>"
            f"<td>{e(_utc(v.start_utc))}</td><td>{e(_utc(v.end_utc))}</td><td>{blocks}</td>"
            f"<td>{e(visit_instruction(v))}</td></tr>"
        )
    head = (
        "<tr><th>#</th><th>visit</th><th>target</th><th>start (UTC)</th><th>end (UTC)</th>"
        "<th>exposure sequence</th><th>tell the night assistant</th></tr>"
    )
    return (
        f"<section><h2>{e(site.name)}, night of {e(chart.window.label)}</h2>"
        f"<p>{e(sky_line(chart, site))}</p>"
        f'<img alt="altitude chart of the night of {e(chart.window.label)}" '
        f'src="data:image/png;base64,{_png(chart, site, constraints)}">'
        f"<table>{head}{''.join(rows)}</table></section>"
    )


def _html(
    charts: Sequence[NightChart], site: Site, constraints: ConstraintSet | None, note: str
) -> str:
    body = "".join(_html_night(c, site, constraints) for c in charts)
    return (
        '<!DOCTYPE html><html lang="en"><head><meta charset="utf-8">'
        f"<title>Night sheet: {html.escape(site.name)}</title><style>{_STYLE}</style></head>"
        f"<body><h1>Night sheet: {html.escape(site.name)}, {len(charts)} night(s)</h1>"
        f"<p>{html.escape(note)}</p>"
        f"{body}</body></html>\n"
    )


def sheet_format(path: Path) -> str:
    """The sheet format of ``path`` by its suffix (``pdf`` or ``html``); check it before planning.

    Raises
    ------
    InputError
        Any other suffix.
    """
    fmt = path.suffix.lstrip(".").lower()
    if fmt == "htm":
        return "html"
    if fmt not in SHEET_FORMATS:
        raise InputError(
            f"--sheet: expected a .pdf or .html file, got {shorten(path.name, 60)}; "
            "name the sheet e.g. night.pdf"
        )
    return fmt


def write_night_sheet(
    table: Table,
    site: Site,
    path: Path,
    *,
    constraints: ConstraintSet | None = None,
    overwrite: bool = False,
) -> int:
    """Write the night sheet of a blocks table to ``path`` (.pdf or .html); the number of nights.

    Parameters
    ----------
    table : astropy.table.Table
        The blocks table (columns of :data:`ucbplan.observing.blocktable.COLUMNS`; visits by
        ``visit_id`` when present, else ``session_id``).
    site : Site
        The observatory of the plan.
    path : Path
        Output file; the suffix picks the format (:data:`SHEET_FORMATS`).
    constraints : ConstraintSet, optional
        The plan's constraints (airmass/altitude limits drawn, twilight named).
    overwrite : bool
        Replace an existing file.

    Raises
    ------
    InputError
        Unknown suffix or a table without blocks.
    OutputExistsError
        ``path`` exists and ``overwrite`` is false.
    """
    fmt = sheet_format(path)
    charts = night_chart(table, site)
    if not charts:
        raise InputError("--sheet: the plan has no blocks; nothing to put on a night sheet")
    if fmt == "pdf":
        write_output(
            path,
            lambda h: _write_pdf(h, charts, site, constraints, plan_note(table)),
            overwrite=overwrite,
            binary=True,
        )
    else:
        text = _html(charts, site, constraints, plan_note(table))

        def _write_html(handle: IO[str]) -> None:
            handle.write(text)

        write_output(path, _write_html, overwrite=overwrite)
    return len(charts)
