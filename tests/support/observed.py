"""Spectra already taken: the base case and the brute-force Fisher information that the
observed-log tests share."""

from __future__ import annotations

import csv
import math
import warnings
from pathlib import Path
from typing import Any

import numpy as np
from astropy.table import Table
from astropy.time import Time
from typer.testing import CliRunner

import ucbplan
from support.paths import CATALOGS
from ucbplan.cli.app import app
from ucbplan.core.phase import arg_latitude
from ucbplan.observing.blocks.read import read_blocks
from ucbplan.targets import load_target

TARGET = CATALOGS / "hm-cnc-simulated.yaml"


NAME = "HM Cnc (simulated)"


BASE: dict[str, Any] = {
    "site": "paranal",
    "sigma_v": "30km/s@300s",
    "visit": "1h",
    "instrument": "xshooter-vis",
}


CLI_BASE = [
    "plan",
    str(TARGET),
    *("--site", "paranal", "--sigma-v", "30km/s@300s", "--visit", "1h"),
    *("--instrument", "xshooter-vis"),
]


def brute_force_info(tau: np.ndarray, exptime: np.ndarray, sigma: np.ndarray) -> float:
    """1/σ_K² from the design matrix built row by row (Λ_K = sin x/x, x = n̄ T/2 written out)
    and inverted with numpy."""
    target = load_target(TARGET)
    rows, weights = [], []
    for t, te, s in zip(tau, exptime, sigma, strict=True):
        u = float(arg_latitude(target.params, t))
        x = target.params.n_bar * te / 2.0
        rows.append([1.0, math.sin(x) / x * math.cos(u)])
        weights.append(1.0 / s**2)
    a, w = np.array(rows), np.diag(weights)
    cov = np.linalg.inv(a.T @ w @ a)
    return 1.0 / float(cov[1, 1])


def fisher_of_taken(plan: Path, log: Path) -> float:
    """1/σ_K² of the log's taken exposures, from the plan's own rows (their block ids)."""
    table = read_blocks(plan)
    with log.open(newline="", encoding="utf-8") as handle:
        taken = {r["block_id"] for r in csv.DictReader(handle) if r["status"] == "taken"}
    rows = table[[str(b) in taken for b in table["block_id"]]]
    assert len(rows) == len(taken) and set(rows["n_exp"]) == {1}
    tau = (Time(list(rows["t_mid_tdb_bary"]), scale="tdb") - load_target(TARGET).t_ref).to_value(
        "s"
    )
    return brute_force_info(tau, np.asarray(rows["exptime_s"]), np.asarray(rows["sigma_v_kms"]))


def plan_base(night: str, nights: int = 1, **kw: Any) -> Any:
    """``ucbplan.plan`` of the base case from NIGHT, its warnings silenced."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return ucbplan.plan(str(TARGET), night=night, nights=nights, **{**BASE, **kw})


def written_plan(out: Path, *args: str) -> Path:
    """``CLI_BASE ARGS -o OUT`` run through the CLI (which must succeed); returns OUT."""
    result = CliRunner().invoke(app, [*CLI_BASE, *args, "-o", str(out)])
    assert result.exit_code == 0, result.output
    return out


def with_status(src: Path, dst: Path, status: list[str] | None = None, **edit: Any) -> Path:
    """The blocks table SRC given a ``status`` column (all taken unless STATUS) and its columns
    edited (a value, or a function of the column), written to DST."""
    table = Table.read(src, format="ascii.ecsv")
    table["status"] = np.array(status or ["taken"] * len(table), dtype=object)
    for name, value in edit.items():
        table[name] = value(table[name]) if callable(value) else value
    table.write(dst, format="ascii.ecsv", overwrite=True)
    return dst
