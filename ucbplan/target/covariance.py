"""``lisa.covariance`` of a target file → (parameter names, covariance matrix).

Two forms are accepted: ``parameters`` + ``matrix`` (a full matrix), or ``sigma`` (marginal
standard deviations, each in its parameter's unit) with optional ``correlation`` coefficients.
Either way the result must be symmetric positive semi-definite.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ucbplan.target.schema import COVARIANCE_PARAMETERS, field
from ucbplan.target.values import Ctx, check_range, parse_quantity, to_float

__all__ = ["parse_covariance"]

FloatArray = NDArray[np.float64]
Named = tuple[tuple[str, ...], FloatArray]

_PATH = "lisa.covariance"
_ALLOWED = ", ".join(COVARIANCE_PARAMETERS)


def parse_covariance(ctx: Ctx, cov: Any) -> Named:
    """Names and matrix of ``lisa.covariance`` (``((), 0×0)`` when absent).

    Raises
    ------
    TargetFileError
        Unknown or repeated names, a matrix of the wrong shape, σ < 0, |ρ| > 1, or a matrix
        that is not symmetric positive semi-definite.
    """
    if cov is None:
        return (), np.zeros((0, 0))
    if not isinstance(cov, Mapping):
        raise ctx.fail(_PATH, "expected a mapping with parameters+matrix or sigma")
    if "matrix" in cov:
        names, mat = _from_matrix(ctx, cov)
    elif "sigma" in cov:
        names, mat = _from_sigma(ctx, cov)
    else:
        raise ctx.fail(_PATH, "expected either 'parameters'+'matrix' or 'sigma' (+ 'correlation')")
    _check_symmetric(ctx, mat)
    _check_psd(ctx, mat)
    return names, mat


def _from_matrix(ctx: Ctx, cov: Mapping[str, Any]) -> Named:
    """The ``parameters`` + ``matrix`` form."""
    where = f"{_PATH}.parameters"
    names = cov.get("parameters")
    if not isinstance(names, list) or not names:
        raise ctx.fail(where, "expected a list of parameter names")
    names_t = tuple(str(n) for n in names)
    for n in names_t:
        if n not in COVARIANCE_PARAMETERS:
            raise ctx.fail(where, f"unknown parameter {n!r}; expected some of {_ALLOWED}")
    if len(set(names_t)) != len(names_t):
        raise ctx.fail(where, "parameter names repeat")
    try:
        mat = np.array(
            [[to_float(x) for x in row] for row in cov["matrix"]], dtype=np.float64, ndmin=2
        )
    except (TypeError, ValueError):
        raise ctx.fail(f"{_PATH}.matrix", "expected a square list of lists of numbers") from None
    size = len(names_t)
    if mat.shape != (size, size):
        raise ctx.fail(f"{_PATH}.matrix", f"expected a {size}×{size} matrix, got shape {mat.shape}")
    return names_t, mat


def _from_sigma(ctx: Ctx, cov: Mapping[str, Any]) -> Named:
    """The ``sigma`` (+ ``correlation``) form: Σ = ρ ∘ σσᵀ."""
    sig = cov["sigma"]
    if not isinstance(sig, Mapping) or not sig:
        raise ctx.fail(f"{_PATH}.sigma", "expected a mapping parameter: sigma")
    names = tuple(str(n) for n in sig)
    sigmas = np.array([_sigma(ctx, n, sig[n]) for n in names])
    corr = _correlation_matrix(ctx, names, cov.get("correlation"))
    return names, corr * np.outer(sigmas, sigmas)


def _sigma(ctx: Ctx, name: str, raw: Any) -> float:
    """One marginal σ, read in the unit of parameter ``name``."""
    where = f"{_PATH}.sigma.{name}"
    if name not in COVARIANCE_PARAMETERS:
        raise ctx.fail(where, f"unknown parameter; expected some of {_ALLOWED}")
    s = parse_quantity(ctx, field(f"lisa.{name}"), raw, where=where)
    check_range(ctx, field(f"{_PATH}.sigma"), s, raw, where=where)
    return s


def _correlation_matrix(ctx: Ctx, names: tuple[str, ...], raw: Any) -> FloatArray:
    """Correlation matrix of ``names``: identity plus the given coefficients."""
    corr = np.eye(len(names))
    for (a, b), rho_raw in _iter_correlations(ctx, raw):
        where = f"{_PATH}.correlation.{a},{b}"
        if a not in names or b not in names or a == b:
            raise ctx.fail(
                where, f"names must be two different parameters of sigma ({', '.join(names)})"
            )
        rho = to_float(rho_raw)  # NaN lies outside every range
        check_range(ctx, field(f"{_PATH}.correlation"), rho, rho_raw, where=where)
        i, j = names.index(a), names.index(b)
        corr[i, j] = corr[j, i] = rho
    return corr


def _iter_correlations(ctx: Ctx, corr: Any) -> list[tuple[tuple[str, str], Any]]:
    """``((a, b), ρ)`` pairs from the mapping form ``{"a,b": ρ}`` or the list form."""
    if corr is None:
        return []
    if isinstance(corr, Mapping):
        return [_pair_from_key(ctx, key, val) for key, val in corr.items()]
    if isinstance(corr, list):
        out: list[tuple[tuple[str, str], Any]] = []
        for item in corr:
            if not (isinstance(item, list) and len(item) == 3):
                raise ctx.fail(f"{_PATH}.correlation", "expected entries like [phase, fdot, -0.7]")
            out.append(((str(item[0]), str(item[1])), item[2]))
        return out
    raise ctx.fail(f"{_PATH}.correlation", 'expected a mapping like {"phase,fdot": -0.7}')


def _pair_from_key(ctx: Ctx, key: Any, val: Any) -> tuple[tuple[str, str], Any]:
    """``"phase,fdot"`` (or ``"(phase fdot)"`` …) → ``(("phase", "fdot"), val)``."""
    parts = [s for s in re.split(r"[,\s]+", str(key).strip("()[] ")) if s]
    if len(parts) != 2:
        raise ctx.fail(
            f"{_PATH}.correlation.{key}",
            'expected a key naming two parameters, like "phase,fdot": -0.7',
        )
    return (parts[0], parts[1]), val


def _check_symmetric(ctx: Ctx, mat: FloatArray) -> None:
    """Finite entries, non-negative variances, symmetric to 1e-9 of σ_i σ_j."""
    if not np.all(np.isfinite(mat)):
        raise ctx.fail(_PATH, "contains non-finite values")
    if np.any(np.diag(mat) < 0):
        raise ctx.fail(_PATH, "negative variance on the diagonal")
    scale = np.sqrt(np.abs(np.diag(mat)))
    tol = 1e-9 * np.outer(scale, scale) + 1e-300
    if np.any(np.abs(mat - mat.T) > tol):
        raise ctx.fail(_PATH, "matrix is not symmetric; check the off-diagonal entries")


def _check_psd(ctx: Ctx, mat: FloatArray) -> None:
    """Positive semi-definite: the correlation matrix has no eigenvalue below −1e-9."""
    scale = np.sqrt(np.abs(np.diag(mat)))
    safe = np.where(scale > 0, scale, 1.0)
    corr = mat / np.outer(safe, safe)
    eig = np.linalg.eigvalsh(0.5 * (corr + corr.T))
    if eig.size and eig.min() < -1e-9:
        raise ctx.fail(
            _PATH,
            f"matrix is not positive semi-definite (smallest correlation eigenvalue "
            f"{eig.min():.3g}); export the full posterior covariance again",
        )
