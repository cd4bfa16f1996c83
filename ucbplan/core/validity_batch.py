"""Horizon tables of many targets at once: the columns of Tables 4 and 7, vectorised over targets.

:func:`horizon_columns` is what :func:`ucbplan.core.forecast.horizon_table` computes for one
target (tolerance, σ_u at the end of the information, T_valid and δt_u per anchor × α, and for a
timing ephemeris the same before T0), for arrays of parameters and covariances in one pass: the
per-target cost is a few array operations (:mod:`ucbplan.core.validity_poly`), not a Python loop.
:func:`horizons` takes the targets themselves and returns the long table of ``ucbplan horizon``
for several targets: a row per target × anchor × α (:data:`HORIZON_COLUMNS`).
"""

from __future__ import annotations

import math
import operator
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ucbplan.core.constants import DAY_S
from ucbplan.core.forecast import (
    AFTER,
    anchor_kind,
    anchor_u_values,
    t_valid_batch,
    time_reversed,
    tolerance,
    two_sided,
)
from ucbplan.core.params import PARAM_NAMES, EphemerisSource
from ucbplan.core.validity_grid import HORIZON_CAP_S, anchor_sigma_batch, oscillating
from ucbplan.core.validity_poly import sigma2_polys, t_valid_from_sigma2
from ucbplan.errors import InputError

if TYPE_CHECKING:
    from astropy.table import Table

FloatArray = NDArray[np.float64]
#: A target's parameters as a tuple in PARAM_NAMES order (PhaseParams.as_array without the array).
_PARAMS = operator.attrgetter(*PARAM_NAMES)
_UNNAMED = object()


def _max_sigma(
    pars: FloatArray, covs: FloatArray, tau: FloatArray, us: Sequence[float], star: int
) -> FloatArray:
    """Largest anchor σ_u over the anchor's u★ at one epoch per target [rad], shape (n,)."""
    vals = [anchor_sigma_batch(pars, covs, tau[:, None], u, star)[:, 0] for u in us]
    out: FloatArray = np.max(vals, axis=0)
    return out


def _timing_error(
    pars: FloatArray, covs: FloatArray, tau: FloatArray, us: Sequence[float], star: int
) -> FloatArray:
    """δt_u = σ_u/Φ̇_asc at τ per target (Eq. timing_unc) [s]."""
    rate = math.pi * (pars[:, 1] + pars[:, 2] * tau + pars[:, 3] * tau**2 / 2)
    out: FloatArray = _max_sigma(pars, covs, tau, us, star) / np.abs(rate)
    return out


def _tolerances(kind: str, pair: FloatArray, n_epochs: int, u_star: float) -> FloatArray:
    """:func:`~ucbplan.core.forecast.tolerance` of each (σ_v, K) row of ``pair`` (n, 2) [rad]:
    the same operations on arrays (so the same bits); any input it refuses goes to it, one
    distinct pair at a time, for its error."""
    sv, k = pair[:, 0], pair[:, 1]
    valid = (sv > 0) & (k > 0) & np.isfinite(sv) & np.isfinite(k)
    if not valid.all() or n_epochs not in (1, 2) or kind not in _TOLERANCE_KINDS:
        pairs, which = np.unique(pair, axis=0, return_inverse=True)
        tol = np.array([tolerance(kind, a, b, n_epochs, u_star) for a, b in pairs])
        out: FloatArray = tol[which.reshape(-1)]
        return out
    quad = np.sqrt((2.0 if n_epochs == 1 else math.sqrt(2.0)) * sv / k)
    if kind in ("conjunction", "zero-crossing"):
        return sv / k
    if kind == "quadrature":
        return quad
    s = abs(math.sin(u_star))  # generic
    return quad if s == 0 else np.minimum(sv / (k * s), quad)


#: The kinds :func:`_tolerances` computes itself (any other goes to ``tolerance`` for its error).
_TOLERANCE_KINDS = ("conjunction", "zero-crossing", "quadrature", "generic")


def _t_valid_alphas(
    pars: FloatArray,
    covs: FloatArray,
    t_obs: FloatArray,
    thrs: Sequence[FloatArray],
    us: Sequence[float],
    star: int,
) -> list[FloatArray]:
    """``t_valid_batch(pars, covs, t_obs, thr, us, star)`` for each threshold array of ``thrs``
    (one per α) [s]: the σ_u² polynomials of the non-oscillating rows are built once and the
    roots of all thresholds found in one stacked pass (each row's root is its own, so the numbers
    are those of one call per α); oscillating rows go to :func:`t_valid_batch` as they are."""
    out = [np.zeros(pars.shape[0]) for _ in thrs]
    osc = oscillating(pars, covs)
    flat, prec = np.nonzero(~osc)[0], np.nonzero(osc)[0]
    if flat.size:
        polys = sigma2_polys(pars[flat], covs[flat], t_obs[flat], us, star, HORIZON_CAP_S)
        stacked = [np.tile(q, (len(thrs), 1)) for q in polys]
        thr = np.concatenate([t[flat] for t in thrs])
        tv = t_valid_from_sigma2(stacked, thr, HORIZON_CAP_S).reshape(len(thrs), -1)
        for o, row in zip(out, tv, strict=True):
            o[flat] = row
    if prec.size:
        p, c, o = pars[prec], covs[prec], t_obs[prec]
        for res, t in zip(out, thrs, strict=True):
            res[prec] = t_valid_batch(p, c, o, t[prec], us, star, AFTER)
    return out


def horizon_columns(
    pars: ArrayLike,
    covs: ArrayLike,
    t_obs_s: ArrayLike,
    sigma_v: ArrayLike,
    k_eff: ArrayLike,
    alphas: Sequence[float] = (0.5, 1.0),
    anchors: Sequence[str | float] = ("conjunction", "quadrature"),
    n_epochs: int = 2,
    star: int = 1,
    two_sided: ArrayLike = False,
) -> dict[str, FloatArray]:
    """Horizon columns for n targets, keyed ``"{field}:{anchor}:{alpha:g}"`` [units in field].

    Parameters
    ----------
    pars : (n, 7) parameters at the reference (midpoint); covs : (n, 7, 7);
    t_obs_s : (n,) information span T_obs [s] (0 for a timing ephemeris);
    sigma_v, k_eff : (n,) or float, RV precision and semi-amplitude [km/s];
    two_sided : (n,) bool, horizons before the reference too (timing ephemerides).

    Returns
    -------
    dict
        Per anchor: ``delta_u_tol_rad``, ``sigma_u_end_rad``; per anchor × α: ``t_valid_days``,
        ``dt_u_s``, and ``t_valid_before_days``/``dt_u_before_s`` (NaN for one-sided rows).
        Keys are ``field:anchor`` or ``field:anchor:alpha``.
    """
    p = np.atleast_2d(np.asarray(pars, dtype=np.float64))
    c = np.asarray(covs, dtype=np.float64).reshape(-1, 7, 7)
    n = p.shape[0]
    t_obs = np.broadcast_to(np.asarray(t_obs_s, dtype=np.float64), (n,))
    pair = np.column_stack(
        [np.broadcast_to(np.asarray(v, dtype=np.float64), (n,)) for v in (sigma_v, k_eff)]
    )
    both = np.broadcast_to(np.asarray(two_sided, dtype=bool), (n,))
    back = np.nonzero(both)[0]
    out: dict[str, FloatArray] = {}
    for anchor in anchors:
        out.update(_anchor_columns(p, c, t_obs, pair, back, anchor, alphas, n_epochs, star))
    return out


def _anchor_columns(
    p: FloatArray,
    c: FloatArray,
    t_obs: FloatArray,
    pair: FloatArray,
    back: NDArray[np.intp],
    anchor: str | float,
    alphas: Sequence[float],
    n_epochs: int,
    star: int,
) -> dict[str, FloatArray]:
    """The columns of one anchor (:func:`horizon_columns`); ``back``: the two-sided rows."""
    n = p.shape[0]
    label, us = anchor_u_values(anchor)
    tol = _tolerances(anchor_kind(label, us), pair, n_epochs, us[0])
    out = {
        f"delta_u_tol_rad:{label}": tol,
        f"sigma_u_end_rad:{label}": _max_sigma(p, c, t_obs / 2.0, us, star),
    }
    thrs = [alpha * tol for alpha in alphas]
    after = _t_valid_alphas(p, c, t_obs, thrs, us, star)
    if back.size:  # BEFORE: the time-reversed rows' horizons after (as t_valid_batch)
        pb, cb, ob = p[back], c[back], t_obs[back]
        pr, cr = time_reversed(pb, cb)
        before = _t_valid_alphas(pr, cr, ob, [t[back] for t in thrs], us, star)
    for j, alpha in enumerate(alphas):
        key = f"{label}:{alpha:g}"
        tv = after[j]
        out[f"t_valid_days:{key}"] = tv / DAY_S
        out[f"dt_u_s:{key}"] = _timing_error(p, c, t_obs / 2.0 + tv, us, star)
        tb = np.full(n, np.nan)
        dtb = np.full(n, np.nan)
        if back.size:
            tb[back] = before[j]
            dtb[back] = _timing_error(pb, cb, -ob / 2.0 - tb[back], us, star)
        out[f"t_valid_before_days:{key}"] = tb / DAY_S
        out[f"dt_u_before_s:{key}"] = dtb
    return out


#: The horizon table of many targets, declared once: (name, unit, dtype, description). One row
#: per target × anchor × α, in that order; a one-target call of :func:`~ucbplan.core.forecast.
#: horizon_table` gives the same numbers for its rows.
HORIZON_COLUMNS: tuple[tuple[str, str, str, str], ...] = (
    ("target", "", "str", "target name"),
    ("file", "", "str", "target file ('' for a target built in memory)"),
    ("kind", "", "str", "lisa: horizons after the end of LISA | timing: before and after T0"),
    ("anchor", "", "str", "anchor (conjunction, quadrature, zero-crossing or u★)"),
    ("alpha", "", "f8", "planning margin α"),
    ("sigma_v_kms", "km / s", "f8", "RV precision σ_v of the tolerance"),
    ("k_eff_kms", "km / s", "f8", "semi-amplitude K of the tolerance"),
    ("n_epochs", "", "i8", "tolerance form (2: two-epoch difference, 1: single epoch)"),
    ("tolerance_rad", "rad", "f8", "α·δu_tol"),
    ("delta_u_tol_rad", "rad", "f8", "δu_tol"),
    ("t_valid_days", "d", "f8", "T_valid after the end of the information (T0 for timing)"),
    ("dt_u_s", "s", "f8", "δt_u = σ_u/|u̇| at T_valid"),
    ("sigma_u_end_rad", "rad", "f8", "σ_u at the end of the information (at T0 for timing)"),
    ("t_valid_before_days", "d", "f8", "T_valid before T0 (timing; NaN for a LISA posterior)"),
    ("dt_u_before_s", "s", "f8", "δt_u before T0 (timing; NaN for a LISA posterior)"),
)
#: Columns that only a two-sided (timing) row has: JSON rows of one-sided targets omit them.
TWO_SIDED_COLUMNS = ("t_valid_before_days", "dt_u_before_s")


def _spectroscopy(
    t: EphemerisSource, name: str, sigma_v: float | None, k_eff: float | None
) -> tuple[float, float]:
    """σ_v and K [km/s] of one target: the arguments, else its ``spectroscopy`` record."""
    spec = getattr(t, "spectroscopy", None)
    sv = sigma_v if sigma_v is not None else getattr(spec, "sigma_v_kms", None)
    k = k_eff if k_eff is not None else getattr(spec, "k_for_tolerance", None)
    if sv is None:
        raise InputError(
            f"{name}: no RV precision; give sigma_v (km/s) or add spectroscopy.sigma_v to the "
            "target file"
        )
    if k is None:
        raise InputError(
            f"{name}: no semi-amplitude; give k_eff (km/s) or add spectroscopy.K1/K2 (or K_eff) "
            "to the target file"
        )
    for what, v, low in (("sigma_v", sv, 0.0), ("k_eff", k, 0.1)):
        if not low < v <= 1e4:
            raise InputError(f"{name}: {what}: expected a number in ({low:g}, 1e4] km/s, got {v!r}")
    if sv >= k:
        raise InputError(
            f"{name}: sigma_v ({sv:g} km/s) must be smaller than k_eff ({k:g} km/s): with "
            "σ_v ≥ K no phase tolerance exists"
        )
    return float(sv), float(k)


def horizons(
    targets: Sequence[EphemerisSource],
    sigma_v: float | None = None,
    k_eff: float | None = None,
    alphas: Sequence[float] = (0.5, 1.0),
    anchors: Sequence[str | float] = ("conjunction", "quadrature"),
    n_epochs: int = 2,
    star: int = 1,
) -> Table:
    """The horizon table of many targets in one vectorised pass (:data:`HORIZON_COLUMNS`).

    Parameters
    ----------
    targets : sequence of EphemerisSource
        Targets (e.g. :class:`ucbplan.targets.Target`); ``name``, ``source`` (its file),
        ``kind`` and ``spectroscopy`` are read when present.
    sigma_v, k_eff : float, optional
        RV precision and semi-amplitude [km/s] for every target (default: each target's
        ``spectroscopy``).
    alphas, anchors, n_epochs, star
        As :func:`ucbplan.core.forecast.horizon_table`.

    Returns
    -------
    astropy.table.Table
        One row per target × anchor × α (target-major). The before-T0 columns are NaN for a
        LISA posterior (one-sided); ``meta`` holds ``n_epochs`` and ``star``.

    Raises
    ------
    InputError
        No targets, or a target without σ_v or K (one line naming it), or σ_v ≥ K.

    Notes
    -----
    The same numbers as :func:`ucbplan.core.forecast.horizon_table` per target (Eqs.
    T_valid_alpha, timing_unc), from :func:`horizon_columns`.
    """
    names, files = _names_files(targets)
    sk = np.array(
        [_spectroscopy(t, n, sigma_v, k_eff) for t, n in zip(targets, names, strict=True)]
    )
    both = np.array([two_sided(t) for t in targets], dtype=bool)
    cols = horizon_columns(
        np.array(list(map(_PARAMS, (t.params for t in targets))), dtype=np.float64),
        _covariances(targets),
        np.array([t.t_obs_s for t in targets]),
        sk[:, 0],
        sk[:, 1],
        alphas=alphas,
        anchors=anchors,
        n_epochs=n_epochs,
        star=star,
        two_sided=both,
    )
    return _long_table(cols, names, files, both, sk, alphas, anchors, n_epochs, star)


def _names_files(targets: Sequence[EphemerisSource]) -> tuple[list[str], list[str]]:
    """Each target's name (``target N`` for one without) and file ('' for one in memory)."""
    if not targets:
        raise InputError("targets: expected at least one target, got none")
    names = [  # the fallback name formatted only for a target without one
        f"target {i + 1}" if (v := getattr(t, "name", _UNNAMED)) is _UNNAMED else str(v)
        for i, t in enumerate(targets)
    ]
    return names, [str(getattr(t, "source", None) or "") for t in targets]


def _covariances(targets: Sequence[EphemerisSource]) -> FloatArray:
    """The (n, 7, 7) covariances: targets that name their covariance's parameters
    (``cov_names``, ``cov_matrix``, as :class:`ucbplan.targets.Target`) are scattered into
    :data:`~ucbplan.core.params.PARAM_NAMES` order one group of equal names at a time; any other
    source gives its ``covariance``."""
    out = np.zeros((len(targets), 7, 7))
    groups: dict[tuple[str, ...], list[int]] = {}
    for i, t in enumerate(targets):
        names = getattr(t, "cov_names", None)
        if isinstance(names, tuple) and isinstance(getattr(t, "cov_matrix", None), np.ndarray):
            groups.setdefault(names, []).append(i)
        else:
            out[i] = t.covariance
    for names, rows in groups.items():
        sub = [k for k, n in enumerate(names) if n in PARAM_NAMES]
        idx = [PARAM_NAMES.index(names[k]) for k in sub]
        mats = np.array([targets[i].cov_matrix for i in rows])  # type: ignore[attr-defined]
        out[np.ix_(rows, idx, idx)] = mats[np.ix_(range(len(rows)), sub, sub)]
    return out


def _long_table(
    cols: dict[str, FloatArray],
    names: list[str],
    files: list[str],
    both: NDArray[np.bool_],
    sk: FloatArray,
    alphas: Sequence[float],
    anchors: Sequence[str | float],
    n_epochs: int,
    star: int,
) -> Table:
    """:func:`horizon_columns`' per-target columns as the long table (target × anchor × α)."""
    from astropy.table import Table

    labels = [anchor_u_values(a)[0] for a in anchors]
    n, per = len(names), len(labels) * len(alphas)

    def grid(field: str, with_alpha: bool = True) -> FloatArray:
        """(n, anchors, α) values of a column, flattened target-major."""
        out = np.empty((n, len(labels), len(alphas)))
        for i, lab in enumerate(labels):
            for j, al in enumerate(alphas):
                out[:, i, j] = cols[f"{field}:{lab}:{al:g}" if with_alpha else f"{field}:{lab}"]
        return out.reshape(-1)

    tol = grid("delta_u_tol_rad", with_alpha=False)
    values: dict[str, Any] = {
        "target": np.repeat(np.array(names, dtype=str), per),
        "file": np.repeat(np.array(files, dtype=str), per),
        "kind": np.repeat(np.where(both, "timing", "lisa"), per),
        "anchor": np.tile(np.repeat(np.array(labels, dtype=str), len(alphas)), n),
        "alpha": np.tile(np.asarray(alphas, dtype=np.float64), n * len(labels)),
        "sigma_v_kms": np.repeat(sk[:, 0], per),
        "k_eff_kms": np.repeat(sk[:, 1], per),
        "n_epochs": np.full(n * per, n_epochs, dtype=np.int64),
        "delta_u_tol_rad": tol,
        "t_valid_days": grid("t_valid_days"),
        "dt_u_s": grid("dt_u_s"),
        "sigma_u_end_rad": grid("sigma_u_end_rad", with_alpha=False),
        "t_valid_before_days": grid("t_valid_before_days"),
        "dt_u_before_s": grid("dt_u_before_s"),
    }
    values["tolerance_rad"] = values["alpha"] * tol
    tab = Table()
    for name, unit, _, desc in HORIZON_COLUMNS:
        tab[name] = values[name]
        tab[name].description = desc
        if unit:
            tab[name].unit = unit
    tab.meta.update({"n_epochs": n_epochs, "star": star})
    return tab


def horizon_rows(tab: Table) -> list[dict[str, Any]]:
    """The table's rows as JSON-ready dicts: plain Python values, NaN as None, and a one-sided
    (LISA) row without the before-T0 keys (as :meth:`ucbplan.core.forecast.HorizonRow.as_dict`)."""
    names = list(tab.colnames)
    lists = [np.asarray(tab[c]).tolist() for c in names]
    numeric = [c for c in names if np.asarray(tab[c]).dtype.kind == "f"]
    nan = np.zeros(len(tab), dtype=bool)
    for c in numeric:
        if c not in TWO_SIDED_COLUMNS:
            nan |= np.isnan(np.asarray(tab[c]))
    one_sided = np.asarray(tab["kind"]) != "timing"
    keep = [c not in TWO_SIDED_COLUMNS for c in names]
    short = [n for n, k in zip(names, keep, strict=True) if k]
    out: list[dict[str, Any]] = []
    for i, values in enumerate(zip(*lists, strict=True)):
        if one_sided[i]:
            row = dict(zip(short, (v for v, k in zip(values, keep, strict=True) if k), strict=True))
        else:
            row = dict(zip(names, values, strict=True))
        if nan[i] or not one_sided[i]:
            row = {
                k: (None if isinstance(v, float) and math.isnan(v) else v) for k, v in row.items()
            }
        out.append(row)
    return out


def horizon_json(tab: Table) -> str:
    """The JSON text of :func:`horizon_rows`: an array with one row per line, as
    ``json.dumps(horizon_rows(tab), allow_nan=False, ensure_ascii=False)`` would write each row,
    built by column (each column's values encoded in one pass, each row filled into a template of
    its keys) instead of row by row. NaN is ``null``; a table with an infinite value takes the
    row-by-row path, whose error says so."""
    import json
    from json.encoder import encode_basestring  # the string encoder of ensure_ascii=False

    names = list(tab.colnames)
    cols: dict[str, list[str]] = {}
    for name in names:
        col = np.asarray(tab[name])
        if col.dtype.kind == "f":
            if np.isinf(col).any():
                return _rows_text(
                    json.dumps(horizon_rows(tab), allow_nan=False, ensure_ascii=False)
                )
            vals = _float_texts(col)
        elif col.dtype.kind in "iu":
            vals = list(map(int.__repr__, col.tolist()))
        else:  # each distinct text encoded once (names repeat over a target's rows)
            texts = col.tolist()
            codes = {v: encode_basestring(v) for v in dict.fromkeys(texts)}
            vals = list(map(codes.__getitem__, texts))
        cols[name] = vals
    one_sided = np.asarray(tab["kind"]) != "timing"
    text = [""] * len(tab)
    for keys, rows in (
        ([c for c in names if c not in TWO_SIDED_COLUMNS], np.flatnonzero(one_sided)),
        (names, np.flatnonzero(~one_sided)),
    ):
        if not rows.size:
            continue
        template = "{" + ", ".join(f"{encode_basestring(k)}: %s" for k in keys) + "}"
        if rows.size == len(tab):  # one kind of target: no scatter
            text = list(map(template.__mod__, zip(*[cols[k] for k in keys], strict=True)))
            break
        take = rows.tolist()
        values = [[cols[k][i] for i in take] for k in keys]
        for i, row in zip(take, map(template.__mod__, zip(*values, strict=True)), strict=True):
            text[i] = row
    return "[\n" + ",\n".join(text) + "\n]\n"


def _float_texts(col: FloatArray) -> list[str]:
    """``repr`` of each float of a column (as ``json`` writes it), NaN as ``null``: each distinct
    value (bit pattern, so 0.0 and -0.0 stay apart) formatted once; α, σ_v, K, the tolerances
    and σ_u at the end repeat over a target's rows or over the targets."""
    bits = np.ascontiguousarray(col, dtype=np.float64).view(np.int64)
    uniq, inverse = np.unique(bits, return_inverse=True)
    texts = ["null" if v != v else repr(v) for v in uniq.view(np.float64).tolist()]
    return list(map(texts.__getitem__, inverse.reshape(-1).tolist()))


def _rows_text(array: str) -> str:
    """A JSON array of rows (each starting with its ``target`` key) one row per line: inside an
    encoded string a quote is always escaped, so ``}, {"target": `` occurs only between rows."""
    return "[\n" + array[1:-1].replace('}, {"target": ', '},\n{"target": ') + "\n]\n"
