"""The fused waveform kernel (issue 14) gives the pre-optimisation waveform to 1e-12 relative.

``tests/golden/lisa_bands.npz`` holds :meth:`FourLineModel.bands` of the implementation before
the fused kernel (commit 7938afd), written by running this file as a script
(``python tests/test_lisa_waveform_kernel.py``). That implementation is itself checked against a
brute-force time-domain TDI in ``tests/test_lisa_waveform.py`` (the independent check of these
numbers); here the new kernel must reproduce it, plus batch invariance (a batch equals its rows
one at a time, across the internal walker blocks).
"""

from __future__ import annotations

from functools import cache
from pathlib import Path

import numpy as np
import pytest

from ucbplan.lisa.likelihood import model_for_target, source_from_target
from ucbplan.lisa.waveform import FourLineModel
from ucbplan.target import load_target

ROOT = Path(__file__).resolve().parents[1]
INJECTION = ROOT / "catalogs" / "fiducial-injection.yaml"
GOLDEN = Path(__file__).resolve().parent / "golden" / "lisa_bands.npz"
KEYS = (
    "amplitude",
    "f_gw",
    "fdot",
    "cos_inclination",
    "psi",
    "phase",
    "eta",
    "kappa",
    "omega_dot",
    "fddot",
)


@cache
def _models() -> dict[str, FourLineModel]:
    target = load_target(INJECTION)
    f_c = source_from_target(target).f_gw
    return {
        "ecc128": model_for_target(target, target.t_obs_s, 128, True, f_c),
        "ecc512": model_for_target(target, target.t_obs_s, 512, True, f_c),
        "circ64": model_for_target(target, target.t_obs_s, 64, False, f_c),
    }


def _params(case: str) -> dict[str, np.ndarray]:
    """Parameter batches: the fiducial and variants across the prior (f, fdot, e, psi, wdot)."""
    truth = source_from_target(load_target(INJECTION))
    base = {k: getattr(truth, k) for k in KEYS}
    t_obs = load_target(INJECTION).t_obs_s
    rows = [
        base,
        base | {"f_gw": base["f_gw"] + 3.3 / t_obs, "fdot": 2.5e-15, "psi": 2.9, "phase": 0.2},
        base | {"eta": -0.05, "kappa": 0.07, "omega_dot": 2 * np.pi * 12.5 / t_obs},
        base | {"fdot": -3e-19, "cos_inclination": -0.8, "fddot": 1e-24, "f_gw": 8.4061e-3},
    ]
    if case == "ecc512":
        rows = rows[:1]
    if case == "circ64":
        rows = [r | {"eta": 0.0, "kappa": 0.0, "omega_dot": 0.0} for r in rows[:2]]
    return {k: np.array([r[k] for r in rows]) for k in KEYS}


def _compute() -> dict[str, np.ndarray]:
    return {case: model.bands(**_params(case)) for case, model in _models().items()}


@pytest.mark.parametrize("case", ["ecc128", "ecc512", "circ64"])
def test_kernel_matches_the_previous_implementation(case: str) -> None:
    """Every bin within 1e-12 of the largest |value| of its band (the model's round-off)."""
    old = np.load(GOLDEN)[case]
    new = _models()[case].bands(**_params(case))
    assert new.shape == old.shape
    scale = np.max(np.abs(old), axis=-1, keepdims=True)
    assert np.max(np.abs(new - old) / scale) <= 1e-12


def test_batch_equals_rows_one_at_a_time() -> None:
    """40 walkers (three internal blocks) give each row's single-walker result."""
    model = _models()["ecc128"]
    p = _params("ecc128")
    rng = np.random.default_rng(5)
    idx = rng.integers(0, 4, 40)
    batch = {k: v[idx] * (1.0 + 1e-9 * rng.standard_normal(40)) for k, v in p.items()}
    out = model.bands(**batch)
    for i in (0, 17, 39):
        one = model.bands(**{k: v[i] for k, v in batch.items()})[0]
        np.testing.assert_allclose(out[i], one, rtol=0, atol=1e-13 * np.max(np.abs(one)))


if __name__ == "__main__":
    np.savez_compressed(GOLDEN, **_compute())
    print(f"wrote {GOLDEN}")
