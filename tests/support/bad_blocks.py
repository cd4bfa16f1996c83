"""The blocks-table bad-input corpus: each way a blocks table given to ``export`` (or its export
options) can be wrong, with a phrase of its one-line error. Run by
tests/observing/exports/test_exports_hardening.py."""

from __future__ import annotations

import io
import math
import shlex
from typing import Any

from astropy.table import Table

from ucbplan.observing.blocks.write import write_table

#: (column, value given in row 2, phrase of the error): cells the reader refuses by row and column.
BAD_CELLS: list[tuple[str, str, str]] = [
    ("sigma_t_s", "", "row 2, column sigma_t_s: expected a number in [0, 86400] s (blank"),
    ("exptime_s", "", "row 2, column exptime_s: expected a number"),
    ("target", "", "row 2, column target: expected a value (blank cell)"),
    ("t_mid_utc", "", "row 2, column t_mid_utc: expected a value (blank cell)"),
    ("t_start_utc", "9999-12-31T23:59:00", "row 2, column t_start_utc: expected an ISO time"),
    ("t_end_utc", "2037-01-15T04:00:00", "row 2, column t_end_utc: expected a time after"),
    ("sigma_t_s", "nan", "row 2, column sigma_t_s: expected a number in [0, 86400] s"),
    ("sigma_t_s", "1e300", "row 2, column sigma_t_s: expected a number"),
    ("ra_deg", "inf", "row 2, column ra_deg: expected a number in [0, 360] deg"),
    ("n_exp", "0", "column n_exp"),
    ("block_id", "HM_Cnc-001", "rows 1 and 2: block_id 'HM_Cnc-001' appears twice"),
]

#: Kinds of target file named in a table's provenance that must neither hang nor crash.
PROVENANCE_KINDS: list[str] = ["fifo", "folder", "missing", "device", "changed", "not-a-path"]

#: Export formats that need an ASCII name (a name without one is refused).
ASCII_FORMATS: list[str] = ["keck-starlist", "ing-cat", "eso-p2"]

#: (format, phrase of the error) for targets 'HM Cnc' and 'HM_Cnc', one name once sanitised.
COLLIDING_NAMES: list[tuple[str, str]] = [
    ("ing-cat", "ING catalogue: targets 'HM Cnc' and 'HM_Cnc' both become 'HM_Cnc'"),
    ("keck-starlist", "Keck starlist: targets 'HM Cnc' and 'HM_Cnc' both become 'HM_Cnc'"),
    ("eso-p2", "ESO p2 target list: targets 'HM Cnc' and 'HM_Cnc' both become 'HM_Cnc'"),
]

#: ExportOptions keywords out of range, and the option the error names.
EXPORT_OPTIONS: list[tuple[dict[str, Any], str]] = [
    ({"tolerance_sigma": math.nan}, "tolerance_sigma:"),
    ({"tolerance_sigma": 1e300}, "tolerance_sigma:"),
    ({"tolerance_floor_s": -1.0}, "tolerance_floor:"),
    ({"tolerance_floor_s": math.inf}, "tolerance_floor:"),
    ({"acquisition_s": -5.0}, "acquisition:"),
    ({"acquisition_s": 1e300}, "acquisition:"),  # was OverflowError in timedelta
    ({"keck_rotmode": "vertical\nx"}, "rotmode:"),
]


def ecsv_text(table: Table) -> str:
    """TABLE as the ECSV text ``plan -o`` writes."""
    buf = io.StringIO()
    write_table(table, buf, "ecsv")
    return buf.getvalue()


def replace_cell(text: str, row: int, column: str, value: str) -> str:
    """ECSV text with one data cell replaced (space-separated, quoted cells kept whole)."""
    lines = text.splitlines()
    first = next(i for i, ln in enumerate(lines) if not ln.startswith("#"))
    names = shlex.split(lines[first])
    cells = shlex.split(lines[first + 1 + row])
    cells[names.index(column)] = value
    lines[first + 1 + row] = " ".join(f'"{c}"' if not c or " " in c else c for c in cells)
    return "\n".join(lines) + "\n"


def untrusted_files(text: str) -> dict[str, tuple[bytes, str]]:
    """Files the reader cannot trust, made from a good table's ECSV TEXT: file name → (bytes,
    phrase of the error)."""
    bomb = "# meta: !!omap\n# - bomb: &a [1]\n# - b2: [" + ", ".join(["*a"] * 60) + "]\n"
    return {
        "latin.ecsv": (text.replace("HM Cnc", "HM Cnç").encode("latin-1"), "not UTF-8"),
        "cut.ecsv": (text.encode()[:900], "not a readable ECSV blocks table"),
        "nocol.ecsv": (
            ecsv_text(Table({"target": ["x"], "block_id": ["b"]})).encode(),
            "lacks required columns anchor, u_star_rad",
        ),
        "bomb.ecsv": (text.replace("# meta: !!omap\n", bomb).encode(), "more than 50 YAML aliases"),
        "empty.csv": (b"", "empty file"),
        "ragged.csv": (b"target,block_id\nx\n", "row 1: 1 cells for 2 columns"),
        "rows.json": (b'{"target": 1}', "expected a JSON list of row objects"),
        "bad.json": (b"[1, 2", "not valid JSON"),
    }
