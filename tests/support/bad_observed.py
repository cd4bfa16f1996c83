"""The observed-file bad-input corpus: blocks tables with a status column, velocity files and
observing logs that ``plan --observed`` refuses in one line (exit 2, nothing written), with a
phrase of the error. Run by tests/observing/precision/test_observed_bad_input.py."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
from astropy.table import Table

from support.observed import with_status
from ucbplan.observing.night.observing_log import LOG_COLUMNS

#: Kinds of bad observed file made from the first night's plan (bad_observed_file), and a phrase
#: of the error.
OBSERVED_FILES: list[tuple[str, str]] = [
    ("target", "'V407 Vul' is not planned"),
    ("site", "observed at 'La Silla', but the plan is for Paranal"),
    ("status", "row 14, column status: expected one of taken, missed, skipped, got 'done'"),
    ("validity", "outside the validity"),
    ("nostatus", "expected a status column"),
    ("rv-validity", "outside the validity"),
    ("sigma", "row 1, column sigma_v_kms: expected the measured σ_v"),
]

#: Observing-log cells given a bad value (column, value; every row for the site), and a phrase of
#: the error.
LOG_CELLS: list[tuple[str, str, str]] = [
    ("status", "lost", "row 1, column status: expected one of taken, missed, skipped"),
    ("site", "La Silla", "observed at 'La Silla', but the plan is for Paranal"),
    ("sigma_v_kms", "fast", "row 1, column sigma_v_kms: expected a positive number"),
]


def bad_observed_file(first_night: Path, tmp_path: Path, kind: str) -> Path:
    """The observed file of KIND (OBSERVED_FILES) made from the plan FIRST_NIGHT in TMP_PATH."""
    path = tmp_path / f"{kind}.ecsv"
    if kind == "target":
        return with_status(first_night, path, target=lambda c: ["V407 Vul"] * len(c))
    if kind == "status":
        return with_status(first_night, path, status=["taken"] * 13 + ["done"])
    if kind == "validity":
        late = "2099-06-01T00:00:00.000"
        return with_status(first_night, path, t_mid_tdb_bary=lambda c: [late] * len(c))
    if kind == "sigma":
        return with_status(first_night, path, sigma_v_kms=lambda c: np.where(c > 0, np.nan, c))
    if kind == "rv-validity":
        path = tmp_path / "late.csv"
        rows = [f"{2472730.5 + k / 24!r},65.0,0.0,30.0" for k in range(4)]  # in 2058
        path.write_text("bjd_tdb,exptime_s,v,sigma_v\n" + "\n".join(rows) + "\n", "utf-8")
        return path
    if kind == "nostatus":
        Table.read(first_night, format="ascii.ecsv").write(path, format="ascii.ecsv")
        return path
    table = Table.read(with_status(first_night, path), format="ascii.ecsv")
    table.meta["site"] = {**table.meta["site"], "name": "La Silla"}
    table.write(path, format="ascii.ecsv", overwrite=True)
    return path


def edited_log(src: Path, dst: Path, column: str, value: str, row: int = 0) -> Path:
    """The observing log SRC with the cell (ROW, COLUMN) set to VALUE, written to DST."""
    with src.open(newline="", encoding="utf-8") as handle:
        rows = list(csv.reader(handle))
    rows[row + 1][LOG_COLUMNS.index(column)] = value
    with dst.open("w", newline="", encoding="utf-8") as handle:
        csv.writer(handle, lineterminator="\n").writerows(rows)
    return dst
