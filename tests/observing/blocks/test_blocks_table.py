"""Master blocks table: columns, ISO precision, provenance and round trips through every format."""

from __future__ import annotations

import io
import json
from pathlib import Path

import astropy.units as u
import numpy as np
import pytest
from support.blocks import block_meta, make_block

from ucbplan.errors import InputFileError
from ucbplan.observing.blocks.block import Block
from ucbplan.observing.blocks.make import blocks_to_table
from ucbplan.observing.blocks.read import read_blocks
from ucbplan.observing.blocks.schema import REQUIRED_COLUMNS
from ucbplan.observing.blocks.write import write_table

# Dates past the leap-second table are intended (2040 nights); the planner warns once itself.
pytestmark = pytest.mark.filterwarnings("ignore::erfa.ErfaWarning")


def test_required_columns_first_and_iso_precision() -> None:
    table = blocks_to_table([make_block(0), make_block(1, alt=False)], block_meta())
    assert tuple(table.colnames[: len(REQUIRED_COLUMNS)]) == REQUIRED_COLUMNS
    # ms precision for UTC (23 chars), us for TDB (26 chars).
    assert table["t_mid_utc"][0] == "2040-02-16T02:00:00.000"
    assert table["t_mid_tdb_bary"][0] == "2040-02-16T02:03:12.123456"
    assert table["t_alt_utc"][1] == ""
    assert table["block_width_s"][0] == pytest.approx(300.0, abs=1e-6)
    # Santiago in February: UTC-3 (summer time).
    assert table["t_mid_local"][0] == "2040-02-15T23:00:00-03:00"
    assert table["ra_hms"][0].startswith("08:06:23.2")
    assert table["dec_dms"][0].startswith("+15:27:29")
    assert table.meta["site"]["name"] == "Paranal"


def test_table_holds_its_own_arrays_not_the_blocks() -> None:
    """The table is made without copying its columns again: each must be a new array, so that
    editing the table never edits the plan's blocks (nor one column another)."""
    from ucbplan.observing.blocks.arrays import BlockList, block_columns

    cols = block_columns([make_block(0), make_block(1, alt=False), make_block(2)])
    before = {k: v.copy() for k, v in cols.values.items()}
    table = blocks_to_table(BlockList(cols), block_meta())
    sources = [*cols.values.values(), cols.has_alt]
    for name in table.colnames:
        data = table[name].data
        assert not any(np.shares_memory(data, a) for a in sources), name
        others = [table[n].data for n in table.colnames if n != name]
        assert not any(np.shares_memory(data, a) for a in others), name
        data[...] = data[0] if data.dtype.kind in "U" else 0
    assert all(repr(cols.values[k].tolist()) == repr(v.tolist()) for k, v in before.items())


def test_ecsv_round_trip(tmp_path: Path) -> None:
    table = blocks_to_table([make_block(0), make_block(1, alt=False)], block_meta())
    path = tmp_path / "blocks.ecsv"
    with path.open("w") as handle:
        write_table(table, handle, "ecsv")
    back = read_blocks(path)
    for name in table.colnames:
        if table[name].dtype.kind == "f":
            np.testing.assert_array_equal(np.asarray(back[name]), np.asarray(table[name]))
        else:
            assert [str(v) for v in back[name]] == [str(v) for v in table[name]], name
    assert back.meta["targets"][0]["sha256"] == "0" * 64
    assert back["u_star_rad"].unit == "rad"


def test_empty_table_has_all_columns(tmp_path: Path) -> None:
    table = blocks_to_table([], block_meta())
    assert tuple(table.colnames[: len(REQUIRED_COLUMNS)]) == REQUIRED_COLUMNS
    path = tmp_path / "empty.ecsv"
    with path.open("w") as handle:
        write_table(table, handle, "ecsv")
    assert len(read_blocks(path)) == 0


def test_json_rows_and_csv() -> None:
    table = blocks_to_table([make_block(0)], block_meta())
    buf = io.StringIO()
    write_table(table, buf, "json")
    rows = json.loads(buf.getvalue())
    assert isinstance(rows, list) and rows[0]["target"] == "HM Cnc"
    assert rows[0]["smear_kms"] is None  # NaN -> null, valid JSON
    assert rows[0]["n_exp"] == 4
    buf = io.StringIO()
    write_table(table, buf, "json", json_meta=True)  # plan --format json: {"meta", "rows"}
    doc = json.loads(buf.getvalue())
    assert doc["meta"]["mode"] == table.meta["mode"] and doc["rows"] == rows
    buf = io.StringIO()
    write_table(table, buf, "csv")
    header = buf.getvalue().splitlines()[0].split(",")
    assert tuple(header[: len(REQUIRED_COLUMNS)]) == REQUIRED_COLUMNS


def test_read_blocks_errors(tmp_path: Path) -> None:
    with pytest.raises(InputFileError, match="not found"):
        read_blocks(tmp_path / "nope.ecsv")
    bad = tmp_path / "bad.ecsv"
    bad.write_text("# %ECSV 1.0\n# ---\n# datatype:\n# - {name: a, datatype: int64}\na\n1\n")
    with pytest.raises(InputFileError, match="required columns"):
        read_blocks(bad)


def test_required_columns_are_the_exporters_contract() -> None:
    # Spelled out here (not derived): the columns every export may rely on, in file order.
    assert REQUIRED_COLUMNS == (
        "target",
        "block_id",
        "anchor",
        "u_star_rad",
        "t_mid_utc",
        "t_start_utc",
        "t_end_utc",
        "t_mid_tdb_bary",
        "sigma_t_s",
        "t_alt_utc",
        "exptime_s",
        "n_exp",
        "lambda_k",
        "altitude_deg",
        "airmass",
        "moon_sep_deg",
    )


def test_column_list_covers_every_block_field_and_reads_back_typed(tmp_path: Path) -> None:
    from dataclasses import fields

    from ucbplan.observing.blocks.schema import COLUMNS, EXTRA_COLUMNS

    assert len({c.name for c in COLUMNS}) == len(COLUMNS)
    assert {f.name for f in fields(Block)} <= {c.attribute for c in COLUMNS}
    assert (*REQUIRED_COLUMNS, *EXTRA_COLUMNS) == tuple(c.name for c in COLUMNS)
    table = blocks_to_table([make_block(0)], block_meta())
    path = tmp_path / "b.ecsv"
    with path.open("w") as handle:
        write_table(table, handle, "ecsv")
    back = read_blocks(path)
    kinds = {"str": "U", "float64": "f", "int64": "i"}
    for c in COLUMNS:
        assert back[c.name].dtype.kind == kinds[c.dtype], c.name
        assert (back[c.name].unit is None) == (c.unit is None), c.name
        if c.unit is not None:
            assert back[c.name].unit == u.Unit(c.unit), c.name
        assert back[c.name].description == (c.description if c.in_header else None), c.name


def test_column_reference_lists_every_column() -> None:
    from ucbplan.observing.blocks.schema import COLUMNS, column_reference

    text = column_reference()
    rows = [line for line in text.splitlines() if line.startswith("| `")]
    assert [r.split("`")[1] for r in rows] == [c.name for c in COLUMNS]
    assert "| `smear_kms` | float64 | km / s |  | velocity smear" in text
