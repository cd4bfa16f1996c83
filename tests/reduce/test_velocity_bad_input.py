"""Velocity files: every case of the bad-input corpus (tests/support/bad_velocities.py) is refused
in one line naming the file, the row and the column."""

from __future__ import annotations

from pathlib import Path

import pytest
from support.bad_velocities import CSV_TABLES, CSV_TABLES_MORE, ECSV_ROWS
from support.reduce import write_velocity_ecsv, write_velocity_file

from ucbplan.errors import VelocityFileError
from ucbplan.reduce.velocities import read_velocities


@pytest.mark.parametrize("text, needle", CSV_TABLES)
def test_malformed_tables_raise_one_line_errors(tmp_path: Path, text: str, needle: str) -> None:
    """Each malformed table raises VelocityFileError naming the file and the row/column."""
    p = write_velocity_file(tmp_path, text)
    with pytest.raises(VelocityFileError) as exc:
        read_velocities(p)
    msg = str(exc.value)
    assert needle in msg and str(p) in msg and "\n" not in msg


@pytest.mark.parametrize("body, needle", ECSV_ROWS)
def test_ecsv_blank_and_bad_cells_are_refused(tmp_path: Path, body: list[str], needle: str) -> None:
    """A blank ECSV cell is masked by astropy; it used to be read as a number (0.0 or NaN)."""
    with pytest.raises(VelocityFileError) as exc:
        read_velocities(write_velocity_ecsv(tmp_path, body))
    assert needle in str(exc.value)


@pytest.mark.parametrize("text, needle", CSV_TABLES_MORE)
def test_more_malformed_tables(tmp_path: Path, text: str, needle: str) -> None:
    p = write_velocity_file(tmp_path, text)
    with pytest.raises(VelocityFileError) as exc:
        read_velocities(p)
    msg = str(exc.value)
    assert needle in msg and str(p) in msg and "\n" not in msg and len(msg) < 400
