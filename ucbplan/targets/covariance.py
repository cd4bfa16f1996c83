"""``lisa.covariance`` and ``timing.covariance`` of a target file → (names, covariance matrix).

Two forms are accepted: ``parameters`` + ``matrix`` (a full matrix), or ``sigma`` (marginal
standard deviations, each in its parameter's unit) with optional ``correlation`` coefficients.
The forms cannot be mixed and unknown keys are refused (a misspelt ``correlation`` would
otherwise drop the correlations silently). Either way the result must be finite, symmetric and
positive semi-definite.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from contextvars import ContextVar
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ucbplan.errors import shorten
from ucbplan.targets.fieldtypes import Field
from ucbplan.targets.schema import (
    COVARIANCE_PARAMETERS,
    TIMING_COVARIANCE_PARAMETERS,
    field,
    section_fields,
    timing_parameter_field,
)
from ucbplan.targets.values import (
    Ctx,
    check_keys,
    check_range,
    did_you_mean,
    parse_quantity,
    to_float,
)

FloatArray = NDArray[np.float64]
Named = tuple[tuple[str, ...], FloatArray]

_FORMS = "give either parameters + matrix or sigma (+ correlation)"


class _Section:
    """Where a covariance lives: its path, allowed parameter names and their unit fields."""

    def __init__(self, section: str) -> None:
        self.path = f"{section}.covariance"
        self.keys = tuple(f.name for f in section_fields(self.path))
        self.names = COVARIANCE_PARAMETERS if section == "lisa" else TIMING_COVARIANCE_PARAMETERS
        self.allowed = ", ".join(self.names)
        self.section = section

    def unit_field(self, name: str) -> Field:
        """The field a σ of parameter ``name`` is read with (its unit and example)."""
        if self.section == "lisa":
            return field(f"lisa.{name}")
        return timing_parameter_field(name)


_SECTIONS = {name: _Section(name) for name in ("lisa", "timing")}


def parse_covariance(ctx: Ctx, cov: Any, section: str = "lisa") -> Named:
    """Names and matrix of ``<section>.covariance`` (``((), 0×0)`` when absent).

    ``section`` is ``"lisa"`` (phase-model parameters and cos ι, amplitude, ψ) or
    ``"timing"`` (t0, period, pdot, pddot, eta, kappa, omega_dot; σ(t0) and σ(period) must carry
    their unit).

    Raises
    ------
    TargetFileError
        Unknown keys or names, mixed forms, repeated names or pairs, a matrix of the wrong
        shape, σ ≤ 0, ρ outside [−1, 1] or not a number, non-finite entries, or a matrix that
        is not symmetric positive semi-definite.
    """
    sec = _SECTIONS[section]
    if cov is None:
        return (), np.zeros((0, 0))
    if not isinstance(cov, Mapping):
        raise ctx.fail(sec.path, f"expected a mapping: {_FORMS}; got {shorten(cov)}")
    check_keys(ctx, sec.path, cov, sec.keys)
    full = {"parameters", "matrix"} & set(cov)
    marginal = {"sigma", "correlation"} & set(cov)
    if full and marginal:
        got = ", ".join(sorted(full | marginal, key=sec.keys.index))
        raise ctx.fail(sec.path, f"{_FORMS}, not both; got {got}")
    with np.errstate(all="ignore"), ctx.reading(sec.path, "a covariance"):
        if full:
            names, mat = _from_matrix(ctx, sec, cov)
        elif marginal:
            names, mat = _from_sigma(ctx, sec, cov)
        elif "exact" in cov:  # every parameter declared exact (timing.covariance.exact)
            return (), np.zeros((0, 0))
        else:
            raise ctx.fail(sec.path, f"{_FORMS}; got an empty mapping")
        if full or cov.get("correlation"):  # σ's alone: a finite σ² diagonal passes both
            _check_matrix(ctx, sec.path, mat)
    return names, mat


def exact_parameters(ctx: Ctx, cov: Any, given: tuple[str, ...]) -> tuple[str, ...]:
    """``timing.covariance.exact``: the timing parameters declared known exactly (``()`` when
    absent); none of them may also have a σ (``given``, the covariance's names).

    Raises
    ------
    TargetFileError
        Not a list, unknown or repeated names, or a name that also has a σ.
    """
    if not isinstance(cov, Mapping) or "exact" not in cov:
        return ()
    sec = _SECTIONS["timing"]
    where = f"{sec.path}.exact"
    raw = cov["exact"]
    if not isinstance(raw, list):
        f = field(where)
        raise ctx.fail(where, f"expected {f.what} like {f.example}, got {shorten(raw)}")
    names = _parameter_names(ctx, sec, where, raw)
    both = [n for n in names if n in given]
    if both:
        raise ctx.fail(
            where, f"{both[0]} has a σ in the covariance and is listed as exact; keep one"
        )
    return names


def _parameter_names(ctx: Ctx, sec: _Section, where: str, names: list[Any]) -> tuple[str, ...]:
    """Known, distinct parameter names (each a string)."""
    for n in names:
        if not isinstance(n, str) or n not in sec.names:
            hint = did_you_mean(n, sec.names)
            raise ctx.fail(
                where, f"unknown parameter {shorten(n, 60)}; {hint}expected some of {sec.allowed}"
            )
    if len(set(names)) != len(names):
        raise ctx.fail(where, "parameter names repeat")
    return tuple(names)


def _from_matrix(ctx: Ctx, sec: _Section, cov: Mapping[str, Any]) -> Named:
    """The ``parameters`` + ``matrix`` form."""
    where = f"{sec.path}.parameters"
    for key in ("parameters", "matrix"):
        if key not in cov:
            raise ctx.fail(f"{sec.path}.{key}", f"missing; {_FORMS}")
    names = cov["parameters"]
    if not isinstance(names, list) or not names:
        raise ctx.fail(
            where,
            f"expected a list of parameter names like {field(where).example}, got {shorten(names)}",
        )
    names_t = _parameter_names(ctx, sec, where, names)
    size = len(names_t)
    rows = cov["matrix"]
    where = f"{sec.path}.matrix"
    if not (isinstance(rows, list) and all(isinstance(r, list) for r in rows)):
        raise ctx.fail(where, f"expected a {size}×{size} list of lists of numbers")
    if len(rows) != size or any(len(r) != size for r in rows):
        shape = f"{len(rows)} rows of {sorted({len(r) for r in rows})} entries"
        raise ctx.fail(where, f"expected a {size}×{size} matrix, got {shape}")
    try:
        mat = np.array([[to_float(x) for x in row] for row in rows], dtype=np.float64)
    except ValueError:
        bad = next(x for row in rows for x in row if not _is_number(x))
        raise ctx.fail(where, f"expected numbers, got {shorten(bad)}") from None
    return names_t, mat.reshape(size, size)


def _is_number(x: Any) -> bool:
    try:
        to_float(x)
    except ValueError:
        return False
    return True


def _from_sigma(ctx: Ctx, sec: _Section, cov: Mapping[str, Any]) -> Named:
    """The ``sigma`` (+ ``correlation``) form: Σ = ρ ∘ σσᵀ."""
    where = f"{sec.path}.sigma"
    if "sigma" not in cov:
        raise ctx.fail(where, "missing; correlation needs the σ of its parameters")
    sig = cov["sigma"]
    if not isinstance(sig, Mapping) or not sig:
        raise ctx.fail(
            where,
            f"expected a mapping parameter: sigma like {field(where).example}, got {shorten(sig)}",
        )
    for n in sig:
        if not isinstance(n, str) or n not in sec.names:
            hint = did_you_mean(n, sec.names)
            raise ctx.fail(
                f"{where}.{ctx.key(n)}", f"unknown parameter; {hint}expected some of {sec.allowed}"
            )
    names = tuple(sig)
    listed = [_sigma(ctx, sec, n, sig[n]) for n in names]
    if cov.get("correlation", ()) is None:  # σ's alone: ρ = I, Σ = diag(σ²)
        return names, _diagonal(ctx, where, listed)
    sigmas = np.array(listed)
    corr = _correlation_matrix(ctx, sec, names, cov.get("correlation"))
    out = corr * (sigmas[:, None] * sigmas)  # ρ ∘ σσᵀ, σσᵀ as np.outer forms it
    if not np.isfinite(out).all():
        raise ctx.fail(where, "σ² overflows a float; check the units of sigma")
    return names, out


def _diagonal(ctx: Ctx, where: str, sigmas: list[float]) -> FloatArray:
    """I ∘ σσᵀ without the products off the diagonal: each σ is finite and > 0 (read and range
    checked), so σᵢσⱼ ≤ max(σᵢ², σⱼ²) and those products are finite when the squares are, and
    0 × a finite product is the 0.0 the identity gives."""
    squares = [s * s for s in sigmas]
    if not all(map(math.isfinite, squares)):
        raise ctx.fail(where, "σ² overflows a float; check the units of sigma")
    return np.diag(squares)


def _sigma(ctx: Ctx, sec: _Section, name: str, raw: Any) -> float:
    """One marginal σ, read in the unit of parameter ``name``."""
    where = f"{sec.path}.sigma.{name}"
    s = parse_quantity(ctx, sec.unit_field(name), raw, where=where)
    check_range(ctx, field(f"{sec.path}.sigma"), s, raw, where=where)
    return s


def _correlation_matrix(ctx: Ctx, sec: _Section, names: tuple[str, ...], raw: Any) -> FloatArray:
    """Correlation matrix of ``names``: identity plus the given coefficients."""
    corr = np.eye(len(names))
    seen: set[frozenset[str]] = set()
    f = field(f"{sec.path}.correlation")
    for (a, b), rho_raw in _iter_correlations(ctx, sec, raw):
        where = f"{sec.path}.correlation.{ctx.key(a)},{ctx.key(b)}"
        if a not in names or b not in names or a == b:
            raise ctx.fail(
                where, f"names must be two different parameters of sigma ({', '.join(names)})"
            )
        if frozenset((a, b)) in seen:
            raise ctx.fail(where, "pair given twice; keep one coefficient per pair")
        seen.add(frozenset((a, b)))
        try:
            rho = to_float(rho_raw)
        except ValueError:
            raise ctx.fail(
                where, f"expected a number ρ in [-1, 1] like -0.7, got {shorten(rho_raw)}"
            ) from None
        check_range(ctx, f, rho, rho_raw, where=where)  # NaN lies outside every range
        i, j = names.index(a), names.index(b)
        corr[i, j] = corr[j, i] = rho
    return corr


def _iter_correlations(ctx: Ctx, sec: _Section, corr: Any) -> list[tuple[tuple[str, str], Any]]:
    """``((a, b), ρ)`` pairs from the mapping form ``{"a,b": ρ}`` or the list form."""
    where = f"{sec.path}.correlation"
    example = field(where).example
    if corr is None:
        return []
    if isinstance(corr, Mapping):
        return [_pair_from_key(ctx, where, key, val) for key, val in corr.items()]
    if isinstance(corr, list):
        out: list[tuple[tuple[str, str], Any]] = []
        for item in corr:
            if not (
                isinstance(item, list)
                and len(item) == 3
                and isinstance(item[0], str)
                and isinstance(item[1], str)
            ):
                raise ctx.fail(
                    where, f"expected entries like [phase, fdot, -0.7], got {shorten(item)}"
                )
            out.append(((item[0], item[1]), item[2]))
        return out
    raise ctx.fail(where, f"expected {example}, got {shorten(corr)}")


def _pair_from_key(ctx: Ctx, where: str, key: Any, val: Any) -> tuple[tuple[str, str], Any]:
    """``"phase,fdot"`` (or ``"(phase fdot)"`` …) → ``(("phase", "fdot"), val)``."""
    parts = (
        [s for s in re.split(r"[,\s]+", key.strip("()[] ")) if s]
        if isinstance(key, str) and len(key) <= 100
        else []
    )
    if len(parts) != 2:
        raise ctx.fail(
            f"{where}.{ctx.key(key)}",
            'expected a key naming two parameters, like "phase,fdot": -0.7',
        )
    return (parts[0], parts[1]), val


def _check_symmetric(ctx: Ctx, path: str, mat: FloatArray) -> None:
    """Finite entries, non-negative variances, symmetric to 1e-9 of σ_i σ_j."""
    if not np.all(np.isfinite(mat)):
        raise ctx.fail(path, "contains non-finite values; give finite numbers")
    if np.any(np.diag(mat) < 0):
        raise ctx.fail(path, "negative variance on the diagonal (a variance is σ² ≥ 0)")
    scale = np.sqrt(np.abs(np.diag(mat)))
    tol = 1e-9 * np.outer(scale, scale) + 1e-300
    if np.any(np.abs(mat - mat.T) > tol):
        raise ctx.fail(path, "matrix is not symmetric; check the off-diagonal entries")


def _check_psd(ctx: Ctx, path: str, mat: FloatArray) -> None:
    """Positive semi-definite: the correlation matrix has no eigenvalue below −1e-9."""
    scale = np.sqrt(np.abs(np.diag(mat)))
    safe = np.where(scale > 0, scale, 1.0)
    corr = mat / np.outer(safe, safe)
    try:
        eig = np.linalg.eigvalsh(0.5 * (corr + corr.T))
    except np.linalg.LinAlgError:
        raise ctx.fail(path, "matrix cannot be decomposed; check its entries") from None
    if not np.all(np.isfinite(eig)):
        raise ctx.fail(path, "matrix cannot be decomposed; check its entries")
    if eig.size and eig.min() < -1e-9:
        raise ctx.fail(
            path,
            f"matrix is not positive semi-definite (smallest correlation eigenvalue "
            f"{eig.min():.3g}); export the full posterior covariance again",
        )


#: Inside :func:`batched_checks`: the matrices whose checks wait for the batch, with the
#: context and field path their message would name.
_PENDING: ContextVar[list[tuple[Ctx, str, FloatArray]] | None] = ContextVar(
    "ucbplan_pending_covariances", default=None
)


def _check_matrix(ctx: Ctx, path: str, mat: FloatArray) -> None:
    """Finite, symmetric and positive semi-definite, now or (inside :func:`batched_checks`)
    with the batch."""
    pending = _PENDING.get()
    if pending is None:
        _check_symmetric(ctx, path, mat)
        _check_psd(ctx, path, mat)
    else:
        pending.append((ctx, path, mat))


@contextmanager
def batched_checks() -> Iterator[None]:
    """Within: the covariance matrices read are checked (finite, symmetric, positive
    semi-definite) in batches, one ``eigvalsh`` per matrix size, when the scope ends or an
    error leaves it; the first matrix (in reading order) that fails raises its own message,
    before the error that left the scope, as checking each in turn would.

    Raises
    ------
    TargetFileError
        As :func:`parse_covariance`, for the first matrix that fails.
    """
    token = _PENDING.set([])
    try:
        yield
    except Exception:
        _check_pending()
        raise
    else:
        _check_pending()
    finally:
        _PENDING.reset(token)


def _check_pending() -> None:
    """Check the waiting matrices: a batch passes each plainly good one; any other is checked
    alone, in reading order, so the first bad one raises its message."""
    pending = _PENDING.get() or []
    _PENDING.set([])
    by_size: dict[int, list[int]] = {}
    for k, (_, _, mat) in enumerate(pending):
        by_size.setdefault(mat.shape[0], []).append(k)
    good = np.zeros(len(pending), dtype=bool)
    for idx in by_size.values():
        good[idx] = _plainly_good(np.stack([pending[k][2] for k in idx]))
    for bad in np.flatnonzero(~good):
        ctx, path, mat = pending[bad]
        with np.errstate(all="ignore"), ctx.reading(path, "a covariance"):
            _check_symmetric(ctx, path, mat)
            _check_psd(ctx, path, mat)


def _plainly_good(mats: FloatArray) -> NDArray[np.bool_]:
    """Which of the stacked matrices (n, k, k) pass :func:`_check_symmetric` and
    :func:`_check_psd` (False: check it alone), the same tests on the whole stack."""
    with np.errstate(all="ignore"):
        diag = np.diagonal(mats, axis1=1, axis2=2)
        scale = np.sqrt(np.abs(diag))
        outer = scale[:, :, None] * scale[:, None, :]
        ok = np.isfinite(mats).all(axis=(1, 2)) & (diag >= 0).all(axis=1)
        ok &= ~(np.abs(mats - mats.transpose(0, 2, 1)) > 1e-9 * outer + 1e-300).any(axis=(1, 2))
        safe = np.where(scale > 0, scale, 1.0)
        corr = mats / (safe[:, :, None] * safe[:, None, :])
        ok &= np.isfinite(corr).all(axis=(1, 2))
        corr[~ok] = np.eye(mats.shape[1])  # refused already; not to spoil the others' eigvalsh
        try:
            eig = np.linalg.eigvalsh(0.5 * (corr + corr.transpose(0, 2, 1)))
        except np.linalg.LinAlgError:
            return np.zeros(len(mats), dtype=bool)
        if eig.shape[1] == 0:
            return ok
        # a margin below the limit: near it, the matrix is checked alone (its own eigvalsh)
        return ok & np.isfinite(eig).all(axis=1) & (eig.min(axis=1) >= -0.5e-9)
