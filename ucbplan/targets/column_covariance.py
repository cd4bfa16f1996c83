"""``lisa.covariance`` of many target documents read at once (:mod:`~ucbplan.targets.columnwise`).

The documents with σ's are grouped by their σ's names (in order) and each σ read as a column;
correlations and full matrices are read by :mod:`~ucbplan.targets.covariance`'s own functions,
and the matrices that need it are checked (finite, symmetric, positive semi-definite) in one
batch per size, the batch ``batched_checks`` runs: a matrix not plainly good fails here, and its
document goes the one-file way, which checks it alone and gives the message.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from ucbplan.errors import TargetFileError
from ucbplan.targets.column_values import Column, in_range, quantity
from ucbplan.targets.covariance import (
    _SECTIONS,
    _correlation_matrix,
    _from_matrix,
    _plainly_good,
)
from ucbplan.targets.schema import COVARIANCE_PARAMETERS, field
from ucbplan.targets.values import MALFORMED, Ctx

FloatArray = NDArray[np.float64]

_SIGMA = field("lisa.covariance.sigma")
_NAMES = frozenset(COVARIANCE_PARAMETERS)
_LISA = _SECTIONS["lisa"]
#: The covariance forms the columns read (keys of ``lisa.covariance``).
_MARGINAL = frozenset(("sigma", "correlation"))
_FULL = frozenset(("parameters", "matrix"))
#: The context messages of the one-file readers are written in (never shown: a failure here
#: sends the document the one-file way).
_CTX = Ctx(None)


def plain_covariance(cov: Any) -> bool:
    """No covariance; σ's of known parameters (with correlations); or a full matrix."""
    if cov is None:
        return True
    if type(cov) is not dict:
        return False
    if cov.keys() == _FULL:
        return True
    sig = cov.get("sigma")
    return cov.keys() <= _MARGINAL and type(sig) is dict and bool(sig) and sig.keys() <= _NAMES


def covariances(covs: list[Any]) -> Column:
    """Names and matrix of each ``lisa.covariance`` (None: absent), as ``parse_covariance``
    reads and checks them."""
    values: list[Any] = [None] * len(covs)
    ok = np.ones(len(covs), dtype=bool)
    checked: list[int] = []  # the matrices parse_covariance checks
    groups: dict[tuple[str, ...], list[int]] = {}
    for k, cov in enumerate(covs):
        if cov is None:
            values[k] = ((), np.zeros((0, 0)))
        elif "sigma" in cov:
            groups.setdefault(tuple(cov["sigma"]), []).append(k)
        else:
            values[k] = _full(cov)
            checked.append(k)
    for names, idx in groups.items():
        sigmas, good = _sigmas([covs[k]["sigma"] for k in idx], names)
        diagonal = _diagonals(sigmas)
        for row, k in enumerate(idx):
            if not good[row]:
                continue
            if covs[k].get("correlation") is None:  # I ∘ σσᵀ: the σ² on the diagonal
                values[k] = None if diagonal[row] is None else (names, diagonal[row])
            else:
                values[k] = _correlated(covs[k]["correlation"], names, sigmas[row])
                if covs[k]["correlation"]:  # {} or [] is I: parse_covariance checks no more
                    checked.append(k)
    ok &= [v is not None for v in values]
    _check(values, ok, checked)
    return values, ok


def _sigmas(sigmas: list[dict[str, Any]], names: tuple[str, ...]) -> tuple[FloatArray, Any]:
    """The σ's of documents that give ``names`` (in that order), (n, len(names)), and which
    pass: each read in its parameter's unit, finite and > 0."""
    out = np.zeros((len(sigmas), len(names)))
    good = np.ones(len(sigmas), dtype=bool)
    for j, name in enumerate(names):
        own = field(f"lisa.{name}")  # a σ is read in its parameter's unit
        sig = [quantity(s[name], str(own.unit), own.unit_required) for s in sigmas]
        good &= in_range(sig, [True] * len(sig), _SIGMA)
        out[:, j] = [np.nan if v is None else v for v in sig]
    return out, good


def _diagonals(sigmas: FloatArray) -> list[FloatArray | None]:
    """diag(σ²) of each row of σ's, as ``_from_sigma`` builds it without correlations (None:
    σ² overflows): I ∘ σσᵀ, whose products off the diagonal are 0 where the squares are
    finite."""
    n, size = sigmas.shape
    with np.errstate(all="ignore"):
        squares = sigmas * sigmas
    mats = np.zeros((n, size, size))
    mats[:, np.arange(size), np.arange(size)] = squares
    finite = np.isfinite(squares).sum(axis=1) == size
    return [mats[k].copy() if finite[k] else None for k in range(n)]


def _correlated(raw: Any, names: tuple[str, ...], sig: FloatArray) -> Any:
    """Σ = ρ ∘ σσᵀ as ``_from_sigma`` builds it, or None where it refuses it."""
    with np.errstate(all="ignore"):
        try:
            corr = _correlation_matrix(_CTX, _LISA, names, raw)
        except (TargetFileError, *MALFORMED):
            return None
        out = corr * (sig[:, None] * sig)
    return (names, out) if np.isfinite(out).all() else None


def _full(cov: dict[str, Any]) -> Any:
    """``parameters`` + ``matrix`` as ``_from_matrix`` reads them, or None where it refuses."""
    try:
        with np.errstate(all="ignore"):
            return _from_matrix(_CTX, _LISA, cov)
    except (TargetFileError, *MALFORMED):
        return None


def _check(values: list[Any], ok: Any, checked: list[int]) -> None:
    """Fail each matrix of ``checked`` (still passing) that is not plainly good, one batch
    per size."""
    by_size: dict[int, list[int]] = {}
    for k in checked:
        if ok[k]:
            by_size.setdefault(values[k][1].shape[0], []).append(k)
    for idx in by_size.values():
        ok[idx] &= _plainly_good(np.stack([values[k][1] for k in idx]))
