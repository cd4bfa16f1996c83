"""A posterior given only as samples: its covariance comes from the samples (issue 26, item 4).

Reference: the fiducial target's own covariance C (catalogs/fiducial-eccentric.yaml). Samples are
drawn from N(θ, C) with a seeded generator; the samples-only target must give the σ_u and T_valid
of C within Monte-Carlo error, and exactly those of a covariance target written from the sample
covariance of the same rows.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import yaml
from astropy.table import Table

from ucbplan.core.forecast import horizon_s, sigma_u_end
from ucbplan.core.params import PARAM_NAMES
from ucbplan.targets import Target, load_target

ROOT = Path(__file__).resolve().parents[2]
FIDUCIAL = ROOT / "catalogs" / "fiducial-eccentric.yaml"
N_ROWS = 20_000


def _doc() -> dict:
    return yaml.safe_load(FIDUCIAL.read_text())


def _write_samples(tmp_path: Path, doc: dict, t_ref_is: str) -> tuple[Path, np.ndarray]:
    """Seeded N(θ, C) draws of the file's numbers as written (θ, C at the epoch it states).

    The numbers as written are those of the same document read as midpoint-referenced (nothing
    moved); a start-referenced samples file holds draws of these start values.
    """
    as_written = load_target_from(tmp_path / "written.yaml", doc)
    mean = as_written.params.as_array()
    cov = as_written.covariance
    rng = np.random.default_rng(2604)
    keep = np.diag(cov) > 0
    draws = np.tile(mean, (N_ROWS, 1))
    chol = np.linalg.cholesky(cov[np.ix_(keep, keep)])
    draws[:, keep] += rng.standard_normal((N_ROWS, int(keep.sum()))) @ chol.T
    path = tmp_path / f"post-{t_ref_is}.ecsv"
    cols = {n: draws[:, k] for k, n in enumerate(PARAM_NAMES) if keep[k]}
    Table(cols).write(path, format="ascii.ecsv")
    return path, draws


def load_target_from(path: Path, doc: dict) -> Target:
    """The target of ``doc`` written to ``path`` (samples are found next to it)."""
    path.write_text(yaml.safe_dump(doc))
    return load_target(path)


@pytest.mark.parametrize("t_ref_is", ["midpoint", "start"])
def test_samples_only_target_has_the_covariance_of_its_samples(
    tmp_path: Path, t_ref_is: str
) -> None:
    doc = _doc()
    doc["lisa"]["t_ref_is"] = t_ref_is
    ref = load_target_from(tmp_path / "ref.yaml", doc)
    samples, _ = _write_samples(tmp_path, _doc(), t_ref_is)
    only = dict(doc, lisa={k: v for k, v in doc["lisa"].items() if k != "covariance"})
    only["lisa"]["samples"] = samples.name
    t = load_target_from(tmp_path / "only.yaml", only)
    assert "samples" in t.covariance_source
    assert ref.covariance_source == "lisa.covariance"
    # σ_u at the end of the observation: MC error of a σ from 2e4 draws is 1/√(2N) = 0.5 %;
    # 3 % leaves room for the φ–ḟ correlation estimate (σ_u is dominated by the f, ḟ terms)
    for anchor in ("quadrature", "conjunction"):
        assert sigma_u_end(t, anchor) == pytest.approx(sigma_u_end(ref, anchor), rel=0.03)
        assert sigma_u_end(t, anchor) > 0.0
    # T_valid: was the 300-year cap for a samples-only target; σ_u grows ∝ τ² late, so a 3 %
    # σ error moves T_valid by ~1.5 %; 5 % tolerance
    tv, tv_ref = horizon_s(t, 15.0, 1297.9), horizon_s(ref, 15.0, 1297.9)
    assert tv == pytest.approx(tv_ref, rel=0.05)
    assert tv < 50 * 365.25 * 86400.0


def test_samples_covariance_equals_the_covariance_target_of_the_same_rows(
    tmp_path: Path,
) -> None:
    """Exactly (1e-9): a target whose lisa.covariance is np.cov of the same rows."""
    doc = _doc()
    samples, draws = _write_samples(tmp_path, doc, "midpoint")
    only = dict(doc, lisa={k: v for k, v in doc["lisa"].items() if k != "covariance"})
    only["lisa"]["samples"] = samples.name
    t = load_target_from(tmp_path / "only.yaml", only)
    keep = [k for k in range(7) if np.ptp(draws[:, k]) > 0]
    cov = np.cov(draws[:, keep], rowvar=False)
    names = [PARAM_NAMES[k] for k in keep]
    with_cov = dict(
        doc, lisa=dict(doc["lisa"], covariance={"parameters": names, "matrix": cov.tolist()})
    )
    ref = load_target_from(tmp_path / "cov.yaml", with_cov)
    np.testing.assert_allclose(t.covariance, ref.covariance, rtol=1e-9, atol=0.0)
    assert sigma_u_end(t) == pytest.approx(sigma_u_end(ref), rel=1e-9)
    assert horizon_s(t, 15.0, 1297.9) == pytest.approx(horizon_s(ref, 15.0, 1297.9), rel=1e-9)
    assert math.isfinite(sigma_u_end(t))


def test_validate_says_which_covariance_was_used(tmp_path: Path) -> None:
    """`validate --format json` names the covariance's source and the samples' σ's."""
    import json

    from typer.testing import CliRunner

    from ucbplan.cli.app import app

    doc = _doc()
    samples, draws = _write_samples(tmp_path, doc, "midpoint")
    only = dict(doc, lisa={k: v for k, v in doc["lisa"].items() if k != "covariance"})
    only["lisa"]["samples"] = samples.name
    path = tmp_path / "only.yaml"
    path.write_text(yaml.safe_dump(only))
    res = CliRunner().invoke(app, ["validate", str(path), str(FIDUCIAL), "--format", "json"])
    assert res.exit_code == 0, res.output
    rows = json.loads(res.stdout)
    rows = rows if isinstance(rows, list) else rows["targets"]
    assert rows[0]["covariance_from"].startswith("samples file post-midpoint.ecsv")
    assert rows[1]["covariance_from"] == "lisa.covariance"
    # σ(f_gw) of the samples: np.std of the same rows (ddof=1), 1e-9 relative
    assert rows[0]["sigmas"]["f_gw"] == pytest.approx(np.std(draws[:, 1], ddof=1), rel=1e-9)
