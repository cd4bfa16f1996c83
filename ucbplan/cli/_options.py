"""Option and argument types shared by several commands (declared once)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from ucbplan.api.plan_options import PLAN_FLAGS
from ucbplan.cli._derive import annotated

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
StartOpt = Annotated[str, typer.Option("--start", help="Window start, ISO, TDB at the barycentre.")]
EndOpt = Annotated[str, typer.Option("--end", help="Window end, ISO, TDB at the barycentre.")]
AnchorOpt = Annotated[
    str,
    typer.Option(
        "--anchor",
        help="quadrature | conjunction | eclipse (primary and secondary) | zero-crossing | U_RAD",
    ),
]
StarOpt = Annotated[
    int, typer.Option("--star", help="Component whose argument of latitude (1 or 2).")
]
MaxEpochsOpt = Annotated[
    int, typer.Option("--max-epochs", help="Refuse windows with more epochs than this.")
]
SigmaVOpt = Annotated[
    float | None,
    typer.Option("--sigma-v", help="RV precision per epoch σ_v [km/s] (default: target file)."),
]
KEffOpt = Annotated[
    float | None,
    typer.Option(
        "--k-eff", help="Semi-amplitude of the observable [km/s] (default: K_eff or K1+K2)."
    ),
]
AlphaOpt = Annotated[list[float], typer.Option("--alpha", help="Margin α (repeatable).")]
EpochsOpt = Annotated[
    int, typer.Option("--epochs", help="1: single epoch, 2: two-epoch difference.")
]
AnchorsOpt = Annotated[list[str], typer.Option("--anchor", help="Anchors (repeatable).")]
PlotOpt = Annotated[Path | None, typer.Option("--plot", help="Write the σ_u(t) horizon figure.")]
CompareAArg = Annotated[Path, typer.Argument(help="Target YAML file A (e.g. a LISA posterior).")]
CompareBArg = Annotated[Path, typer.Argument(help="Target YAML file B (e.g. a timing ephemeris).")]
AtOpt = Annotated[
    str | None,
    typer.Option(
        "--at",
        help='Epoch, "BJD_TDB …" or ISO TDB (default: midway between the two reference epochs).',
    ),
]
CompareFormatOpt = Annotated[
    str | None,
    typer.Option("--format", help="table | json (default: the -o suffix, else table)"),
]
# the σ_v law and the goal's longest visit, as ``plan`` declares them (ucbplan.api.plan_options)
SigmaLawOpt = Annotated[str | None, annotated(PLAN_FLAGS, "sigma_v")]
SigmaFloorOpt = Annotated[float, annotated(PLAN_FLAGS, "sigma_floor")]
ExtinctionOpt = Annotated[float | None, annotated(PLAN_FLAGS, "extinction")]
MaxVisitOpt = Annotated[str | None, annotated(PLAN_FLAGS, "max_visit")]
