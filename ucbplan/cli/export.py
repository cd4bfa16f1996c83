"""``ucbplan export``: observatory and proposal files from the blocks table.

A thin shell: parse options, call :func:`ucbplan.api.exporting.export`, write the file (notes on
stderr). Each option that :func:`~ucbplan.api.exporting.export` takes is declared there
(:data:`~ucbplan.api.exporting.EXPORT_FLAGS`: default, flag and help); the command line adds
only what is its own (the output file, ``--create`` in p2).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import IO, Annotated, Any

import typer
from rich.markup import escape

from ucbplan.api import exporting as api
from ucbplan.api.exporting import EXPORT_FLAGS, P2_FLAGS
from ucbplan.cli._console import check_output_path, err_console, pick_format, write_output
from ucbplan.cli._derive import argument, flag, option
from ucbplan.cli._flags import cli_text
from ucbplan.errors import InputError, shorten

_Output = Annotated[
    Path | None, typer.Option("-o", "--output", help="Output file (default stdout).")
]
_Overwrite = Annotated[bool, typer.Option("--overwrite", help="Replace an existing output file.")]
_Create = Annotated[
    bool,
    typer.Option(
        "--create",
        help="ESO p2: create the OBs in a p2 container with p2api (a dry run unless --no-dry-run).",
    ),
]


def _proposal_format(
    to: str, output: Path | None, fmt: str | None, semester: str | None
) -> str | None:
    """The proposal table format (``--format``, else the ``-o`` suffix); refuses an unknown
    ``--to`` and the proposal-only options with another format."""
    formats, proposal = api.export_formats()
    if to not in formats:
        raise InputError(
            f"--to: unknown export format {shorten(to, 40)}; expected one of {', '.join(formats)}"
        )
    if to == "proposal":
        return pick_format(output, fmt, proposal)
    if semester is not None:
        raise InputError(f"--semester chooses the proposal's semester: --to {to} takes none")
    if fmt is not None:
        raise InputError(
            f"--format chooses the proposal table format ({' | '.join(proposal)}); "
            f"--to {to} writes one fixed format: leave --format out"
        )
    return None


def _check_eso_only(to: str, given: dict[str, bool]) -> None:
    """Refuse an ESO p2 option with another format (it would be ignored without a word)."""
    used = [name for name, on in given.items() if on]
    if to != "eso-p2" and used:
        raise InputError(f"{used[0]} is an ESO p2 option: use it with --to eso-p2, not --to {to}")


def _create(content: bytes, c: dict[str, Any]) -> None:
    """``--create``: list (dry run) or create the OBs of an eso-p2 export with p2api."""
    if c["container"] is None:
        raise InputError("--create: expected --container ID (the p2 run or folder for the OBs)")
    password = None
    if not c["dry_run"]:
        if not c["user"]:
            raise InputError("--no-dry-run: expected --p2-user NAME (your ESO user portal name)")
        password = os.environ.get("UCBPLAN_P2_PASSWORD") or typer.prompt(
            "ESO password", hide_input=True
        )
    report = api.eso_p2_create(
        content,
        c["container"],
        dry_run=c["dry_run"],
        environment=c["environment"],
        user=c["user"],
        password=password,
    )
    sys.stdout.write(report)


def export_command(
    blocks: Path = argument(EXPORT_FLAGS, "blocks"),
    to: str = flag(EXPORT_FLAGS, "to", ...),
    output: _Output = None,
    overwrite: _Overwrite = False,
    fmt: str | None = flag(EXPORT_FLAGS, "proposal_format"),
    acquisition: float | None = option(api.export, EXPORT_FLAGS, "acquisition"),
    tolerance_sigma: float = option(api.export, EXPORT_FLAGS, "tolerance_sigma"),
    tolerance_floor: float = option(api.export, EXPORT_FLAGS, "tolerance_floor"),
    merge_overlaps: bool = option(api.export, EXPORT_FLAGS, "merge_overlaps"),
    strict: bool = option(api.export, EXPORT_FLAGS, "strict"),
    rotmode: str = option(api.export, EXPORT_FLAGS, "rotmode"),
    force: bool = option(api.export, EXPORT_FLAGS, "force"),
    semester: str | None = option(api.export, EXPORT_FLAGS, "semester"),
    seeing: float = option(api.export, EXPORT_FLAGS, "seeing"),
    instrument: str | None = option(api.export, EXPORT_FLAGS, "instrument"),
    eso_templates: Path | None = option(api.export, EXPORT_FLAGS, "eso_templates"),
    create: _Create = False,
    dry_run: bool = option(api.eso_p2_create, P2_FLAGS, "dry_run"),
    container: int | None = flag(P2_FLAGS, "container"),
    p2_environment: str = option(api.eso_p2_create, P2_FLAGS, "environment"),
    p2_user: str | None = option(api.eso_p2_create, P2_FLAGS, "user"),
) -> None:
    """Export a blocks table for an observatory (ESO p2, Keck, ING, LCO, Gemini), a phase table,
    a calendar or a proposal.

    All times are UTC at the site with their 1σ uncertainty; notes go to stderr. With --create
    (ESO p2), the OBs are listed (dry run) or created in p2 and the file is written only with -o.
    """
    fmt = _proposal_format(to, output, fmt, semester)
    eso_only = {"--create": create, "--instrument": instrument is not None}
    _check_eso_only(to, {**eso_only, "--eso-templates": eso_templates is not None})
    if output is not None:
        check_output_path(output, overwrite)
    result = api.export(
        blocks,
        to,
        proposal_format=fmt,
        acquisition=acquisition,
        tolerance_sigma=tolerance_sigma,
        tolerance_floor=tolerance_floor,
        merge_overlaps=merge_overlaps,
        rotmode=rotmode,
        force=force,
        semester=semester,
        seeing=seeing,
        instrument=instrument,
        eso_templates=eso_templates,
        strict=strict,
    )
    _print_notes(result.notes)
    if create:
        p2 = {"container": container, "dry_run": dry_run, "environment": p2_environment}
        _create(result.content, {**p2, "user": p2_user})
        if output is None:
            return
    _write(result.content, output, overwrite, f"{to} export of {result.n_blocks} blocks")


def _print_notes(notes: tuple[str, ...]) -> None:
    """Each note on stderr, one line each, parameters named by their flags."""
    for note in notes:
        err_console.print(f"[yellow]note:[/] {escape(cli_text(note))}", soft_wrap=True)


def _write(content: bytes, output: Path | None, overwrite: bool, what: str) -> None:
    """``content`` to ``output`` (standard output without -o), and a line saying so."""

    def writer(handle: IO[bytes]) -> None:
        handle.write(content)

    write_output(output, writer, overwrite=overwrite, binary=True)
    if output is not None:
        err_console.print(f"wrote {what} to {escape(str(output))}", soft_wrap=True)


def register(app: typer.Typer) -> None:
    """Add ``export`` to the ucbplan app."""
    app.command("export")(export_command)
