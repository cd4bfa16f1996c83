"""Shared fixtures: offline astropy for every test, paths to bundled catalogs."""

from __future__ import annotations

import os
from collections.abc import Iterator
from pathlib import Path

import pytest
from hypothesis import settings

from ucbplan.offline import offline

# CI runs hypothesis derandomized, so a red CI is reproducible; locally the search is random and
# remembers failing examples in .hypothesis/.
settings.register_profile("ci", derandomize=True, print_blob=True)
if os.environ.get("CI"):
    settings.load_profile("ci")

# The parsed-IERS cache goes to a per-run temporary folder, not the user's ~/.cache (set before
# any test imports the tables; CLI subprocesses inherit it).
if "UCBPLAN_CACHE_DIR" not in os.environ:
    import tempfile

    os.environ["UCBPLAN_CACHE_DIR"] = tempfile.mkdtemp(prefix="ucbplan-test-cache-")

ROOT = Path(__file__).resolve().parents[1]
CATALOGS = ROOT / "catalogs"


@pytest.fixture(autouse=True, scope="session")
def _offline() -> Iterator[None]:
    """No test may touch the network: astropy's IERS/data offline for the session (a scope,
    as every public entry point of ucbplan enters it; tests of the lower layers need it too)."""
    with offline():
        yield


@pytest.fixture
def hm_cnc_path() -> Path:
    return CATALOGS / "hm-cnc-simulated.yaml"


@pytest.fixture
def eccentric_path() -> Path:
    return CATALOGS / "fiducial-eccentric.yaml"
