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

from ucbplan.api import populations as api
from ucbplan.api.flagspec import Flag, default_of

if TYPE_CHECKING:
    from ucbplan.api.populations import ExecutorSpec, RunControl

CatalogArg = Annotated[Path, typer.Argument(help="LDC-style catalog: ECSV, CSV or HDF5 (.h5).")]
TableOut = Annotated[Path, typer.Option("-o", "--output", help="Output table (ECSV).")]
Overwrite = Annotated[bool, typer.Option("--overwrite", help="Replace existing outputs.")]

#: The command line's type of each shared option (flag, help and default: the API's).
_TYPES: dict[str, Any] = {
    "sigma_v": float,
    "k_eff": float | None,
    "t_obs": str | None,
    "t_start": str,
    "n_bins": int,
    "columns": str | None,
    "hdf5_path": str | None,
    "skip_bad": bool,
    "workers": int,
    "scheduler": str | None,
    "cluster": str | None,
    "jobs": int,
    "chunk": int | None,
    "resume": bool,
    "keep_parts": bool,
}


def _declared(flags: dict[str, Flag]) -> tuple[tuple[str, Any, Any], ...]:
    """(parameter, typer alias, default) of each option in ``flags``: the flag and help from
    the table, the default from :func:`ucbplan.api.population_forecast`'s signature."""
    out = []
    for name, flag in flags.items():
        alias = Annotated[_TYPES[name], typer.Option(*flag.decls, help=flag.help)]  # type: ignore[valid-type]
        out.append((name, alias, default_of(api.population_forecast, name)))
    return tuple(out)


#: The shared options in ``--help`` order: (parameter, alias, default).
SHARED_OPTIONS: tuple[tuple[str, Any, Any], ...] = _declared(api.POPULATION_FLAGS)
#: The options of commands that keep part files (all but ``rank``).
PARTS_OPTIONS: tuple[tuple[str, Any, Any], ...] = _declared(api.PARTS_FLAGS)


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
        return api.executor(
            workers=self.workers, scheduler=self.scheduler, cluster=self.cluster, jobs=self.jobs
        )

    def control(self, parts: Path, overwrite: bool) -> RunControl:
        """The run control of these options with part files in ``parts``."""
        spec = self.executor()
        return api.run_control(
            parts, spec, chunk=self.chunk, resume=self.resume, overwrite=overwrite
        )


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
