"""Option and argument types shared by several commands (declared once)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

TargetArg = Annotated[Path, typer.Argument(help="Target YAML file.")]
TargetsArg = Annotated[list[Path], typer.Argument(help="Target YAML files to check.")]
ValidateFormatOpt = Annotated[str, typer.Option("--format", help="table | json")]
TableFormatOpt = Annotated[
    str | None,
    typer.Option("--format", help="table | ecsv | csv | json (default: the -o suffix, else table)"),
]
OutputOpt = Annotated[Path | None, typer.Option("-o", "--output", help="Write here (else stdout).")]
OverwriteOutputOpt = Annotated[
    bool, typer.Option("--overwrite", help="Replace an existing -o file.")
]
OverwriteAllOpt = Annotated[
    bool, typer.Option("--overwrite", help="Replace existing output files.")
]
PlotOpt = Annotated[Path | None, typer.Option("--plot", help="Write the σ_u(t) horizon figure.")]
CompareFormatOpt = Annotated[
    str | None,
    typer.Option("--format", help="table | json (default: the -o suffix, else table)"),
]
SigmaLawOpt = Annotated[
    str | None,
    typer.Option(
        "--sigma-v",
        help="RV precision: km/s fixed per exposure (30), or of one spectrum of T_ref seconds "
        "(30km/s@600s; ,V=20.0 at that magnitude): then exposure time and cadence are chosen.",
    ),
]
SigmaFloorOpt = Annotated[
    float,
    typer.Option("--sigma-floor", help="Systematic σ_v floor added in quadrature [km/s]."),
]
ExtinctionOpt = Annotated[
    float | None,
    typer.Option(
        "--extinction",
        help="Extinction k [mag/airmass] of the σ_v law (default: the instrument's, else 0).",
    ),
]
MaxVisitOpt = Annotated[
    str | None,
    typer.Option("--max-visit", help="Longest visit a --goal plans (default 2h)."),
]
