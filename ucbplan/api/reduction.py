"""``ucbplan.reduce``, ``ucbplan.simulate`` and ``ucbplan.population_forecast``: the
measuring half of the public API (each the library behind one command)."""

from __future__ import annotations

import io
import json
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ucbplan.api._convert import as_float, scope
from ucbplan.api.ephemeris import TargetLike, get_site, load_target
from ucbplan.errors import InputError, ReduceWarning, SamplerConvergenceWarning, emit, shorten
from ucbplan.lisa import MIN_T_OBS_S  # shortest LISA observation [s] (t_obs, --t-obs)
from ucbplan.population.defaults import DEFAULT_N_BINS, DEFAULT_SIGMA_V_KMS, DEFAULT_T_START

if TYPE_CHECKING:
    from astropy.table import Table

    from ucbplan.lisa.simulation import SimulationResult
    from ucbplan.reduce.pipeline import ReduceOptions, Reduction

__all__ = ["MIN_T_OBS_S", "Report", "population_forecast", "reduce", "simulate", "t_obs_seconds"]


@dataclass(frozen=True)
class Report:
    """A finished reduction: K_j, γ_j, masses, Δκ and Δv_CM with their uncertainties.

    Attributes
    ----------
    reduction : Reduction
        Everything the reduction found (fits, Monte-Carlo samples …).
    """

    reduction: Reduction

    @cached_property
    def _doc(self) -> dict[str, Any]:
        from ucbplan.reduce.report import build_report

        return build_report(self.reduction)

    def to_dict(self) -> dict[str, Any]:
        """The report exactly as ``ucbplan reduce --format json`` writes it, parsed: plain
        floats (km/s, M_sun …, units named in each entry), lists and dicts; NaN as None."""
        from ucbplan.io import dump_json

        buf = io.StringIO()
        dump_json(self._doc, buf)
        return dict(json.loads(buf.getvalue()))

    @property
    def warnings(self) -> list[str]:
        """What the reduction warns about (also emitted as :class:`ucbplan.ReduceWarning`)."""
        return [str(w) for w in self._doc.get("warnings", [])]

    def em_prior(self) -> dict[str, Any]:
        """The EM prior for a later LISA analysis (``reduce --em-prior``)."""
        from ucbplan.reduce.report import em_prior

        return em_prior(self.reduction)

    def plot(self, folder: str | Path, overwrite: bool = False) -> list[Path]:
        """The reduction's PNG figures in ``folder`` (``reduce --plots``); their paths."""
        from ucbplan.reduce.plots import plot_all

        return list(plot_all(self.reduction, Path(folder), overwrite=overwrite))


def reduce(
    target: TargetLike,
    velocities: Any,
    seed: int | None = None,
    *,
    samples: int = 20_000,
    light_time: bool = False,
    mass_radius: str | None = None,
    cos_i_sigma: float = 0.0,
    site: Any = None,
) -> Report:
    """Reduce measured velocities against a target (``ucbplan reduce``; paper Secs. 3–5).

    Parameters
    ----------
    target : str, Path, dict or Target
        LISA ephemeris and posterior (see :func:`ucbplan.load_target`).
    velocities : str, Path or VelocityTable
        Velocity table (CSV or ECSV): ``bjd_tdb``, ``exptime_s``, ``v1``, ``sigma_v1`` … [km/s].
    seed, samples : int, optional
        Seed of the Monte-Carlo draws (None: fresh entropy, reported in the report); their number.
    light_time, mass_radius, cos_i_sigma : bool, str, float, optional
        Correct for the light travel time across the orbit; WD mass–radius relation for the
        redshift check (``eggleton``, ``nauenberg``); 1σ of cos ι [1] if neither the covariance
        nor the samples carry it.
    site : str, EarthLocation or astroplan Observer, optional
        Telescope, when the table's times are UTC at the site.

    Returns
    -------
    Report
        K_j, γ_j [km/s], masses [M_sun], Δκ, Δv_CM; ``warnings`` also emitted as ReduceWarning.

    Raises
    ------
    InputError
        Bad options (naming the parameter); VelocityFileError, TargetFileError for the files.
    """
    from ucbplan.reduce.pipeline import reduce_options

    options = reduce_options(
        samples=samples,
        seed=seed,
        light_time=light_time,
        mass_radius=mass_radius,
        cos_i_sigma=cos_i_sigma,
    )
    report, lines = _report(target, velocities, site, options)
    emit(lines, ReduceWarning)
    return report


def _report(
    target: TargetLike, velocities: Any, site: Any, options: ReduceOptions
) -> tuple[Report, list[str]]:
    """Load the target and the velocities, reduce; the report and its warnings, both built
    inside the API's astropy scope."""
    from ucbplan.reduce.pipeline import reduce as _reduce

    with scope():
        tgt = load_target(target)
        table = _velocity_table(velocities, tgt, site)
        report = Report(_reduce(tgt, table, options))
        return report, report.warnings


def _velocity_table(velocities: Any, tgt: Any, site: Any) -> Any:
    """The velocity table, site-UTC times converted to barycentric TDB at ``site``."""
    from ucbplan.reduce.velocities import VelocityTable, read_velocities, to_barycentric

    table = velocities if isinstance(velocities, VelocityTable) else read_velocities(velocities)
    if table.site_utc:
        if site is None:
            raise InputError(
                f"site: {table.source}: times are UTC at the telescope; pass site=NAME to "
                "convert them",
                parameter="site",
            )
        table = to_barycentric(table, tgt.coord, get_site(site).location)
    return table


def simulate(
    target: TargetLike,
    seed: int = 0,
    *,
    t_obs: Any = None,
    n_bins: int = 512,
    circular: bool = False,
    walkers: int = 32,
    steps: int = 2000,
    until_converged: bool = False,
    max_steps: int = 50_000,
    noise: bool = True,
) -> SimulationResult:
    """Simulate a LISA observation and sample the targeted-search posterior (``ucbplan
    simulate``).

    Parameters
    ----------
    target : str, Path, dict or Target
        Target or injection (needs ``lisa.amplitude``, ``cos_inclination``, ``psi``).
    seed : int
        Seed of the noise draw and the sampler.
    t_obs : str, float or Quantity, optional
        Observation length (``"4yr"``, seconds or a time Quantity; default: the target's).
    n_bins, circular, walkers, steps, until_converged, max_steps, noise
        As the ``simulate`` options.

    Returns
    -------
    SimulationResult
        Posterior samples, mean, σ and the Fisher σ; write it with
        :func:`ucbplan.lisa.outputs.write_simulation`.

    Raises
    ------
    InputError
        Bad options (one line each).
    """
    from ucbplan.lisa.pipeline import run_simulation, setup_simulation

    with scope():
        tgt = load_target(target)
        problem = setup_simulation(
            tgt,
            t_obs_s=t_obs_seconds(t_obs, tgt.t_obs_s),
            n_bins=n_bins,
            circular=circular,
            seed=seed,
            walkers=walkers,
            steps=steps,
            until_converged=until_converged,
            max_steps=max_steps,
            noise=noise,
        )
        result = run_simulation(problem)
    emit(list(result.warnings), SamplerConvergenceWarning)
    return result


def t_obs_seconds(t_obs: Any, default_s: float, parameter: str = "t_obs") -> float:
    """An observation length [s] from text (``4yr``, Julian years), seconds or a Quantity.

    Raises
    ------
    InputError
        Not a duration of at least a day (naming ``parameter``).
    """
    if t_obs is None:
        return default_s
    import astropy.units as u

    value = as_float(t_obs, "s", parameter)
    if isinstance(value, str):
        try:
            value = float(u.Quantity(value.replace(" ", "")).to_value(u.s))
        except (TypeError, ValueError, u.UnitsError):
            raise InputError(
                f"{parameter}: expected a duration like '4yr' (Julian) or '126232599.054s', "
                f"got {shorten(t_obs)}",
                parameter=parameter,
            ) from None
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise InputError(f"{parameter}: expected a duration, got {shorten(t_obs)}", parameter)
    if not MIN_T_OBS_S <= value < float("inf"):
        raise InputError(
            f"{parameter}: expected a finite duration of at least 1 day, got {shorten(t_obs)}",
            parameter=parameter,
        )
    return float(value)


def population_forecast(
    catalog: str | Path,
    sigma_v: Any = DEFAULT_SIGMA_V_KMS,
    k_eff: Any = None,
    *,
    t_obs: str | None = None,
    t_start: str = DEFAULT_T_START,
    n_bins: int = DEFAULT_N_BINS,
    workers: int = 1,
) -> Table:
    """Per-source Fisher forecast of an LDC catalog (``ucbplan population forecast``).

    Parameters
    ----------
    catalog : str or Path
        LDC catalog (CSV, ECSV or HDF5).
    sigma_v, k_eff : float or Quantity
        RV precision [km/s]; semi-amplitude [km/s] (None: from the catalog's masses).
    t_obs, t_start : str, optional
        LISA observation length (``4yr``) and start (ISO, TDB).
    n_bins : int
        Band width N in frequency bins.
    workers : int
        Local processes (1 = serial); the table does not depend on it.

    Returns
    -------
    astropy.table.Table
        One row per source: σ_u at the end, T_valid, SNR, status (docs/population.md).
    """
    import tempfile

    from ucbplan.population.catalog import read_catalog
    from ucbplan.population.catalog_forecast import forecast_options
    from ucbplan.population.execute import ExecutorSpec
    from ucbplan.population.runner import RunControl, run_forecast

    opts = forecast_options(
        sigma_v_kms=as_float(sigma_v, "km/s", "sigma_v"),
        k_eff_kms=as_float(k_eff, "km/s", "k_eff"),
        t_obs=t_obs,
        t_start=t_start,
        n_bins=n_bins,
    )
    with scope(), tempfile.TemporaryDirectory(prefix="ucbplan-parts-") as parts:
        cat = read_catalog(Path(catalog))
        run = run_forecast(cat, opts, RunControl(Path(parts), ExecutorSpec(workers=workers)))
    return run.table
