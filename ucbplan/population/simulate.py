"""Population simulate: the LISA simulate pipeline per source (posterior summary, target file).

Each catalog row becomes a target at the LISA midpoint (:func:`~ucbplan.population.catalog_forecast.
source_target`), simulated with :func:`ucbplan.lisa.pipeline.simulate` (circular 6-parameter
model, a noise draw and an emcee chain) seeded by :func:`~ucbplan.population.execute.
source_seed` ``(seed, source id)``: the same source gives the same posterior whatever the chunk,
worker or executor. A row holds the posterior mean and σ of each parameter beside the Fisher σ,
the chain's length, τ and convergence, and the posterior target document; the parent writes
that document as a target file per source (with the forecast's σ_v and K in ``spectroscopy``).
Any per-source error is ``failed: <type>: <message>`` and the run goes on.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ucbplan.errors import NumericalError
from ucbplan.inputs import check_int
from ucbplan.lisa.simulation import SimulateOptions
from ucbplan.population.catalog import Catalog, Source
from ucbplan.population.catalog_forecast import ForecastOptions, icrs_of, k_total_kms, source_target
from ucbplan.population.execute import source_seed, worker_setup
from ucbplan.population.tables import (
    SOURCE_COLUMNS,
    blank_row,
    columns_table,
    provenance,
    status_counts,
)

if TYPE_CHECKING:
    from ucbplan.population.runner import ForecastRun, RunControl

#: Parameters of the circular model summarised per source, with their units.
SIMULATED_PARAMETERS: tuple[tuple[str, str], ...] = (
    ("phase", "rad"),
    ("f_gw", "Hz"),
    ("fdot", "Hz / s"),
    ("cos_inclination", ""),
    ("amplitude", ""),
    ("psi", "rad"),
)


def _param_cols() -> list[tuple[str, str, str, str]]:
    cols = []
    for p, unit in SIMULATED_PARAMETERS:
        cols.append((f"mean_{p}", unit, "f8", f"posterior mean of {p} (midpoint)"))
        cols.append((f"sigma_{p}", unit, "f8", f"posterior σ of {p}"))
        cols.append((f"fisher_sigma_{p}", unit, "f8", f"Fisher σ of {p}"))
    return cols


#: The simulate summary table, declared once: (name, unit, dtype, description).
SIMULATE_COLUMNS: tuple[tuple[str, str, str, str], ...] = (
    *SOURCE_COLUMNS,
    ("status", "", "str", "ok | unconstrained | failed: <error>"),
    ("seed", "", "i8", "seed of the noise draw and chain: source_seed(--seed, source_id)"),
    ("snr", "", "f8", "optimal LISA SNR"),
    ("n_steps", "", "i8", "chain length [steps]"),
    ("tau_max", "", "f8", "largest autocorrelation time [steps]"),
    ("converged", "", "i8", "1: chain ≥ 50 τ"),
    ("folded", "", "i8", "samples moved from the π mode"),
    *_param_cols(),
    ("target_file", "", "str", "absolute path of the posterior target file"),
    ("error", "", "str", "why the Fisher matrix leaves the source unconstrained"),
)


#: The sampler's defaults, declared once by :class:`~ucbplan.lisa.simulation.SimulateOptions`.
_SIMULATE_DEFAULTS: dict[str, Any] = {f.name: f.default for f in fields(SimulateOptions)}


@dataclass(frozen=True)
class PopulationSimulateOptions:
    """Options of a population simulation (all go into the table meta and part fingerprints).

    Attributes
    ----------
    seed : int
        Global seed; each source gets ``source_seed(seed, source_id)``.
    walkers, steps, until_converged, max_steps, noise
        As ``ucbplan simulate`` (:class:`ucbplan.lisa.simulation.SimulateOptions`).
    forecast : ForecastOptions
        T_obs, LISA start and band width; σ_v and K written into each target's spectroscopy.
    """

    seed: int = _SIMULATE_DEFAULTS["seed"]
    walkers: int = _SIMULATE_DEFAULTS["walkers"]
    steps: int = _SIMULATE_DEFAULTS["steps"]
    until_converged: bool = _SIMULATE_DEFAULTS["until_converged"]
    max_steps: int = _SIMULATE_DEFAULTS["max_steps"]
    noise: bool = _SIMULATE_DEFAULTS["noise"]
    forecast: ForecastOptions = field(default_factory=ForecastOptions)

    def __post_init__(self) -> None:
        # checked once here, before any source runs (the pipeline would fail every source alike)
        n_params = len(SIMULATED_PARAMETERS)
        why = f"2 per parameter of the circular {n_params}-parameter model"
        check_int("walkers", self.walkers, 2 * n_params, 100_000, why)
        check_int("steps", self.steps, 1, 10_000_000, "chain steps")
        check_int("max_steps", self.max_steps, 1, 10_000_000, "cap of `until_converged`")

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready mapping (fingerprints and meta)."""
        return asdict(self)


def _nan_row(src: Source, seed: int) -> dict[str, Any]:
    row = blank_row(SIMULATE_COLUMNS, -1)
    row.update(source_id=src.source_id, row=src.row, status="ok", seed=seed, target_doc=None)
    row["error"] = ""
    return row


def _spectroscopy(src: Source, opts: ForecastOptions) -> Any:
    from ucbplan.targets.model import Spectroscopy

    k = opts.k_eff_kms
    if k is None and src.m1_msun is not None and src.m2_msun is not None:
        k = k_total_kms(src.m1_msun, src.m2_msun, src.f_hz, math.cos(src.inclination_rad))
    return Spectroscopy(K_eff_kms=k if k and k > 0 else None, sigma_v_kms=opts.sigma_v_kms)


def simulate_source(
    src: Source, ra_deg: float, dec_deg: float, opts: PopulationSimulateOptions
) -> dict[str, Any]:
    """One summary row (and ``target_doc``, the posterior target document) of one source."""
    import dataclasses

    from ucbplan.lisa.pipeline import build_model, simulate
    from ucbplan.targets.write import target_to_dict

    seed = source_seed(opts.seed, src.source_id)
    row = _nan_row(src, seed)
    try:
        target = source_target(src, ra_deg, dec_deg, opts.forecast)
        model = build_model(target, n_bins=opts.forecast.n_bins, circular=True)
        sim = SimulateOptions(
            seed=seed,
            walkers=opts.walkers,
            steps=opts.steps,
            until_converged=opts.until_converged,
            max_steps=opts.max_steps,
            noise=opts.noise,
        )
        res = simulate(model, sim)
        post = res.posterior(None)
    except Exception as exc:  # a batch run lists any per-source failure and goes on
        text = " ".join(str(exc).split())
        unconstrained = isinstance(exc, NumericalError) and "unconstrained" in text
        row["status"] = (
            "unconstrained" if unconstrained else f"failed: {type(exc).__name__}: {text}"
        )
        row["status"] = row["status"][:300]
        row["error"] = text[:300] if unconstrained else ""
        return row
    row.update(snr=res.problem.snr, n_steps=res.n_steps, tau_max=res.tau_max)
    row.update(converged=int(bool(res.chain.converged)), folded=int(res.n_folded))
    mean, sigma, fisher = res.posterior_mean, res.posterior_sigma, res.fisher_sigma
    for p, _ in SIMULATED_PARAMETERS:
        row[f"mean_{p}"] = mean.get(p, math.nan)
        row[f"sigma_{p}"] = sigma.get(p, math.nan)
        row[f"fisher_sigma_{p}"] = fisher.get(p, math.nan)
    post = dataclasses.replace(
        post, name=src.source_id, spectroscopy=_spectroscopy(src, opts.forecast)
    )
    row["target_doc"] = target_to_dict(post)
    return row


def simulate_chunk(
    opts: PopulationSimulateOptions, sources: Sequence[Source]
) -> list[dict[str, Any]]:
    """Rows of ``sources`` in order (a picklable task for any executor)."""
    worker_setup()
    ra, dec = icrs_of(sources)
    return [
        simulate_source(s, float(r), float(d), opts)
        for s, r, d in zip(sources, ra, dec, strict=True)
    ]


def write_posterior_targets(
    rows: list[dict[str, Any]], out_dir: Path, overwrite: bool
) -> list[Path]:
    """Write the posterior target file of each ``ok`` row to ``out_dir/<source id>.yaml``.

    The document is read back through the target parser first (the file is what ``validate``
    and ``plan`` read); ``target_file`` of each row gets the absolute path.

    Raises
    ------
    OutputExistsError
        A file exists and ``overwrite`` is false (all are checked before any is written).
    """
    from ucbplan.io import check_output_path
    from ucbplan.observing.schedule.records import slug
    from ucbplan.targets.parse import target_from_dict
    from ucbplan.targets.write import write_target

    todo = {}
    for i, r in enumerate(rows):
        if r["status"] == "ok" and r.get("target_doc") is not None:
            path = (out_dir / f"{slug(r['source_id'])}.yaml").resolve()
            check_output_path(path, overwrite)
            todo[i] = path
    for i, path in todo.items():
        r = rows[i]
        header = (
            f"ucbplan population simulate: posterior of catalog row {r['row']}, seed {r['seed']}"
        )
        write_target(target_from_dict(r["target_doc"]), path, overwrite=overwrite, header=header)
        r["target_file"] = str(path)
    return list(todo.values())


#: Simulate with a short chain is ~1 s per source, to convergence 20–40 s [s].
SIMULATE_SECONDS_PER_SOURCE = 20.0


def simulate_table(
    rows: list[dict[str, Any]], catalog: Catalog, opts: PopulationSimulateOptions
) -> Any:
    """Astropy summary table of simulate rows with units, descriptions and provenance meta."""
    tab = columns_table(rows, SIMULATE_COLUMNS)
    tab.meta.update(provenance("ucbplan population simulate", catalog))
    f = opts.forecast
    tab.meta.update(
        {
            "seed": opts.seed,
            "per_source_seed": "sha256(seed, source_id) (ucbplan.population.execute.source_seed)",
            "walkers": opts.walkers,
            "steps": opts.steps,
            "until_converged": opts.until_converged,
            "max_steps": opts.max_steps,
            "noise": opts.noise,
            "model": "circular 6-parameter targeted search, Sangria noise, emcee",
            "n_bins": f.n_bins,
            "t_obs_s": f.t_obs_s,
            "t_start_tdb": f.t_start_tdb,
            "reference": "midpoint of the LISA observation (means and sigmas)",
            "sigma_v_kms": f.sigma_v_kms,
            "k_eff_kms": f.k_eff_meta(),
            **status_counts(rows),
            "failed": [
                {"source_id": r["source_id"], "error": r["status"]}
                for r in rows
                if r["status"].startswith("failed")
            ],
        }
    )
    return tab


def run_simulate(
    catalog: Catalog, opts: PopulationSimulateOptions, out_dir: Path, control: RunControl
) -> ForecastRun:
    """Simulate every source; posterior target files in ``out_dir``; the summary table.

    Part files stay in ``control.parts`` (remove them once the table is written). Raises as
    :func:`ucbplan.population.runner.run_catalog`, and OutputExistsError for an existing target
    file without ``control.overwrite``.
    """
    import functools

    from ucbplan.io import check_output_path
    from ucbplan.observing.schedule.records import slug
    from ucbplan.population.runner import CatalogJob, run_catalog

    out_dir.mkdir(parents=True, exist_ok=True)
    for src in catalog.sources:  # refuse before hours of sampling, not after
        check_output_path(out_dir / f"{slug(src.source_id)}.yaml", control.overwrite)

    def table(rows: list[dict[str, Any]]) -> Any:
        write_posterior_targets(rows, out_dir, control.overwrite)
        return simulate_table(rows, catalog, opts)

    task = functools.partial(simulate_chunk, opts)
    job = CatalogJob("simulate", task, opts.as_dict(), SIMULATE_SECONDS_PER_SOURCE, table)
    return run_catalog(catalog, job, control)
