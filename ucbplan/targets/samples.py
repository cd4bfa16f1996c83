"""Posterior-samples files: the one reader (:func:`read_samples_file`) and target-aware loading.

A samples file is an ECSV table with one column per parameter, named like
:data:`~ucbplan.core.params.PARAM_NAMES` (plus ``cos_inclination``, ``amplitude``, ``psi``), bare
SI values, referenced to the same epoch as the target file's ``t_ref`` as written.
"""

from __future__ import annotations

import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ucbplan.core.params import PARAM_NAMES, shift_columns
from ucbplan.errors import InputFileError, TargetFileError
from ucbplan.targets.model import Target
from ucbplan.targets.schema import COVARIANCE_PARAMETERS

FloatArray = NDArray[np.float64]


def read_samples_file(path: Path | str) -> dict[str, FloatArray]:
    """Numeric columns of a posterior-samples ECSV, as float64 arrays keyed by column name.

    Fast path: the ECSV data block parsed with ``numpy.loadtxt`` (10⁵ rows in ~0.1 s); anything
    it cannot parse falls back to astropy's reader (ECSV for ``.ecsv`` files, else astropy
    guesses the format), keeping the numeric columns.

    Parameters
    ----------
    path : Path or str
        The samples file.

    Returns
    -------
    dict of str → ndarray
        Columns in file order, all of the same length ≥ 1.

    Raises
    ------
    InputFileError
        Unreadable file or no rows.
    """
    path = Path(path)
    try:
        cols = _read_data_block(path)
    except (OSError, ValueError, IndexError):
        cols = _read_with_astropy(path)
    if not cols or len(next(iter(cols.values()))) == 0:
        raise InputFileError(f"{path}: posterior samples file has no rows")
    return cols


def _read_data_block(path: Path) -> dict[str, FloatArray]:
    """Columns of an all-numeric ECSV (header line, then rows) with ``numpy.loadtxt``.

    Raises ``OSError``/``ValueError``/``IndexError`` for anything it cannot parse.
    """
    lines = path.read_text(encoding="utf-8").splitlines()
    delim = _ecsv_delimiter(lines)
    split = None if delim == " " else delim
    body = [ln for ln in lines if ln.strip() and not ln.startswith("#")]
    names = body[0].split(split)
    with warnings.catch_warnings():
        # a header without rows: reported as "no rows" by the caller, not as a numpy warning
        warnings.filterwarnings("ignore", "loadtxt: input contained no data", UserWarning)
        data = np.loadtxt(body[1:], delimiter=split, ndmin=2)
    return {nm.strip().strip('"'): data[:, k] for k, nm in enumerate(names)}


def _ecsv_delimiter(lines: list[str]) -> str:
    """The ``delimiter`` of the ECSV header (space if not given)."""
    delim = " "
    for ln in lines:
        if ln.startswith("# delimiter:"):
            delim = ln.split(":", 1)[1].strip().strip("'\"") or " "
    return delim


def _read_with_astropy(path: Path) -> dict[str, FloatArray]:
    """Numeric columns read by astropy's table reader."""
    from astropy.table import Table

    try:
        tab = Table.read(path, format="ascii.ecsv" if path.suffix == ".ecsv" else None)
    except Exception as exc:  # astropy raises many types for unreadable tables
        raise InputFileError(f"{path}: cannot read posterior samples ({exc})") from exc
    return {
        nm: np.asarray(tab[nm], float)
        for nm in tab.colnames
        if np.issubdtype(np.asarray(tab[nm]).dtype, np.number)
    }


def load_samples(t: Target) -> dict[str, FloatArray]:
    """Posterior samples referenced to ``t.t_ref`` (the midpoint), columns named like parameters.

    The samples file must be referenced to the same epoch as the target file's ``t_ref`` as
    written (``t_ref_is``); samples of a start-referenced file are shifted to the midpoint.
    Columns that are not parameters (:data:`~ucbplan.targets.schema.COVARIANCE_PARAMETERS`) are
    dropped.

    Raises
    ------
    TargetFileError
        If the file cannot be read, has no rows, lacks parameter columns or has a NaN or
        infinite value in one.
    """
    if t.samples is None:
        return {}
    try:
        table = read_samples_file(t.samples)
    except InputFileError as exc:
        raise TargetFileError(str(exc)) from exc
    cols = {n: v for n, v in table.items() if n in COVARIANCE_PARAMETERS}
    if not cols:
        raise TargetFileError(
            f"{t.samples.name}: no parameter columns; expected columns named "
            f"{', '.join(PARAM_NAMES)}"
        )
    for name, values in cols.items():
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            raise TargetFileError(
                f"{t.samples.name}: column {name}: data row {int(bad[0]) + 1} is "
                f"{float(values[bad[0]])!r} ({bad.size} such rows); posterior samples must be "
                "finite numbers: drop those rows"
            )
    if t.ref_shift_s:
        base = {n: getattr(t.params, n) for n in PARAM_NAMES}
        cols = shift_columns(cols, t.ref_shift_s, defaults=base)
    return cols


def samples_covariance(t: Target) -> FloatArray:
    """(7, 7) covariance in PARAM_NAMES order of the target's samples, moved to the midpoint.

    Parameters absent from the file are held fixed (zero rows and columns). φ_ref is taken as
    its circular difference from the target's φ_ref, wrapped to (−π, π], so samples on both
    sides of 0 = 2π count as neighbours.

    Raises
    ------
    TargetFileError
        Unreadable file, no parameter columns (:func:`load_samples`), fewer than two rows, or
        values that are not finite.
    """
    cols = load_samples(t)
    assert t.samples is not None  # load_samples returned columns
    n = len(next(iter(cols.values())))
    if n < 2:
        raise TargetFileError(
            f"{t.samples.name}: {n} row; a covariance needs at least 2 posterior samples — "
            "add samples or give lisa.covariance"
        )
    names = [name for name in PARAM_NAMES if name in cols]
    data = np.column_stack([np.asarray(cols[name], float) for name in names])
    if "phase" in cols:
        k = names.index("phase")
        data[:, k] = np.angle(np.exp(1j * (data[:, k] - t.params.phase)))
    idx = [PARAM_NAMES.index(name) for name in names]
    full = np.zeros((7, 7))
    full[np.ix_(idx, idx)] = np.atleast_2d(np.cov(data, rowvar=False))
    return full


def with_samples_covariance(t: Target) -> Target:
    """``t`` with :attr:`~Target.samples_covariance` when its posterior is only a samples file.

    A target whose covariance names no phase-model parameter but which has samples would
    otherwise be treated as exact (σ_u = 0, T_valid at the search cap) by the forecast, the
    planner and validate; its covariance is taken from the samples instead.
    """
    if t.samples is None or any(n in PARAM_NAMES for n in t.cov_names):
        return t
    return replace(t, samples_covariance=samples_covariance(t))
