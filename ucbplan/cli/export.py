"""``ucbplan export``: observatory and proposal files from the blocks table.

A thin shell: parse options, call :func:`ucbplan.observing.exports.export_blocks`, write the file
(notes on stderr). The option declarations are module-level ``Annotated`` aliases so that the
command reads at a glance.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import IO, Annotated, Any

import typer
from rich.markup import escape

from ucbplan.cli._console import check_output_path, err_console, pick_format, write_output
from ucbplan.errors import InputError, shorten

__all__ = ["export_command", "register"]

#: ``--to`` help: the names of ``ucbplan.observing.exports.EXPORT_FORMATS`` (a test keeps them
#: equal). Spelled out because importing the exports (astropy.coordinates) at CLI start-up costs
#: ~0.3 s on every command; the library is imported only when ``export`` runs.
_EXPORT_HELP = "eso-p2 | keck-starlist | ics | proposal | ing-cat | lco | gemini | phase-table"

_Blocks = Annotated[
    Path, typer.Argument(help="Master blocks table (ECSV, CSV or JSON) from `ucbplan plan -o`.")
]
_To = Annotated[str, typer.Option("--to", help=f"Export format: {_EXPORT_HELP}.")]
_Output = Annotated[
    Path | None, typer.Option("-o", "--output", help="Output file (default stdout).")
]
_Overwrite = Annotated[bool, typer.Option("--overwrite", help="Replace an existing output file.")]
_Format = Annotated[
    str | None,
    typer.Option(
        "--format",
        help="Proposal table format: ecsv | csv | latex (default: the -o suffix, else ecsv).",
    ),
]
_Acquisition = Annotated[
    float | None,
    typer.Option(
        "--acquisition", help="Acquisition overhead (s) (default: acq_s column, else 600 s)."
    ),
]
_ToleranceSigma = Annotated[
    float,
    typer.Option(
        "--tolerance-sigma", help="Window half-width in units of the block's 1σ timing error."
    ),
]
_ToleranceFloor = Annotated[
    float, typer.Option("--tolerance-floor", help="Smallest window half-width (s).")
]
_MergeOverlaps = Annotated[
    bool,
    typer.Option(
        "--merge-overlaps", help="ESO p2: merge overlapping OBs of one target into one OB."
    ),
]
_Strict = Annotated[
    bool,
    typer.Option(
        "--strict",
        help="Queue formats (eso-p2, lco, gemini): refuse a visit that waits between exposures "
        "instead of noting it.",
    ),
]
_Rotmode = Annotated[
    str, typer.Option("--rotmode", help="Keck starlist rotmode=: pa | vertical | stationary.")
]
_Force = Annotated[
    bool,
    typer.Option(
        "--force", help="Write the file even if the plan's site is not the format's observatory."
    ),
]
_Semester = Annotated[
    str | None,
    typer.Option(
        "--semester",
        help="Proposal semester: 2041A | 2041B (A = Feb-Jul) or an ESO period like P147 "
        "(default: the one containing the plan).",
    ),
]
_Seeing = Annotated[
    float,
    typer.Option("--seeing", help="ESO p2: seeing limit of the OB constraint set (arcsec)."),
]
_Instrument = Annotated[
    str | None,
    typer.Option(
        "--instrument",
        help="ESO p2: instrument whose readout mode and overheads go into the OB templates.",
    ),
]
_EsoTemplates = Annotated[
    Path | None,
    typer.Option(
        "--eso-templates",
        help="ESO p2: YAML file with the acquisition/science template names and keywords.",
    ),
]
_Create = Annotated[
    bool,
    typer.Option(
        "--create",
        help="ESO p2: create the OBs in a p2 container with p2api (a dry run unless --no-dry-run).",
    ),
]
_DryRun = Annotated[
    bool,
    typer.Option(
        "--dry-run/--no-dry-run", help="With --create: list the OBs only (default) or create them."
    ),
]
_Container = Annotated[
    int | None, typer.Option("--container", help="With --create: p2 container id (a run/folder).")
]
_P2Env = Annotated[
    str,
    typer.Option("--p2-environment", help="With --create: demo | production | production_lasilla."),
]
_P2User = Annotated[
    str | None,
    typer.Option(
        "--p2-user",
        help="With --no-dry-run: ESO user name (password from UCBPLAN_P2_PASSWORD or a prompt).",
    ),
]


def _proposal_format(
    to: str, output: Path | None, fmt: str | None, semester: str | None
) -> str | None:
    """The proposal table format (``--format``, else the ``-o`` suffix); refuses an unknown
    ``--to`` and the proposal-only options with another format."""
    from ucbplan.observing.exports import EXPORT_FORMATS, PROPOSAL_FORMATS

    if to not in EXPORT_FORMATS:
        raise InputError(
            f"--to: unknown export format {shorten(to, 40)}; expected one of "
            f"{', '.join(EXPORT_FORMATS)}"
        )
    if to == "proposal":
        return pick_format(output, fmt, PROPOSAL_FORMATS)
    if semester is not None:
        raise InputError(f"--semester chooses the proposal's semester: --to {to} takes none")
    if fmt is not None:
        raise InputError(
            f"--format chooses the proposal table format ({' | '.join(PROPOSAL_FORMATS)}); "
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
    from ucbplan.observing.exports.eso_create import connect, create_from_export

    if c["container"] is None:
        raise InputError("--create: expected --container ID (the p2 run or folder for the OBs)")
    connection = None
    if not c["dry_run"]:
        if not c["user"]:
            raise InputError("--no-dry-run: expected --p2-user NAME (your ESO user portal name)")
        password = os.environ.get("UCBPLAN_P2_PASSWORD") or typer.prompt(
            "ESO password", hide_input=True
        )
        connection = connect(c["environment"], c["user"], password)
    report = create_from_export(
        content, c["container"], dry_run=c["dry_run"], connection=connection
    )
    sys.stdout.write(report)


def export_command(
    blocks: _Blocks,
    to: _To,
    output: _Output = None,
    overwrite: _Overwrite = False,
    fmt: _Format = None,
    acquisition: _Acquisition = None,
    tolerance_sigma: _ToleranceSigma = 3.0,
    tolerance_floor: _ToleranceFloor = 10.0,
    merge_overlaps: _MergeOverlaps = False,
    strict: _Strict = False,
    rotmode: _Rotmode = "vertical",
    force: _Force = False,
    semester: _Semester = None,
    seeing: _Seeing = 1.0,
    instrument: _Instrument = None,
    eso_templates: _EsoTemplates = None,
    create: _Create = False,
    dry_run: _DryRun = True,
    container: _Container = None,
    p2_environment: _P2Env = "demo",
    p2_user: _P2User = None,
) -> None:
    """Export a blocks table for an observatory (ESO p2, Keck, ING, LCO, Gemini), a phase table,
    a calendar or a proposal.

    All times are UTC at the site with their 1σ uncertainty; notes go to stderr. With --create
    (ESO p2), the OBs are listed (dry run) or created in p2 and the file is written only with -o.
    """
    from ucbplan.observing.exports import PROPOSAL_FORMATS, ExportOptions, export_blocks
    from ucbplan.observing.tableread import read_blocks

    fmt = _proposal_format(to, output, fmt, semester)
    eso_only = {"--create": create, "--instrument": instrument is not None}
    _check_eso_only(to, {**eso_only, "--eso-templates": eso_templates is not None})
    if output is not None:
        check_output_path(output, overwrite)
    options = ExportOptions(
        acquisition_s=acquisition,
        tolerance_sigma=tolerance_sigma,
        tolerance_floor_s=tolerance_floor,
        merge_overlaps=merge_overlaps,
        proposal_format=fmt or PROPOSAL_FORMATS[0],
        keck_rotmode=rotmode,
        force=force,
        semester=semester,
        seeing_arcsec=seeing,
        instrument=instrument,
        eso_templates=str(eso_templates) if eso_templates else None,
        strict=strict,
    )
    table = read_blocks(blocks)
    result = export_blocks(table, to, options)
    _print_notes(result.notes)
    if create:
        p2 = {"container": container, "dry_run": dry_run, "environment": p2_environment}
        _create(result.content, {**p2, "user": p2_user})
        if output is None:
            return
    _write(result.content, output, overwrite, f"{to} export of {len(table)} blocks")


def _print_notes(notes: tuple[str, ...]) -> None:
    """Each note on stderr, one line each."""
    for note in notes:
        err_console.print(f"[yellow]note:[/] {escape(note)}", soft_wrap=True)


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
