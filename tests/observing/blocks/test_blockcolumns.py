"""Blocks as columns and the column-by-column writers against the per-element way (issue 23).

The planner hands out its blocks as columns (:class:`BlockList`) and the table writers format
whole columns; the promise is byte-identical output. Each fast path is compared exactly
(tolerance 0) with what astropy, ``json`` or the Block records give one element at a time, on
inputs chosen for the edge cases: empty cells, quotes, spaces and tabs at the ends of text,
non-ASCII text, NaN and infinities, signed zeros, extreme floats, a leap second, times whose
stored Julian-date split is not astropy's normal one.
"""

from __future__ import annotations

import io
import json
import math
import random
import struct
from dataclasses import fields, replace

import numpy as np
import pytest
from astropy.table import MaskedColumn, Table
from astropy.time import Time
from support.blocks import block_meta, make_block

from ucbplan.io import dump_json
from ucbplan.observing.blocks import ecsv_header as ecsvheader
from ucbplan.observing.blocks import write as tablewrite
from ucbplan.observing.blocks.arrays import BlockColumns, BlockList, block_columns, isot
from ucbplan.observing.blocks.block import Block
from ucbplan.observing.blocks.make import blocks_to_table
from ucbplan.observing.blocks.write import (
    csv_safe_table,
    ecsv_data_lines,
    json_rows_text,
    table_to_json_rows,
    write_table,
)
from ucbplan.offline import offline

pytestmark = pytest.mark.filterwarnings("ignore::erfa.ErfaWarning")

TEXTS = ["", " ", "a", " lead", "trail\t", 'say "hi"', "x y", "é σΛ★", "#c", "a,b", "1e5", "nan"]


def _random_float(rng: random.Random) -> float:
    if rng.random() < 0.3:
        return rng.choice([0.0, -0.0, float("nan"), float("inf"), -1e300, 5e-324, 1e16, 1e-5])
    return float(struct.unpack("d", struct.pack("Q", rng.getrandbits(64)))[0])


def _random_table(seed: int) -> Table:
    rng = random.Random(seed)
    n = rng.choice([0, 1, 2, 7, 40])
    return Table(
        {
            "f": np.array([_random_float(rng) for _ in range(n)], dtype=np.float64),
            "i": np.array([rng.randint(-(2**62), 2**62) for _ in range(n)], dtype=np.int64),
            "s": np.array([rng.choice(TEXTS) for _ in range(n)], dtype=str),
            "b": np.array([rng.random() < 0.5 for _ in range(n)], dtype=bool),
            "g": np.array([rng.uniform(-90, 90) for _ in range(n)]),
        },
        meta={"note": "random", "n": n},
    )


def _astropy_ecsv(table: Table) -> str:
    buf = io.StringIO()
    table.write(buf, format="ascii.ecsv")
    return buf.getvalue()


def _ours(table: Table, fmt: str, json_meta: bool = False) -> str:
    buf = io.StringIO()
    write_table(table, buf, fmt, json_meta=json_meta)
    return buf.getvalue()


def _reference_json(table: Table, json_meta: bool) -> str:
    """The row-by-row way: the rows as dicts, dumped by ``json`` with indent 2."""
    rows = table_to_json_rows(table)
    meta = tablewrite._plain_meta(dict(table.meta))
    buf = io.StringIO()
    dump_json({"meta": meta, "rows": rows} if json_meta else rows, buf)
    return buf.getvalue()


@pytest.mark.parametrize("seed", range(30))
def test_ecsv_rows_as_astropy_writes_them(seed: int) -> None:
    table = _random_table(seed)
    assert ecsv_data_lines(table) is not None
    assert _ours(table, "ecsv") == _astropy_ecsv(table)


@pytest.mark.parametrize(
    "value", [0.0, -0.0, float("nan"), 1e-5, 7, True, *TEXTS, 'a"b', "=1+2", "-3"]
)
def test_ecsv_rows_of_one_value_columns_as_astropy_writes_them(value: object) -> None:
    """A column of one value is formatted once: bit for bit one value (0.0 beside -0.0 is
    two), text cells quoted as the csv writer does (ECSV and CSV)."""
    table = _random_table(7)
    table["one"] = [value] * len(table)
    table["mixed"] = [value, -0.0, *[value] * (len(table) - 2)]
    table["text"] = [value, "x", *[value] * (len(table) - 2)]
    table["texts"] = [str(value)] * len(table)
    table["again"] = [value] * len(table)  # one-value columns side by side: joined once
    table["n"] = [3] * len(table)
    assert ecsv_data_lines(table) is not None
    assert _ours(table, "ecsv") == _astropy_ecsv(table)
    assert _ours(table, "json") == _reference_json(table, False)
    buf = io.StringIO()
    Table(csv_safe_table(table), meta={}).write(buf, format="ascii.csv")
    assert _ours(table, "csv") == buf.getvalue()


@pytest.mark.parametrize("seed", range(30))
def test_csv_rows_as_astropy_writes_them(seed: int) -> None:
    """CSV column by column (texts with commas, quotes, spaces, empty cells, non-ASCII), and a
    table of one text column (astropy's whole writer), byte for byte as astropy writes them."""
    table = _random_table(seed)
    table["t"] = [
        TEXTS[(seed + k) % len(TEXTS)] + ("a,b" if k % 3 else "") for k in range(len(table))
    ]
    for t in (table, table[["s"]]):
        buf = io.StringIO()
        Table(t, meta={}).write(buf, format="ascii.csv")
        assert _ours(t, "csv") == buf.getvalue()
    assert len(table.colnames) < 2 or ecsv_data_lines(table, ",") is not None


@pytest.mark.parametrize("seed", range(30))
def test_json_rows_as_json_writes_them(seed: int) -> None:
    table = _random_table(seed)
    for json_meta in (False, True):
        assert _ours(table, "json", json_meta) == _reference_json(table, json_meta)
    json.loads(_ours(table, "json", True))  # a valid document (NaN written as null)


def test_other_columns_take_the_general_writers() -> None:
    table = _random_table(3)
    table["m"] = MaskedColumn(np.arange(len(table), dtype=float), mask=np.arange(len(table)) % 2)
    assert ecsv_data_lines(table) is None and json_rows_text(table, 0) is None
    assert _ours(table, "ecsv") == _astropy_ecsv(table)
    assert _ours(table, "json", True) == _reference_json(table, True)


def _odd_times() -> Time:
    """A leap second, the edges of a second at each precision, a century's dates, and times
    stored with an unnormalised split."""
    iso = [
        "2016-12-31T23:59:60.5",
        "2040-02-16T02:03:04.9999995",
        "2040-02-16T23:59:59.9996",
        "1900-01-01T00:00:00",
        "2100-12-31T23:59:59.123456789",
    ]
    with offline():
        base = Time(iso, scale="utc")
        odd = Time(np.array([2466000.0, 2466001.0]), np.array([0.75, -0.7]), format="jd")
        return Time([*base, *odd])


@pytest.mark.parametrize("precision", [0, 3, 6, 9])
@pytest.mark.parametrize("scale", ["utc", "tdb"])
def test_isot_as_astropy_formats_it(precision: int, scale: str) -> None:
    with offline():
        times = getattr(_odd_times(), scale)
        ref = list(Time(times.jd1, times.jd2, format="jd", scale=scale, precision=precision).isot)
        assert isot(times, precision) == ref
        early = Time(["0999-12-31T23:59:59.5", "2040-01-01T00:00:00"], scale=scale)
        ref = list(Time(early.jd1, early.jd2, format="jd", scale=scale, precision=precision).isot)
        assert isot(early, precision) == ref  # a year of three digits: time by time
        assert isot(times[:0], precision) == []


def _cells(block: Block) -> list[object]:
    """A block's fields, times as (scale, jd1, jd2) and NaN as a word (NaN != NaN)."""
    out: list[object] = []
    for f in fields(Block):
        v = getattr(block, f.name)
        if isinstance(v, Time):
            v = (v.scale, v.jd1, v.jd2)
        elif isinstance(v, float) and math.isnan(v):
            v = "nan"
        out.append((f.name, v, type(v).__name__))
    return out


def test_columns_round_trip_to_the_same_records_and_table() -> None:
    blocks = [make_block(i, alt=i % 3 != 0) for i in range(7)]
    for k in range(0, 7, 2):  # a block with every number known compares equal as a whole
        blocks[k] = replace(blocks[k], smear_kms=1.25, delta_kappa=0.1, sigma_v_kms=3.0)
    with offline():
        cols = BlockColumns.from_blocks(blocks)
        listed = BlockList(cols)
        assert [_cells(b) for b in listed] == [_cells(b) for b in blocks] and len(listed) == 7
        assert listed[2] == blocks[2] and listed[4:5] == blocks[4:5]
        assert listed != blocks[:-1] and BlockList(cols.take(np.arange(1))) == blocks[:1]
        assert block_columns(listed) is cols
        a, b = blocks_to_table(blocks, block_meta()), blocks_to_table(listed, block_meta())
        joined = BlockColumns.concat([cols.take(np.arange(3)), cols.take(np.arange(3, 7))])
        c = blocks_to_table(BlockList(joined), block_meta())
    for table in (b, c):
        assert table.colnames == a.colnames
        assert all(_ours(table[[n]], "csv") == _ours(a[[n]], "csv") for n in a.colnames)
        a.meta["created_utc"] = table.meta["created_utc"]
        assert _ours(table, "ecsv") == _ours(a, "ecsv")


def test_time_order_is_the_stable_sort_of_the_records() -> None:
    blocks = [make_block(i) for i in (3, 1, 2, 1, 0)]
    with offline():
        cols = BlockColumns.from_blocks(blocks)
        got = BlockList(cols.take(cols.time_order()))
        ref = sorted(blocks, key=lambda b: (b.t_mid_utc.jd1, b.t_mid_utc.jd2))
    assert [b.block_id for b in got] == [b.block_id for b in ref]


WORDS = ["HM", "Cnc", "(simulated)", "UCB03", "a.b", "x/y", "V01", "1.5", "2040-01-01", "true"]


def _random_visits(rng: random.Random, n: int, sep: str = " ") -> list[dict[str, object]]:
    """Visits as a plan's meta holds them, with names of random words (spaces, dates, numbers,
    booleans) joined by ``sep`` and lengths that put breaks anywhere near the 130th column."""
    out = []
    for k in range(n):
        name = sep.join(rng.choice(WORDS) for _ in range(rng.randint(1, 12)))
        out.append(
            {
                "visit_id": f"{name.replace(' ', '_')}-V{k:02d}",
                "target": name,
                "night": "2040-01-01",
                "acq_start_utc": "2040-01-02T00:55:37",
                "start_utc": "2040-01-02T01:02:37",
                "end_utc": "2040-01-02T01:03:37",
                "exposures": rng.choice([1, 20, 10**12]),
                "shutter_s": rng.choice([60.0, 1e17, 1e-5, 123.456, -0.0]),
                "overhead_s": round(rng.uniform(0, 1e5), 3),
                "idle_s": _random_float(rng) if rng.random() < 0.2 else 0.0,
            }
        )
    return out


@pytest.mark.parametrize("seed", range(25))
def test_ecsv_header_visits_as_libyaml_writes_them(seed: int) -> None:
    rng = random.Random(seed)
    table = _random_table(seed)
    table.meta = {"site": {"name": "x"}, "visits": _random_visits(rng, 30), "after": [1, 2]}
    assert _ours(table, "ecsv") == _astropy_ecsv(table)
    assert table.meta["visits"] and "after" in table.meta  # the caller's meta is kept


@pytest.mark.parametrize("seed", range(12))
def test_json_meta_visits_as_json_writes_them(seed: int) -> None:
    """A plan's visits in the JSON meta written key by key: the bytes ``json`` writes for the
    whole document (NaN as null: those visits take the whole-document path), and a valid
    document."""
    rng = random.Random(seed)
    table = _random_table(seed)
    visits = _random_visits(rng, 20)
    if seed % 3 == 0:
        visits[rng.randrange(20)]["idle_s"] = float("nan")
    if seed % 4 == 1:
        visits[0]["note"] = 'é ★ "q"'  # other keys: the whole-document path
    if seed % 4 == 2:
        for v in visits:
            v["flag"] = rng.choice([True, None, "é ★", 3])
    table.meta = {"site": {"name": "x"}, "visits": visits, "after": [1.5, float("inf")]}
    buf = io.StringIO()
    dump_json({"meta": table.meta, "rows": table_to_json_rows(table)}, buf)
    assert _ours(table, "json", True) == buf.getvalue()
    assert len(json.loads(_ours(table, "json", True))["meta"]["visits"]) == 20


@pytest.mark.parametrize("seed", range(10))
def test_a_text_and_its_shape_are_written_alike(seed: int) -> None:
    """Texts of digits and the characters of numbers, times and ids: each one's text as the
    column path finds it (by shape, each style once) equals its own, value by value."""
    rng = random.Random(seed)
    chars = "0123456789" * 3 + "-:._+eExbTtV Z/"
    texts = ["".join(rng.choice(chars) for _ in range(rng.randint(1, 12))) for _ in range(400)]
    texts += ["2040-01-02T00:55:37", "08", "012", "1_0", "0b10", "1:30", "0x1f", "1e5"]
    for column in (texts, [*texts, 5, 1.5, -0.0]):
        ours = ecsvheader._column_texts(column, ecsvheader._yaml_tag)
        one_by_one = [ecsvheader._yaml_scalar(t, ecsvheader._yaml_tag) for t in column]
        if None in one_by_one:
            assert ours is None
            column = [t for t, got in zip(column, one_by_one, strict=True) if got is not None]
            ours = ecsvheader._column_texts(column, ecsvheader._yaml_tag)
            one_by_one = [ecsvheader._yaml_scalar(t, ecsvheader._yaml_tag) for t in column]
        assert ours == [got[0] for got in one_by_one if got is not None]


@pytest.mark.parametrize("seed", range(10))
def test_ecsv_header_visits_without_spaces_as_libyaml_writes_them(seed: int) -> None:
    """Names without spaces: every mapping from the templates of its texts' widths (lines
    breaking before any key, near the 130th column), as libyaml writes it."""
    rng = random.Random(seed)
    table = _random_table(seed)
    table.meta = {"visits": _random_visits(rng, 60, sep=rng.choice("_-.")), "after": [1]}
    assert _ours(table, "ecsv") == _astropy_ecsv(table)
