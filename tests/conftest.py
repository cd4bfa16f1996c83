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

# The tests do not depend on the terminal they run in: no inherited width (pytest-xdist workers
# inherit the COLUMNS/LINES that readline exported in the parent). A test that wants a width sets
# COLUMNS itself (tests/cli/test_screen_100_columns.py). Done before any test imports the CLI, whose
# console reads the width once.
for _name in ("COLUMNS", "LINES"):
    os.environ.pop(_name, None)

ROOT = Path(__file__).resolve().parents[1]
CATALOGS = ROOT / "catalogs"


@pytest.fixture(autouse=True, scope="session")
def _offline() -> Iterator[None]:
    """No test may touch the network: astropy's IERS/data offline for the session (a scope,
    as every public entry point of ucbplan enters it; tests of the lower layers need it too)."""
    with offline():
        yield


@pytest.fixture(autouse=True)
def _no_inherited_terminal_size() -> None:
    """CLI subprocesses get no terminal size the test did not give them.

    readline (imported during the run) exports ``COLUMNS``/``LINES`` into the process's C
    environment, behind ``os.environ``'s back; a ``ucbplan`` subprocess would inherit them and
    wrap its messages at that width as on a terminal. A test that wants a width passes
    ``COLUMNS`` itself (tests/cli/test_screen_100_columns.py).
    """
    for name in ("COLUMNS", "LINES"):
        if name not in os.environ:
            os.unsetenv(name)


@pytest.fixture
def hm_cnc_path() -> Path:
    return CATALOGS / "hm-cnc-simulated.yaml"


@pytest.fixture
def eccentric_path() -> Path:
    return CATALOGS / "fiducial-eccentric.yaml"


@pytest.fixture(scope="session")
def telescope_plan(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The issue-24 plan: HM Cnc and the eccentric dWD at Paranal, two nights of 1-h visits
    (X-shooter VIS overheads, σ_v = 5 km/s), as ``ucbplan plan -o plan.ecsv`` writes it."""
    from typer.testing import CliRunner

    from ucbplan.cli.app import app

    out = tmp_path_factory.mktemp("telescope") / "plan.ecsv"
    args = [
        "plan",
        str(CATALOGS / "hm-cnc-simulated.yaml"),
        str(CATALOGS / "fiducial-eccentric.yaml"),
        *("--site", "paranal", "--night", "2040-02-15", "--nights", "2"),
        *("--instrument", "xshooter-vis", "--sigma-v", "5", "--visit", "1h", "-o", str(out)),
    ]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    return out


@pytest.fixture(scope="session")
def first_night(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``plan --observed``'s base case (tests/support/observed.py): the plan of 2040-02-15 for
    sigma_K=20km/s (14 spectra), written with -o."""
    from support.observed import written_plan

    out = tmp_path_factory.mktemp("observed") / "night1.ecsv"
    return written_plan(out, "--night", "2040-02-15", "--goal", "sigma_K=20km/s")


@pytest.fixture(scope="session")
def goal_plan(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The observing log's base case: the goal plan of 2040-02-15 to 17 (it books the first two
    nights), written with -o."""
    from support.observed import written_plan

    out = tmp_path_factory.mktemp("obslog") / "goal.ecsv"
    return written_plan(out, "--night", "2040-02-15", "--nights", "3", "--goal", "sigma_K=13km/s")
