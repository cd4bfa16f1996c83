"""``ucbplan export``: observatory and proposal files from the blocks table.

A thin shell: parse options, call :func:`ucbplan.observing.exports.export_blocks`, write the file
(notes on stderr). The option declarations are module-level ``Annotated`` aliases so that the
command reads at a glance.
"""

from __future__ import annotations

from pathlib import Path
from typing import IO, Annotated

import typer

from ucbplan.cli._console import err_console, write_output
from ucbplan.errors import UcbplanError

__all__ = ["export_command", "register"]

#: ``--to`` help: the names of ``ucbplan.observing.exports.EXPORT_FORMATS`` (a test keeps them
#: equal). Spelled out because importing the exports (astropy.coordinates) at CLI start-up costs
#: ~0.3 s on every command; the library is imported only when ``export`` runs.
_EXPORT_HELP = "eso-p2 | keck-starlist | ics | proposal | ing-cat | lco"

_Blocks = Annotated[Path, typer.Argument(help="Master blocks table (ECSV) from `ucbplan plan -o`.")]
_To = Annotated[str, typer.Option("--to", help=f"Export format: {_EXPORT_HELP}.")]
_Output = Annotated[
    Path | None, typer.Option("-o", "--output", help="Output file (default stdout).")
]
_Overwrite = Annotated[bool, typer.Option("--overwrite", help="Replace an existing output file.")]
_Format = Annotated[
    str, typer.Option("--format", help="Proposal table format: ecsv | csv | latex.")
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
_Rotmode = Annotated[str, typer.Option("--rotmode", help="Keck starlist rotmode= value.")]


def export_command(
    blocks: _Blocks,
    to: _To,
    output: _Output = None,
    overwrite: _Overwrite = False,
    fmt: _Format = "ecsv",
    acquisition: _Acquisition = None,
    tolerance_sigma: _ToleranceSigma = 3.0,
    tolerance_floor: _ToleranceFloor = 10.0,
    merge_overlaps: _MergeOverlaps = False,
    rotmode: _Rotmode = "vertical",
) -> None:
    """Export a blocks table for an observatory (ESO p2, Keck, ING, LCO), a calendar or a proposal.

    All times are UTC at the site with their 1σ uncertainty; notes go to stderr.
    """
    from ucbplan.observing.blocktable import read_blocks
    from ucbplan.observing.exports import PROPOSAL_FORMATS, ExportOptions, export_blocks

    if tolerance_sigma < 0 or tolerance_floor < 0 or (acquisition is not None and acquisition < 0):
        raise UcbplanError(
            "--tolerance-sigma, --tolerance-floor and --acquisition must be >= 0; "
            f"got {tolerance_sigma}, {tolerance_floor}, {acquisition}"
        )
    if fmt not in PROPOSAL_FORMATS:
        known = f"{', '.join(PROPOSAL_FORMATS[:-1])} or {PROPOSAL_FORMATS[-1]}"
        raise UcbplanError(f"--format: got {fmt!r}, expected {known} (proposal table)")
    options = ExportOptions(
        acquisition_s=acquisition,
        tolerance_sigma=tolerance_sigma,
        tolerance_floor_s=tolerance_floor,
        merge_overlaps=merge_overlaps,
        proposal_format=fmt,
        keck_rotmode=rotmode,
    )
    table = read_blocks(blocks)
    result = export_blocks(table, to, options)
    for note in result.notes:
        err_console.print(f"[yellow]note:[/] {note}", soft_wrap=True)

    def writer(handle: IO[bytes]) -> None:
        handle.write(result.content)

    write_output(output, writer, overwrite=overwrite, binary=True)
    if output is not None:
        err_console.print(f"wrote {to} export of {len(table)} blocks to {output}")


def register(app: typer.Typer) -> None:
    """Add ``export`` to the ucbplan app."""
    app.command("export")(export_command)
