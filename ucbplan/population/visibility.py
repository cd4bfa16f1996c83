"""Population visibility: per source, what one site offers in one semester.

For each catalog source and a site: the hours of the semester that meet every constraint (night,
airmass ≤ X, Moon separation, zenith hole: the ``plan`` constraints of
:mod:`ucbplan.observing.constraints`), the number of usable nights (nights with at least
``min_hours`` of such time), and per anchor the anchor epochs whose block meets every constraint
(``observable_*``) and those of them inside the validity window σ_u ≤ α·δu_tol (``epochs_*``).

All of it reuses the planner: one :class:`~ucbplan.observing.observatory.sky.SkyModel` and one
light-time :class:`~ucbplan.observing.observatory.barycentric.SiteTrack` per chunk of sources, night
windows from :func:`~ucbplan.observing.schedule.nights.night_windows`, anchor epochs and their
constraint check from :func:`~ucbplan.observing.schedule.candidates.candidate_blocks`, and the
validity window from :func:`ucbplan.core.forecast.valid_window_s` with the per-source Fisher target
of :func:`ucbplan.population.catalog_forecast.forecast_with_target`.
"""

from __future__ import annotations

import datetime as dt
import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from ucbplan.core.constants import HOUR_S
from ucbplan.core.forecast import tolerance, valid_window_s
from ucbplan.errors import UcbplanError
from ucbplan.inputs import check_range
from ucbplan.observing.constraints import ConstraintSet, holds
from ucbplan.observing.observatory.semesters import semester_dates
from ucbplan.observing.observatory.sites import Site
from ucbplan.observing.schedule.candidates import candidate_blocks
from ucbplan.observing.schedule.nights import NightWindow, night_windows
from ucbplan.observing.schedule.settings import PlanSettings, parse_mode
from ucbplan.population.catalog import Source
from ucbplan.population.catalog_forecast import (
    ANCHORS,
    ForecastOptions,
    forecast_with_target,
    icrs_of,
)
from ucbplan.population.execute import worker_setup
from ucbplan.population.tables import SOURCE_COLUMNS

#: Spacing of the time grid on which usable hours are summed [s].
GRID_STEP_S = 300.0


@dataclass(frozen=True, slots=True)
class VisibilityOptions:
    """Options of a population visibility run (all of them go into the table meta).

    Attributes
    ----------
    site : Site
        Observatory.
    semester : str
        ``2041A``, ``2041B`` or an ESO period ``P147``
        (:mod:`ucbplan.observing.observatory.semesters`).
    settings : PlanSettings
        Constraints (twilight, airmass, Moon, zenith hole), the exposure plan (block length),
        α and the tolerance form, as ``ucbplan plan`` takes them.
    min_hours : float
        Usable time that makes a night usable [h].
    forecast : ForecastOptions
        The Fisher forecast behind the validity window (σ_v, K, T_obs, LISA start).
    """

    site: Site
    semester: str
    settings: PlanSettings = field(default_factory=PlanSettings)
    min_hours: float = 1.0
    forecast: ForecastOptions = field(default_factory=ForecastOptions)

    def __post_init__(self) -> None:
        semester_dates(self.semester)
        check_range("min_hours", self.min_hours, 0.0, 24.0, "h", "usable time of a night")

    def dates(self) -> list[dt.date]:
        """Local evening dates of the semester's nights."""
        first, end = semester_dates(self.semester)
        return [first + dt.timedelta(days=k) for k in range((end - first).days)]

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready mapping (fingerprints and meta)."""
        return {
            "site": self.site.as_dict(),
            "semester": self.semester.strip().upper(),
            "settings": {k: str(v) for k, v in asdict(self.settings).items()},
            "min_hours": self.min_hours,
            "forecast": self.forecast.as_dict(),
        }


def _anchor_cols() -> list[tuple[str, str, str, str]]:
    cols = []
    for a in ANCHORS:
        cols.append((f"observable_{a}", "", "i8", f"{a} epochs whose block meets every constraint"))
        cols.append(
            (
                f"epochs_{a}",
                "",
                "i8",
                "of those, inside T_valid (-1: no Fisher target, see status)",
            )
        )
        cols.append((f"valid_until_{a}", "", "str", f"end of validity, {a} (TDB)"))
    return cols


#: The visibility table, declared once: (name, unit, dtype, description).
VISIBILITY_COLUMNS: tuple[tuple[str, str, str, str], ...] = (
    *SOURCE_COLUMNS,
    ("status", "", "str", "ok | unconstrained | failed: <error> (of the Fisher forecast)"),
    ("ra", "deg", "f8", "ICRS right ascension"),
    ("dec", "deg", "f8", "ICRS declination"),
    ("vmag", "mag", "f8", "catalog magnitude (NaN if none)"),
    ("k_eff", "km / s", "f8", "K of the tolerance"),
    ("usable_hours", "h", "f8", "hours meeting every constraint (airmass, night, Moon, hole)"),
    ("usable_nights", "", "i8", "nights with at least min_hours usable"),
    ("best_airmass", "", "f8", "lowest airmass at night (inf: never up at night)"),
    *_anchor_cols(),
)


@dataclass(frozen=True)
class _Frame:
    """What the sources of one chunk share: night windows, axis, sky model, light time."""

    windows: list[NightWindow]
    constraints: ConstraintSet
    axis: Any
    span_x: tuple[float, float]
    sky: Any
    track: Any
    grid_x: np.ndarray
    night_of: np.ndarray


def _frame(opts: VisibilityOptions, ra: np.ndarray, dec: np.ndarray) -> _Frame:
    import astropy.units as u
    from astropy.coordinates import SkyCoord

    from ucbplan.observing.observatory.barycentric import SiteTrack
    from ucbplan.observing.observatory.sky import SkyModel
    from ucbplan.observing.observatory.time_axis import TimeAxis

    site = opts.site
    windows = night_windows(site, opts.dates())
    axis = TimeAxis.starting_at(windows[0].start, site.location)
    span_x = (0.0, axis.x(windows[-1].end))
    coords = SkyCoord(ra * u.deg, dec * u.deg)
    sky = SkyModel.build(site.location, axis.origin, span_x, coords)
    constraints = opts.settings.constraints(site)
    grid = np.arange(0.0, span_x[1], GRID_STEP_S) + 0.5 * GRID_STEP_S
    grid = grid[constraints.night.ok(sky, 0, grid)]
    starts = np.array([axis.x(w.start) for w in windows])
    night_of = np.searchsorted(starts, grid, side="right") - 1
    track = SiteTrack.build(axis.origin, span_x, site.location)
    return _Frame(windows, constraints, axis, span_x, sky, track, grid, night_of)


def _hours(fr: _Frame, i: int, min_hours: float) -> tuple[float, int, float]:
    """(usable hours, usable nights, best airmass at night) of sky target ``i``."""
    from ucbplan.observing.observatory.sky import airmass_from_alt

    x = fr.grid_x
    ok = np.ones(x.size, dtype=bool)
    for c in fr.constraints.active[1:]:  # the grid is already night-only
        ok &= holds(c, fr.sky, i, x)
    per_night = np.bincount(fr.night_of[ok], minlength=len(fr.windows)) * GRID_STEP_S / HOUR_S
    air = airmass_from_alt(fr.sky.target_alt_deg(i, x)) if x.size else np.array([math.inf])
    nights = (
        int(np.count_nonzero(per_night >= min_hours - 1e-9))
        if min_hours > 0
        else int(np.count_nonzero(per_night > 0))
    )
    return float(ok.sum() * GRID_STEP_S / HOUR_S), nights, float(np.min(air))


def _epochs(
    fr: _Frame, i: int, target: Any, anchor: str, opts: VisibilityOptions
) -> tuple[int, int, str]:
    """(observable epochs, of them inside validity, valid-until TDB) for one anchor."""
    import astropy.units as u
    from astropy.time import TimeDelta

    settings = opts.settings
    mode = parse_mode(anchor)
    spec = target.spectroscopy
    u_star = mode.u_values[0] if mode.tol_kind == "generic" else None
    tol = tolerance(mode.tol_kind, spec.sigma_v_kms, spec.K_eff_kms, settings.n_epochs, u_star)
    first, last = valid_window_s(target, tol, mode.u_values, settings.alpha, settings.star)
    cand = candidate_blocks(
        target,
        i,
        mode,
        fr.axis,
        fr.span_x,
        fr.track.delay_interpolator(target.coord),
        fr.sky,
        fr.constraints,
        settings.exposure,
        settings.star,
    )
    tau = cand.tau_origin_s + cand.dt_s
    inside = (tau >= first) & (tau <= last)
    until = (target.t_ref + TimeDelta(last * u.s)).tdb
    until.precision = 0
    return int(cand.ok.sum()), int((cand.ok & inside).sum()), str(until.isot)


def _row(fr: _Frame, i: int, src: Source, ra: float, dec: float, opts: VisibilityOptions) -> dict:
    frow, target = forecast_with_target(src, ra, dec, opts.forecast)
    hours, nights, best = _hours(fr, i, opts.min_hours)
    row: dict[str, Any] = {k: frow[k] for k in ("source_id", "row", "status", "vmag", "k_eff")}
    row.update(ra=ra, dec=dec, usable_hours=hours, usable_nights=nights, best_airmass=best)
    for a in ANCHORS:
        row[f"observable_{a}"], row[f"epochs_{a}"], row[f"valid_until_{a}"] = -1, -1, ""
        if target is None:
            continue
        try:
            obs, inside, until = _epochs(fr, i, target, a, opts)
        except UcbplanError as exc:
            row["status"] = f"failed: {' '.join(str(exc).split())}"[:300]
            break
        row[f"observable_{a}"], row[f"epochs_{a}"], row[f"valid_until_{a}"] = obs, inside, until
    return row


def visibility_chunk(opts: VisibilityOptions, sources: Sequence[Source]) -> list[dict[str, Any]]:
    """Rows of ``sources`` in order (a picklable task for any executor)."""
    worker_setup()
    ra, dec = icrs_of(sources)
    fr = _frame(opts, ra, dec)
    return [_row(fr, i, s, float(ra[i]), float(dec[i]), opts) for i, s in enumerate(sources)]


#: Chunk sizing [s per source]: a source costs ~0.6 s per semester, but each chunk first builds
#: its sky model and light-time track (~2 s), so chunks of ~20 sources amortise that.
VISIBILITY_SECONDS_PER_SOURCE = 0.05
