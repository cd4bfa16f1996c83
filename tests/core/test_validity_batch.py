"""The vectorised horizon columns equal the one-target horizon table, row by row."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from support.targets import random_targets, ztf_j1539_doc

from ucbplan.core.forecast import horizon_table, two_sided
from ucbplan.core.validity_batch import horizon_columns
from ucbplan.targets import load_target, target_from_dict

ROOT = Path(__file__).resolve().parents[2] / "catalogs"
TIMING = ztf_j1539_doc("timing test input", spectroscopy=False)


@pytest.mark.parametrize("anchors", [("conjunction", "quadrature"), ("zero-crossing", 1.0)])
def test_columns_equal_table(anchors: tuple[str | float, ...]) -> None:
    targets = [
        load_target(ROOT / "hm-cnc-simulated.yaml"),
        load_target(ROOT / "fiducial-eccentric.yaml"),
        target_from_dict(TIMING),
    ]
    cols = horizon_columns(
        np.array([t.params.as_array() for t in targets]),
        np.array([t.covariance for t in targets]),
        np.array([t.t_obs_s for t in targets]),
        15.0,
        np.array([390.0, 1298.0, 300.0]),
        alphas=(0.5, 1.0),
        anchors=anchors,
        two_sided=[two_sided(t) for t in targets],
    )
    for i, (t, k) in enumerate(zip(targets, (390.0, 1298.0, 300.0), strict=True)):
        for row in horizon_table(t, 15.0, k, (0.5, 1.0), anchors):
            key = f"{row.anchor}:{row.alpha:g}"
            assert cols[f"delta_u_tol_rad:{row.anchor}"][i] == row.delta_u_tol_rad
            assert cols[f"sigma_u_end_rad:{row.anchor}"][i] == pytest.approx(row.sigma_u_end_rad)
            assert cols[f"t_valid_days:{key}"][i] == pytest.approx(row.t_valid_days, rel=1e-12)
            assert cols[f"dt_u_s:{key}"][i] == pytest.approx(row.dt_u_s, rel=1e-9)
            if row.two_sided:
                got = cols[f"t_valid_before_days:{key}"][i]
                assert got == pytest.approx(row.t_valid_before_days, rel=1e-12)
                assert row.t_valid_before_days > 0
            else:
                assert math.isnan(cols[f"t_valid_before_days:{key}"][i])


def test_a_row_is_the_same_alone_or_in_a_batch() -> None:
    """Each target's columns do not depend on the other rows of the batch, to the last bit: the
    roots of all α are found in one stacked pass, the Newton rows leave as they converge and the
    window search keeps only the points some row needs (random circular, eccentric, timing-like
    targets and thresholds from tests/core/test_validity_poly.py, one call each vs one batch)."""
    pars, covs, t_obs, thr = random_targets(40, 7)
    k_eff = 15.0 / thr  # a spread of tolerances, a few above π (no window)
    kw = {"alphas": (0.3, 1.0, 2.0), "anchors": ("quadrature", "zero-crossing")}
    batch = horizon_columns(pars, covs, t_obs, 15.0, k_eff, two_sided=t_obs == 0, **kw)
    for i in range(len(pars)):
        row = slice(i, i + 1)
        one = horizon_columns(
            pars[row], covs[row], t_obs[row], 15.0, k_eff[row], two_sided=t_obs[row] == 0, **kw
        )
        for key, col in batch.items():
            assert np.array_equal(col[i : i + 1], one[key], equal_nan=True), (i, key)
