"""Night charts: target altitude vs UTC over each night's own span, with twilight, Moon and visits.

A chart runs from 20 min before sunset to 20 min after sunrise (widened to any visit outside),
not over 24 h. :func:`plot_night` charts one night from planned blocks; :func:`night_figures`
charts every night of a blocks table (one figure per night) and :func:`write_night_charts`
writes them: a PDF gets one page per night, a PNG/SVG one panel per night. Visits — blocks that
belong together, grouped by ``visit_id``, else ``session_id``, else one per block — are shaded,
and every block centre (the anchor epoch) gets a tick at the top of the panel.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from datetime import date, datetime, timedelta
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

import numpy as np
from astropy import units as u
from astropy.coordinates import SkyCoord
from astropy.table import Table
from astropy.time import Time
from numpy.typing import NDArray

from ucbplan.core.constants import DAY_S, HOUR_S
from ucbplan.errors import InputError, shorten
from ucbplan.io import write_output
from ucbplan.observing.blocks.block import Block
from ucbplan.observing.blocks.make import blocks_to_table
from ucbplan.observing.constraints import TWILIGHT_SUN_ALT_DEG, ConstraintSet
from ucbplan.observing.observatory.sites import Site
from ucbplan.observing.observatory.sky import SkyModel
from ucbplan.observing.observatory.time_axis import TimeAxis
from ucbplan.observing.schedule.nights import NightWindow, night_windows
from ucbplan.offline import offline
from ucbplan.plotting import FIGURE_FORMATS, figure_format, pyplot

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from ucbplan.targets import Target

FloatArray = NDArray[np.float64]

#: Twilight shading: (Sun altitude limit [deg], grey level) from day to astronomical night.
_SHADES = ((0.0, 0.93), (-6.0, 0.82), (-12.0, 0.68), (-18.0, 0.5))
#: Margin of the chart around sunset and sunrise [s].
_MARGIN_S = 1200.0
#: Altitudes [deg] of the rows of visit numbers, and the least gap [h] between two in one row.
_NUMBER_ALT_DEG = (81.0, 74.0, 67.0)
_NUMBER_GAP_H = 0.4
#: Columns a night chart or sheet reads.
_NEEDED = ("target", "block_id", "ra_deg", "dec_deg", "t_start_utc", "t_mid_utc", "t_end_utc")
#: Formats of :func:`write_night_charts`, by file suffix.
CHART_FORMATS = FIGURE_FORMATS
#: Most nights a PNG/SVG holds (one panel each); longer plans go to a PDF, a page per night.
MAX_PANELS = 7


@dataclass(frozen=True)
class VisitRows:
    """Blocks observed together (one acquisition): a ``visit_id``, ``session_id`` or one block.

    Attributes
    ----------
    visit_id : str
        Identifier (the table's ``visit_id``, ``session_id`` or ``block_id``).
    target : str
        Target name.
    night : str
        Local evening date, ISO.
    rows : astropy.table.Table
        The visit's blocks in time order (columns of the blocks table).
    """

    visit_id: str
    target: str
    night: str
    rows: Table

    @property
    def start_utc(self) -> str:
        """Start of the first exposure, ISO UTC."""
        return str(min(self.rows["t_start_utc"]))

    @property
    def end_utc(self) -> str:
        """End of the last exposure, ISO UTC."""
        return str(max(self.rows["t_end_utc"]))


@dataclass(frozen=True)
class NightChart:
    """What a night's panel draws: the night, its targets (name, RA, Dec [deg]) and visits."""

    window: NightWindow
    targets: tuple[tuple[str, float, float], ...]
    visits: tuple[VisitRows, ...]


def _text(row: Any, name: str) -> str:
    value = row[name] if name in row.colnames else ""
    return "" if np.ma.is_masked(value) else str(value).strip()


def _night_of(row: Any, site: Site) -> str:
    """The row's night: its ``night`` cell, else the local date 12 h before its start."""
    night = _text(row, "night")
    if night:
        return night
    start = Time(str(row["t_start_utc"]), scale="utc").to_datetime(timezone=site.zone)
    return (start - timedelta(hours=12)).date().isoformat()


def group_visits(table: Table, site: Site) -> dict[str, list[VisitRows]]:
    """The visits of a blocks table, by night (in date order), each night's in start order.

    Blocks with the same ``visit_id`` (or, without that column, the same ``session_id``) on the
    same night form one visit; a block with neither is a visit of its own.
    """
    key_col = "visit_id" if "visit_id" in table.colnames else "session_id"
    groups: dict[tuple[str, str], list[int]] = {}
    for i, row in enumerate(table):
        key = _text(row, key_col) if key_col in table.colnames else ""
        groups.setdefault(
            (_night_of(row, site), key or _text(row, "block_id") or f"#{i}"), []
        ).append(i)
    visits = []
    for (night, key), idx in groups.items():
        rows = table[idx]
        rows.sort("t_start_utc")
        visits.append(VisitRows(key, str(rows["target"][0]), night, rows))
    out: dict[str, list[VisitRows]] = {}
    for v in sorted(visits, key=lambda v: (v.night, v.start_utc)):
        out.setdefault(v.night, []).append(v)
    return out


def _targets(table: Table) -> tuple[tuple[str, float, float], ...]:
    seen: dict[str, tuple[str, float, float]] = {}
    for row in table:
        name = str(row["target"])
        if name not in seen:
            seen[name] = (name, float(row["ra_deg"]), float(row["dec_deg"]))
    return tuple(seen.values())


def night_chart(table: Table, site: Site) -> list[NightChart]:
    """One :class:`NightChart` per night of the table (all the table's targets on each).

    Raises
    ------
    InputError
        The table lacks a column the chart needs (positions, times, exposures).
    """
    missing = [c for c in _NEEDED if c not in table.colnames]
    if missing:
        raise InputError(
            f"blocks table: expected the columns {', '.join(missing)} (as `ucbplan plan` writes "
            "them), got a table without; re-run plan or add them"
        )
    targets = _targets(table)
    nights = group_visits(table, site)
    windows = night_windows(site, [date.fromisoformat(n) for n in nights])
    return [NightChart(w, targets, tuple(nights[w.label])) for w in windows]


def _seconds(axis: TimeAxis, iso: Sequence[str]) -> FloatArray:
    """Axis coordinates [s] of ISO UTC strings."""
    if len(iso) == 0:
        return np.zeros(0)
    t = Time(list(iso), scale="utc", location=axis.location)
    return np.asarray((t.tdb - axis.origin).to_value(u.s), dtype=np.float64)


def _span(sky: SkyModel, visits: Sequence[VisitRows], axis: TimeAxis) -> tuple[float, float]:
    """Sunset − 20 min to sunrise + 20 min [s on the axis], widened to every visit."""
    x = np.linspace(0.0, DAY_S, 1441)
    dark = np.flatnonzero(sky.sun_alt_deg(x) < 0.0)
    lo, hi = (x[dark[0]] - _MARGIN_S, x[dark[-1]] + _MARGIN_S) if dark.size else (0.0, DAY_S)
    for v in visits:
        lo = min(lo, float(_seconds(axis, [v.start_utc])[0]) - 600.0)
        hi = max(hi, float(_seconds(axis, [v.end_utc])[0]) + 600.0)
    return max(lo, 0.0), min(hi, DAY_S)


def _draw_sky(ax: Any, sky: SkyModel, x: FloatArray, chart: NightChart, colours: Any) -> None:
    """Twilight shading, target and Moon altitudes (x in s, drawn in h)."""
    hours = x / HOUR_S
    sun = sky.sun_alt_deg(x)
    for limit, grey in _SHADES:
        ax.fill_between(hours, 0, 90, where=sun <= limit, color=str(grey), lw=0, zorder=0)
    for i, (name, _, _) in enumerate(chart.targets):
        ax.plot(hours, sky.target_alt_deg(i, x), color=colours(i % 10), label=name, zorder=2)
    ax.plot(hours, sky.moon_alt_deg(x), color="goldenrod", ls=":", label="Moon", zorder=2)


def _draw_limits(ax: Any, constraints: ConstraintSet | None, airmass_max: float | None) -> None:
    """The airmass limit (dashed) and the altitude limit of the constraints."""
    if constraints is not None:
        airmass_max = constraints.airmass.max_airmass
    if airmass_max is not None:
        alt = math.degrees(math.asin(1.0 / airmass_max))
        ax.axhline(alt, color="k", ls="--", lw=0.8, label=f"airmass {airmass_max:g}")
    if constraints is not None and constraints.altitude is not None:
        ax.axhline(constraints.altitude.min_deg, color="k", ls="-.", lw=0.8, label="altitude limit")


def _draw_visits(ax: Any, axis: TimeAxis, chart: NightChart, colours: Any) -> None:
    """Visits as shaded spans numbered as on the night sheet, block centres (anchor epochs) as
    ticks at the top [h]."""
    names = [t[0] for t in chart.targets]
    last = [-math.inf] * len(_NUMBER_ALT_DEG)
    for k, v in enumerate(chart.visits):
        h0 = _seconds(axis, [v.start_utc])[0] / HOUR_S
        h1 = _seconds(axis, [v.end_utc])[0] / HOUR_S
        colour = colours(names.index(v.target) % 10)
        ax.axvspan(h0, h1, color=colour, alpha=0.35, lw=0, zorder=1)
        mids = _seconds(axis, [str(t) for t in v.rows["t_mid_utc"]]) / HOUR_S
        ax.plot(mids, np.full(mids.shape, 88.0), "|", color="k", ms=9, mew=1.2, zorder=4)
        centre = (h0 + h1) / 2.0
        level = next((j for j, x in enumerate(last) if centre - x > _NUMBER_GAP_H), 0)
        last[level] = centre
        box = {"fc": "white", "ec": colour, "pad": 1.5, "alpha": 0.8}
        y = _NUMBER_ALT_DEG[level]
        ax.text(centre, y, str(k + 1), ha="center", va="center", fontsize="small", bbox=box)
    if chart.visits:
        ax.plot([], [], "|", color="k", ms=9, mew=1.2, label="anchor epoch (block centre)")
        ax.axvspan(np.nan, np.nan, color="0.5", alpha=0.35, lw=0, label="visit (number)")


def _utc_ticks(ax: Any, axis: TimeAxis, span: tuple[float, float]) -> None:
    """Ticks on whole UTC hours (every 1 h up to 12 h of span, else 2 h), labelled hh:mm."""
    utc0 = axis.utc(0.0).datetime
    past = utc0.minute * 60 + utc0.second + utc0.microsecond / 1e6
    step = 1 if span[1] - span[0] <= 12 * HOUR_S else 2
    first = HOUR_S - past
    xs = np.arange(first, span[1] + 1, HOUR_S)
    hours = [(utc0.hour + 1 + k) % 24 for k in range(len(xs))]
    keep = [(x, h) for x, h in zip(xs, hours, strict=True) if x >= span[0] and h % step == 0]
    ax.set_xticks([x / HOUR_S for x, _ in keep], [f"{h:02d}:00" for _, h in keep])
    ax.set_xlim(span[0] / HOUR_S, span[1] / HOUR_S)


def level_crossings(x: FloatArray, f: FloatArray) -> list[tuple[float, bool]]:
    """Where ``f`` changes sign between samples ``x`` (linear interpolation), and whether it falls
    there (e.g. the Sun's altitude minus a twilight limit: setting is falling)."""
    out = []
    for i in np.flatnonzero(np.signbit(f[:-1]) != np.signbit(f[1:])):
        xc = x[i] - f[i] * (x[i + 1] - x[i]) / (f[i + 1] - f[i])
        out.append((float(xc), bool(f[i] >= 0.0)))
    return out


def hhmm(iso: str) -> str:
    """``HH:MM`` of an ISO time string, rounded to the nearest minute."""
    t = datetime.fromisoformat(iso[:19]) + timedelta(seconds=30)
    return t.strftime("%H:%M")


def _label(ax: Any, axis: TimeAxis, chart: NightChart, site_name: str, sky: SkyModel) -> None:
    """Axis labels and a title with the UTC date, sunset/sunrise and the Moon's illumination."""
    night = chart.window.label
    start = axis.utc(ax.get_xlim()[0] * HOUR_S).iso[:16]
    x = np.linspace(0.0, DAY_S, 1441)
    illum = float(sky.moon_illum(np.array([43200.0]))[0])
    sun = sky.sun_alt_deg(x)
    ax.set_xlabel(f"UTC [hh:mm] from {start} UTC")
    ax.set_ylabel("altitude [deg]")
    ax.set_ylim(0, 90)
    sun_txt = ""
    edges = level_crossings(x, sun)
    sets = [xc for xc, falling in edges if falling]
    rises = [xc for xc, falling in edges if not falling]
    if sets and rises:
        t = axis.utc([sets[0], rises[-1]])
        sun_txt = f"; sunset {hhmm(t[0].isot)}, sunrise {hhmm(t[1].isot)} UTC"
    ax.set_title(
        f"{site_name}, night of {night} (local evening){sun_txt}; Moon {illum:.0%} lit",
        fontsize="medium",
    )


def _panel(
    ax: Any, chart: NightChart, site: Site, constraints: ConstraintSet | None, **kw: Any
) -> None:
    """Draw one night into ``ax`` (no pyplot: the caller's backend stays as it is)."""
    import matplotlib

    axis = TimeAxis.starting_at(chart.window.start, site.location)
    coords = SkyCoord([t[1] for t in chart.targets] * u.deg, [t[2] for t in chart.targets] * u.deg)
    sky = SkyModel.build(site.location, axis.origin, (0.0, DAY_S), coords)
    span = _span(sky, chart.visits, axis)
    colours = matplotlib.colormaps["tab10"]
    x = np.linspace(span[0], span[1], 721)
    _draw_sky(ax, sky, x, chart, colours)
    _draw_limits(ax, constraints, kw.get("airmass_max"))
    _draw_visits(ax, axis, chart, colours)
    _utc_ticks(ax, axis, span)
    _label(ax, axis, chart, site.name, sky)


def _shading_note(constraints: ConstraintSet | None) -> str:
    lim = ", ".join(f"{k} {v:g}°" for k, v in TWILIGHT_SUN_ALT_DEG.items())
    used = f"; planned for {constraints.night.twilight} night" if constraints is not None else ""
    return f"grey: Sun below 0°, {lim}{used}"


def _chart_size(n_panels: int) -> tuple[float, float]:
    """Figure size of ``n_panels`` night panels [in]."""
    return (11, 1.0 + 4.2 * n_panels)


def _legend(ax: Any) -> None:
    """The legend beside the panel, not on the curves."""
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, fontsize="small")


def chart_figure(
    charts: Sequence[NightChart],
    site: Site,
    constraints: ConstraintSet | None = None,
    *,
    airmass_max: float | None = None,
    figure: Figure | None = None,
) -> Figure:
    """One figure, one panel per night chart, the legend beside the first panel.

    ``constraints`` (the plan's) draws its airmass and altitude limits and names its twilight;
    without it, ``airmass_max`` draws an airmass limit. ``figure``: an empty figure to draw in
    (default: a new one on the file-only backend, :func:`ucbplan.plotting.pyplot`).
    """
    fig = figure
    if fig is None:
        fig = pyplot().figure(figsize=_chart_size(len(charts)), layout="constrained")
    axes = fig.subplots(len(charts), 1, squeeze=False)[:, 0]
    for ax, chart in zip(axes, charts, strict=True):
        _panel(ax, chart, site, constraints, airmass_max=airmass_max)
    _legend(axes[0])
    fig.supxlabel(_shading_note(constraints), fontsize="small")
    return fig


def _charts_of(table: Table, site: Site, night: date | str | None) -> list[NightChart]:
    """The night charts of ``table`` (only ``night``'s when given).

    Raises
    ------
    InputError
        No blocks, or none on ``night``.
    """
    charts = night_chart(table, site)
    if not charts:
        raise InputError("plan: the plan has no blocks; nothing to chart")
    if night is None:
        return charts
    label = night.isoformat() if isinstance(night, date) else str(night)
    mine = [c for c in charts if c.window.label == label]
    if not mine:
        known = ", ".join(c.window.label for c in charts)
        raise InputError(
            f"night: expected a night with blocks ({known}), got {shorten(night, 40)}", "night"
        )
    return mine


def plot_charts(
    table: Table,
    site: Site,
    constraints: ConstraintSet | None = None,
    *,
    ax: Axes | None = None,
    night: date | str | None = None,
) -> Axes:
    """Chart a blocks table into ``ax`` (one night: ``night``, else the first) or, without
    ``ax``, into a new pyplot figure (the user's backend: inline in a notebook) with one panel
    per night (or ``night``'s), as ``--plot nights.png`` draws it; the (first) panel.

    Raises
    ------
    InputError
        No blocks, none on ``night``, or more than :data:`MAX_PANELS` nights for one figure.
    """
    charts = _charts_of(table, site, night)
    if ax is not None:
        _panel(ax, charts[0], site, constraints)
        _legend(ax)
        return ax
    if len(charts) > MAX_PANELS:
        raise InputError(
            f"night: {len(charts)} nights do not fit one figure (at most {MAX_PANELS} panels); "
            "give night=..., or write a PDF with a page per night",
            "night",
        )
    import matplotlib.pyplot as plt  # the user's backend, not the file-only one

    fig = plt.figure(figsize=_chart_size(len(charts)), layout="constrained")
    return chart_figure(charts, site, constraints, figure=fig).axes[0]


def plot_night(
    targets: Sequence[Target],
    site: Site,
    night: date,
    blocks: Sequence[Block],
    airmass_max: float | None = None,
) -> Figure:
    """Altitude [deg] vs UTC over one night's span, twilight shaded, the night's blocks as visits.

    Parameters
    ----------
    targets : sequence of Target
        Targets to draw.
    site : Site
        Observatory.
    night : date
        Local date of the evening.
    blocks : sequence of Block
        Planned blocks (those of other nights are ignored).
    airmass_max : float, optional
        Draws the airmass limit as a dashed line.

    Returns
    -------
    matplotlib.figure.Figure
        Write it with :func:`ucbplan.plotting.save_figure` (which also closes it).
    """
    window = night_windows(site, [night])[0]
    mine = [b for b in blocks if b.night == window.label]
    visits = group_visits(blocks_to_table(mine, {}), site).get(window.label, []) if mine else []
    chart = NightChart(window, tuple((t.name, t.ra_deg, t.dec_deg) for t in targets), tuple(visits))
    return chart_figure([chart], site, None, airmass_max=airmass_max)


def night_figures(
    table: Table, site: Site, constraints: ConstraintSet | None = None
) -> list[Figure]:
    """One figure per night of a blocks table (columns of :data:`~ucbplan.observing.blocks.schema.
    COLUMNS`), each over the night's own span; close them (or save with ``save_figure``)."""
    return [chart_figure([c], site, constraints) for c in night_chart(table, site)]


def chart_format(path: Path) -> str:
    """The chart format of ``path`` by its suffix (:data:`CHART_FORMATS`); check it before
    planning.

    Raises
    ------
    InputError
        Any other suffix.
    """
    return figure_format(path)


@offline()  # a notebook's call works with no network, like the CLI's
def write_night_charts(
    table: Table,
    site: Site,
    path: Path,
    *,
    constraints: ConstraintSet | None = None,
    overwrite: bool = False,
) -> int:
    """Chart every night of a blocks table into ``path``; the number of nights.

    A ``.pdf`` gets one page per night; a ``.png``/``.svg`` one panel per night (at most
    :data:`MAX_PANELS`). Written atomically.

    Raises
    ------
    InputError
        The suffix is not one of :data:`CHART_FORMATS`, the table has no blocks, or it has too
        many nights for one image.
    OutputExistsError
        ``path`` exists and ``overwrite`` is false.
    """
    fmt = chart_format(path)
    charts = night_chart(table, site)
    if not charts:
        raise InputError(f"plot {path.name}: the plan has no blocks; nothing to chart")
    if fmt != "pdf" and len(charts) > MAX_PANELS:
        raise InputError(
            f"plot {path.name}: {len(charts)} nights do not fit one image (at most "
            f"{MAX_PANELS} panels); give a .pdf path for one page per night"
        )
    plt = pyplot()

    def _write(handle: IO[Any]) -> None:
        if fmt == "pdf":
            from matplotlib.backends.backend_pdf import PdfPages

            with PdfPages(handle) as pdf:
                for c in charts:
                    fig = chart_figure([c], site, constraints)
                    pdf.savefig(fig)
                    plt.close(fig)
            return
        fig = chart_figure(charts, site, constraints)
        try:
            fig.savefig(handle, format=fmt, dpi=110)
        finally:
            plt.close(fig)

    write_output(path, _write, overwrite=overwrite, binary=True)
    return len(charts)
