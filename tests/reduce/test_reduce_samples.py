"""reduce reads posterior samples through ucbplan.targets.load_samples (issue 11).

Bug: reduce had its own samples reader and ignored ``t_ref_is: start`` for a samples file, so a
start-referenced file was used as if it were at the midpoint (f off by ḟT/2 ≈ 1e-7 Hz, (η, κ)
rotated by ω̇T/2 ≈ 94 rad). A start-referenced file must give the same reduction as the same
samples moved to the midpoint by hand.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
import yaml
from astropy.table import Table

from ucbplan.core.mvnormal import sample_normal
from ucbplan.core.params import PARAM_NAMES, shift_columns
from ucbplan.errors import UcbplanError
from ucbplan.reduce import ReduceOptions, read_velocities, reduce
from ucbplan.targets import Target, load_target

ROOT = Path(__file__).resolve().parents[2]
INJECTION = ROOT / "catalogs" / "fiducial-injection.yaml"  # t_ref_is: start
VELS = ROOT / "catalogs" / "fiducial-eccentric-velocities.csv"
SIGMA = {
    "phase": 0.002,
    "f_gw": 5.5e-12,
    "fdot": 3.4e-19,
    "fddot": 0.0,
    "eta": 5.4e-4,
    "kappa": 5.4e-4,
    "omega_dot": 1.5e-9,
}


def _start_samples(n: int = 3000) -> dict[str, np.ndarray]:
    """Samples around the injection's start-epoch values (as written in its YAML)."""
    raw = yaml.safe_load(INJECTION.read_text())["lisa"]
    start = {
        "phase": raw["phase"],
        "f_gw": float(raw["f_gw"].split()[0]),
        "fdot": float(raw["fdot"].split()[0]),
        "fddot": 0.0,
        "eta": raw["eta"],
        "kappa": raw["kappa"],
        "omega_dot": float(raw["omega_dot"].split()[0]),
    }
    mean = np.array([start[k] for k in PARAM_NAMES])
    cov = np.diag([SIGMA[k] ** 2 for k in PARAM_NAMES])
    draws = sample_normal(mean, cov, n, np.random.default_rng(11))
    cols = {k: draws[:, i] for i, k in enumerate(PARAM_NAMES)}
    cols["cos_inclination"] = np.random.default_rng(12).normal(raw["cos_inclination"], 0.01, n)
    return cols


def _write(cols: dict[str, np.ndarray], path: Path) -> Path:
    Table({k: np.asarray(v) for k, v in cols.items()}).write(path, format="ascii.ecsv")
    return path


def _target_with_samples(tmp_path: Path, samples: Path) -> Target:
    doc = yaml.safe_load(INJECTION.read_text())
    doc["lisa"]["samples"] = str(samples)
    path = tmp_path / "start.yaml"
    path.write_text(yaml.safe_dump(doc), encoding="utf-8")
    return load_target(path)


def test_start_referenced_samples_equal_samples_moved_by_hand(tmp_path: Path) -> None:
    """Same seed, same rows: the start-referenced file and the file moved to the midpoint by
    hand (f + ḟT/2, (η, κ) rotated by ω̇T/2, φ advanced) give identical summaries (1e-9)."""
    cols = _start_samples()
    start_file = _write(cols, tmp_path / "start.ecsv")
    t_start = _target_with_samples(tmp_path, start_file)
    assert t_start.ref_shift_s == pytest.approx(0.5 * t_start.t_obs_s)
    half = 0.5 * t_start.t_obs_s
    moved = shift_columns(cols, half)
    # by hand, for the record: the frequency and the apsidal rotation
    np.testing.assert_allclose(moved["f_gw"], cols["f_gw"] + cols["fdot"] * half, rtol=1e-15)
    w = cols["omega_dot"] * half
    np.testing.assert_allclose(
        moved["kappa"], cols["kappa"] * np.cos(w) - cols["eta"] * np.sin(w), atol=1e-15
    )
    mid_file = _write(moved, tmp_path / "mid.ecsv")
    t_mid = dataclasses.replace(t_start, samples=mid_file, ref_shift_s=0.0)

    table = read_velocities(VELS)
    opts = ReduceOptions(n_samples=4000, seed=5)
    a = reduce(t_start, table, opts).summaries
    b = reduce(t_mid, table, opts).summaries
    assert a.keys() == b.keys() and "M1" in a
    for key in a:
        assert a[key].value == pytest.approx(b[key].value, rel=1e-9, abs=1e-30), key
        assert a[key].sigma == pytest.approx(b[key].sigma, rel=1e-6, abs=1e-30), key


def test_samples_file_sets_the_period_spread(tmp_path: Path) -> None:
    """The samples (the target has no covariance here) drive the Monte Carlo: P_b's spread is
    that of 2π/(πf − ω̇) over the samples at the midpoint (10 %: 4000 draws)."""
    cols = _start_samples()
    t = _target_with_samples(tmp_path, _write(cols, tmp_path / "s.ecsv"))
    red = reduce(t, read_velocities(VELS), ReduceOptions(n_samples=4000, seed=1))
    mid = shift_columns(cols, 0.5 * t.t_obs_s)
    expected = np.std(2 * math.pi / (math.pi * mid["f_gw"] - mid["omega_dot"]))
    assert red.summaries["P_b"].sigma == pytest.approx(expected, rel=0.1)


@pytest.mark.parametrize(
    "text",
    [
        "# %ECSV 1.0\n# ---\n# datatype:\n# - {name: phase, datatype: float64}\n# schema: "
        "astropy-2.0\nphase\n",
        "not a table at all\n\x00\x01",
        "# %ECSV 1.0\n# ---\n# datatype:\n# - {name: color, datatype: string}\n# schema: "
        "astropy-2.0\ncolor\nred\n",
    ],
)
def test_bad_samples_file_is_one_line_error(tmp_path: Path, text: str) -> None:
    """A samples file without rows or parameter columns: one line naming the file."""
    bad = tmp_path / "bad.ecsv"
    bad.write_text(text, encoding="utf-8")
    # the injection target has no lisa.covariance: the samples are read when it is loaded
    with pytest.raises(UcbplanError) as err:
        _target_with_samples(tmp_path, bad)
    msg = str(err.value)
    assert "bad.ecsv" in msg and "\n" not in msg and len(msg) < 400
