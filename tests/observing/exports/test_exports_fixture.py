"""The fixed blocks table behind every export golden file (tests/support/exports.py) is complete."""

from __future__ import annotations

from pathlib import Path

from support.exports import SDSS, written_table

from ucbplan.observing.blocks.schema import EXTRA_COLUMNS, REQUIRED_COLUMNS


def test_fixture_is_a_full_blocks_table(tmp_path: Path) -> None:
    # The goldens must exercise every column the planner writes, not a hand-made subset.
    table = written_table(tmp_path)
    assert set(REQUIRED_COLUMNS) | set(EXTRA_COLUMNS) <= set(table.colnames)
    assert len(table) == 4 and set(table["target"]) == {"HM Cnc", SDSS}
