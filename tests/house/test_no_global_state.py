"""No global state: every public call leaves astropy, PyYAML, the warning filters and the
caller's objects as it found them, and the night sheet works with no network.

The snapshot holds astropy's configuration (every item of its config namespaces, the IERS set-up
of the offline scope: ``test_offline_cache.astropy_state``), its YAML dumper and loader and
their representer / constructor registries (an ECSV write must not swap or register anything
there), PyYAML's own registries and ``warnings.filters``.
"""

from __future__ import annotations

import copy
import warnings
from collections.abc import Callable
from pathlib import Path

import astropy.io.misc.yaml as astropy_yaml
import numpy as np
import pytest
from astropy.table import Table
from astropy.utils import data
from support.network import BLOCK_SOCKETS
from support.state import snapshot

import ucbplan

# the libraries ucbplan calls set warning filters when first imported: import them before any
# snapshot, so that a snapshot sees what ucbplan does, not what they do once
_FIRST = ("astroplan", "astropy.table", "astropy.coordinates", "matplotlib.pyplot")
for _module in (*_FIRST, "scipy.special", "scipy.optimize", "scipy.interpolate", "scipy.sparse"):
    __import__(_module)

CATALOGS = Path(__file__).resolve().parents[2] / "catalogs"
HM = CATALOGS / "hm-cnc-simulated.yaml"
ECC = CATALOGS / "fiducial-eccentric.yaml"
VELOCITIES = CATALOGS / "fiducial-eccentric-velocities.csv"


def test_the_snapshot_sees_what_it_must() -> None:
    """Planted changes: each kind of global state the snapshot holds is noticed."""
    before = snapshot()
    with data.conf.set_temp("allow_internet", not data.conf.allow_internet):
        assert snapshot()["config"] != before["config"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ucbplan.UcbplanWarning)
        assert snapshot()["warnings.filters"] != before["warnings.filters"]
    swapped = type("Swapped", (astropy_yaml.AstropyDumper,), {})
    original = astropy_yaml.AstropyDumper
    astropy_yaml.AstropyDumper = swapped  # type: ignore[misc]
    try:
        assert snapshot()["AstropyDumper"] is not before["AstropyDumper"]
    finally:
        astropy_yaml.AstropyDumper = original  # type: ignore[misc]
    saved = dict(original.yaml_representers)
    original.add_representer(np.ndarray, lambda d, x: d.represent_list(x.tolist()))
    try:
        assert snapshot()["astropy yaml registries"] != before["astropy yaml registries"]
    finally:
        original.yaml_representers = saved  # type: ignore[assignment]
    assert snapshot() == before


def _eclipse_times(tmp: Path) -> Path:
    """Ten eclipse times of a 0.0595 d binary over two nights and a month (BJD_TDB)."""
    period, t0 = 0.05949718, 2458305.68
    cycles = [0, 1, 2, 3, 4, 17, 18, 19, 500, 501]
    rows = [f"{t0 + c * period:.7f},3.0" for c in cycles]
    path = tmp / "times.csv"
    path.write_text("bjd_tdb,sigma_s\n" + "\n".join(rows) + "\n", encoding="utf-8")
    return path


def _small_catalog(tmp: Path) -> Path:
    table = Table.read(CATALOGS / "population" / "ldc-200.ecsv", format="ascii.ecsv")[:3]
    path = tmp / "three.ecsv"
    table.write(path, format="ascii.ecsv")
    return path


#: Each public function of ``ucbplan.__all__`` on a small input.
CALLS: dict[str, Callable[[Path], object]] = {
    "load_target": lambda tmp: ucbplan.load_target(HM),
    "get_site": lambda tmp: ucbplan.get_site("paranal"),
    "ephemeris": lambda tmp: ucbplan.ephemeris(HM, "2040-02-15T00:00", "2040-02-15T00:20"),
    "horizon": lambda tmp: ucbplan.horizon(HM),
    "default_constraints": lambda tmp: ucbplan.default_constraints("paranal"),
    "plan": lambda tmp: ucbplan.plan(HM, "paranal", "2040-02-15"),
    "replan": lambda tmp: ucbplan.replan(
        ucbplan.plan(HM, "paranal", "2040-02-15", 3), "2040-02-16T18:00", lost=["2040-02-16"]
    ),
    "reduce": lambda tmp: ucbplan.reduce(ECC, VELOCITIES, samples=200, seed=1),
    "fit_ephemeris": lambda tmp: ucbplan.fit_ephemeris(_eclipse_times(tmp), period="0.0595 d"),
    "population_forecast": lambda tmp: ucbplan.population_forecast(_small_catalog(tmp)),
    "compare_ephemerides": lambda tmp: ucbplan.compare_ephemerides(HM, HM),
    "validate": lambda tmp: ucbplan.validate([HM]),
    "write_target": lambda tmp: ucbplan.write_target(ucbplan.load_target(HM), tmp / "t.yaml"),
    "feasibility": lambda tmp: ucbplan.feasibility(ECC),
    "fisher": lambda tmp: ucbplan.fisher(ECC, n_bins=64),
    "waveform": lambda tmp: ucbplan.waveform(ECC, n_bins=64),
    "read_blocks": lambda tmp: ucbplan.read_blocks(_plan_file(tmp)),
    "export": lambda tmp: ucbplan.export(_plan_file(tmp), "ics"),
}


def _plan_file(tmp: Path) -> Path:
    path = tmp / "plan.ecsv"
    if not path.exists():
        ucbplan.plan(HM, "paranal", "2040-02-15").write(path)
    return path


def test_every_public_function_is_snapshotted() -> None:
    functions = {n for n in ucbplan.__all__ if n.islower() and callable(getattr(ucbplan, n))}
    # simulate samples a posterior (tens of seconds): test_simulate_leaves_no_state (slow)
    assert functions - {"simulate"} == set(CALLS)


@pytest.mark.parametrize("name", sorted(CALLS))
def test_public_call_leaves_no_global_state(name: str, tmp_path: Path) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the snapshot compares the filters inside this scope
        before = snapshot()
        CALLS[name](tmp_path)
        assert snapshot() == before


@pytest.mark.slow
def test_simulate_leaves_no_global_state() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        before = snapshot()
        ucbplan.simulate(CATALOGS / "fiducial-injection.yaml", seed=1, steps=20, n_bins=64)
        assert snapshot() == before


def test_plan_write_leaves_the_table_and_astropy_alone(tmp_path: Path) -> None:
    """Writing a plan (ECSV, with its visits list, and JSON) changes neither the caller's table
    (meta deep-compared, columns) nor astropy's dumper; the file reads back with astropy's own
    ECSV reader."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        run = ucbplan.plan(HM, "paranal", "2040-02-15", visit="1h")
        table = run.text_table  # what the files hold
        meta, columns = copy.deepcopy(dict(table.meta)), table.copy(copy_data=True)
        before = snapshot()
        for suffix in ("ecsv", "json", "csv"):
            run.write(tmp_path / f"plan.{suffix}")
        assert snapshot() == before
    assert dict(table.meta) == meta and table.meta["visits"]  # the visits list is back, same
    assert table.colnames == columns.colnames
    for name in table.colnames:
        np.testing.assert_array_equal(table[name], columns[name])
    back = Table.read(tmp_path / "plan.ecsv", format="ascii.ecsv")
    assert back.colnames == table.colnames and len(back) == len(table)
    assert back.meta["visits"] == table.meta["visits"]


#: The documented recipe (docs/plots.md) in a fresh interpreter: astropy's defaults (IERS
#: auto-download on, internet allowed), no ``ucbplan.offline.offline()`` around it, every socket
#: connection refused; prints the connection attempts (none expected).
SHEET_SCRIPT = (
    BLOCK_SOCKETS
    + """
import sys
from pathlib import Path
import ucbplan
from ucbplan.observing.night.chart import write_night_charts
from ucbplan.observing.night.sheet import write_night_sheet
out = Path(sys.argv[1])
run = ucbplan.plan(sys.argv[2], "paranal", "2040-02-15", visit="1h")
site = ucbplan.get_site("paranal")
write_night_sheet(run.text_table, site, out / "night.html")
write_night_charts(run.text_table, site, out / "nights.png")
run.sheet(out / "night2.html")
print(len(_attempts))
"""
)


@pytest.mark.slow
def test_night_sheet_recipe_works_with_no_network(tmp_path: Path) -> None:
    import os
    import subprocess
    import sys

    env = {**os.environ, "PYTHONPATH": str(Path(ucbplan.__file__).parents[1])}
    argv = [sys.executable, "-c", SHEET_SCRIPT, str(tmp_path), str(HM)]
    proc = subprocess.run(argv, capture_output=True, text=True, env=env, timeout=120, check=False)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert proc.stdout.strip() == "0"  # no connection even tried
    assert (tmp_path / "night.html").read_text(encoding="utf-8").startswith("<!DOCTYPE html>")
    assert (tmp_path / "nights.png").read_bytes()[:4] == b"\x89PNG"
