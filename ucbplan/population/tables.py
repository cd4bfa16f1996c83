"""What every population table shares: its first columns, its blank row, the astropy table of
declared columns, the provenance and status tally of its meta, and its one ECSV writer.

Each table declares its own columns (``FORECAST_COLUMNS``, ``VISIBILITY_COLUMNS``,
``RANK_COLUMNS``, ``SIMULATE_COLUMNS``) as (name, unit, dtype, description) tuples; the
functions here turn any of them into a table.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ucbplan._version import __version__

if TYPE_CHECKING:
    from ucbplan.population.catalog import Catalog

#: The first columns of every population table (name, unit, dtype, description): which source.
SOURCE_COLUMNS: tuple[tuple[str, str, str, str], ...] = (
    ("source_id", "", "str", "catalog Name (or row number)"),
    ("row", "", "i8", "catalog row (1 = first data row)"),
)


def blank_row(columns: Sequence[tuple[str, str, str, str]], int_fill: int) -> dict[str, Any]:
    """A row of the declared ``columns`` with nothing computed: "" (text), ``int_fill``
    (integers), NaN (floats)."""
    fill = {"str": "", "i8": int_fill}
    return {name: fill.get(dtype, math.nan) for name, _, dtype, _ in columns}


def columns_table(rows: list[dict[str, Any]], columns: Sequence[tuple[str, str, str, str]]) -> Any:
    """Astropy table of ``rows`` with the declared (name, unit, dtype, description) columns."""
    import numpy as np
    from astropy.table import Column, Table

    cols = []
    for name, unit, dtype, desc in columns:
        vals = [r[name] for r in rows]
        data = np.array(vals, dtype=str if dtype == "str" else dtype)
        cols.append(Column(data, name=name, unit=unit or None, description=desc))
    return Table(cols)


def provenance(command: str, catalog: Catalog) -> dict[str, Any]:
    """Meta every population table starts with: version, command, catalog and its bad rows."""
    return {
        "ucbplan_version": __version__,
        "command": command,
        "catalog": catalog.path.name,
        "catalog_path": str(catalog.path),
        "catalog_sha256": catalog.sha256,
        "catalog_rows": catalog.n_rows,
        "bad_rows": [{"row": r, "error": m} for r, m in catalog.bad],
    }


def status_counts(rows: list[dict[str, Any]]) -> dict[str, int]:
    """``n_ok``, ``n_below_threshold``, ``n_unconstrained``, ``n_failed`` of a table's rows
    (the meta's tally)."""
    status = [r["status"] for r in rows]
    return {
        "n_ok": status.count("ok"),
        "n_below_threshold": status.count("below-threshold"),
        "n_unconstrained": status.count("unconstrained"),
        "n_failed": sum(s.startswith("failed") for s in status),
    }


def write_table(tab: Any, path: Path | None, overwrite: bool) -> None:
    """Write the table as ECSV (atomic; stdout when ``path`` is None)."""
    from ucbplan.io import write_output

    write_output(path, lambda h: tab.write(h, format="ascii.ecsv"), overwrite=overwrite)
