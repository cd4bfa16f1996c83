"""``ucbplan.population_forecast``: per-source Fisher forecasts of a whole LISA catalog, the
library behind ``ucbplan population forecast``; its shared options are declared once, in
:data:`POPULATION_FLAGS` (the defaults in the signature, from
:mod:`ucbplan.population.defaults`)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from datetime import date
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ucbplan.api._convert import as_float, as_tdb, scope
from ucbplan.api.flagspec import Flag
from ucbplan.api.lisa_analysis import check_n_bins, t_obs_seconds
from ucbplan.core.constants import DAY_S
from ucbplan.errors import InputError, shorten
from ucbplan.population.defaults import DEFAULT_N_BINS, DEFAULT_SIGMA_V_KMS, DEFAULT_T_START

if TYPE_CHECKING:
    from astropy.table import Table

    from ucbplan.population.catalog import Catalog
    from ucbplan.population.catalog_forecast import ForecastOptions
    from ucbplan.population.execute import ExecutorSpec
    from ucbplan.population.runner import RunControl

#: Longest LISA observation of a population forecast [yr].
MAX_T_OBS_YR = 100.0

#: How the ``population`` commands spell the parameters of :func:`population_forecast` they
#: share, in ``--help`` order.
POPULATION_FLAGS: dict[str, Flag] = {
    "sigma_v": Flag(("--sigma-v",), "RV precision per epoch [km/s].", unit="km/s"),
    "k_eff": Flag(
        ("--k-eff",),
        "K for the tolerance [km/s] (default: K1+K2 from Mass1, Mass2).",
        unit="km/s",
    ),
    "t_obs": Flag(("--t-obs",), "LISA observation, e.g. '4yr'."),
    "t_start": Flag(("--t-start",), "LISA start (TDB): the catalog's t = 0."),
    "n_bins": Flag(("--n-bins",), "Band width N of the Fisher model."),
    "columns": Flag(("--columns",), "Column map old=new,... onto the LDC names."),
    "hdf5_path": Flag(("--hdf5-path",), "Table inside an HDF5 file."),
    "skip_bad": Flag(("--skip-bad",), "Skip bad rows (listed in meta)."),
    "workers": Flag(("--workers",), "Local processes (1 = serial)."),
    "scheduler": Flag(
        ("--scheduler",), "Existing Dask scheduler, tcp://HOST:PORT (ucbplan[dask])."
    ),
    "cluster": Flag(
        ("--cluster",), "Start Dask workers on a batch system: slurm | pbs (dask-jobqueue)."
    ),
    "jobs": Flag(("--jobs",), "Batch jobs to start with --cluster."),
}
#: The options of the commands that keep part files (all but ``rank``), in ``--help`` order.
PARTS_FLAGS: dict[str, Flag] = {
    "chunk": Flag(("--chunk",), "Sources per task (default ≥ ~1 s)."),
    "resume": Flag(("--resume",), "Reuse finished part files."),
    "keep_parts": Flag(("--keep-parts",), "Keep part files after merging."),
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
    chunk, reused, n_chunks : int
        Sources per task; part files reused (``resume``); tasks.
    """

    table: Table
    catalog: str
    chunk: int = 0
    reused: int = 0
    n_chunks: int = 0

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

    def plot(self, folder: str | Path, *, overwrite: bool = False) -> list[Path]:
        """Write the summary plots (``population forecast --plots``) in ``folder``.

        Parameters
        ----------
        folder : str or Path
            An existing folder: ``tvalid_vs_f.png``, ``tvalid_vs_snr.png`` (T_valid of the ``ok``
            rows against f_GW and SNR) and ``tvalid_cumulative.png`` go there.
        overwrite : bool
            Replace existing figures.

        Returns
        -------
        list of Path
            The three figures written.

        Raises
        ------
        OutputExistsError
            A figure exists and ``overwrite`` is false (the figures before it are written).
        """
        from ucbplan.population.plots import forecast_plots

        return list(forecast_plots(self.table, Path(folder), overwrite=overwrite))

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
    t_obs_text = t_obs if isinstance(t_obs, str) or t_obs is None else None
    if t_obs_text is None and t_obs is not None:  # seconds or a Quantity: as text, exactly
        t_obs_s = t_obs_seconds(t_obs, 0.0)
        if t_obs_s > MAX_T_OBS_YR * 365.25 * DAY_S:
            raise InputError(
                f"t_obs: expected a duration from 1 day to 100 yr, got {shorten(t_obs)}", "t_obs"
            )
        t_obs_text = f"{t_obs_s!r}s"
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
    columns: str | None = None,
    hdf5_path: str | None = None,
    skip_bad: bool = False,
    workers: int = 1,
    scheduler: str | None = None,
    cluster: str | None = None,
    jobs: int = 2,
    chunk: int | None = None,
    output: str | Path | None = None,
    resume: bool = False,
    keep_parts: bool = False,
    overwrite: bool = False,
    progress: Callable[[int, int], None] | None = None,
    on_ready: Callable[[Catalog, ExecutorSpec], None] | None = None,
) -> PopulationForecast:
    """Per-source Fisher forecast of an LDC catalog (``ucbplan population forecast``).

    Parameters
    ----------
    catalog, columns, hdf5_path, skip_bad
        LDC catalog (CSV, ECSV or HDF5) and how to read it (:func:`read_population`).
    sigma_v, k_eff : float or Quantity
        RV precision [km/s]; semi-amplitude [km/s] (None: K1+K2 from the catalog's masses).
    t_obs, t_start, n_bins
        LISA observation length (``"4yr"`` Julian, seconds or a time Quantity; 1 day to
        100 yr; default 4 sidereal years), its start (ISO TDB or ``Time``: the catalog's
        t = 0), and the band width N in bins (even, >= 16).
    workers, scheduler, cluster, jobs, chunk
        Where the sources run (:func:`executor`) and how many per task (None: about a second's
        worth); the table does not depend on them.
    output, resume, keep_parts, overwrite
        Write the table here (ECSV) with its part files in ``OUTPUT.parts`` (else a temporary
        folder); reuse finished parts; keep them after the merge; replace existing files.
    progress, on_ready : callable, optional
        ``progress(done, total)`` after each chunk; ``on_ready(catalog, executor)`` once the
        catalog is read, before the run (its skipped rows in ``catalog.bad``).

    Returns
    -------
    PopulationForecast
        One row per source: σ_u at the end, T_valid, SNR, status (docs/population.md).

    Raises
    ------
    InputError
        Bad options (one line naming the parameter), before the catalog is read.

    Examples
    --------
    >>> import ucbplan
    >>> ucbplan.population_forecast("catalogs/population/ldc-200.ecsv")
    <PopulationForecast ldc-200.ecsv: 200 sources (158 ok, 26 unconstrained, 0 failed)>
    """
    import tempfile

    opts = forecast_settings(
        sigma_v=sigma_v, k_eff=k_eff, t_obs=t_obs, t_start=t_start, n_bins=n_bins
    )
    spec = executor(workers=workers, scheduler=scheduler, cluster=cluster, jobs=jobs)
    cat = read_population(catalog, columns=columns, hdf5_path=hdf5_path, skip_bad=skip_bad)
    check_k_source(cat, k_eff)
    if on_ready is not None:
        on_ready(cat, spec)
    with tempfile.TemporaryDirectory(prefix="ucbplan-parts-") as scratch:
        parts = Path(scratch) if output is None else parts_of(output)
        control = run_control(parts, spec, chunk=chunk, resume=resume, overwrite=overwrite)
        out = None if output is None else Path(output)
        return _forecast(cat, opts, control, out, progress, keep_parts)


def _forecast(
    cat: Catalog,
    opts: ForecastOptions,
    control: RunControl,
    output: Path | None,
    progress: Callable[[int, int], None] | None,
    keep_parts: bool,
) -> PopulationForecast:
    """Run the forecast; write the table to ``output`` (if given), then drop its parts."""
    import dataclasses

    from ucbplan.population.runner import run_forecast

    with scope():
        run = run_forecast(cat, opts, dataclasses.replace(control, progress=progress))
    if output is not None:
        write_run(run.table, output, control.parts, overwrite=control.overwrite, keep=keep_parts)
    return PopulationForecast(run.table, cat.path.name, run.chunk, run.reused, run.n_chunks)


def check_k_source(catalog: Catalog, k_eff: Any) -> None:
    """Refuse a forecast with neither ``k_eff`` nor the catalog's masses to take K from.

    Raises
    ------
    InputError
        Naming ``k_eff``.
    """
    if k_eff is None and not {"Mass1", "Mass2"} <= set(catalog.optional):
        raise InputError(
            f"k_eff: needed: {catalog.path.name} has no Mass1 and Mass2 columns", "k_eff"
        )


def read_population(
    catalog: str | Path,
    *,
    columns: str | None = None,
    hdf5_path: str | None = None,
    skip_bad: bool = False,
) -> Catalog:
    """Read an LDC-style catalog (ECSV, CSV or HDF5 by suffix).

    ``columns`` maps other column names onto the LDC ones (``old=new,…``), ``hdf5_path`` is
    the table inside an HDF5 file, ``skip_bad`` skips bad rows (listed in ``.bad``) instead of
    refusing the file.
    """
    from ucbplan.population.catalog import parse_column_map, read_catalog

    if not isinstance(catalog, str | Path):
        raise InputError(f"catalog: expected a file, got {shorten(catalog, 40)}", "catalog")
    if not isinstance(skip_bad, bool):
        raise InputError(f"skip_bad: expected True or False, got {shorten(skip_bad)}", "skip_bad")
    for name, value in (("columns", columns), ("hdf5_path", hdf5_path)):
        if value is not None and not isinstance(value, str):
            raise InputError(f"{name}: expected text or None, got {shorten(value, 40)}", name)
    with scope():
        return read_catalog(
            Path(catalog), parse_column_map(columns), skip_bad=skip_bad, hdf5_path=hdf5_path
        )


def executor(
    *, workers: int = 1, scheduler: str | None = None, cluster: str | None = None, jobs: int = 2
) -> ExecutorSpec:
    """Where a whole-catalog run runs: ``workers`` local processes (1 = serial), an existing
    Dask ``scheduler`` (``tcp://HOST:PORT``), or ``jobs`` batch jobs of a ``cluster``
    (``slurm`` | ``pbs``, dask-jobqueue)."""
    from ucbplan.population.execute import ExecutorSpec

    workers, jobs = _at_least_one("workers", workers), _at_least_one("jobs", jobs)
    for name, value in (("scheduler", scheduler), ("cluster", cluster)):
        if value is not None and not isinstance(value, str):
            raise InputError(f"{name}: expected text or None, got {shorten(value, 40)}", name)
    return ExecutorSpec(workers, scheduler, cluster, jobs)


def _at_least_one(name: str, value: Any) -> int:
    """A count >= 1 (workers, jobs, sources per task), one line naming ``name`` if not."""
    from ucbplan.inputs import is_number

    if not (is_number(value) and math.isfinite(float(value)) and float(value) == int(value)):
        raise InputError(f"{name}: expected a whole number >= 1, got {shorten(value, 40)}", name)
    if value < 1:
        raise InputError(f"{name}: expected >= 1, got {value}", name)
    return int(value)


def run_control(
    parts: str | Path,
    spec: ExecutorSpec,
    *,
    chunk: int | None = None,
    resume: bool = False,
    overwrite: bool = False,
) -> RunControl:
    """How a run on ``spec`` goes: its part files in the folder ``parts``, ``chunk`` sources
    per task (None: about a second's worth), reusing finished parts with ``resume``."""
    from ucbplan.population.runner import RunControl

    chunk = None if chunk is None else _at_least_one("chunk", chunk)
    for name, value in (("resume", resume), ("overwrite", overwrite)):
        if not isinstance(value, bool):
            raise InputError(f"{name}: expected True or False, got {shorten(value)}", name)
    return RunControl(Path(parts), spec, chunk, resume, overwrite)


def parts_of(output: str | Path) -> Path:
    """The folder of the part files of a run that writes ``output``: ``OUTPUT.parts``."""
    from ucbplan.population.runner import parts_folder

    return parts_folder(Path(output))


def semester(name: str) -> tuple[date, date]:
    """The first day and the (exclusive) end of a semester (``2041A``: Feb–Jul, ``2041B``:
    Aug–Jan) or an ESO period (``P110`` starts 2022-10) (``ucbplan population semester``)."""
    from ucbplan.observing.observatory.semesters import semester_dates

    if not isinstance(name, str):
        raise InputError(f"name: expected a semester like 2041A or P147, got {shorten(name)}")
    first, end = semester_dates(name)
    return first, end


def write_run(
    table: Table, output: str | Path, parts: str | Path, *, overwrite: bool, keep: bool = False
) -> None:
    """Write a whole-catalog run's merged ``table`` (ECSV), then remove its part files in
    ``parts`` unless ``keep``."""
    from ucbplan.population.execute import remove_parts
    from ucbplan.population.tables import write_table

    write_table(table, Path(output), overwrite)
    if not keep:
        remove_parts(Path(parts))


def progress_rate() -> Any:
    """A meter of sources per second and the ETA: ``.eta(done, total) -> (rate, eta_s)``."""
    from ucbplan.population.execute import Rate

    return Rate()
