"""The library behind ``ucbplan population visibility | rank | simulate``: each command's options
declared once (defaults in the signatures here, flags and help in :data:`VISIBILITY_FLAGS`,
:data:`RANK_FLAGS`, :data:`POPULATION_SIMULATE_FLAGS`), and the few calls its shell makes, so
that the command line imports only the API. The shared catalog and run options are those of
:func:`ucbplan.api.populations.population_forecast`.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from ucbplan.api.flagspec import Flag
from ucbplan.api.plan_options import PLAN_FLAGS
from ucbplan.lisa import DEFAULT_MAX_STEPS, DEFAULT_STEPS, DEFAULT_WALKERS

if TYPE_CHECKING:
    from astropy.table import Table

    from ucbplan.population.catalog import Catalog
    from ucbplan.population.catalog_forecast import ForecastOptions
    from ucbplan.population.rank import RankOptions
    from ucbplan.population.runner import ForecastRun, RunControl
    from ucbplan.population.simulate import PopulationSimulateOptions
    from ucbplan.population.visibility import VisibilityOptions

#: How ``ucbplan population visibility`` spells the parameters of :func:`visibility_settings`.
VISIBILITY_FLAGS: dict[str, Flag] = {
    "semester": Flag(("--semester",), "2041A, 2041B or an ESO period P147."),
    # the site and the constraints as plan declares them
    "site": PLAN_FLAGS["site"],
    "site_lonlat": PLAN_FLAGS["site_lonlat"],
    "sites_file": Flag(("--sites-file",), "YAML site table."),
    "airmass_max": PLAN_FLAGS["airmass_max"],
    "twilight": Flag(("--twilight",), "civil|nautical|astronomical"),
    "moon_sep": PLAN_FLAGS["moon_sep"],
    "min_hours": Flag(("--min-hours",), "Usable hours of a usable night.", unit="h"),
    "exptime": Flag(("--exptime",), "Block (exposure) length [s].", unit="s"),
    "alpha": PLAN_FLAGS["alpha"],
}
#: How ``ucbplan population rank`` spells the parameters of :func:`rank_settings`.
RANK_FLAGS: dict[str, Flag] = {
    "top": Flag(("--top",), "Write target files for the best N."),
    "goal": Flag(("--goal",), "Precision goal (K1=5%, M1=2%, q=3%…)."),
    "instrument": Flag(("--instrument",), "σ_ref and overheads."),
    "instruments_file": Flag(("--instruments-file",), "YAML table."),
    "sigma_ref": Flag(("--sigma-ref",), "SIGMA_KMS,MAG,EXPTIME_S: σ_v of one exposure at V = MAG."),
    "exptime": Flag(("--exptime",), "One exposure [s].", unit="s"),
    "readout": Flag(("--readout",), "Readout per exposure [s].", unit="s"),
    "overhead": Flag(("--overhead",), "Acquisition per visit [s].", unit="s"),
    "visit": Flag(("--visit",), "Visit length [s].", unit="s"),
}
#: How ``ucbplan population simulate`` spells the parameters of :func:`simulation_settings`.
POPULATION_SIMULATE_FLAGS: dict[str, Flag] = {
    "seed": Flag(("--seed",), "Global seed (per source: seed + source id)."),
    "walkers": Flag(("--walkers",), "emcee walkers (≥ 12)."),
    "steps": Flag(("--steps",), "Chain steps (minimum with --until-conv.)."),
    "until_converged": Flag(
        ("--until-converged",), "Extend each chain to ≥ 50 τ (or --max-steps)."
    ),
    "max_steps": Flag(("--max-steps",), "Cap for --until-converged."),
    "no_noise": Flag(("--no-noise",), "Zero-noise data."),
}


def visibility_settings(
    semester: str,
    *,
    site: Any = None,
    site_lonlat: str | None = None,
    sites_file: str | Path | None = None,
    airmass_max: float = 2.0,
    twilight: str = "nautical",
    moon_sep: float = 30.0,
    min_hours: float = 1.0,
    exptime: float = 60.0,
    alpha: float = 1.0,
    forecast: ForecastOptions | None = None,
) -> VisibilityOptions:
    """The checked options of a population visibility run.

    Parameters
    ----------
    semester : str
        ``2041A`` (Feb–Jul), ``2041B`` (Aug–Jan) or an ESO period ``P147``.
    site, site_lonlat, sites_file
        The observatory: a name or alias (of ``sites_file``'s table too), or ``LON,LAT,HEIGHT``
        (deg east, deg north, m).
    airmass_max, twilight, moon_sep, min_hours, exptime, alpha
        Largest airmass; twilight (civil | nautical | astronomical); smallest Moon separation
        [deg]; usable hours that make a night usable [h]; block length [s]; planning margin α.
    forecast : ForecastOptions, optional
        The forecast behind the validity window (:func:`~ucbplan.api.populations.
        forecast_settings`; default: its defaults).
    """
    from ucbplan.observing.blocks.block import ExposurePlan
    from ucbplan.observing.observatory.sites import resolve_site
    from ucbplan.observing.schedule.settings import PlanSettings
    from ucbplan.population.visibility import VisibilityOptions

    where = resolve_site(site, site_lonlat, None if sites_file is None else Path(sites_file))
    settings = PlanSettings(
        twilight=twilight,
        airmass_max=airmass_max,
        moon_sep_deg=moon_sep,
        exposure=ExposurePlan(exptime_s=exptime),
        alpha=alpha,
    )
    extra = {} if forecast is None else {"forecast": forecast}
    return VisibilityOptions(
        site=where, semester=semester, settings=settings, min_hours=min_hours, **extra
    )


def run_visibility(
    catalog: Catalog, options: VisibilityOptions, control: RunControl
) -> ForecastRun:
    """Visibility of every source of ``catalog`` (part files stay in ``control.parts``)."""
    from ucbplan.population.runner import run_visibility as _run

    return _run(catalog, options, control)


def run_forecast(catalog: Catalog, options: ForecastOptions, control: RunControl) -> ForecastRun:
    """The forecast of every source of ``catalog`` (part files stay in ``control.parts``)."""
    from ucbplan.population.runner import run_forecast as _run

    return _run(catalog, options, control)


def remove_parts(parts: str | Path) -> None:
    """Delete a run's part files (and their folder once empty)."""
    from ucbplan.population.execute import remove_parts as _remove

    _remove(Path(parts))


def rank_settings(
    *,
    top: int = 10,
    goal: str = "K1=5%",
    instrument: str | None = None,
    instruments_file: str | Path | None = None,
    sigma_ref: str | None = None,
    exptime: float = 60.0,
    readout: float | None = None,
    overhead: float | None = None,
    visit: float = 3600.0,
) -> RankOptions:
    """The checked options of a ranking: how many target files, the precision goal, and the
    instrument (a name of ``instruments_file``'s table, or ``sigma_ref``
    ``SIGMA_KMS,MAG,EXPTIME_S``) with its exposure, readout and visit [s] and acquisition
    ``overhead`` [s] (default: the instrument's, else 0)."""
    from ucbplan.population.rank import rank_options

    return rank_options(
        top=top,
        goal=goal,
        instrument=instrument,
        instruments_file=None if instruments_file is None else Path(instruments_file),
        sigma_ref=sigma_ref,
        exptime_s=exptime,
        readout_s=readout,
        acquisition_s=overhead,
        visit_s=visit,
    )


def read_forecast(source: str | Path) -> tuple[Table, ForecastOptions, Path] | None:
    """A forecast table with its options and its catalog's path, or None when ``source`` is
    not a forecast table (a catalog, then)."""
    from ucbplan.population import rank as rk

    tab = rk.read_forecast_table(Path(source))
    if tab is None:
        return None
    fopts = rk.forecast_options_of(tab.meta, Path(source))
    return tab, fopts, Path(str(tab.meta.get("catalog_path", tab.meta.get("catalog"))))


def check_forecast_catalog(table: Table, catalog: Catalog, source: str | Path) -> None:
    """Refuse a catalog that is not the one ``table`` (read from ``source``) forecast."""
    from ucbplan.population.rank import check_catalog_of

    check_catalog_of(table, catalog, Path(source))


def rank_sources(table: Table, catalog: Catalog, options: RankOptions) -> Table:
    """The forecast ``table`` ordered by the stated figure of merit."""
    from ucbplan.population.rank import rank_table

    return rank_table(table, catalog, options)


def write_ranked(
    ranked: Table,
    catalog: Catalog,
    forecast: ForecastOptions,
    out_dir: str | Path,
    *,
    top: int,
    overwrite: bool = False,
) -> list[Path]:
    """Write the target files of the ``top`` sources and ``ranked.ecsv`` into ``out_dir``;
    the target files' paths."""
    from ucbplan.population import rank as rk
    from ucbplan.population.tables import write_table

    paths = rk.write_top_targets(ranked, catalog, forecast, Path(out_dir), top, overwrite)
    write_table(ranked, Path(out_dir) / "ranked.ecsv", overwrite)
    return list(paths)


def simulation_settings(
    *,
    seed: int = 0,
    walkers: int = DEFAULT_WALKERS,
    steps: int = DEFAULT_STEPS,
    until_converged: bool = False,
    max_steps: int = DEFAULT_MAX_STEPS,
    no_noise: bool = False,
    forecast: ForecastOptions | None = None,
) -> PopulationSimulateOptions:
    """The checked options of a population simulation: the global seed (per source: seed +
    source id) and the sampler's, as :func:`ucbplan.simulate`; ``no_noise``: zero-noise
    data."""
    from ucbplan.population.simulate import PopulationSimulateOptions

    extra = {} if forecast is None else {"forecast": forecast}
    return PopulationSimulateOptions(
        seed=seed,
        walkers=walkers,
        steps=steps,
        until_converged=until_converged,
        max_steps=max_steps,
        noise=not no_noise,
        **extra,
    )


def run_simulations(
    catalog: Catalog, options: PopulationSimulateOptions, out_dir: str | Path, control: RunControl
) -> ForecastRun:
    """Simulate every source of ``catalog``: a posterior target file each in ``out_dir``."""
    from ucbplan.population.simulate import run_simulate

    return run_simulate(catalog, options, Path(out_dir), control)
