"""A plan as an astroplan ``Schedule``, so astroplan's plots and tools work on it.

ucbplan plans exact phase-locked instants itself (astroplan's schedulers place blocks on a time
grid and cannot centre an exposure on an orbital phase; docs/scheduling.md); once planned, the
blocks are an ordinary observing schedule. :func:`to_astroplan` hands them over, e.g.::

    from astroplan.plots import plot_schedule_airmass
    schedule = to_astroplan(Table.read("plan.ecsv"), get_site("paranal"))
    plot_schedule_airmass(schedule)
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from astropy import units as u
from astropy.coordinates import SkyCoord
from astropy.time import Time

from ucbplan.errors import InputError, shorten

if TYPE_CHECKING:
    from astropy.table import Table

    from ucbplan.observing.sites import Site

__all__ = ["to_astroplan"]

#: Columns :func:`to_astroplan` reads from a blocks table.
REQUIRED = ("target", "t_start_utc", "t_end_utc", "ra_deg", "dec_deg")


def _groups(table: Table) -> list[np.ndarray]:
    """Row indices of each scheduled unit: one visit (``visit_id``) or one block per row."""
    if "visit_id" not in table.colnames:
        return [np.array([i]) for i in range(len(table))]
    ids = np.asarray(table["visit_id"]).astype(str)
    return [np.flatnonzero(ids == v) for v in dict.fromkeys(ids)]


def _spans(table: Table, start: Time, end: Time, ids: list[str]) -> list[tuple[Time, Time, int]]:
    """(first start, last end, first row) of each visit or lone block, in time order."""
    units = []
    for rows in _groups(table):
        t0, t1 = start[rows].min(), end[rows].max()
        if t1 <= t0:
            raise InputError(
                f"to_astroplan: block {shorten(ids[rows[0]], 60)} ends before it starts; "
                "check t_start_utc and t_end_utc"
            )
        units.append((t0, t1, rows[0]))
    units.sort(key=lambda un: float(un[0].jd))
    return units


def to_astroplan(table: Table, site: Site) -> Any:
    """The planned blocks (or visits) of ``table`` as an astroplan ``Schedule`` at ``site``.

    Parameters
    ----------
    table : astropy.table.Table
        A blocks table (``ucbplan plan -o plan.ecsv``, or
        :func:`~ucbplan.observing.tablemake.blocks_to_table`): one row per block or exposure,
        with ``target``, ``t_start_utc``, ``t_end_utc`` (UTC ISO), ``ra_deg``, ``dec_deg``
        and optionally ``priority`` and ``visit_id``.
    site : Site
        The observatory the plan is for.

    Returns
    -------
    astroplan.Schedule
        From the first start to the last end (UTC); one ``ObservingBlock`` per visit (rows
        sharing a ``visit_id``: first start to last end) or, without ``visit_id``, per row, in
        time order, named by the visit or block id. Its ``observer`` is the site, so
        ``schedule.to_table()`` and ``astroplan.plots.plot_schedule_airmass(schedule)`` work
        (the latter needs a matplotlib that still has ``Axes.plot_date``, i.e. < 3.10, as of
        astroplan 0.10.1). astroplan fits blocks into its slots to within 1 s.

    Raises
    ------
    InputError
        If astroplan is not installed, a required column is missing or a block ends before it
        starts.
    """
    try:
        from astroplan import FixedTarget, Observer, ObservingBlock, Schedule
    except ImportError:
        raise InputError("to_astroplan needs astroplan: pip install 'ucbplan[astroplan]'") from None
    missing = [c for c in REQUIRED if c not in table.colnames]
    if missing:
        raise InputError(
            f"to_astroplan: expected a blocks table with columns {', '.join(REQUIRED)}, "
            f"missing {shorten(', '.join(missing), 80)} (write one with ucbplan plan -o plan.ecsv)"
        )
    start = Time(np.asarray(table["t_start_utc"]).astype(str), scale="utc")
    end = Time(np.asarray(table["t_end_utc"]).astype(str), scale="utc")
    id_col = next((c for c in ("visit_id", "block_id") if c in table.colnames), None)
    ids = [str(v) for v in table[id_col]] if id_col else [str(i) for i in range(len(table))]
    units = _spans(table, start, end, ids)
    schedule = Schedule(start.min(), end.max())
    schedule.observer = Observer(location=site.location, name=site.name, timezone="UTC")
    for t0, t1, i in units:
        coord = SkyCoord(float(table["ra_deg"][i]) * u.deg, float(table["dec_deg"][i]) * u.deg)
        priority = float(table["priority"][i]) if "priority" in table.colnames else 1.0
        block = ObservingBlock(
            FixedTarget(coord, name=str(table["target"][i])),
            (t1 - t0).to(u.s),
            priority,
            name=str(ids[i]),
        )
        schedule.insert_slot(t0, block)
    return schedule
