"""Property-based tests of ``ucbplan reduce`` on mutated velocity tables (issue 11).

A valid 24-spectrum SB2 table (three sessions of the fiducial example) is mutated the ways real
files go wrong — deleted, blanked or garbled cells, swapped columns, unicode, a byte-order mark,
latin-1 bytes, huge numbers, a single row, duplicate headers, CRLF line ends — as CSV and as
ECSV, and run through the CLI writing ``-o`` into a fresh folder. Every run must either reduce
(exit 0, the report written) or fail with one UcbplanError line < 400 characters naming the file,
never another exception, and leave the folder exactly as it was.
"""

from __future__ import annotations

import csv
import io
import tempfile
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from ucbplan.cli.app import app
from ucbplan.errors import UcbplanError

ROOT = Path(__file__).resolve().parents[2]
TARGET = ROOT / "catalogs" / "fiducial-eccentric.yaml"
SOURCE = ROOT / "catalogs" / "fiducial-eccentric-velocities.csv"


def _base() -> tuple[list[str], list[list[str]]]:
    """Header and 24 rows: 8 consecutive spectra of each of the three sessions."""
    lines = [ln for ln in SOURCE.read_text().splitlines() if not ln.startswith("#")]
    rows = list(csv.reader(lines))
    header, body = rows[0], rows[1:]
    picked: list[list[str]] = []
    for session in ("S1", "S2", "S3"):
        picked += [r for r in body if r[header.index("session")] == session][:8]
    return header, picked


HEADER, ROWS = _base()
N_COLS, N_ROWS = len(HEADER), len(ROWS)

_cell = st.one_of(
    st.sampled_from(
        [
            *("", " ", "nan", "inf", "-inf", "1e400", "-1e308", "9" * 400, "0", "-15"),
            *("1e-320", "abc", "NULL", "—", "１２３", "12,5", '"', "'", "\\x00", "2465800.5e9"),
            "3e5",
            "\x00",
        ]
    ),
    st.text(max_size=30),
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
)

_mutation = st.one_of(
    st.tuples(st.just("blank"), st.integers(0, N_ROWS - 1), st.integers(0, N_COLS - 1)),
    st.tuples(st.just("delete"), st.integers(0, N_ROWS - 1), st.integers(0, N_COLS - 1)),
    st.tuples(st.just("garble"), st.integers(0, N_ROWS - 1), st.integers(0, N_COLS - 1), _cell),
    st.tuples(st.just("swap"), st.integers(0, N_COLS - 1), st.integers(0, N_COLS - 1)),
    st.tuples(st.just("swap_data"), st.integers(0, N_COLS - 1), st.integers(0, N_COLS - 1)),
    st.tuples(st.just("header"), st.integers(0, N_COLS - 1), st.text(max_size=12)),
    st.tuples(st.just("duplicate"), st.integers(0, N_COLS - 1), st.integers(0, N_COLS - 1)),
    st.tuples(st.just("keep"), st.integers(0, 3)),
    st.tuples(st.just("drop_column"), st.integers(0, N_COLS - 1)),
    st.tuples(
        st.just("same_time"),
    ),
    st.tuples(st.just("long_window"), st.floats(200.0, 1e6)),
)


def _mutate(muts: list[tuple[Any, ...]]) -> tuple[list[str], list[list[str]]]:
    header = list(HEADER)
    rows = [list(r) for r in ROWS]
    for m in muts:
        kind = m[0]
        if kind == "blank" and m[1] < len(rows) and m[2] < len(rows[m[1]]):
            rows[m[1]][m[2]] = ""
        elif kind == "delete" and m[1] < len(rows) and m[2] < len(rows[m[1]]):
            del rows[m[1]][m[2]]
        elif kind == "garble" and m[1] < len(rows) and m[2] < len(rows[m[1]]):
            rows[m[1]][m[2]] = m[3]
        elif kind == "swap" and max(m[1], m[2]) < len(header):
            header[m[1]], header[m[2]] = header[m[2]], header[m[1]]
        elif kind == "swap_data":
            for r in rows:
                if max(m[1], m[2]) < len(r):
                    r[m[1]], r[m[2]] = r[m[2]], r[m[1]]
        elif kind == "header" and m[1] < len(header):
            header[m[1]] = m[2]
        elif kind == "duplicate" and max(m[1], m[2]) < len(header):
            header[m[1]] = header[m[2]].upper()
        elif kind == "keep":
            rows = rows[: m[1]]
        elif kind == "drop_column" and m[1] < len(header):
            del header[m[1]]
            rows = [r[: m[1]] + r[m[1] + 1 :] for r in rows]
        elif kind == "same_time" and "bjd_tdb" in header:
            i = header.index("bjd_tdb")
            for r in rows:
                if i < len(r):
                    r[i] = rows[0][i] if i < len(rows[0]) else r[i]
        elif kind == "long_window" and "exptime_s" in header:
            i = header.index("exptime_s")
            for r in rows[:3]:
                if i < len(r):
                    r[i] = repr(m[1])
    return header, rows


def _csv_text(header: list[str], rows: list[list[str]], crlf: bool) -> str:
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\r\n" if crlf else "\n")
    writer.writerow(header)
    writer.writerows(rows)
    return buf.getvalue()


def _ecsv_cell(cell: str) -> str:
    if cell == "" or any(c.isspace() for c in cell) or '"' in cell:
        return '"' + cell.replace('"', '""') + '"'
    return cell


def _ecsv_text(header: list[str], rows: list[list[str]], crlf: bool) -> str:
    types = {"session": "string"}
    lines = ["# %ECSV 1.0", "# ---", "# datatype:"]
    for name in header:
        quoted = '"' + name.replace('"', "'") + '"'
        lines.append(f"# - {{name: {quoted}, datatype: {types.get(name, 'float64')}}}")
    lines.append("# schema: astropy-2.0")
    lines.append(" ".join(_ecsv_cell(h) for h in header))
    lines += [" ".join(_ecsv_cell(c) for c in r) for r in rows]
    return ("\r\n" if crlf else "\n").join(lines) + "\n"


def _encode(text: str, encoding: str) -> bytes:
    if encoding == "bom":
        return b"\xef\xbb\xbf" + text.encode("utf-8")
    if encoding == "latin-1":
        return text.replace("bjd_tdb", "bjd_tdb", 1).encode("latin-1", errors="replace") + (
            "# café\n".encode("latin-1")
        )
    return text.encode("utf-8", errors="surrogatepass")


def _check_run(data: bytes, suffix: str) -> None:
    """Run the CLI; success writes the report, failure is one UcbplanError line, no files."""
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        table = folder / f"velocities{suffix}"
        table.write_bytes(data)
        out = folder / "report.json"
        args = ["reduce", str(TARGET), str(table), "-o", str(out), "--samples", "100"]
        res = CliRunner().invoke(app, [*args, "--seed", "1"])
        if res.exit_code == 0:
            assert out.exists() and out.stat().st_size > 100
            return
        exc = res.exception
        assert isinstance(exc, UcbplanError), (type(exc), exc, res.output)
        msg = str(exc)
        assert "\n" not in msg and len(msg) < 400, msg
        assert table.name in msg, msg
        assert sorted(p.name for p in folder.iterdir()) == [table.name], msg


def _settings(n: int) -> Any:
    return settings(
        max_examples=n,
        deadline=None,
        suppress_health_check=[HealthCheck.too_slow],
        derandomize=True,
        database=None,
    )


@_settings(40)
@given(
    muts=st.lists(_mutation, min_size=0, max_size=3),
    fmt=st.sampled_from([".csv", ".ecsv"]),
    encoding=st.sampled_from(["utf-8", "bom", "latin-1"]),
    crlf=st.booleans(),
)
def test_mutated_velocity_tables(
    muts: list[tuple[Any, ...]], fmt: str, encoding: str, crlf: bool
) -> None:
    header, rows = _mutate(muts)
    text = _ecsv_text(header, rows, crlf) if fmt == ".ecsv" else _csv_text(header, rows, crlf)
    _check_run(_encode(text, encoding), fmt)


@pytest.mark.slow
@_settings(400)
@given(
    muts=st.lists(_mutation, min_size=1, max_size=5),
    fmt=st.sampled_from([".csv", ".ecsv"]),
    encoding=st.sampled_from(["utf-8", "bom", "latin-1"]),
    crlf=st.booleans(),
)
def test_mutated_velocity_tables_many(
    muts: list[tuple[Any, ...]], fmt: str, encoding: str, crlf: bool
) -> None:
    header, rows = _mutate(muts)
    text = _ecsv_text(header, rows, crlf) if fmt == ".ecsv" else _csv_text(header, rows, crlf)
    _check_run(_encode(text, encoding), fmt)


@_settings(25)
@given(data=st.binary(max_size=300), fmt=st.sampled_from([".csv", ".ecsv"]))
def test_arbitrary_bytes(data: bytes, fmt: str) -> None:
    _check_run(data, fmt)


@pytest.mark.parametrize("fmt", [".csv", ".ecsv"])
@pytest.mark.parametrize("encoding", ["utf-8", "bom"])
@pytest.mark.parametrize("crlf", [False, True])
def test_valid_table_reduces_in_every_encoding(fmt: str, encoding: str, crlf: bool) -> None:
    """The unmutated table in UTF-8 with or without BOM, LF or CRLF: always a reduction."""
    text = _ecsv_text(HEADER, ROWS, crlf) if fmt == ".ecsv" else _csv_text(HEADER, ROWS, crlf)
    with tempfile.TemporaryDirectory() as tmp:
        table = Path(tmp) / f"v{fmt}"
        table.write_bytes(_encode(text, encoding))
        out = Path(tmp) / "r.json"
        res = CliRunner().invoke(
            app, ["reduce", str(TARGET), str(table), "-o", str(out), "--samples", "100"]
        )
        assert res.exit_code == 0, (res.exception, res.output)
        assert out.exists()
