"""Covariance checks batched across many target files (issue 34): the same targets, the same
first error with the same message as checking each file in turn."""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st
from support.targets import BASE

from ucbplan.errors import TargetFileError
from ucbplan.targets import load_target, load_target_documents, load_target_files, target_from_dict
from ucbplan.targets.covariance import _check_psd, _check_symmetric, _plainly_good
from ucbplan.targets.values import Ctx

#: A LISA target with correlated σ's (its covariance goes through the batched checks).
GOOD = copy.deepcopy(BASE)
GOOD["lisa"]["covariance"] = {
    "sigma": {"phase": 0.02, "f_gw": "7.7e-12 Hz", "fdot": "4e-19 Hz / s"},
    "correlation": {"phase,fdot": -0.7},
}
#: Full matrices each check refuses: not PSD, not symmetric, non-finite, a negative variance.
BAD_MATRICES = [
    [[1.0, 2.0], [2.0, 1.0]],
    [[1.0, 0.5], [0.1, 1.0]],
    [[1.0, float("inf")], [float("inf"), 1.0]],
    [[-1.0, 0.0], [0.0, 1.0]],
]


def _doc(name: str, matrix: list[list[float]] | None = None) -> dict:
    doc = copy.deepcopy(GOOD)
    doc["name"] = name
    if matrix is not None:
        doc["lisa"]["covariance"] = {"parameters": ["phase", "f_gw"], "matrix": matrix}
    return doc


def _write(folder: Path, name: str, *docs: dict) -> Path:
    path = folder / f"{name}.yaml"
    path.write_text(yaml.safe_dump_all(docs), encoding="utf-8")
    return path


def _error(call) -> str:
    with pytest.raises(TargetFileError) as exc:
        call()
    return str(exc.value)


def test_many_files_load_as_each_alone(tmp_path: Path) -> None:
    paths = [_write(tmp_path, f"t{k}", _doc(f"T{k}")) for k in range(5)]
    many = load_target_files(paths)
    for path, t in zip(paths, many, strict=True):
        alone = load_target(path)
        assert t.name == alone.name and np.array_equal(t.cov_matrix, alone.cov_matrix)


@pytest.mark.parametrize("matrix", BAD_MATRICES)
def test_a_bad_matrix_among_many_raises_its_own_message(tmp_path: Path, matrix: list) -> None:
    good = [_write(tmp_path, f"g{k}", _doc(f"G{k}")) for k in range(3)]
    bad = _write(tmp_path, "bad", _doc("Bad", matrix))
    alone = _error(lambda: load_target(bad))
    assert _error(lambda: load_target_files([*good[:2], bad, good[2]])) == alone


def test_the_first_failing_file_is_named(tmp_path: Path) -> None:
    """A bad matrix before another error wins, and after it loses, as in turn."""
    bad = _write(tmp_path, "bad", _doc("Bad", BAD_MATRICES[0]))
    broken_doc = _doc("Broken")
    broken_doc["sky"]["dec"] = "+95d"
    broken = _write(tmp_path, "broken", broken_doc)
    assert _error(lambda: load_target_files([bad, broken])) == _error(lambda: load_target(bad))
    assert _error(lambda: load_target_files([broken, bad])) == _error(lambda: load_target(broken))


def test_a_bad_matrix_wins_over_a_later_field_of_its_own_file(tmp_path: Path) -> None:
    doc = _doc("Both", BAD_MATRICES[0])
    doc["spectroscopy"] = {"lines": "SB3"}
    both = _write(tmp_path, "both", doc)
    message = _error(lambda: load_target_files([both]))
    assert "positive semi-definite" in message and message == _error(lambda: load_target(both))


def test_a_catalog_document_is_named(tmp_path: Path) -> None:
    catalog = _write(tmp_path, "cat", _doc("A"), _doc("B", BAD_MATRICES[0]))
    message = _error(lambda: load_target_files([catalog]))
    assert "(document 2)" in message
    assert message == _error(lambda: load_target_documents(catalog))


def _checked_alone(mat: np.ndarray) -> bool:
    try:
        with np.errstate(all="ignore"):
            _check_symmetric(Ctx(None), "m", mat)
            _check_psd(Ctx(None), "m", mat)
    except TargetFileError:
        return False
    return True


_ENTRY = st.one_of(
    st.floats(-2.0, 2.0), st.sampled_from([0.0, 1e-300, 1e300, float("nan"), float("inf")])
)


@settings(max_examples=300, deadline=None, derandomize=True)
@given(st.integers(1, 4).flatmap(lambda k: st.lists(st.lists(_ENTRY, min_size=k, max_size=k),
                                                     min_size=k, max_size=k)))  # fmt: skip
def test_the_batch_passes_only_what_each_check_passes(rows: list[list[float]]) -> None:
    """Random matrices, some symmetrised: every one the batch calls good passes alone."""
    mat = np.array(rows)
    with np.errstate(all="ignore"):
        product = mat @ mat.T
    for m in (mat, 0.5 * (mat + mat.T), product):
        good = _plainly_good(np.stack([m, np.eye(len(m))]))
        assert good[1]
        if good[0]:
            assert _checked_alone(m)


@settings(max_examples=200, deadline=None)
@given(
    st.lists(
        st.floats(min_value=5e-324, max_value=1.7e308, allow_nan=False, allow_infinity=False),
        min_size=1,
        max_size=4,
    )
)
def test_sigmas_alone_give_the_matrix_rho_sigma_sigma_gives(sigmas: list[float]) -> None:
    """σ's without correlations take diag(σ²): bit for bit ρ ∘ σσᵀ with ρ = I, and refused
    (the same message) exactly when that has a non-finite entry."""
    names = ("phase", "f_gw", "fdot", "fddot")[: len(sigmas)]
    doc = copy.deepcopy(BASE)
    doc["lisa"]["covariance"] = {"sigma": {n: repr(s) for n, s in zip(names, sigmas, strict=True)}}
    s = np.array(sigmas)
    with np.errstate(all="ignore"):
        want = np.eye(len(s)) * (s[:, None] * s)  # the ρ ∘ σσᵀ of the correlated form
    try:
        got = target_from_dict(doc)
    except TargetFileError as exc:
        assert not np.isfinite(want).all() and "σ² overflows a float" in str(exc)
        return
    assert got.cov_names == names
    assert got.cov_matrix.tobytes() == want.tobytes() and got.cov_matrix.shape == want.shape
