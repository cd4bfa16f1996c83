"""Population forecast: identical tables serial / pool / Dask, resume, per-source statuses."""

from __future__ import annotations

import dataclasses
import json
import re
from pathlib import Path

import numpy as np
import pytest

from ucbplan.errors import NumericalError, OutputExistsError, UcbplanError
from ucbplan.population import execute
from ucbplan.population.catalog import Catalog, read_catalog
from ucbplan.population.catalog_forecast import ForecastOptions
from ucbplan.population.execute import (
    ExecutorSpec,
    SerialExecutor,
    run_chunks,
    source_seed,
)
from ucbplan.population.runner import RunControl, run_forecast
from ucbplan.population.tables import write_table

ROOT = Path(__file__).resolve().parents[2]
CATALOG = ROOT / "catalogs" / "population" / "ldc-200.ecsv"
OPTS = ForecastOptions(sigma_v_kms=15.0)


def _subset(n: int) -> Catalog:
    cat = read_catalog(CATALOG)
    return dataclasses.replace(cat, sources=cat.sources[:n])


def _table_bytes(tmp: Path, cat: Catalog, name: str, **kw: object) -> bytes:
    run = run_forecast(cat, OPTS, RunControl(tmp / f"{name}.parts", **kw))  # type: ignore[arg-type]
    out = tmp / f"{name}.ecsv"
    write_table(run.table, out, overwrite=False)
    return out.read_bytes()


@pytest.fixture(scope="module")
def cat40() -> Catalog:
    return _subset(40)


@pytest.fixture(scope="module")
def serial40(tmp_path_factory: pytest.TempPathFactory, cat40: Catalog) -> bytes:
    return _table_bytes(tmp_path_factory.mktemp("serial"), cat40, "serial", executor=ExecutorSpec())


def test_pool_is_byte_identical_to_serial(tmp_path: Path, cat40: Catalog, serial40: bytes) -> None:
    pool = _table_bytes(tmp_path, cat40, "pool", executor=ExecutorSpec(workers=2))
    assert pool == serial40


def test_chunking_does_not_change_the_table(
    tmp_path: Path, cat40: Catalog, serial40: bytes
) -> None:
    assert _table_bytes(tmp_path, cat40, "c7", executor=ExecutorSpec(), chunk=7) == serial40
    assert _table_bytes(tmp_path, cat40, "c1", executor=ExecutorSpec(), chunk=40) == serial40


def test_table_has_provenance_and_statuses(cat40: Catalog, serial40: bytes) -> None:
    text = serial40.decode()
    for key in (
        "sigma_v_kms: 15.0",
        "catalog_sha256: " + cat40.sha256,
        "reference_epoch_tdb",
        "t_obs_s",
        "ucbplan_version",
        "k_eff_kms",
    ):
        assert key in text
    from astropy.table import Table

    tab = Table.read(text, format="ascii.ecsv")
    assert tab["f_gw"].unit == "Hz" and tab["t_valid_quadrature_a1"].unit == "d"
    assert set(tab["status"]) <= {"ok", "below-threshold", "unconstrained"}
    ok = tab["status"] == "ok"
    assert ok.sum() > 20
    assert np.all(np.isfinite(tab["t_valid_quadrature_a1"][ok]))


def test_face_on_source_is_unconstrained_not_a_300_year_horizon(serial40: bytes) -> None:
    from astropy.table import Table

    tab = Table.read(serial40.decode(), format="ascii.ecsv")
    row = tab[tab["source_id"] == "GB13-00001"][0]  # written face-on by the generator
    assert row["cos_inclination"] == 1.0
    assert row["status"] == "unconstrained"
    for name in tab.colnames:
        if name.startswith("t_valid_"):
            assert np.isnan(row[name])


def test_numerical_error_and_other_errors_are_per_source(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from ucbplan.lisa import pipeline

    cat = _subset(3)
    calls = {"n": 0}
    real = pipeline.fisher_forecast

    def fake(model):  # type: ignore[no-untyped-def]
        calls["n"] += 1
        if calls["n"] == 2:
            raise NumericalError("Fisher matrix: phase unconstrained (face-on)")
        if calls["n"] == 3:
            raise UcbplanError("something else went wrong")
        return real(model)

    monkeypatch.setattr(pipeline, "fisher_forecast", fake)
    run = run_forecast(cat, OPTS, RunControl(tmp_path / "p"))
    status = list(run.table["status"])
    assert status[1] == "unconstrained"
    assert status[2] == "failed: something else went wrong"
    assert run.table.meta["n_failed"] == 1


def test_no_k_fails_the_source_not_the_run(tmp_path: Path) -> None:
    cat = _subset(3)
    srcs = tuple(dataclasses.replace(s, m1_msun=None, m2_msun=None) for s in cat.sources[1:3])
    run = run_forecast(dataclasses.replace(cat, sources=srcs), OPTS, RunControl(tmp_path / "p"))
    assert all(s.startswith("failed: no K") for s in run.table["status"])


def test_resume_reuses_parts_and_recomputes_deleted_or_corrupt(
    tmp_path: Path, cat40: Catalog, serial40: bytes
) -> None:
    parts = tmp_path / "out.parts"
    first = run_forecast(cat40, OPTS, RunControl(parts, chunk=10))
    files = sorted(parts.glob("part-*.json"))
    assert len(files) == 4
    files[1].unlink()
    files[2].write_text("{not json", encoding="utf-8")
    with pytest.raises(OutputExistsError, match="`resume`"):
        run_forecast(cat40, OPTS, RunControl(parts, chunk=10))
    again = run_forecast(cat40, OPTS, RunControl(parts, chunk=10, resume=True))
    assert again.reused == 2
    out = tmp_path / "resumed.ecsv"
    write_table(again.table, out, overwrite=False)
    assert out.read_bytes() == serial40
    # other options: parts are not reused
    other = dataclasses.replace(OPTS, sigma_v_kms=10.0)
    third = run_forecast(cat40, other, RunControl(parts, chunk=10, resume=True))
    assert third.reused == 0
    assert first.n_chunks == 4


def _square(xs: list[int]) -> list[dict[str, int]]:
    return [{"x": x * x} for x in xs]


def test_interrupted_run_keeps_finished_parts(tmp_path: Path) -> None:
    parts = tmp_path / "p"
    parts.mkdir()
    items = list(range(10))
    ids = [str(i) for i in items]
    seen: list[int] = []

    def dies_on_third(xs: list[int]) -> list[dict[str, int]]:
        seen.append(xs[0])
        if len(seen) == 3:
            raise KeyboardInterrupt
        return _square(xs)

    common = dict(chunk=3, slots=1, parts=parts, kind="t", options={}, catalog_sha256="x")
    with pytest.raises(KeyboardInterrupt):
        run_chunks(dies_on_third, items, ids, executor=SerialExecutor(), **common)  # type: ignore[arg-type]
    # chunks 0 and 1 finished before the interrupt; chunk 3 may have finished beside chunk 2 (the
    # order in which completed futures are handled is not defined); chunk 2 never finished
    kept = {p.name for p in parts.glob("part-*.json")}
    assert {"part-000000.json", "part-000001.json"} <= kept
    assert "part-000002.json" not in kept
    rows, reused = run_chunks(
        _square,
        items,
        ids,
        executor=SerialExecutor(),
        resume=True,
        **common,  # type: ignore[arg-type]
    )
    assert reused == len(kept) and [r["x"] for r in rows] == [i * i for i in items]
    doc = json.loads((parts / "part-000000.json").read_text())
    assert doc["ids"] == ["0", "1", "2"]


def test_source_seed_depends_on_seed_and_id_only() -> None:
    assert source_seed(1, "GB-1") == source_seed(1, "GB-1")
    seeds = {source_seed(1, f"GB-{i}") for i in range(1000)}
    assert len(seeds) == 1000
    assert source_seed(2, "GB-1") != source_seed(1, "GB-1")
    assert all(0 <= s < 2**63 for s in seeds)


def test_default_chunk_is_about_one_second() -> None:
    assert execute.default_chunk(10_000, 2, 0.02) == 50
    assert execute.default_chunk(40, 2, 0.02) == 10
    assert execute.default_chunk(1, 8, 0.02) == 1


def test_worker_setup_is_offline() -> None:
    from astropy.utils import data, iers

    execute.worker_setup()
    assert data.conf.allow_internet is False and iers.conf.auto_download is False


def test_bad_executor_options(tmp_path: Path, cat40: Catalog) -> None:
    with pytest.raises(UcbplanError, match=r"^workers: "):
        run_forecast(cat40, OPTS, RunControl(tmp_path / "a", ExecutorSpec(workers=0)))
    with pytest.raises(UcbplanError, match=r"^scheduler: "):
        run_forecast(cat40, OPTS, RunControl(tmp_path / "b", ExecutorSpec(scheduler="localhost")))
    with pytest.raises(UcbplanError, match=r"^chunk: "):
        run_forecast(cat40, OPTS, RunControl(tmp_path / "c", chunk=0))


#: The CI identity check: all 200 sources on a narrow band (N = 64 bins) — the same code path
#: as N = 512, a quarter of the Fisher cost — so it runs in the default test run (~5 s).
CHEAP = dataclasses.replace(OPTS, n_bins=64)


def test_200_sources_serial_pool_and_dask_are_byte_identical(tmp_path: Path) -> None:
    distributed = pytest.importorskip("distributed")
    cat = read_catalog(CATALOG)
    assert len(cat.sources) == 200

    def table(name: str, spec: ExecutorSpec) -> bytes:
        run = run_forecast(cat, CHEAP, RunControl(tmp_path / f"{name}.parts", spec))
        write_table(run.table, tmp_path / f"{name}.ecsv", overwrite=False)
        return (tmp_path / f"{name}.ecsv").read_bytes()

    serial = table("serial", ExecutorSpec())
    pool = table("pool", ExecutorSpec(workers=2))
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster:
        dask = table("dask", ExecutorSpec(scheduler=cluster.scheduler_address))
    assert serial == pool == dask
    counts = {k: int(v) for k, v in re.findall(rb"(n_ok|n_below_threshold): (\d+)", serial)}
    assert counts[b"n_ok"] + counts[b"n_below_threshold"] == 174  # 174 of 200 constrained
    assert counts[b"n_ok"] > 100  # the table is not empty


@pytest.mark.slow
def test_cli_run_killed_then_resumed(tmp_path: Path) -> None:
    """A run killed after its third part file resumes from the parts to the same table.

    The kill is deterministic: the child process ends itself with ``os._exit`` (no clean-up,
    like SIGKILL) right after writing its third part, instead of being killed on a timer that a
    fast or a busy machine turns into a different state (the batched forecast can finish first).
    """
    import os
    import subprocess
    import sys

    out = tmp_path / "f.ecsv"
    killer = (
        "import os, sys, typer; import ucbplan.population.execute as ex; "
        "real = ex.write_output; n = [0]\n"
        "def write(path, *a, **k):\n"
        "    real(path, *a, **k)\n"
        "    if path.name.startswith('part-'):\n"
        "        n[0] += 1\n"
        "        if n[0] == 3: os._exit(137)\n"
        "ex.write_output = write\n"
    )
    code = (
        "import sys, typer; from ucbplan.cli import population as p; app = typer.Typer(); "
        "p.register(app); app(['population', *sys.argv[1:]])"
    )
    args = [sys.executable, "-c", code, "forecast", str(CATALOG), "-o", str(out), "--chunk", "5"]
    args += ["--n-bins", "64"]
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    killed = subprocess.run(
        [sys.executable, "-c", killer + code.replace("import sys, typer; ", ""), *args[3:]],
        env=env,
        stderr=subprocess.DEVNULL,
        check=False,
    )
    parts = tmp_path / "f.ecsv.parts"
    assert killed.returncode == 137
    assert len(list(parts.glob("part-*.json"))) == 3 and not out.exists()
    subprocess.run([*args, "--resume"], env=env, check=True, stderr=subprocess.DEVNULL)
    ref = tmp_path / "ref.ecsv"
    ref_args = [*args[:6], str(ref), *args[7:]]
    subprocess.run(ref_args, env=env, check=True, stderr=subprocess.DEVNULL)
    assert out.read_bytes() == ref.read_bytes()
    assert not parts.exists()


def _per_source_reference(src: object, ra: float, dec: float) -> dict[str, float]:
    """One source the way the library's parts compute it one at a time: astropy converts its
    position, the zero-noise data, the SNR and the Fisher matrix are separate template calls
    (:func:`fisher_covariance` builds its own difference points), and :func:`horizon_table`
    gives its horizons."""
    from ucbplan.core.forecast import horizon_table
    from ucbplan.lisa.fisher import fisher_covariance
    from ucbplan.lisa.likelihood import simulate_data
    from ucbplan.lisa.noise import SANGRIA
    from ucbplan.lisa.pipeline import build_model
    from ucbplan.lisa.posterior import gaussian_target
    from ucbplan.population.catalog_forecast import ALPHAS, ANCHORS, k_total_kms, source_target

    target = source_target(src, ra, dec, OPTS)  # type: ignore[arg-type]
    model = build_model(target, n_bins=OPTS.n_bins, circular=True)
    theta0 = model.theta0()
    like = model.likelihood(simulate_data(model.model, model.truth, SANGRIA, None))
    cov_theta = fisher_covariance(like, theta0, within_prior=False)
    fis = gaussian_target(model.base, theta0, cov_theta, model.t_obs_s, like.prior.names)
    s = np.sqrt(np.diag(fis.covariance)[:3])
    k = k_total_kms(src.m1_msun, src.m2_msun, src.f_hz, np.cos(src.inclination_rad))  # type: ignore[attr-defined]
    out = {
        "snr": float(like.snr(theta0[None])[0]),
        "sigma_phase": s[0],
        "sigma_f_gw": s[1],
        "sigma_fdot": s[2],
        "corr_phase_f_gw": fis.covariance[0, 1] / (s[0] * s[1]),
        "corr_f_gw_fdot": fis.covariance[1, 2] / (s[1] * s[2]),
        "k_eff": k,
    }
    for hr in horizon_table(fis, OPTS.sigma_v_kms, k, ALPHAS, ANCHORS):
        out[f"sigma_u_end_{hr.anchor}"] = hr.sigma_u_end_rad
        out[f"tol_{hr.anchor}"] = hr.delta_u_tol_rad
        out[f"t_valid_{hr.anchor}_a{hr.alpha:g}"] = hr.t_valid_days
    return out


def test_batched_chunk_matches_the_per_source_path() -> None:
    """A chunk shares its sky conversion, LISA midpoint, one template batch per source (data,
    SNR and Fisher points) and one vectorised horizon pass; each row must equal the per-source
    path to 1e-9 relative (issue 23: tables unchanged). Measured: <= 2e-10 relative (the
    Fisher matrix's round-off: the batch and the per-source path difference different points).
    A correlation coefficient is compared absolutely, to 1e-9: its round-off is that of the
    covariance entry relative to s_i*s_j (the same ~1e-10 as the σ's), not relative to the
    coefficient, which may be ~0 (issue 33: corr_phase_f_gw = -0.003 differed by 2.5e-11)."""
    from ucbplan.population.catalog_forecast import forecast_chunk, icrs_of

    cat = _subset(12)
    rows = forecast_chunk(OPTS, cat.sources)
    ra, dec = icrs_of(cat.sources)
    assert rows[0]["status"] == "unconstrained"  # face-on: the batch keeps per-source statuses
    ok = [i for i, r in enumerate(rows) if r["status"] == "ok"]
    assert len(ok) >= 8
    for i in ok:
        ref = _per_source_reference(cat.sources[i], float(ra[i]), float(dec[i]))
        for key, want in ref.items():
            tol = {"abs": 1e-9} if key.startswith("corr_") else {"rel": 1e-9, "abs": 0.0}
            assert rows[i][key] == pytest.approx(want, **tol), key


def test_sources_below_the_detection_threshold_are_flagged() -> None:
    """Issue 33: sources at SNR 1.3-7 were "ok" with T_valid = 0. A source below the LISA
    detection threshold (SNR < SNR_THRESHOLD = 7) keeps its numbers but gets its own status,
    ``below-threshold``; the ranking and the tally count it apart from "ok"."""
    from ucbplan.population.catalog_forecast import forecast_chunk
    from ucbplan.population.defaults import SNR_THRESHOLD
    from ucbplan.population.tables import status_counts

    rows = forecast_chunk(OPTS, _subset(13).sources)
    assert SNR_THRESHOLD == 7.0
    low = [r for r in rows if r["status"] == "below-threshold"]
    assert [round(r["snr"], 2) for r in low] == [6.06, 1.81]  # rows 10 and 12
    assert all(np.isfinite(r["sigma_phase"]) for r in low)  # the numbers are kept
    assert all(r["snr"] >= SNR_THRESHOLD for r in rows if r["status"] == "ok")
    assert rows[3]["status"] == "ok" and rows[3]["snr"] == pytest.approx(7.002, abs=1e-3)
    counts = status_counts(rows)
    assert counts["n_below_threshold"] == 2 and counts["n_ok"] == 8
