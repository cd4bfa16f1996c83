"""The night sheet for the telescope: per night the chart, then per visit what to do, exposure by
exposure, in UTC.

:func:`write_night_sheet` writes a PDF (A4 portrait, a page per night; a long night continues on
further pages) or a self-contained HTML page (:mod:`ucbplan.observing.night.sheet_html`: charts
embedded as base64 PNG, its own CSS and a live clock in plain JavaScript, no network). Each visit
has a short header — target, ICRS position, acquisition start — two lines for the night
assistant ("acquire by HH:MM:SS UTC, then N × T s with R s readout; starts are phase-critical
±σ s") and one row per exposure (:data:`ucbplan.observing.night.sheet_html.EXPOSURE_COLUMNS`): UTC
start and end (HH:MM:SS, rounded to the second), anchor and its epoch, airmass, Λ_K and σ_t.
The HTML rows also have a button per status (taken, missed, skipped) and the page a "save log"
button that downloads the observing log (:mod:`ucbplan.observing.night.observing_log`) of the rows
marked.
"""

from __future__ import annotations

import base64
import io
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import IO, Any

import numpy as np
from astropy import units as u
from astropy.coordinates import SkyCoord
from astropy.table import Table

from ucbplan.core.constants import DAY_S
from ucbplan.errors import InputError, shorten
from ucbplan.io import write_output
from ucbplan.observing.constraints import ConstraintSet
from ucbplan.observing.night.chart import (
    NightChart,
    VisitRows,
    chart_figure,
    hhmm,
    level_crossings,
    night_chart,
)
from ucbplan.observing.night.countdown import TimedExposure, hms, seconds_text, visit_exposures
from ucbplan.observing.night.observing_log import LOG_COLUMNS, log_cells, log_file_name
from ucbplan.observing.night.sheet_html import (
    EXPOSURE_COLUMNS,
    SheetNight,
    SheetVisit,
    exposure_cells,
    render_html,
)
from ucbplan.observing.observatory.sites import Site
from ucbplan.observing.observatory.sky import SkyModel
from ucbplan.observing.observatory.time_axis import TimeAxis
from ucbplan.offline import offline
from ucbplan.plotting import pyplot

#: Formats of :func:`write_night_sheet`, by file suffix.
SHEET_FORMATS = ("pdf", "html")
#: The PDF page [inch]: A4 portrait.
_PAGE_IN = (8.27, 11.69)
#: Text lines below the chart on a night's first PDF page, and on a continuation page.
_LINES_PER_PAGE = 40
_LINES_PER_CONTINUATION = 72
#: Characters per line and font size [pt] of the PDF text (fits the A4 portrait width).
_WIDTH, _FONT_PT = 92, 8.5


def _cell(row: Any, name: str) -> float | None:
    """A float cell, None when the column is absent, masked or NaN."""
    if name not in row.colnames or np.ma.is_masked(row[name]):
        return None
    value = float(row[name])
    return value if np.isfinite(value) else None


def _text(row: Any, name: str) -> str:
    """A text cell, empty when the column is absent or masked."""
    if name not in row.colnames or np.ma.is_masked(row[name]):
        return ""
    return str(row[name]).strip()


def visit_heading(number: int, visit: VisitRows, exposures: Sequence[TimedExposure]) -> str:
    """``Visit 1: HM Cnc (V01), 2040-02-16 UTC``: number in the night, target, visit, UTC date."""
    short = exposures[0].label.split("/")[0]
    return f"Visit {number}: {visit.target} ({short}), {exposures[0].start.date()} UTC"


def visit_about(visit: VisitRows, exposures: Sequence[TimedExposure]) -> str:
    """One line on the target of a visit: ICRS position, magnitude (if the table has ``vmag``),
    acquisition start (UTC), first start and last end."""
    row = visit.rows[0]
    names = visit.rows.colnames
    ra = str(row["ra_hms"]) if "ra_hms" in names else f"{float(row['ra_deg']):.5f}°"
    dec = str(row["dec_dms"]) if "dec_dms" in names else f"{float(row['dec_deg']):+.5f}°"
    vmag = _cell(row, "vmag")
    mag = f", V = {vmag:.1f} mag" if vmag is not None else ""
    first, last = exposures[0], exposures[-1]
    acq = first.acq_start
    acq_text = f"acquisition starts {hms(acq)} UTC; " if acq is not None else ""
    local = _text(row, "t_start_local")
    local = f" (local {local[11:16]})" if len(local) >= 16 else ""
    return (
        f"RA {ra}, Dec {dec} (ICRS){mag}; {acq_text}first exposure starts "
        f"{hms(first.start)} UTC{local}, last ends {hms(last.end)} UTC"
    )


def visit_instruction(exposures: Sequence[TimedExposure]) -> tuple[str, str]:
    """What to tell the night assistant about a visit, in two lines: when to be acquired and the
    exposures, then that the starts are phase-critical and what to do about a missed one."""
    first = exposures[0]
    times = sorted({seconds_text(e.exptime_s) for e in exposures}, key=float)
    each = times[0] if len(times) == 1 else f"{times[0]}–{times[-1]}"
    dead = max(e.readout_s for e in exposures)
    readout = f" with {seconds_text(dead)} s readout" if dead > 0 else ""
    sigma = max(e.sigma_t_s for e in exposures)
    return (
        f"Acquire by {hms(first.start)} UTC, then {len(exposures)} × {each} s{readout}.",
        f"Starts are phase-critical ±{sigma:.2g} s: start each exposure at its UTC time below; "
        "a missed start is skipped, never made up late.",
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
    sky = SkyModel.build(site.location, axis.origin, (0.0, DAY_S), probe)
    x = np.linspace(0.0, DAY_S, 1441)
    sun = sky.sun_alt_deg(x)
    found = [
        (xc, evening if falling else morning)
        for level, evening, morning in _SUN_EVENTS
        for xc, falling in level_crossings(x, sun - level)
    ]
    dark = [xc for xc, name in found if name in ("sunset", "sunrise")]
    lo, hi = (min(dark), max(dark)) if len(dark) == 2 else (0.0, DAY_S)
    moon = level_crossings(x, sky.moon_alt_deg(x))
    found += [(xc, "moonset" if down else "moonrise") for xc, down in moon if lo <= xc <= hi]
    found.sort()
    times = axis.utc([xc for xc, _ in found]) if found else []
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


def _visits(chart: NightChart, meta: Any) -> list[tuple[VisitRows, list[TimedExposure]]]:
    return [(v, visit_exposures(v, meta)) for v in chart.visits]


# -- PDF ------------------------------------------------------------------------------------------


def _wrap(text: str, width: int = _WIDTH) -> list[str]:
    import textwrap

    return textwrap.wrap(text, width=width, subsequent_indent="    ") or [""]


def _table_lines(exposures: Sequence[TimedExposure]) -> list[str]:
    """The exposure table as fixed-width text (one line per exposure)."""
    rows = [EXPOSURE_COLUMNS, *(exposure_cells(e) for e in exposures)]
    widths = [max(len(r[k]) for r in rows) for k in range(len(EXPOSURE_COLUMNS))]
    return ["  " + "  ".join(_aligned(r, widths)) for r in rows]


def _aligned(cells: Sequence[str], widths: Sequence[int]) -> list[str]:
    """Cells padded to their column width: the anchor left-aligned, numbers right-aligned."""
    return [
        c.ljust(w) if k == 3 else c.rjust(w)
        for k, (c, w) in enumerate(zip(cells, widths, strict=True))
    ]


def _text_lines(chart: NightChart, meta: Any) -> list[str]:
    lines: list[str] = []
    for k, (v, exposures) in enumerate(_visits(chart, meta), start=1):
        lines += _wrap(visit_heading(k, v, exposures))
        lines += _wrap(f"  {visit_about(v, exposures)}")
        for line in visit_instruction(exposures):
            lines += _wrap(f"  > {line}")
        lines += [*_table_lines(exposures), ""]
    return lines


def _pdf_pages(
    chart: NightChart,
    site: Site,
    constraints: ConstraintSet | None,
    note: str = "",
    meta: Any = None,
) -> list[Any]:
    """The figures of one night (A4 portrait): chart and first lines, then continuation pages."""
    plt = pyplot()
    lines = [*_wrap(note), ""] if note else []
    lines += [*_wrap(sky_line(chart, site)), ""]
    lines += _text_lines(chart, meta or {})
    first = chart_figure([chart], site, constraints)
    first.set_size_inches(*_PAGE_IN)
    engine: Any = first.get_layout_engine()
    engine.set(rect=(0.0, 0.6, 1.0, 0.4))
    pages = [first]
    chunk, rest = lines[:_LINES_PER_PAGE], lines[_LINES_PER_PAGE:]
    first.text(0.04, 0.585, "\n".join(chunk), family="monospace", fontsize=_FONT_PT, va="top")
    while rest:
        fig = plt.figure(figsize=_PAGE_IN)
        head = f"{site.name}, night of {chart.window.label} (continued; times UTC)"
        fig.text(0.04, 0.97, head, fontsize=10, va="top")
        body, rest = rest[:_LINES_PER_CONTINUATION], rest[_LINES_PER_CONTINUATION:]
        fig.text(0.04, 0.945, "\n".join(body), family="monospace", fontsize=_FONT_PT, va="top")
        pages.append(fig)
    return pages


def _write_pdf(
    handle: IO[Any], charts: Sequence[NightChart], site: Site, cs: Any, note: str, meta: Any
) -> None:
    from matplotlib.backends.backend_pdf import PdfPages

    plt = pyplot()
    with PdfPages(handle) as pdf:
        for chart in charts:
            for fig in _pdf_pages(chart, site, cs, note, meta):
                pdf.savefig(fig)
                plt.close(fig)


# -- HTML -----------------------------------------------------------------------------------------


def _png(chart: NightChart, site: Site, constraints: ConstraintSet | None) -> str:
    fig = chart_figure([chart], site, constraints)
    buf = io.BytesIO()
    try:
        fig.savefig(buf, format="png", dpi=100)
    finally:
        pyplot().close(fig)
    return base64.b64encode(buf.getvalue()).decode("ascii")


def sheet_nights(
    charts: Sequence[NightChart],
    site: Site,
    constraints: ConstraintSet | None,
    meta: Any,
    log: Mapping[tuple[str, str], tuple[str, ...]] | None = None,
) -> list[SheetNight]:
    """What the HTML sheet shows, night by night (``meta``: the blocks table's; ``log``: the
    observing-log cells by block id and exposure label, None for no log buttons)."""
    out = []
    for chart in charts:
        visits = tuple(
            SheetVisit(
                heading=visit_heading(k, v, exposures),
                about=visit_about(v, exposures),
                tell=visit_instruction(exposures),
                exposures=tuple(exposures),
                log=tuple(log[e.block_id, e.label] for e in exposures) if log else (),
            )
            for k, (v, exposures) in enumerate(_visits(chart, meta), start=1)
        )
        heading = f"{site.name}, night of {chart.window.label}"
        out.append(
            SheetNight(heading, sky_line(chart, site), _png(chart, site, constraints), visits)
        )
    return out


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
            f"sheet: expected a .pdf or .html file, got {shorten(path.name, 60)}; "
            "name the sheet e.g. night.pdf"
        )
    return fmt


@offline()  # a notebook's call works with no network, like the CLI's
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
        The blocks table (columns of :data:`ucbplan.observing.blocks.schema.COLUMNS`; visits by
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
        raise InputError("sheet: the plan has no blocks; nothing to put on a night sheet")
    note, meta = plan_note(table), table.meta
    if fmt == "pdf":
        write_output(
            path,
            lambda h: _write_pdf(h, charts, site, constraints, note, meta),
            overwrite=overwrite,
            binary=True,
        )
    else:
        cells = {(e.block_id, e.label): c for e, c in log_cells(table, site)}
        nights = sheet_nights(charts, site, constraints, meta, cells)
        title = f"Night sheet: {site.name}, {len(charts)} night(s)"
        text = render_html(title, note, nights, (LOG_COLUMNS, log_file_name(table)))

        def _write_html(handle: IO[str]) -> None:
            handle.write(text)

        write_output(path, _write_html, overwrite=overwrite)
    return len(charts)
