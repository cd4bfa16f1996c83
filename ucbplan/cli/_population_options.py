"""The options the ``population`` commands share, declared once.

Each shared option is a typer ``Annotated`` alias with its default in :data:`SHARED_OPTIONS`;
:func:`population_options` puts them into a command's signature in place of its ``shared``
parameter and hands the command their values as one :class:`PopulationArgs`. ``--help`` and
the generated CLI reference list them where ``shared`` stands, in this order.
"""

from __future__ import annotations

import functools
import inspect
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from ucbplan.population.defaults import DEFAULT_N_BINS, DEFAULT_SIGMA_V_KMS, DEFAULT_T_START

if TYPE_CHECKING:
    from ucbplan.population.execute import ExecutorSpec
    from ucbplan.population.runner import RunControl

__all__ = ["PopulationArgs", "population_options"]

CatalogArg = Annotated[Path, typer.Argument(help="LDC-style catalog: ECSV, CSV or HDF5 (.h5).")]
TableOut = Annotated[Path, typer.Option("-o", "--output", help="Output table (ECSV).")]
Overwrite = Annotated[bool, typer.Option("--overwrite", help="Replace existing outputs.")]
SigmaV = Annotated[float, typer.Option("--sigma-v", help="RV precision per epoch [km/s].")]
KEff = Annotated[
    float | None,
    typer.Option("--k-eff", help="K for the tolerance [km/s] (default: K1+K2 from Mass1, Mass2)."),
]
TObs = Annotated[str | None, typer.Option("--t-obs", help="LISA observation, e.g. '4yr'.")]
TStart = Annotated[str, typer.Option("--t-start", help="LISA start (TDB): the catalog's t = 0.")]
NBins = Annotated[int, typer.Option("--n-bins", help="Band width N of the Fisher model.")]
Columns = Annotated[
    str | None, typer.Option("--columns", help="Column map old=new,... onto the LDC names.")
]
Hdf5Path = Annotated[str | None, typer.Option("--hdf5-path", help="Table inside an HDF5 file.")]
SkipBad = Annotated[bool, typer.Option("--skip-bad", help="Skip bad rows (listed in meta).")]
Workers = Annotated[int, typer.Option("--workers", help="Local processes (1 = serial).")]
Scheduler = Annotated[
    str | None,
    typer.Option("--scheduler", help="Existing Dask scheduler, tcp://HOST:PORT (ucbplan[dask])."),
]
Cluster = Annotated[
    str | None,
    typer.Option(
        "--cluster", help="Start Dask workers on a batch system: slurm | pbs (dask-jobqueue)."
    ),
]
Jobs = Annotated[int, typer.Option("--jobs", help="Batch jobs to start with --cluster.")]
Chunk = Annotated[int | None, typer.Option("--chunk", help="Sources per task (default ≥ ~1 s).")]
Resume = Annotated[bool, typer.Option("--resume", help="Reuse finished part files.")]
KeepParts = Annotated[bool, typer.Option("--keep-parts", help="Keep part files after merging.")]

#: The shared options in ``--help`` order: (parameter, alias, default).
SHARED_OPTIONS: tuple[tuple[str, Any, Any], ...] = (
    ("sigma_v", SigmaV, DEFAULT_SIGMA_V_KMS),
    ("k_eff", KEff, None),
    ("t_obs", TObs, None),
    ("t_start", TStart, DEFAULT_T_START),
    ("n_bins", NBins, DEFAULT_N_BINS),
    ("columns", Columns, None),
    ("hdf5_path", Hdf5Path, None),
    ("skip_bad", SkipBad, False),
    ("workers", Workers, 1),
    ("scheduler", Scheduler, None),
    ("cluster", Cluster, None),
    ("jobs", Jobs, 2),
)
#: The options of commands that keep part files (all but ``rank``).
PARTS_OPTIONS: tuple[tuple[str, Any, Any], ...] = (
    ("chunk", Chunk, None),
    ("resume", Resume, False),
    ("keep_parts", KeepParts, False),
)


@dataclass(frozen=True, slots=True)
class PopulationArgs:
    """The values of the shared options of one ``population`` command."""

    sigma_v: float
    k_eff: float | None
    t_obs: str | None
    t_start: str
    n_bins: int
    columns: str | None
    hdf5_path: str | None
    skip_bad: bool
    workers: int
    scheduler: str | None
    cluster: str | None
    jobs: int
    chunk: int | None = None
    resume: bool = False
    keep_parts: bool = False

    def executor(self) -> ExecutorSpec:
        """The checked executor of ``--workers``/``--scheduler``/``--cluster``/``--jobs``."""
        from ucbplan.population.execute import ExecutorSpec

        return ExecutorSpec(self.workers, self.scheduler, self.cluster, self.jobs)

    def control(self, parts: Path, overwrite: bool) -> RunControl:
        """The run control of these options with part files in ``parts``."""
        from ucbplan.population.runner import RunControl

        return RunControl(parts, self.executor(), self.chunk, self.resume, overwrite)


def population_options(*, parts: bool = True) -> Callable[[Callable[..., Any]], Any]:
    """Decorator: the shared options (and, with ``parts``, ``--chunk``, ``--resume``,
    ``--keep-parts``) in place of the command's keyword-only ``shared: PopulationArgs``."""
    declared = SHARED_OPTIONS + (PARTS_OPTIONS if parts else ())
    kind = inspect.Parameter.KEYWORD_ONLY  # typer passes every value by name

    def decorate(func: Callable[..., Any]) -> Any:
        signature = inspect.signature(func, eval_str=True)
        if "shared" not in signature.parameters:
            raise TypeError(f"{func.__name__}: no 'shared' parameter to put the options in")
        params: list[inspect.Parameter] = []
        for p in signature.parameters.values():
            if p.name != "shared":
                params.append(p.replace(kind=kind))
                continue
            params += [inspect.Parameter(n, kind, default=d, annotation=a) for n, a, d in declared]

        @functools.wraps(func)
        def command(**kwargs: Any) -> Any:
            shared = PopulationArgs(**{n: kwargs.pop(n) for n, _, _ in declared})
            return func(**kwargs, shared=shared)

        command.__signature__ = inspect.Signature(params, return_annotation=None)  # type: ignore[attr-defined]
        command.__annotations__ = {p.name: p.annotation for p in params} | {"return": None}
        return command

    return decorate
