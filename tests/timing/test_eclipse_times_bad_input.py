"""Eclipse-time tables and the ``ephemeris fit`` inputs: every case of the bad-input corpus
(tests/support/bad_eclipse_times.py) is refused in one line naming the file, the row and the
column (the command's options: tests/timing/test_timing_fit.py::test_bad_options)."""

from __future__ import annotations

from pathlib import Path

import pytest
from support.bad_eclipse_times import (
    BAD_INITIAL_FILES,
    BAD_PERIOD_GUESSES,
    BAD_TABLES,
    GOOD,
    times_table,
)

from ucbplan.errors import InputError, InputFileError, UcbplanError
from ucbplan.timing import fit_times, period_guess, read_initial, read_times


def one_line(exc: BaseException) -> str:
    msg = str(exc)
    assert "\n" not in msg and len(msg) < 400, msg
    return msg


@pytest.mark.parametrize(("text", "expect"), [pytest.param(t, e, id=i) for i, t, e in BAD_TABLES])
def test_bad_table_is_one_line_error(tmp_path: Path, text: str, expect: str) -> None:
    path = tmp_path / "times.csv"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(InputFileError) as info:
        read_times(path)
    msg = one_line(info.value)
    assert msg.startswith("times.csv: ") and expect in msg, msg


def test_fewer_points_than_parameters(tmp_path: Path) -> None:
    path = tmp_path / "times.csv"
    path.write_text(times_table(GOOD[:2]), encoding="utf-8")
    with pytest.raises(InputError, match="fewer than the 3 parameters") as info:
        fit_times(read_times(path))
    one_line(info.value)
    path.write_text(times_table([GOOD[0], GOOD[0], GOOD[1]]), encoding="utf-8")
    with pytest.raises(InputError, match="2 distinct cycles"):
        fit_times(read_times(path))


def test_file_level_errors(tmp_path: Path) -> None:
    with pytest.raises(UcbplanError, match="not found"):
        read_times(tmp_path / "missing.csv")
    latin = tmp_path / "latin.csv"
    latin.write_bytes(times_table(GOOD).replace("primary", "prim\xe4ry").encode("latin-1"))
    with pytest.raises(UcbplanError, match="UTF-8"):
        read_times(latin)
    bom = tmp_path / "bom.csv"
    bom.write_bytes(b"\xef\xbb\xbf" + times_table(GOOD).encode())
    assert read_times(bom).n == 4
    ecsv = tmp_path / "t.ecsv"
    ecsv.write_text(
        "# %ECSV 1.0\n# ---\n# datatype:\n# - {name: bjd_tdb, datatype: float64}\n"
        "# - {name: sigma_s, unit: m, datatype: float64}\n# schema: astropy-2.0\n"
        "bjd_tdb sigma_s\n2458305.68 1\n2458305.69 1\n",
        encoding="utf-8",
    )
    with pytest.raises(InputFileError, match="time unit"):
        read_times(ecsv)
    ecsv.write_text(
        ecsv.read_text().replace("unit: m", "unit: s").replace("2458305.69 1", '2458305.69 ""')
    )
    with pytest.raises(InputFileError, match="row 2"):
        read_times(ecsv)


@pytest.mark.parametrize(("doc", "expect"), BAD_INITIAL_FILES)
def test_bad_initial_file(tmp_path: Path, doc: str, expect: str) -> None:
    path = tmp_path / "init.yaml"
    path.write_text(doc, encoding="utf-8")
    with pytest.raises(InputError) as info:
        read_initial(path)
    assert expect in one_line(info.value)


@pytest.mark.parametrize("text", BAD_PERIOD_GUESSES)
def test_bad_period_guess(text: str) -> None:
    with pytest.raises(InputError) as info:
        period_guess(text)
    assert one_line(info.value).startswith("period: ")
