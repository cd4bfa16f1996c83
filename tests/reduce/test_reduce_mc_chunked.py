"""The chunked mass Monte Carlo: the same random stream and summaries as the one-shot run."""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path

import numpy as np
import pytest
from astropy.table import Table

from ucbplan.core.mvnormal import sample_normal
from ucbplan.core.params import PARAM_NAMES
from ucbplan.reduce.pipeline import ReduceOptions, reduce
from ucbplan.targets import load_target

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "benchmarks"))

from reduce_scaling import make_table  # noqa: E402


def _run(monkeypatch: pytest.MonkeyPatch, target, chunk: int, n: int = 20_000):  # type: ignore[no-untyped-def]
    from ucbplan.reduce import montecarlo

    monkeypatch.setattr(montecarlo, "CHUNK", chunk)
    return reduce(target, make_table(target, 480), ReduceOptions(n_samples=n, seed=5))


def _compare(one, chunked) -> None:  # type: ignore[no-untyped-def]
    assert one.samples and not chunked.samples  # the chunked run keeps summaries only
    assert set(one.summaries) == set(chunked.summaries)
    for key, a in one.summaries.items():
        b = chunked.summaries[key]
        assert b.n_valid == a.n_valid
        for x, y in ((a.value, b.value), (a.lo, b.lo), (a.hi, b.hi), (a.sigma, b.sigma)):
            assert y == pytest.approx(x, rel=1e-12, abs=1e-15 * abs(a.value)), key
    assert one.warnings == chunked.warnings


def test_chunked_equals_one_shot(monkeypatch: pytest.MonkeyPatch) -> None:
    t = load_target(ROOT / "catalogs" / "fiducial-eccentric.yaml")
    _compare(_run(monkeypatch, t, 10**9), _run(monkeypatch, t, 3_001))


def test_chunked_equals_one_shot_with_samples_file(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    t = load_target(ROOT / "catalogs" / "fiducial-eccentric.yaml")
    th = sample_normal(t.params.as_array(), t.covariance, 5000, np.random.default_rng(9))
    path = tmp_path / "post.ecsv"
    Table({name: th[:, k] for k, name in enumerate(PARAM_NAMES)}).write(path)
    ts = dataclasses.replace(t, samples=path)
    _compare(_run(monkeypatch, ts, 10**9), _run(monkeypatch, ts, 4_999))
