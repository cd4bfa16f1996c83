"""``ucbplan.population_forecast``: per-source Fisher forecasts of a whole LISA catalog, the
library behind ``ucbplan population forecast``; its shared options are declared once, in
:data:`POPULATION_FLAGS` (the defaults in the signature, from
:mod:`ucbplan.population.defaults`)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ucbplan.api._convert import as_float, as_tdb, scope
from ucbplan.api.lisa_analysis import check_n_bins, t_obs_seconds
from ucbplan.api.options import Flag
from ucbplan.api.reduction import check_count
from ucbplan.errors import InputError, shorten
from ucbplan.population.defaults import DEFAULT_N_BINS, DEFAULT_SIGMA_V_KMS, DEFAULT_T_START

if TYPE_CHECKING:
    from astropy.table import Table

    from ucbplan.population.catalog_forecast import ForecastOptions

__all__ = [
    "MAX_LOCAL_WORKERS",
    "POPULATION_FLAGS",
    "PopulationForecast",
    "forecast_settings",
    "population_forecast",
]

#: Most local worker processes.
MAX_LOCAL_WORKERS = 4096
#: Longest LISA observation of a population forecast [yr].
MAX_T_OBS_YR = 100.0

#: How the ``population`` commands spell the forecast parameters they share.
POPULATION_FLAGS: dict[str, Flag] = {
    "catalog": Flag((), "LDC-style catalog: ECSV, CSV or HDF5 (.h5)."),
    "sigma_v": Flag(("--sigma-v",), "RV precision per epoch [km/s].", unit="km/s"),
    "k_eff": Flag(
        ("--k-eff",),
        "K for the tolerance [km/s] (default: K1+K2 from Mass1, Mass2).",
        unit="km/s",
    ),
    "t_obs": Flag(("--t-obs",), "LISA observation, e.g. '4yr'."),
    "t_start": Flag(("--t-start",), "LISA start (TDB): the catalog's t = 0."),
    "n_bins": Flag(("--n-bins",), "Band width N of the Fisher model."),
    "workers": Flag(("--workers",), "Local processes (1 = serial)."),
}


@dataclass(frozen=True)
class PopulationForecast:
    """A catalog's forecast: one row per source (σ_u at the end, T_valid, SNR, status).

    Attributes
    ----------
    table : astropy.table.Table
        The table ``ucbplan population forecast`` writes (columns in docs/population.md).
    catalog : str
        The catalog's file name.
    """

    table: Table
    catalog: str

    def __repr__(self) -> str:
        meta = self.table.meta
        return (
            f"<PopulationForecast {self.catalog}: {len(self.table)} sources "
            f"({meta['n_ok']} ok, {meta['n_unconstrained']} unconstrained, "
            f"{meta['n_failed']} failed)>"
        )

    def __len__(self) -> int:
        return len(self.table)

    def __getitem__(self, key: Any) -> Any:
        """A column (by name) or rows of :attr:`table`."""
        return self.table[key]

    @property
    def colnames(self) -> list[str]:
        """The table's columns."""
        return list(self.table.colnames)

    @property
    def meta(self) -> dict[str, Any]:
        """The table's provenance and options (as written into the ECSV header)."""
        return dict(self.table.meta)


def forecast_settings(
    *,
    sigma_v: Any = DEFAULT_SIGMA_V_KMS,
    k_eff: Any = None,
    t_obs: Any = None,
    t_start: Any = DEFAULT_T_START,
    n_bins: Any = DEFAULT_N_BINS,
) -> ForecastOptions:
    """The checked forecast options (one line naming the parameter at fault).

    ``sigma_v`` and ``k_eff`` in km/s or as velocity Quantities, ``t_obs`` as text (``4yr``),
    seconds or a time Quantity, ``t_start`` as ISO text (TDB) or a ``Time``.
    """
    from ucbplan.inputs import check_number, check_range
    from ucbplan.population.catalog_forecast import forecast_options

    sigma_v, k_eff = as_float(sigma_v, "km/s", "sigma_v"), as_float(k_eff, "km/s", "k_eff")
    check_range("sigma_v", sigma_v, 0.0, 1e4, "km/s", low_open=True)
    check_number("k_eff", k_eff, 0.1, 1e4, "km/s", "a binary's velocity semi-amplitude")
    t_obs_text = None
    if t_obs is not None:
        t_obs_s = t_obs_seconds(t_obs, 0.0)
        if t_obs_s > MAX_T_OBS_YR * 365.25 * 86400.0:
            raise InputError(
                f"t_obs: expected a duration from 1 day to 100 yr, got {shorten(t_obs)}", "t_obs"
            )
        t_obs_text = f"{t_obs_s!r}s" if not isinstance(t_obs, str) else t_obs
    with scope():
        start = as_tdb(t_start, "t_start").isot
    return forecast_options(
        sigma_v_kms=float(sigma_v),
        k_eff_kms=None if k_eff is None else float(k_eff),
        t_obs=t_obs_text,
        t_start=start,
        n_bins=check_n_bins(n_bins),
    )


def population_forecast(
    catalog: str | Path,
    sigma_v: Any = DEFAULT_SIGMA_V_KMS,
    k_eff: Any = None,
    *,
    t_obs: Any = None,
    t_start: Any = DEFAULT_T_START,
    n_bins: int = DEFAULT_N_BINS,
    workers: int = 1,
) -> PopulationForecast:
    """Per-source Fisher forecast of an LDC catalog (``ucbplan population forecast``).

    Parameters
    ----------
    catalog : str or Path
        LDC catalog (CSV, ECSV or HDF5).
    sigma_v, k_eff : float or Quantity
        RV precision [km/s]; semi-amplitude [km/s] (None: K1+K2 from the catalog's masses).
    t_obs : str, float or Quantity, optional
        LISA observation length (``"4yr"`` Julian, seconds, or a time Quantity; 1 day to
        100 yr; default: 4 sidereal years).
    t_start : str or Time
        LISA start (ISO, TDB): the catalog's t = 0.
    n_bins : int
        Band width N in frequency bins (even, >= 16).
    workers : int
        Local processes (1 = serial); the table does not depend on it.

    Returns
    -------
    PopulationForecast
        ``.table``: one row per source: σ_u at the end, T_valid, SNR, status
        (docs/population.md).

    Raises
    ------
    InputError
        Bad options (one line naming the parameter), before the catalog is read.
    """
    import tempfile

    from ucbplan.population.catalog import read_catalog
    from ucbplan.population.execute import ExecutorSpec
    from ucbplan.population.runner import RunControl, run_forecast

    opts = forecast_settings(
        sigma_v=sigma_v, k_eff=k_eff, t_obs=t_obs, t_start=t_start, n_bins=n_bins
    )
    executor = ExecutorSpec(workers=check_count("workers", workers, 1, MAX_LOCAL_WORKERS))
    if not isinstance(catalog, str | Path):
        raise InputError(f"catalog: expected a file, got {shorten(catalog, 40)}", "catalog")
    with scope(), tempfile.TemporaryDirectory(prefix="ucbplan-parts-") as parts:
        cat = read_catalog(Path(catalog))
        if k_eff is None and not {"Mass1", "Mass2"} <= set(cat.optional):
            raise InputError(
                f"k_eff: needed: {cat.path.name} has no Mass1 and Mass2 columns", "k_eff"
            )
        run = run_forecast(cat, opts, RunControl(Path(parts), executor))
    return PopulationForecast(run.table, Path(catalog).name)
