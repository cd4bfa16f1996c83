"""Issue 23: plain numeric CSVs are read by numpy's C reader (ucbplan.reduce.columnar).

The reference is the strict per-cell reader (float() of every cell): every value read the fast
way must be its double bit for bit, and every file the fast way cannot take whole must end with
the strict reader's table or its one-line error. Which reader ran is checked too, so a test
cannot pass because the fast path was silently skipped.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from support.reduce import JD, assert_same_velocities

from ucbplan.errors import VelocityFileError
from ucbplan.reduce import columnar
from ucbplan.reduce import velocities as vel
from ucbplan.reduce.velocities import read_velocities

HEADER = "bjd_tdb,exptime_s,v1,sigma_v1,v2,sigma_v2\n"


def _rows(n: int, fmt: str = "{!r}") -> str:
    rng = np.random.default_rng(7)
    jd = JD + np.sort(rng.integers(0, 3, n) + rng.uniform(0, 0.3, n))
    return "".join(
        f"{float(jd[k])!r},{fmt.format(30.0 + k % 7)},{fmt.format(rng.normal(0, 300))},15,"
        f"{fmt.format(rng.normal(0, 300))},{fmt.format(rng.uniform(5, 20))}\n"
        for k in range(n)
    )


def _strict(path: Path, monkeypatch: pytest.MonkeyPatch) -> vel.VelocityTable:
    with monkeypatch.context() as m:
        m.setattr(vel, "_fast_csv", lambda p: None)
        return read_velocities(path)


def _numpy_read(path: Path) -> bool:
    """Whether the numpy reader takes the file (else astropy's or the strict one)."""
    text = path.read_bytes().decode("utf-8-sig")
    line, skip, body = columnar._header_line(text)  # type: ignore[misc]
    return columnar._plain_numbers(path, text, body, skip, line.count(",") + 1) is not None


@pytest.mark.parametrize(
    ("text", "numpy_path"),
    [
        (HEADER + _rows(300), True),
        ("\ufeff# measured\n# by hand\n" + HEADER + _rows(50), True),  # BOM, comments above
        (HEADER + _rows(50).replace("\n", "\r\n"), True),  # CRLF
        (HEADER + _rows(50).rstrip("\n"), True),  # no final newline
        (HEADER + _rows(50, "{:.4e}"), True),
        (HEADER + _rows(50, " {:+.6f} "), True),  # spaces and signs around numbers
        (HEADER + _rows(5) + "\n" + _rows(5), False),  # a blank line: astropy's reader
        (HEADER + _rows(5) + "   \n" + _rows(5), False),
        (HEADER + _rows(5) + "   ", False),  # a white-space last line
        (HEADER + _rows(5) + "# note\n" + _rows(5), False),  # a comment below the header
        (HEADER + _rows(5).replace(",15,", ",1_5,", 1), False),  # float() reads 15
        (HEADER + _rows(5).replace(",30.0,", ",-0,", 1), True),  # float("-0") = -0.0
    ],
)
def test_numpy_reader_equals_the_strict_reader(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, text: str, numpy_path: bool
) -> None:
    p = tmp_path / "v.csv"
    p.write_bytes(text.encode())
    assert _numpy_read(p) is numpy_path
    assert_same_velocities(read_velocities(p), _strict(p, monkeypatch))


@pytest.mark.parametrize(
    ("body", "needle"),
    [
        (f"{JD},30,1,15,2,\n", "row 1, column 'sigma_v2': blank cell"),
        (f"{JD},30,1,15,2,14\n{JD},30,x,15,2,14\n", "row 2, column 'v1': got 'x'"),
        (f"{JD},30,1,15,2,14\n{JD},30,nan,15,2,14\n", "row 2, column 'v1'"),
        (f"{JD},30,1,15,2,14\n{JD},30,inf,15,2,14\n", "row 2, column 'v1'"),
        (f"{JD},30,1,15,2,14\n{JD},30,1,15\n", "row 2 (line 3): has 4 fields, expected 6"),
        (f"{JD},30,1,15,2,14\n{JD},30,1,15,2,14,9\n", "row 2 (line 3): has 7 fields"),
        (f'{JD},30,"1",15,2,14\n', None),  # a quoted number: the strict reader's reading
    ],
)
def test_bad_plain_files_get_the_strict_readers_message(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, body: str, needle: str | None
) -> None:
    p = tmp_path / "v.csv"
    p.write_text(HEADER + body, encoding="utf-8")
    assert not _numpy_read(p)
    if needle is None:
        assert_same_velocities(read_velocities(p), _strict(p, monkeypatch))
        return
    with pytest.raises(VelocityFileError, match=needle.replace("(", r"\(").replace(")", r"\)")):
        read_velocities(p)


_cell = st.floats(-2.9e5, 2.9e5, allow_nan=False).flatmap(
    lambda x: st.sampled_from([repr(x), f"{x:.3f}", f"{x:.6e}", f"{x:.17g}", f" {x:g} ", f"{x:+}"])
)


@settings(
    max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(st.lists(st.tuples(_cell, _cell), min_size=2, max_size=20))
def test_random_number_texts_read_as_float_does(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, cells: list[tuple[str, str]]
) -> None:
    """Any way of writing the velocities: the numpy reader's doubles are float()'s."""
    body = "".join(f"{JD + 0.01 * k!r},30,{a},15,{b},12.5\n" for k, (a, b) in enumerate(cells))
    p = tmp_path / "v.csv"
    p.write_text(HEADER + body, encoding="utf-8")
    assert _numpy_read(p)
    assert columnar._scan_mapped(p) is not None  # the bytes path read it
    assert_same_velocities(read_velocities(p), _strict(p, monkeypatch))


def _sessions_file(path: Path, comment_chars: int) -> Path:
    """A valid SB2 file with a session column (astropy's reader) under a long first comment."""
    body = "".join(f"{ln.rstrip()},S{k % 2}\n" for k, ln in enumerate(_rows(40).splitlines()))
    path.write_text(
        "#" + "x" * (comment_chars - 1) + "\n" + HEADER.rstrip() + ",session\n" + body,
        encoding="utf-8",
    )
    return path


def test_a_long_comment_line_is_read_in_linear_time(tmp_path: Path) -> None:
    """Issue 33: astropy's reader is quadratic in a comment line's length (10⁶ characters took
    7-29 s); comment lines are emptied before it, in one linear pass. A comment at the limit
    (10⁶ characters) now reads in ~0.05 s; 2 s leaves room for a loaded machine."""
    import time

    from ucbplan.inputs import MAX_COMMENT_CHARS

    p = _sessions_file(tmp_path / "v.csv", MAX_COMMENT_CHARS)
    t0 = time.process_time()
    tab = read_velocities(p)
    assert time.process_time() - t0 < 2.0
    assert tab.n == 40 and set(tab.session) == {"S0", "S1"}


def test_a_comment_line_over_the_limit_is_one_line_error(tmp_path: Path) -> None:
    from ucbplan.inputs import MAX_COMMENT_CHARS

    p = _sessions_file(tmp_path / "v.csv", MAX_COMMENT_CHARS + 1)
    with pytest.raises(VelocityFileError, match=r"line 1: a comment of 1000001 characters") as e:
        read_velocities(p)
    assert "\n" not in str(e.value) and len(str(e.value)) < 300


def _table_or_error(read: object) -> object:
    try:
        return read()  # type: ignore[operator]
    except VelocityFileError as exc:
        return str(exc)


@pytest.mark.parametrize(
    ("text", "mapped"),
    [
        (HEADER + _rows(300), True),
        ("\n \t\n" + HEADER + _rows(20), True),  # blank lines above the header
        (HEADER + _rows(50).replace("\n", "\r\n"), True),  # CRLF
        (HEADER + _rows(50).rstrip("\n"), True),  # no final newline
        (HEADER + _rows(50, " {:+.6f} "), True),
        ("\ufeff" + HEADER + _rows(20), False),  # a byte-order mark: the text path
        ("# measured\n" + HEADER + _rows(20), False),  # a comment: the text path blanks it
        (HEADER + _rows(5) + "\r\n" + _rows(5), False),  # a blank line
        (HEADER + _rows(5) + '"1"', False),  # a quote
        (HEADER + _rows(5).replace(",15,", ",\uff11\uff15,", 1), False),  # float() reads 15
        (HEADER.replace("v2", "V2"), False),  # no data row
        (" \n", False),
        ("", False),
    ],
)
def test_the_mapped_scan_reads_what_the_text_path_reads(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, text: str, mapped: bool
) -> None:
    """Issue 34: a plain ASCII file is scanned as bytes through a memory map, never decoded.
    Its header, lines above the data and row count are the text path's, and every other file
    goes to the text path; either way the table (or the one-line error) is the strict reader's.
    """
    p = tmp_path / "v.csv"
    p.write_bytes(text.encode())
    scan = columnar._scan_mapped(p)
    assert (scan is not None) is mapped
    if scan is not None:
        text = p.read_bytes().decode("ascii")
        line, skip, body = columnar._header_line(text)  # type: ignore[misc]
        assert scan == (line, skip, text.count("\n", body) + (not text.endswith("\n")))
        assert vel._fast_csv(p) is not None  # and numpy's reader took it
    fast = _table_or_error(lambda: read_velocities(p))
    strict = _table_or_error(lambda: _strict(p, monkeypatch))
    if isinstance(fast, str) or isinstance(strict, str):
        assert fast == strict
    else:
        assert_same_velocities(fast, strict)


@pytest.mark.parametrize("counted", [2, 3, 4])
def test_the_numpy_reader_takes_exactly_the_counted_rows(tmp_path: Path, counted: int) -> None:
    """numpy reads at most one row more than the scan counted (its array made at that size, not
    grown): a body with more or fewer rows than counted is refused as before, three of three
    is read whole."""
    path = tmp_path / "v.csv"
    path.write_text("bjd_tdb,v1\n1.5,2.5\n3.5,4.5\n5.5,6.5\n", encoding="utf-8")
    cols = columnar._loadtxt(path, 1, counted, 2)
    if counted == 3:
        assert cols is not None and cols.tolist() == [[1.5, 3.5, 5.5], [2.5, 4.5, 6.5]]
    else:
        assert cols is None
