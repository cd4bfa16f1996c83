"""Population simulate: per-source seeds, posterior vs Fisher, failures listed, resume."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from astropy.table import Table

from ucbplan.population.catalog import Catalog, read_catalog
from ucbplan.population.catalog_forecast import ForecastOptions
from ucbplan.population.runner import RunControl
from ucbplan.population.simulate import PopulationSimulateOptions, run_simulate
from ucbplan.population.tables import write_table
from ucbplan.targets import load_target

ROOT = Path(__file__).resolve().parents[2]
CATALOG = ROOT / "catalogs" / "population" / "ldc-200.ecsv"
#: Short chains on a narrow band: seconds for the whole file.
OPTS = PopulationSimulateOptions(seed=7, walkers=12, steps=40, forecast=ForecastOptions(n_bins=64))


@pytest.fixture(scope="module")
def catalog(tmp_path_factory: pytest.TempPathFactory) -> Catalog:
    """Rows 1-4 of the 200-source catalog (row 1 face-on) and a bright source with ḟ < 1e-18."""
    tab = Table.read(CATALOG)[:4]
    tab.add_row(tab[2])
    tab["Name"][4] = "slow-chirp"
    tab["Frequency"][4] = 1.5e-3
    tab["FrequencyDerivative"][4] = 5e-19
    tab["Amplitude"][4] = 1e-21
    path = tmp_path_factory.mktemp("cat") / "five.ecsv"
    tab.write(path, format="ascii.ecsv")
    return read_catalog(path)


def _run(tmp: Path, cat: Catalog, name: str, **kw: object) -> tuple[object, bytes]:
    control = RunControl(tmp / f"{name}.p", **kw)  # type: ignore[arg-type]
    run = run_simulate(cat, OPTS, tmp / f"{name}-targets", control)
    write_table(run.table, tmp / f"{name}.ecsv", overwrite=False)
    return run, (tmp / f"{name}.ecsv").read_bytes()


@pytest.fixture(scope="module")
def first(tmp_path_factory: pytest.TempPathFactory, catalog: Catalog) -> tuple[object, bytes]:
    return _run(tmp_path_factory.mktemp("sim"), catalog, "a", chunk=2)


def test_posterior_sigmas_agree_with_fisher_and_targets_load(first: tuple[object, bytes]) -> None:
    tab = first[0].table  # type: ignore[attr-defined]
    status = list(tab["status"])
    assert status[0] == "unconstrained" and "face-on" in tab["error"][0]
    assert status[4] in ("ok",) or status[4].startswith("failed")  # ḟ < 1e-18: never a crash
    for row in tab[np.asarray(tab["status"]) == "ok"]:
        if row["snr"] > 50 and row["source_id"] != "slow-chirp":
            # a 40-step chain of 12 walkers: its σ is the Fisher σ within a factor 2 (not for
            # the slow chirp, whose ḟ posterior meets the prior's edge: not Gaussian)
            for p in ("phase", "f_gw"):
                assert 0.5 < row[f"sigma_{p}"] / row[f"fisher_sigma_{p}"] < 2.0, (
                    row["source_id"],
                    p,
                )
        path = Path(row["target_file"])
        assert path.is_absolute() and path.is_file()
        t = load_target(path)
        assert t.name == row["source_id"] and t.params.f_gw == pytest.approx(row["mean_f_gw"])
        assert t.spectroscopy is not None and t.spectroscopy.sigma_v_kms == 15.0
    assert tab.meta["n_ok"] >= 3 and tab.meta["seed"] == 7


def test_seeded_per_source_not_per_chunk_or_order(
    tmp_path: Path, catalog: Catalog, first: tuple[object, bytes]
) -> None:
    _, one = _run(tmp_path, catalog, "b", chunk=5)
    # byte-identical but for the output folder named in target_file
    folder_a = str(Path(first[0].table["target_file"][1]).parent)  # type: ignore[attr-defined]
    ref = first[1].decode().replace(folder_a, "TARGETS")
    assert one.decode().replace(str(tmp_path / "b-targets"), "TARGETS") == ref
    rev = dataclasses.replace(catalog, sources=catalog.sources[::-1])
    run, _ = _run(tmp_path, rev, "c", chunk=1)
    a = first[0].table  # type: ignore[attr-defined]
    b = run.table  # type: ignore[attr-defined]
    for name in ("seed", "mean_phase", "sigma_f_gw", "status"):
        np.testing.assert_array_equal(np.asarray(b[name])[::-1], np.asarray(a[name]))


def test_failed_source_is_listed_and_resume_reuses_parts(
    tmp_path: Path, catalog: Catalog, monkeypatch: pytest.MonkeyPatch
) -> None:
    from ucbplan.lisa import pipeline

    real = pipeline.simulate

    def flaky(model, options, progress=None):  # type: ignore[no-untyped-def]
        if abs(model.truth.f_gw - 1.5e-3) < 1e-6:
            raise ValueError("prior excludes this source")
        return real(model, options, progress)

    monkeypatch.setattr(pipeline, "simulate", flaky)
    run, _ = _run(tmp_path, catalog, "d", chunk=1)
    tab = run.table  # type: ignore[attr-defined]
    assert tab["status"][4] == "failed: ValueError: prior excludes this source"
    assert tab.meta["failed"] == [{"source_id": "slow-chirp", "error": tab["status"][4]}]
    assert list(tab["status"][1:4]) == ["ok", "ok", "ok"]
    monkeypatch.setattr(pipeline, "simulate", real)
    parts = tmp_path / "d.p"
    (parts / "part-000002.json").unlink()
    again = run_simulate(catalog, OPTS, tmp_path / "e", RunControl(parts, chunk=1, resume=True))
    assert again.reused == 4
    assert list(again.table["mean_phase"][:4]) == pytest.approx(
        list(tab["mean_phase"][:4]), nan_ok=True
    )
