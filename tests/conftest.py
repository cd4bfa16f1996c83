"""Shared fixtures: offline astropy for every test, paths to bundled catalogs."""

from __future__ import annotations

from pathlib import Path

import pytest

from ucbplan.offline import configure_offline

ROOT = Path(__file__).resolve().parents[1]
CATALOGS = ROOT / "catalogs"


@pytest.fixture(autouse=True, scope="session")
def _offline() -> None:
    """No test may touch the network: configure astropy's IERS/data offline once."""
    configure_offline()


@pytest.fixture
def hm_cnc_path() -> Path:
    return CATALOGS / "hm-cnc.yaml"


@pytest.fixture
def eccentric_path() -> Path:
    return CATALOGS / "fiducial-eccentric.yaml"
