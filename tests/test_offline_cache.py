"""The offline scope and its parsed IERS cache.

The cache is filled on first use, read back identical, ignored when broken; the scope leaves
astropy's configuration, its ``IERS_Auto`` class and its default table exactly as it found them.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from astropy.time import Time
from astropy.utils import data, iers
from support.state import astropy_state

from ucbplan import offline as offline_module
from ucbplan.offline import bundled_iers_table, iers_cache_path, offline

# 2040 is past the bundled leap-second table: ERFA calls the year dubious, as intended
pytestmark = pytest.mark.filterwarnings("ignore::erfa.ErfaWarning")


@pytest.fixture
def fresh_iers(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> Path:
    monkeypatch.setenv("UCBPLAN_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(offline_module, "_TABLE", {})
    return tmp_path


def _same(a: iers.IERS_Auto, b: iers.IERS_Auto) -> None:
    assert a.colnames == b.colnames and len(a) == len(b)
    for name in a.colnames:
        np.testing.assert_array_equal(np.asarray(a[name]), np.asarray(b[name]))
    assert a.meta["predictive_mjd"] == b.meta["predictive_mjd"]


def test_cache_round_trip(fresh_iers: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    parsed = iers.IERS_Auto.read()
    first = bundled_iers_table()  # parses and writes the cache
    path = iers_cache_path()
    assert path is not None and path.parent == fresh_iers and path.exists()
    monkeypatch.setattr(offline_module, "_TABLE", {})
    second = bundled_iers_table()  # from the cache
    assert second is not first
    _same(second, parsed)
    assert bundled_iers_table() is second  # once per process


def test_broken_cache_falls_back(fresh_iers: Path) -> None:
    path = iers_cache_path()
    assert path is not None
    path.write_bytes(b"not a pickle")
    _same(bundled_iers_table(), iers.IERS_Auto.read())


def test_empty_dir_disables(monkeypatch: pytest.MonkeyPatch, fresh_iers: Path) -> None:
    monkeypatch.setenv("UCBPLAN_CACHE_DIR", "")
    assert iers_cache_path() is None
    bundled_iers_table()
    assert list(fresh_iers.iterdir()) == []


def test_scope_restores_astropy(monkeypatch: pytest.MonkeyPatch) -> None:
    # the test session runs inside one scope (conftest); step out of it to astropy's defaults
    monkeypatch.setattr(iers.earth_orientation_table, "_value", None)
    with iers.conf.set_temp("auto_download", True), data.conf.set_temp("allow_internet", True):
        before = astropy_state()
        with offline():
            assert iers.conf.auto_download is False and data.conf.allow_internet is False
            assert iers.earth_orientation_table.get() is bundled_iers_table()
            # a night past the bundled predictions converts to UT1 instead of raising
            assert Time("2040-02-15T00:00:00", scale="utc").ut1.jd > 0
        assert astropy_state() == before


def test_scope_keeps_a_table_the_caller_chose() -> None:
    b_table = iers.IERS_B.open(iers.IERS_B_FILE)
    with iers.earth_orientation_table.set(b_table):
        with offline():
            assert iers.earth_orientation_table.get() is b_table
        assert iers.earth_orientation_table.get() is b_table
