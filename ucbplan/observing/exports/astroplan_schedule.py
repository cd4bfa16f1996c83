"""A plan as an astroplan ``Schedule``, so astroplan's plots and tools work on it.

ucbplan plans exact phase-locked instants itself (astroplan's schedulers place blocks on a time
grid and cannot centre an exposure on an orbital phase; docs/scheduling.md); once planned, the
exposures are an ordinary observing schedule. :func:`to_astroplan` hands them over, one
``ObservingBlock`` per exposure, each with the plan's constraints as astroplan objects and its
time window, e.g.::

    from astroplan.plots import plot_schedule_airmass
    schedule = to_astroplan(Table.read("plan.ecsv"), get_site("paranal"))
    plot_schedule_airmass(schedule)

Building the schedule needs no network (no IERS download): the objects only hold numbers and
times; evaluating astroplan's constraints later needs Earth-orientation data, which
``ucbplan.offline()`` (or ``Plan.to_astroplan``, which enters it) provides from the bundled
table.
"""

from __future__ import annotations

import re
import warnings
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from astropy import units as u
from astropy.coordinates import SkyCoord
from astropy.time import Time

from ucbplan.errors import InputError, PlanWarning, shorten

if TYPE_CHECKING:
    from astropy.table import Table

    from ucbplan.observing.observatory.sites import Site

#: Columns :func:`to_astroplan` reads from a blocks table.
REQUIRED = ("target", "t_start_utc", "t_end_utc", "ra_deg", "dec_deg")
#: Smallest half-width of an exposure's time window when the table has no ``sigma_t_s`` [s]
#: (the exports' default ``--tolerance-floor``).
WINDOW_FLOOR_S = 10.0
#: Window half-width in units of the exposure's 1σ timing error (the exports' default k).
WINDOW_SIGMA = 3.0

_NUMBER = r"([0-9]+(?:\.[0-9]*)?(?:[eE][-+]?[0-9]+)?)"


def _translators(ap: Any) -> list[tuple[re.Pattern[str], Callable[[float | str], Any]]]:
    """Each ucbplan constraint description (``describe()``, as in the table's
    ``meta['constraints']``) → the astroplan constraint with its meaning."""
    night = {
        "civil": ap.AtNightConstraint.twilight_civil,
        "nautical": ap.AtNightConstraint.twilight_nautical,
        "astronomical": ap.AtNightConstraint.twilight_astronomical,
    }
    return [
        (re.compile(r"(civil|nautical|astronomical) night"), lambda m: night[str(m)]()),
        (re.compile(rf"airmass <= {_NUMBER}"), lambda x: ap.AirmassConstraint(max=float(x))),
        (
            re.compile(rf"outside the {_NUMBER} deg zenith hole"),
            lambda x: ap.AltitudeConstraint(max=(90.0 - float(x)) * u.deg),
        ),
        (
            re.compile(rf"altitude >= {_NUMBER} deg"),
            lambda x: ap.AltitudeConstraint(min=float(x) * u.deg),
        ),
        (
            re.compile(rf"Moon separation >= {_NUMBER} deg"),
            lambda x: ap.MoonSeparationConstraint(min=float(x) * u.deg),
        ),
        (
            re.compile(rf"Moon illumination <= {_NUMBER}"),
            lambda x: ap.MoonIlluminationConstraint(max=float(x)),
        ),
    ]


def astroplan_constraints(texts: Sequence[Any]) -> list[Any]:
    """The plan's constraints (``meta['constraints']``) as astroplan constraint objects.

    Night → ``AtNightConstraint.twilight_*``; airmass → ``AirmassConstraint(max)``; zenith hole
    of radius r → ``AltitudeConstraint(max=90° − r)``; altitude → ``AltitudeConstraint(min)``;
    Moon separation → ``MoonSeparationConstraint(min)`` (astroplan's counts while the Moon is
    down too, so it is stricter than ucbplan's "or Moon down"); Moon illumination →
    ``MoonIlluminationConstraint(max)``. A text none of these match (a user's own constraint)
    is left out with a :class:`~ucbplan.errors.PlanWarning`.
    """
    import astroplan

    out = []
    rules = _translators(astroplan)
    for text in texts:
        found = next(
            ((p.search(str(text)), make) for p, make in rules if p.search(str(text))), None
        )
        if found is None or found[0] is None:
            warnings.warn(
                f"to_astroplan: constraint {shorten(text, 60)} has no astroplan equivalent: left "
                "out of the blocks' constraints",
                PlanWarning,
                stacklevel=3,
            )
            continue
        out.append(found[1](found[0].group(1)))
    return out


def _column(table: Table, name: str, default: float) -> np.ndarray:
    if name not in table.colnames:
        return np.full(len(table), default)
    values: np.ndarray = np.ma.filled(np.ma.asarray(table[name], dtype=float), np.nan)
    return np.where(np.isfinite(values), values, default)


def _exposures(table: Table, start: Time, end: Time) -> list[tuple[int, int, Time, float]]:
    """(row, exposure number, start, exposure time [s]) of every exposure, in time order: a
    row's ``n_exp`` exposures of ``exptime_s``, one ``readout_s`` apart (a row without them: one
    exposure from its start to its end)."""
    width = (end - start).to_value(u.s)
    n_exp = _column(table, "n_exp", 1.0).astype(int)
    exptime = _column(table, "exptime_s", np.nan)
    readout = _column(table, "readout_s", 0.0)
    out = []
    for i in range(len(table)):
        if width[i] <= 0:
            raise InputError(
                f"to_astroplan: row {i} ends before it starts; check t_start_utc and t_end_utc"
            )
        if not np.isfinite(exptime[i]) or n_exp[i] < 1:
            out.append((i, 1, start[i], float(width[i])))
            continue
        for k in range(n_exp[i]):
            t0 = start[i] + k * (exptime[i] + readout[i]) * u.s
            out.append((i, k + 1, t0, float(exptime[i])))
    out.sort(key=lambda e: (float(e[2].jd), e[0], e[1]))
    return out


def _check(table: Table) -> None:
    missing = [c for c in REQUIRED if c not in table.colnames]
    if missing:
        raise InputError(
            f"to_astroplan: expected a blocks table with columns {', '.join(REQUIRED)}, "
            f"missing {shorten(', '.join(missing), 80)} (write one with ucbplan plan -o plan.ecsv)"
        )


def to_astroplan(table: Table, site: Site) -> Any:
    """The planned exposures of ``table`` as an astroplan ``Schedule`` at ``site``.

    Parameters
    ----------
    table : astropy.table.Table
        A blocks table (``ucbplan plan -o plan.ecsv``, or
        :func:`~ucbplan.observing.blocks.make.blocks_to_table`) with ``target``, ``t_start_utc``,
        ``t_end_utc`` (UTC ISO), ``ra_deg``, ``dec_deg`` and optionally ``exptime_s``,
        ``n_exp``, ``readout_s``, ``sigma_t_s``, ``priority``, ``block_id``, ``visit_id`` and
        ``meta['constraints']``.
    site : Site
        The observatory the plan is for.

    Returns
    -------
    astroplan.Schedule
        From the first start to the last end (UTC); one ``ObservingBlock`` per exposure, in time
        order: its duration is the exposure time, its name the block id (``/k`` appended for
        the k-th exposure of a block of several), its ``configuration`` the block and visit ids,
        the exposure number and time [s], and its ``constraints`` the plan's
        (:func:`astroplan_constraints`) plus a ``TimeConstraint`` on its window: exposure start
        − h to exposure end + h with h = max(3 σ_t, 10 s). Its ``observer`` is the site, so
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
        from astroplan import FixedTarget, Observer, ObservingBlock, Schedule, TimeConstraint
    except ImportError:
        raise InputError("to_astroplan needs astroplan: pip install 'ucbplan[astroplan]'") from None
    _check(table)
    start = Time(np.asarray(table["t_start_utc"]).astype(str), scale="utc")
    end = Time(np.asarray(table["t_end_utc"]).astype(str), scale="utc")
    schedule = Schedule(start.min(), end.max())
    schedule.observer = Observer(location=site.location, name=site.name, timezone="UTC")
    make = _block_maker(table, ObservingBlock, FixedTarget, TimeConstraint)
    for i, k, t0, exptime in _exposures(table, start, end):
        schedule.insert_slot(t0, make(i, k, t0, exptime))
    return schedule


def _block_maker(
    table: Table, block_class: Any, target_class: Any, window_class: Any
) -> Callable[[int, int, Time, float], Any]:
    """A function (row, exposure number, start, exposure time [s]) → its ``ObservingBlock``
    (see :func:`to_astroplan`), with the plan's constraints built once."""
    ids = [str(v) for v in table["block_id"]] if "block_id" in table.colnames else None
    visits = [str(v) for v in table["visit_id"]] if "visit_id" in table.colnames else None
    half = np.maximum(WINDOW_SIGMA * _column(table, "sigma_t_s", 0.0), WINDOW_FLOOR_S) * u.s
    shared = astroplan_constraints(list(table.meta.get("constraints") or []))
    n_exp = _column(table, "n_exp", 1.0).astype(int)

    def make(i: int, k: int, t0: Time, exptime: float) -> Any:
        coord = SkyCoord(float(table["ra_deg"][i]) * u.deg, float(table["dec_deg"][i]) * u.deg)
        name = ids[i] if ids else str(i)
        t1 = t0 + exptime * u.s
        return block_class(
            target_class(coord, name=str(table["target"][i])),
            exptime * u.s,
            float(table["priority"][i]) if "priority" in table.colnames else 1.0,
            configuration={
                "block_id": name,
                "visit_id": visits[i] if visits else name,
                "exposure": k,
                "n_exp": int(max(n_exp[i], 1)),
                "exptime_s": exptime,
            },
            constraints=[*shared, window_class(t0 - half[i], t1 + half[i])],
            name=f"{name}/{k}" if n_exp[i] > 1 else name,
        )

    return make
