"""Whole-catalog runs: chunks through the execution seam, part files, the merged ECSV table.

:func:`run_forecast` is the library behind ``ucbplan population forecast``; it returns an astropy
table whose bytes do not depend on the executor, the number of workers or the chunk size.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ucbplan.observing.observatory.semesters import semester_dates
from ucbplan.population.catalog import Catalog
from ucbplan.population.catalog_forecast import (
    ALPHAS,
    ANCHORS,
    FORECAST_COLUMNS,
    HORIZON_CAP_DAYS,
    ForecastOptions,
    forecast_chunk,
)
from ucbplan.population.execute import (
    ExecutorSpec,
    Progress,
    default_chunk,
    open_executor,
    prepare_parts,
    run_chunks,
)
from ucbplan.population.tables import columns_table, provenance, status_counts
from ucbplan.population.visibility import (
    GRID_STEP_S,
    VISIBILITY_COLUMNS,
    VISIBILITY_SECONDS_PER_SOURCE,
    VisibilityOptions,
    visibility_chunk,
)

#: Measured Fisher + horizons per source on one core (batched: 3–5 ms) [s]; chunks
#: of ~1 s of work also amortise the per-chunk sky conversion and horizon pass.
FORECAST_SECONDS_PER_SOURCE = 0.004


def parts_folder(output: Path) -> Path:
    """Default folder of part files next to ``output``: ``OUTPUT.parts``."""
    return output.with_name(output.name + ".parts")


def forecast_table(rows: list[dict[str, Any]], catalog: Catalog, opts: ForecastOptions) -> Any:
    """Astropy table of forecast rows with units, descriptions and provenance meta."""
    from astropy.time import Time, TimeDelta

    tab = columns_table(rows, FORECAST_COLUMNS)
    t0 = Time(opts.t_start_tdb, scale="tdb")
    t_ref = t0 + TimeDelta(0.5 * opts.t_obs_s, format="sec")
    tab.meta.update(provenance("ucbplan population forecast", catalog))
    tab.meta.update(
        {
            "sigma_v_kms": opts.sigma_v_kms,
            "k_eff_kms": opts.k_eff_meta(),
            "t_obs_s": opts.t_obs_s,
            "t_start_tdb": t0.isot,
            "reference_epoch_tdb": t_ref.isot,
            "reference": "midpoint of the LISA observation (covariances and f_gw, fdot)",
            "model": "circular 6-parameter Fisher forecast, zero-noise data, Sangria noise",
            "n_bins": opts.n_bins,
            "n_epochs": opts.n_epochs,
            "anchors": list(ANCHORS),
            "alphas": list(ALPHAS),
            "t_valid_cap_days": HORIZON_CAP_DAYS,
            "catalog_convention": "LDC: Frequency, FrequencyDerivative, InitialPhase at t_start",
            **status_counts(rows),
        }
    )
    return tab


class ForecastRun:
    """What a run did: rows, chunk size, chunks reused by ``resume``."""

    def __init__(self, table: Any, chunk: int, reused: int, n_chunks: int) -> None:
        self.table, self.chunk, self.reused, self.n_chunks = table, chunk, reused, n_chunks


@dataclass(frozen=True, slots=True)
class RunControl:
    """How a whole-catalog run runs, whatever it computes: where, in what chunks, with which
    part files, and whom to tell about progress.

    Attributes
    ----------
    parts : Path
        Folder of the part files (remove them with
        :func:`~ucbplan.population.execute.remove_parts` once the table is
        written).
    executor : ExecutorSpec
        Serial, local processes or Dask.
    chunk : int or None
        Sources per task (None: :func:`~ucbplan.population.execute.default_chunk`).
    resume : bool
        Reuse the part files of an earlier run with the same fingerprint.
    overwrite : bool
        Replace earlier part files (and, for ``simulate``, target files) instead of refusing.
    progress : callable or None
        ``progress(sources_done, sources_total)`` after each chunk.
    """

    parts: Path
    executor: ExecutorSpec = field(default_factory=ExecutorSpec)
    chunk: int | None = None
    resume: bool = False
    overwrite: bool = False
    progress: Progress | None = field(default=None, compare=False, repr=False)


@dataclass(frozen=True)
class CatalogJob:
    """What a whole-catalog run computes: one picklable ``task`` per chunk of sources, and the
    ``table`` of all rows.

    Attributes
    ----------
    kind : str
        ``forecast``, ``visibility``, ``simulate`` (part fingerprints).
    task : callable
        ``task(sources) -> rows`` (one dict per source, in order), picklable.
    options : dict
        JSON-ready options of the run (part fingerprints).
    seconds_per_source : float
        Work per source on one core [s] (the default chunk size).
    table : callable
        ``table(rows) -> astropy Table``, called once with all rows in catalog order.
    """

    kind: str
    task: Callable[[Sequence[Any]], list[dict[str, Any]]]
    options: dict[str, Any]
    seconds_per_source: float
    table: Callable[[list[dict[str, Any]]], Any]


def run_catalog(catalog: Catalog, job: CatalogJob, control: RunControl) -> ForecastRun:
    """Run ``job`` over the catalog's sources in chunks through the seam; its merged table.

    Raises
    ------
    OutputExistsError
        ``control.parts`` holds parts of an earlier run and neither ``resume`` nor
        ``overwrite``.
    InputError
        Bad ``--workers``/``--chunk``/``--scheduler``/``--cluster``.
    """
    prepare_parts(control.parts, resume=control.resume, overwrite=control.overwrite)
    sources = catalog.sources
    with open_executor(control.executor) as (executor, slots):
        size = control.chunk
        if size is None:
            size = default_chunk(len(sources), slots, job.seconds_per_source)
        rows, reused = run_chunks(
            job.task,
            sources,
            [s.source_id for s in sources],
            chunk=size,
            executor=executor,
            slots=slots,
            parts=control.parts,
            kind=job.kind,
            options=job.options,
            catalog_sha256=catalog.sha256,
            resume=control.resume,
            progress=control.progress,
        )
    return ForecastRun(job.table(rows), size, reused, math.ceil(len(sources) / size))


def run_forecast(catalog: Catalog, opts: ForecastOptions, control: RunControl) -> ForecastRun:
    """Forecast every source of ``catalog``; part files stay in ``control.parts``.

    Remove them with :func:`ucbplan.population.execute.remove_parts` once the table is written.
    Raises as :func:`run_catalog`.
    """
    task = functools.partial(forecast_chunk, opts)
    table = functools.partial(forecast_table, catalog=catalog, opts=opts)
    job = CatalogJob("forecast", task, opts.as_dict(), FORECAST_SECONDS_PER_SOURCE, table)
    return run_catalog(catalog, job, control)


def run_visibility(catalog: Catalog, opts: VisibilityOptions, control: RunControl) -> ForecastRun:
    """Visibility of every source of ``catalog`` at one site in one semester (ECSV table).

    Part files stay in ``control.parts``; raises as :func:`run_catalog`.
    """
    task = functools.partial(visibility_chunk, opts)
    table = functools.partial(visibility_table, catalog=catalog, opts=opts)
    job = CatalogJob("visibility", task, opts.as_dict(), VISIBILITY_SECONDS_PER_SOURCE, table)
    return run_catalog(catalog, job, control)


def visibility_table(rows: list[dict[str, Any]], catalog: Catalog, opts: VisibilityOptions) -> Any:
    """Astropy table of visibility rows with units, descriptions and provenance meta."""
    first, end = semester_dates(opts.semester)
    tab = columns_table(rows, VISIBILITY_COLUMNS)
    tab.meta.update(provenance("ucbplan population visibility", catalog))
    tab.meta.update(
        {
            "site": opts.site.as_dict(),
            "semester": opts.semester.strip().upper(),
            "nights": f"{first.isoformat()} .. {end.isoformat()} (local evening dates, end "
            "exclusive)",
            "constraints": opts.settings.constraints(opts.site).describe(),
            "min_hours": opts.min_hours,
            "grid_step_s": GRID_STEP_S,
            "block_s": opts.settings.exposure.span_s,
            "alpha": opts.settings.alpha,
            "n_epochs": opts.settings.n_epochs,
            "sigma_v_kms": opts.forecast.sigma_v_kms,
            "k_eff_kms": opts.forecast.k_eff_meta(),
            "t_obs_s": opts.forecast.t_obs_s,
            "t_start_tdb": opts.forecast.t_start_tdb,
            "validity": "epochs_* counts blocks inside sigma_u <= alpha * delta_u_tol "
            "(Fisher forecast, circular model)",
            **status_counts(rows),
        }
    )
    return tab
