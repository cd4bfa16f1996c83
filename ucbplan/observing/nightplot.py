"""Night chart: target altitude vs UTC with twilight shading and the planned blocks drawn."""

from __future__ import annotations

from collections.abc import Sequence
from datetime import date
from typing import TYPE_CHECKING, Any

import numpy as np
from astropy import units as u
from astropy.coordinates import SkyCoord
from numpy.typing import NDArray

from ucbplan.observing.blocks import Block
from ucbplan.observing.constraints import TWILIGHT_SUN_ALT_DEG
from ucbplan.observing.schedule.nights import night_windows
from ucbplan.observing.sites import Site
from ucbplan.observing.sky import SkyModel
from ucbplan.observing.timeaxis import TimeAxis
from ucbplan.observing.timeconv import quiet_erfa
from ucbplan.plotting import pyplot

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ucbplan.target import Target

__all__ = ["plot_night"]

FloatArray = NDArray[np.float64]

#: Twilight shading: (Sun altitude limit [deg], grey level) from day to astronomical night.
_SHADES = ((0.0, 0.93), (-6.0, 0.82), (-12.0, 0.68), (-18.0, 0.5))


def plot_night(
    targets: Sequence[Target],
    site: Site,
    night: date,
    blocks: Sequence[Block],
    airmass_max: float | None = None,
) -> Figure:
    """Altitude [deg] vs UTC for one night, twilight shaded, blocks as spans.

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
    plt = pyplot()
    window = night_windows(site, [night])[0]
    axis = TimeAxis.starting_at(window.start, site.location)
    span = axis.x(window.end)
    coords = SkyCoord([t.ra_deg for t in targets] * u.deg, [t.dec_deg for t in targets] * u.deg)
    sky = SkyModel.build(site.location, axis.origin, (0.0, span), coords)
    fig = plt.figure(figsize=(10, 5.5), layout="constrained")
    ax: Any = fig.add_subplot()
    colours = plt.get_cmap("tab10")
    x = np.linspace(0.0, span, 1441)
    _draw_sky(ax, sky, x, [t.name for t in targets], colours, airmass_max)
    _draw_blocks(ax, axis, blocks, window.label, [t.name for t in targets], colours)
    _label_axes(ax, axis, x / 3600.0, window.label, site.name)
    return fig


def _draw_sky(
    ax: Any,
    sky: SkyModel,
    x: FloatArray,
    names: list[str],
    colours: Any,
    airmass_max: float | None,
) -> None:
    """Twilight shading, target and Moon altitudes, the airmass limit (x in s, drawn in h)."""
    hours = x / 3600.0
    sun = sky.sun_alt_deg(x)
    for limit, grey in _SHADES:
        ax.fill_between(hours, -5, 95, where=sun <= limit, color=str(grey), lw=0, zorder=0)
    for i, name in enumerate(names):
        ax.plot(hours, sky.target_alt_deg(i, x), color=colours(i % 10), label=name, zorder=2)
    ax.plot(hours, sky.moon_alt_deg(x), color="goldenrod", ls=":", label="Moon", zorder=2)
    if airmass_max is not None:
        ax.axhline(
            np.degrees(np.arcsin(1.0 / airmass_max)),
            color="k",
            ls="--",
            lw=0.8,
            label=f"airmass {airmass_max:g}",
        )


def _draw_blocks(
    ax: Any, axis: TimeAxis, blocks: Sequence[Block], night: str, names: list[str], colours: Any
) -> None:
    """The blocks of ``night`` as coloured spans [h on the axis]."""
    for b in blocks:
        if b.night != night or b.target not in names:
            continue
        h0, h1 = axis.x(b.t_start_utc) / 3600.0, axis.x(b.t_end_utc) / 3600.0
        ax.axvspan(h0, h1, color=colours(names.index(b.target) % 10), alpha=0.6, zorder=3)


def _label_axes(ax: Any, axis: TimeAxis, hours: FloatArray, night: str, site_name: str) -> None:
    """UTC ticks every 2 h, limits, labels, title and legend."""
    ticks = np.arange(0, np.ceil(hours[-1]) + 1, 2.0)
    with quiet_erfa():
        tick_labels = [t.iso[11:16] for t in axis.utc(ticks * 3600.0)]
        start = axis.utc(0.0).iso[:16]
    ax.set_xticks(ticks, tick_labels)
    ax.set_xlim(hours[0], hours[-1])
    ax.set_ylim(0, 90)
    ax.set_xlabel(f"UTC [hh:mm] from {start} (night of {night}, local evening)")
    ax.set_ylabel("altitude [deg]")
    lim = ", ".join(f"{k} {v:g}°" for k, v in TWILIGHT_SUN_ALT_DEG.items())
    ax.set_title(
        f"{site_name}, night of {night}\nshading darkens as the Sun sets below 0°, {lim}; "
        "coloured spans = blocks",
        fontsize="medium",
    )
    ax.legend(loc="upper right", fontsize="small")
