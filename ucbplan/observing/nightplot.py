"""Night chart: target altitude vs UTC with twilight shading and the planned blocks drawn."""

from __future__ import annotations

from collections.abc import Sequence
from datetime import date
from typing import TYPE_CHECKING, Any

import numpy as np
from astropy import units as u
from astropy.coordinates import SkyCoord
from astropy.time import Time, TimeDelta

from ucbplan.observing.blocks import Block
from ucbplan.observing.constraints import TWILIGHT_SUN_ALT_DEG
from ucbplan.observing.schedule.nights import night_windows
from ucbplan.observing.sites import Site
from ucbplan.observing.sky import SkyModel
from ucbplan.observing.timeconv import quiet_erfa
from ucbplan.plotting import pyplot

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ucbplan.target import Target

__all__ = ["plot_night"]


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
    """
    plt = pyplot()
    label, t0, t1 = night_windows(site, [night])[0]
    with quiet_erfa():
        origin = Time(t0.tdb, location=site.location)
        span = float((t1 - origin).to_value(u.s))
        coords = SkyCoord([t.ra_deg for t in targets] * u.deg, [t.dec_deg for t in targets] * u.deg)
        sky = SkyModel.build(site.location, origin, (0.0, span), coords)
        x = np.linspace(0.0, span, 1441)
        hours = x / 3600.0
        utc0 = origin.utc
    fig = plt.figure(figsize=(10, 5.5), layout="constrained")
    ax: Any = fig.add_subplot()
    sun = sky.sun_alt_deg(x)
    shades = [(0.0, 0.93), (-6.0, 0.82), (-12.0, 0.68), (-18.0, 0.5)]
    for limit, grey in shades:
        ax.fill_between(hours, -5, 95, where=sun <= limit, color=str(grey), lw=0, zorder=0)
    colours = plt.get_cmap("tab10")
    for i, t in enumerate(targets):
        ax.plot(hours, sky.target_alt_deg(i, x), color=colours(i % 10), label=t.name, zorder=2)
    ax.plot(hours, sky.moon_alt_deg(x), color="goldenrod", ls=":", label="Moon", zorder=2)
    if airmass_max is not None:
        ax.axhline(
            np.degrees(np.arcsin(1.0 / airmass_max)),
            color="k",
            ls="--",
            lw=0.8,
            label=f"airmass {airmass_max:g}",
        )
    names = [t.name for t in targets]
    with quiet_erfa():
        for b in blocks:
            if b.night != label or b.target not in names:
                continue
            h0 = float((b.t_start_utc - utc0).to_value(u.s)) / 3600.0
            h1 = float((b.t_end_utc - utc0).to_value(u.s)) / 3600.0
            ax.axvspan(h0, h1, color=colours(names.index(b.target) % 10), alpha=0.6, zorder=3)
    ticks = np.arange(0, np.ceil(hours[-1]) + 1, 2.0)
    with quiet_erfa():
        tick_labels = [(utc0 + TimeDelta(h * 3600.0 * u.s)).utc.iso[11:16] for h in ticks]
    ax.set_xticks(ticks, tick_labels)
    ax.set_xlim(hours[0], hours[-1])
    ax.set_ylim(0, 90)
    ax.set_xlabel(f"UTC [hh:mm] from {utc0.iso[:16]} (night of {label}, local evening)")
    ax.set_ylabel("altitude [deg]")
    lim = ", ".join(f"{k} {v:g}°" for k, v in TWILIGHT_SUN_ALT_DEG.items())
    ax.set_title(
        f"{site.name}, night of {label}\nshading darkens as the Sun sets below 0°, {lim}; "
        "coloured spans = blocks",
        fontsize="medium",
    )
    ax.legend(loc="upper right", fontsize="small")
    return fig
