"""The fused waveform kernel (issue 14) gives the pre-optimisation waveform to 1e-12 relative.

``tests/golden/lisa_bands.npz`` holds :meth:`FourLineModel.bands` of the implementation before
the fused kernel, written by running this file as a script at commit 7938afd
(``python tests/lisa/test_lisa_waveform_kernel.py``). That implementation is itself checked
against a brute-force time-domain TDI in ``tests/lisa/test_lisa_waveform.py`` (the independent
check of these numbers); here the new kernel must reproduce it, plus batch invariance (a batch
equals its rows one at a time, across the internal walker blocks). Random walkers across the
prior check the polynomial link sums and table carriers against Horner's rule with per-sample
sines (the arithmetic before them), and the optional numba loops against the numpy path.
"""

from __future__ import annotations

import sys
from functools import cache
from pathlib import Path

import numpy as np
import pytest

from ucbplan.errors import UcbplanError
from ucbplan.lisa import _fused, numerics, waveform
from ucbplan.lisa.likelihood import model_for_target, source_from_target
from ucbplan.lisa.waveform import FourLineModel
from ucbplan.targets import load_target

ROOT = Path(__file__).resolve().parents[2]
INJECTION = ROOT / "catalogs" / "fiducial-injection.yaml"
GOLDEN = ROOT / "tests" / "golden" / "lisa_bands.npz"
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
def _models(reference: bool = False) -> dict[str, FourLineModel]:
    """The golden cases' models; ``reference``: on the injection's track (as build_model)."""
    target = load_target(INJECTION)
    truth = source_from_target(target)
    ref = {"fdot_ref": truth.fdot, "omega_dot_ref": truth.omega_dot} if reference else {}
    return {
        "ecc128": model_for_target(target, target.t_obs_s, 128, True, truth.f_gw, **ref),
        "ecc512": model_for_target(target, target.t_obs_s, 512, True, truth.f_gw, **ref),
        "circ64": model_for_target(target, target.t_obs_s, 64, False, truth.f_gw, **ref),
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


def _max_rel_diff(new: np.ndarray, old: np.ndarray) -> float:
    """Largest |new - old| relative to the largest |old| of its band and channel."""
    assert new.shape == old.shape
    return float(np.max(np.abs(new - old) / np.max(np.abs(old), axis=-1, keepdims=True)))


@pytest.mark.parametrize("case", ["ecc128", "ecc512", "circ64"])
def test_kernel_matches_the_previous_implementation(
    case: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Same Taylor tolerance (1e-10) and reference (f_c, 0, 0) as before: every bin within
    1e-12 of its band's largest |value| (measured: 1e-14, round-off)."""
    monkeypatch.setattr(waveform, "_TAYLOR_TOL", 1e-10)
    new = _models()[case].bands(**_params(case))
    assert _max_rel_diff(new, np.load(GOLDEN)[case]) <= 1e-12


@pytest.mark.parametrize("case", ["ecc128", "ecc512", "circ64"])
def test_reference_track_changes_only_the_truncation(case: str) -> None:
    """On the injection's track with the 1e-13 tolerance, the templates are the track-free ones
    to 3e-13 (the split of the link phase is exact; only the Taylor remainder differs) and the
    previous implementation's to 5e-12: its own 1e-10-tolerance remainder, measured 2.6e-12
    (with that tolerance the track-free kernel reproduces it to 1e-14, test above)."""
    p = _params(case)
    on_track = _models(True)[case].bands(**p)
    assert _max_rel_diff(on_track, _models()[case].bands(**p)) <= 3e-13
    assert _max_rel_diff(on_track, np.load(GOLDEN)[case]) <= 5e-12


def test_batch_equals_rows_one_at_a_time(monkeypatch: pytest.MonkeyPatch) -> None:
    """40 walkers (three internal blocks of 16) give each row's single-walker result."""
    monkeypatch.setattr(waveform, "_CHUNK", 16)
    model = _models()["ecc128"]
    p = _params("ecc128")
    rng = np.random.default_rng(5)
    idx = rng.integers(0, 4, 40)
    batch = {k: v[idx] * (1.0 + 1e-9 * rng.standard_normal(40)) for k, v in p.items()}
    out = model.bands(**batch)
    for i in (0, 17, 39):
        one = model.bands(**{k: v[i] for k, v in batch.items()})[0]
        np.testing.assert_allclose(out[i], one, rtol=0, atol=1e-13 * np.max(np.abs(one)))


def _random_walkers(n: int, seed: int, fddot: bool = False) -> dict[str, np.ndarray]:
    """Walkers across the prior around the fiducial: f within +-8 bins, fdot x (0.5 .. 1.5),
    wdot x (0.7 .. 1.3), any psi and phase, e up to 0.02 (with fddot: up to 1e-24 Hz/s^2)."""
    target = load_target(INJECTION)
    truth, t_obs = source_from_target(target), target.t_obs_s
    rng = np.random.default_rng(seed)
    base = {k: np.full(n, float(getattr(truth, k))) for k in KEYS}
    return base | {
        "f_gw": base["f_gw"] + rng.uniform(-8.0, 8.0, n) / t_obs,
        "fdot": base["fdot"] * rng.uniform(0.5, 1.5, n),
        "omega_dot": base["omega_dot"] * rng.uniform(0.7, 1.3, n),
        "psi": rng.uniform(0.0, np.pi, n),
        "phase": rng.uniform(0.0, 2.0 * np.pi, n),
        "eta": rng.uniform(-0.02, 0.02, n),
        "kappa": rng.uniform(-0.02, 0.02, n),
        "cos_inclination": rng.uniform(-1.0, 1.0, n),
        "fddot": rng.uniform(-1e-24, 1e-24, n) if fddot else np.zeros(n),
    }


def _direct_carrier(
    a: np.ndarray | None, b: np.ndarray, c: np.ndarray | None, m: int
) -> np.ndarray:
    """exp(i (a + b k + c k^2)) with one sine and cosine per sample (the previous kernel)."""
    k = np.arange(m)
    phase = b[:, None] * k
    if a is not None:
        phase += a[:, None]
    if c is not None:
        phase += c[:, None] * k * k
    return np.exp(1j * phase)


@pytest.mark.parametrize("m", [513, 100, 2049])
def test_quadratic_carrier_from_tables(m: int) -> None:
    """Block tables + doubling give exp(i (a + b k + c k^2)) to 1e-13 (|value| = 1) for phases
    of the size of the orbital carrier's (|c| m^2 ~ 40 rad, |b| m ~ 50 rad); any m (P > Q at
    m = 2049); a, c None: the apsidal rotation's plain outer product. Measured 1.3e-14, the
    round-off of the direct phases themselves."""
    rng = np.random.default_rng(3)
    a, b = rng.uniform(0, 2 * np.pi, 8), rng.uniform(-50, 50, 8) / m
    c = rng.uniform(-40, 40, 8) / m**2
    for args in ((a, b, c), (None, b, None)):
        got = numerics.quadratic_cis(*args, m)
        assert got.shape == (8, m)
        assert np.max(np.abs(got - _direct_carrier(*args, m))) <= 1e-13


@pytest.mark.parametrize("fddot", [False, True])
def test_kernel_matches_horner_with_per_sample_carriers(
    fddot: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Random walkers across the prior: the polynomial link sums and table carriers give the
    previous arithmetic (Horner's rule in beta(t), one sine and cosine per carrier sample) to
    1e-13 of each band's largest value (measured 2e-14: round-off of phases of ~50 rad)."""
    model = _models(True)["ecc512"]
    p = _random_walkers(40, 11, fddot)
    monkeypatch.delenv(_fused.ENV, raising=False)
    new = model.bands(**p)
    monkeypatch.setattr(waveform, "_POLY_ROWS", 0)
    monkeypatch.setattr(waveform, "quadratic_cis", _direct_carrier)
    assert _max_rel_diff(new, model.bands(**p)) <= 1e-13


@pytest.mark.slow  # compiles the numba loops (several seconds)
@pytest.mark.parametrize("case", ["ecc128", "ecc512", "circ64"])
def test_numba_path_matches_numpy_path(case: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """The optional compiled loops give the numpy path's waveforms to 1e-13 (measured 7e-16:
    the same products in another order), including batches over several blocks."""
    pytest.importorskip("numba")
    model = _models(True)[case]
    p = _random_walkers(70, 2)
    if case == "circ64":
        p |= {"eta": np.zeros(70), "kappa": np.zeros(70)}
    monkeypatch.delenv(_fused.ENV, raising=False)
    ref = model.bands(**p)
    monkeypatch.setenv(_fused.ENV, "1")
    assert _fused.kernels() is not None
    assert _fused.describe().startswith("numba")
    assert _max_rel_diff(model.bands(**p), ref) <= 1e-13


def test_numba_only_when_asked(monkeypatch: pytest.MonkeyPatch) -> None:
    """Off by default (every process on the same path: serial and parallel runs agree bit for
    bit); asked for without numba, one clear error saying what to install."""
    monkeypatch.delenv(_fused.ENV, raising=False)
    assert _fused.kernels() is None and _fused.describe() == "numpy"
    monkeypatch.setenv(_fused.ENV, "1")
    monkeypatch.setattr(_fused, "_kernels", None)
    monkeypatch.setitem(sys.modules, "numba", None)  # import numba → ImportError
    with pytest.raises(UcbplanError, match=r"pip install 'ucbplan\[fast\]'"):
        _fused.kernels()


if __name__ == "__main__":
    np.savez_compressed(GOLDEN, **_compute())
    print(f"wrote {GOLDEN}")
