"""``ucbplan replan``: the nights of a plan planned again from an instant on (a thin shell over
:func:`ucbplan.replan`; its options are declared there, :data:`~ucbplan.api.replanning.
REPLAN_FLAGS`)."""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import IO, Annotated

import typer
from rich.markup import escape

from ucbplan.api import replanning as api
from ucbplan.api import terminal
from ucbplan.api.replanning import REPLAN_FLAGS
from ucbplan.cli._console import check_output_path, err_console, write_output
from ucbplan.cli._derive import argument, flag, option
from ucbplan.cli._plan_view import report
from ucbplan.errors import UcbplanWarning

_Output = Annotated[
    Path | None, typer.Option("-o", "--output", help="Write the new blocks table (.ecsv).")
]
_Overwrite = Annotated[bool, typer.Option("--overwrite", help="Replace an existing output file.")]
_Wide = Annotated[bool, typer.Option("--wide", help="Print every column of the plan table.")]
_Verbose = Annotated[
    bool, typer.Option("--verbose", help="Print every night's table, however long the plan.")
]


def replan(
    plan: Path = argument(REPLAN_FLAGS, "plan"),
    from_: str = flag(REPLAN_FLAGS, "from_", ...),
    observed: Path | None = option(api.replan, REPLAN_FLAGS, "observed"),
    lost: list[str] | None = flag(REPLAN_FLAGS, "lost"),
    output: _Output = None,
    overwrite: _Overwrite = False,
    wide: _Wide = False,
    verbose: _Verbose = False,
) -> None:
    """Re-plan the nights of a plan from an instant on (lost nights, spectra taken)."""
    if output is not None:
        check_output_path(output, overwrite)
    old = api.Plan.read(plan)
    with warnings.catch_warnings():  # the report prints them, once, in its words
        warnings.simplefilter("ignore", UcbplanWarning)
        new = api.replan(old, from_, observed=observed, lost=lost or ())
    report(new.run, wide, verbose)
    err_console.print(api.plan_changes(old, new).line(), markup=False)
    short = {x.target for x in new.run.result.shortfalls} if new.run is not None else set()
    for line in new.run.shortfall_lines() if new.run is not None else []:
        err_console.print(line, markup=False)
    for g in (g for g in new.goals if g.target not in short):
        err_console.print(
            f"{g.target}: {g.description}: expected {g.expected.value:.4g} "
            f"{str(g.expected.unit).replace(' / ', '/')} with the spectra taken",
            markup=False,
        )
    if output is not None:
        table = new.text_table

        def _write(handle: IO[str]) -> None:
            terminal.write_table(table, handle, "ecsv", json_meta=True)

        write_output(output, _write, overwrite=overwrite)
        err_console.print(f"wrote {len(table)} blocks to {escape(str(output))} (ecsv)")


def register(app: typer.Typer) -> None:
    """Add ``replan`` to the app."""
    app.command("replan")(replan)
