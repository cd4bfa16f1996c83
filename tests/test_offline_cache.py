"""The parsed IERS cache: filled on first use, read back identical, ignored when broken."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from astropy.utils import iers

from ucbplan.offline import configure_offline, iers_cache_path


@pytest.fixture
def fresh_iers(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> Path:
    configure_offline()
    monkeypatch.setenv("UCBPLAN_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(iers.IERS_Auto, "iers_table", None)
    return tmp_path


def _same(a: iers.IERS_Auto, b: iers.IERS_Auto) -> None:
    assert a.colnames == b.colnames and len(a) == len(b)
    for name in a.colnames:
        np.testing.assert_array_equal(np.asarray(a[name]), np.asarray(b[name]))
    assert a.meta["predictive_mjd"] == b.meta["predictive_mjd"]


def test_cache_round_trip(fresh_iers: Path) -> None:
    parsed = iers.IERS_Auto.read()
    first = iers.IERS_Auto.open()  # parses and writes the cache
    path = iers_cache_path()
    assert path is not None and path.parent == fresh_iers and path.exists()
    iers.IERS_Auto.iers_table = None
    second = iers.IERS_Auto.open()  # from the cache
    assert second is not first
    _same(second, parsed)
    assert iers.IERS_Auto.open() is second  # once per process


def test_broken_cache_falls_back(fresh_iers: Path) -> None:
    path = iers_cache_path()
    assert path is not None
    path.write_bytes(b"not a pickle")
    _same(iers.IERS_Auto.open(), iers.IERS_Auto.read())


def test_empty_dir_disables(monkeypatch: pytest.MonkeyPatch, fresh_iers: Path) -> None:
    monkeypatch.setenv("UCBPLAN_CACHE_DIR", "")
    assert iers_cache_path() is None
    iers.IERS_Auto.open()
    assert list(fresh_iers.iterdir()) == []
