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
