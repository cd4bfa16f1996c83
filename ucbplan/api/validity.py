"""Phase-coherence horizons T_valid (paper Tables 4 and 7): :func:`horizon` and the command's
:func:`horizon_report`, one code path for both (several targets in one vectorised pass,
:func:`ucbplan.core.validity_batch.horizons`), with their options declared once
(:data:`HORIZON_FLAGS`)."""

from __future__ import annotations

import os
import stat
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ucbplan.api._convert import as_float, scope
from ucbplan.api.ephemeris import check_anchor
from ucbplan.api.flagspec import Flag
from ucbplan.api.targets import TargetLike, load_target
from ucbplan.errors import InputError, UcbplanError, shorten

if TYPE_CHECKING:
    from astropy.table import Table

    from ucbplan.targets import Target

#: The options of :func:`horizon` as ``ucbplan horizon`` spells them.
HORIZON_FLAGS: dict[str, Flag] = {
    "sigma_v": Flag(
        ("--sigma-v",), "RV precision per epoch σ_v [km/s] (default: target file).", "km/s"
    ),
    "k_eff": Flag(
        ("--k-eff",), "Semi-amplitude of the observable [km/s] (default: K_eff or K1+K2).", "km/s"
    ),
    "alpha": Flag(("--alpha",), "Margin α (repeatable)."),
    "n_epochs": Flag(("--epochs",), "1: single epoch, 2: two-epoch difference."),
    "anchors": Flag(("--anchor",), "Anchors (repeatable)."),
}


def resolve_k_sigma(t: Target, sigma_v: Any = None, k_eff: Any = None) -> tuple[float, float]:
    """σ_v and K_eff [km/s]: the arguments, else the target file's spectroscopy section.

    Raises
    ------
    InputError
        Neither given nor in the file, out of range, or σ_v ≥ K (naming the parameter).
    """
    from ucbplan.inputs import check_number

    spec = t.spectroscopy
    sv = as_float(sigma_v, "km/s", "sigma_v")
    k = as_float(k_eff, "km/s", "k_eff")
    sv = sv if sv is not None else (spec.sigma_v_kms if spec else None)
    k = k if k is not None else (spec.k_for_tolerance if spec else None)
    if sv is None:
        raise InputError(
            f"sigma_v: {t.name} has no RV precision; pass sigma_v (km/s) or add "
            "spectroscopy.sigma_v to the target file",
            parameter="sigma_v",
        )
    if k is None:
        raise InputError(
            f"k_eff: {t.name} has no semi-amplitude; pass k_eff (km/s) or add "
            "spectroscopy.K1/K2 (or K_eff) to the target file",
            parameter="k_eff",
        )
    check_number("sigma_v", sv, 0.0, 1e4, "km/s")
    check_number("k_eff", k, 0.1, 1e4, "km/s", "a binary's velocity semi-amplitude")
    if sv >= k:
        raise InputError(
            f"sigma_v ({sv:g} km/s) must be smaller than k_eff ({k:g} km/s): with "
            "σ_v ≥ K no phase tolerance exists",
            parameter="sigma_v",
        )
    return float(sv), float(k)


def horizon(
    targets: TargetLike | Sequence[TargetLike],
    sigma_v: Any = None,
    k_eff: Any = None,
    alpha: Sequence[float] | float = (0.5, 1.0),
    n_epochs: int = 2,
    anchors: Sequence[str] = ("conjunction", "quadrature"),
) -> Table:
    """Phase-coherence horizons T_valid (paper Tables 4 and 7) and σ_u at the end of LISA.

    Parameters
    ----------
    targets : target or list of targets
        Each a path (a target file, a folder of them, or a catalog of several documents), a
        target document or a ``Target`` (see :func:`load_target`).
    sigma_v, k_eff : float or Quantity, optional
        RV precision σ_v and semi-amplitude K_eff [km/s]; None takes each target file's.
    alpha : float or sequence of float
        Planning margins α of T_valid.
    n_epochs : int
        Number of epochs the tolerance is shared between (1 or 2 …).
    anchors : sequence of str
        Anchors (``conjunction``, ``quadrature`` …, or a number u★ [rad]).

    Returns
    -------
    astropy.table.Table
        One row per target × anchor × α, what ``ucbplan horizon --format json`` writes: for
        several targets the long table computed in one vectorised pass (``target``, ``file``,
        ``kind``, ``anchor``, ``alpha``, ``sigma_v_kms`` [km/s], ``tolerance_rad`` [rad],
        ``t_valid_days`` [d], ``dt_u_s`` [s], ``sigma_u_end_rad`` [rad], and for a timing
        ephemeris ``t_valid_before_days`` …); for one target its rows (``anchor`` … ``n_epochs``,
        ``target``) with σ_v and K [km/s] in ``meta``.

    Raises
    ------
    InputError
        A bad α, σ_v, K, epochs or anchor (naming the parameter); TargetFileError for a target.

    Notes
    -----
    Eq. tol_quad and Eq. tol_conj for the tolerances; T_valid is the first root of
    σ_u(τ) = α·δu_tol (docs/method.md).

    Examples
    --------
    >>> import ucbplan
    >>> table = ucbplan.horizon("catalogs/hm-cnc-simulated.yaml")
    >>> table["t_valid_days"].info.format = ".0f"
    >>> table["anchor", "alpha", "t_valid_days"]
    <Table length=4>
       anchor    alpha  t_valid_days
       str11    float64   float64
    ----------- ------- ------------
    conjunction     0.5         2511
    conjunction     1.0         3607
     quadrature     0.5         4446
     quadrature     1.0         6004
    """
    got = horizon_report(targets, sigma_v, k_eff, alpha, n_epochs, anchors)
    if not got.rows:
        return got.table
    from astropy.table import Table

    name = got.targets[0].name
    tab = Table(rows=[r.as_dict() | {"target": name} for r in got.rows])
    tab.meta.update(got.table.meta)
    return tab


@dataclass(frozen=True, slots=True)
class HorizonReport:
    """What ``ucbplan horizon`` shows: the targets, their horizon table, and for one target its
    rows (:class:`ucbplan.core.forecast.HorizonRow`) with the σ_v and K [km/s] used."""

    targets: tuple[Target, ...]
    table: Table
    rows: tuple[Any, ...] = ()
    sigma_v: float = 0.0
    k_eff: float = 0.0
    n_epochs: int = 2

    def __repr__(self) -> str:
        return f"<HorizonReport: {len(self.targets)} target(s), {len(self.table)} rows>"


def horizon_report(
    targets: TargetLike | Sequence[TargetLike],
    sigma_v: Any,
    k_eff: Any,
    alpha: Sequence[float] | float,
    n_epochs: int,
    anchors: Sequence[str],
    plot: str | Path | None = None,
    overwrite: bool = False,
) -> HorizonReport:
    """:func:`horizon` and what the command shows with it (parameters and their defaults as
    there: declared once, in :func:`horizon`).

    One target gives its rows as well, and ``plot`` draws its σ_u(t) figure there (refused
    before any work when it exists and not ``overwrite``).

    Raises
    ------
    InputError
        As :func:`horizon`; ``plot`` with several targets.
    """
    alphas, anchors = _checked(alpha, n_epochs, anchors)
    with scope():
        if plot is not None:
            from ucbplan.plotting import check_figure_path

            check_figure_path(Path(plot), overwrite)
        loaded = _load_all(targets)
        if len(loaded) > 1:
            if plot is not None:
                raise InputError("plot: takes one target; give a single target file", "plot")
            return _many(loaded, sigma_v, k_eff, alphas, n_epochs, anchors)
        return _one(loaded[0], sigma_v, k_eff, alphas, n_epochs, anchors, plot, overwrite)


def _checked(alpha: Any, n_epochs: Any, anchors: Any) -> tuple[list[float], list[Any]]:
    """α's, anchors: checked at the door, one line naming the parameter."""
    from ucbplan.inputs import check_alpha, is_number

    alphas = [alpha] if is_number(alpha) or isinstance(alpha, str) else alpha
    if not isinstance(alphas, Sequence) or isinstance(alphas, str) or not alphas:
        raise InputError(f"alpha: expected a number or a list of numbers, got {shorten(alpha)}")
    for a in alphas:
        check_alpha(a)
    if not (is_number(n_epochs) and n_epochs in (1, 2)):
        raise InputError(
            f"n_epochs: expected 1 (single epoch) or 2 (two-epoch difference), got "
            f"{shorten(n_epochs)}",
            parameter="n_epochs",
        )
    names = [anchors] if isinstance(anchors, str) else anchors
    if not isinstance(names, Sequence) or not names:
        raise InputError(f"anchors: expected a list of anchors, got {shorten(anchors, 60)}")
    for a in names:
        check_anchor(a, "anchors")
    return [float(a) for a in alphas], list(names)


def _load_all(targets: Any) -> list[Target]:
    """Every target of ``targets``: files, folders of *.yaml, catalogs, documents, Targets."""
    from ucbplan.targets import check_distinct_files, load_target_documents, load_target_files

    many = isinstance(targets, Sequence) and not isinstance(targets, str)
    items, keys = _expand(list(targets) if many else [targets])
    if not items:
        raise InputError("targets: expected at least one target, got none", "targets")
    files = [k for k, i in enumerate(items) if isinstance(i, str | Path)]
    check_distinct_files([items[k] for k in files], [keys[k] for k in files])
    if all(isinstance(i, str | Path) for i in items):
        return load_target_files(items)  # files only: each folder resolved once
    out: list[Target] = []
    for item in items:
        is_path = isinstance(item, str | Path)
        out.extend(load_target_documents(item) if is_path else [load_target(item)])
    return out


def _expand(items: list[Any]) -> tuple[list[Any], list[tuple[int, int] | None]]:
    """Paths as given (text stays text, ~2 µs each); a folder gives its *.yaml, *.yml, sorted.
    With each item its file key where its ``os.stat`` was taken here (None: not taken)."""
    from ucbplan.targets.parse import file_key

    out: list[Any] = []
    keys: list[tuple[int, int] | None] = []
    for item in items:
        st = _stat(item or ".") if isinstance(item, str | Path) else None  # "" is "." as before
        if st is not None and stat.S_ISDIR(st.st_mode):
            path = Path(item)
            found = sorted([*path.glob("*.yaml"), *path.glob("*.yml")])
            if not found:
                raise UcbplanError(f"{path}: no *.yaml target files in this directory")
            out.extend(found)
            keys.extend([None] * len(found))
        else:
            out.append(item)
            keys.append(None if st is None else file_key(st))
    return out, keys


def _stat(path: str | Path) -> os.stat_result | None:
    """``os.stat`` of ``path`` (None where ``os.path.isdir`` would say False: no such file)."""
    try:
        return os.stat(path)
    except (OSError, ValueError):
        return None


def _one(
    t: Target,
    sigma_v: Any,
    k_eff: Any,
    alphas: list[float],
    n_epochs: int,
    anchors: list[Any],
    plot: str | Path | None,
    overwrite: bool,
) -> HorizonReport:
    """One target: its horizon rows (and figure)."""
    from astropy.table import Table

    from ucbplan.core.forecast import horizon_table

    sv, k = resolve_k_sigma(t, sigma_v, k_eff)
    rows = horizon_table(t, sv, k, alphas=alphas, anchors=anchors, n_epochs=n_epochs)
    if plot is not None:
        from ucbplan.plotting.validity import horizon_plot

        horizon_plot(t, rows, Path(plot), overwrite=overwrite)
    tab = Table(rows=[r.as_dict() for r in rows])
    tab.meta.update({"target": t.name, "sigma_v_kms": sv, "k_eff_kms": k, "n_epochs": n_epochs})
    return HorizonReport((t,), tab, tuple(rows), sv, k, n_epochs)


def _many(
    targets: list[Target],
    sigma_v: Any,
    k_eff: Any,
    alphas: list[float],
    n_epochs: int,
    anchors: list[Any],
) -> HorizonReport:
    """Several targets: the long table in one vectorised pass."""
    from ucbplan.core.validity_batch import horizons

    sv, k = as_float(sigma_v, "km/s", "sigma_v"), as_float(k_eff, "km/s", "k_eff")
    _check_k_sigma(targets, sv, k)
    tab = horizons(targets, sv, k, alphas=alphas, anchors=anchors, n_epochs=n_epochs)
    return HorizonReport(tuple(targets), tab, n_epochs=n_epochs)


def _check_k_sigma(targets: list[Target], sigma_v: Any, k_eff: Any) -> None:
    """:func:`resolve_k_sigma` of every target (one-line errors naming the parameter), once per
    distinct (σ_v, K) a target would use, on which alone its outcome depends, and only where a
    plain float pair is not plainly in range: the first target that fails is still the one
    named."""
    from ucbplan.inputs import is_number

    if not all(v is None or is_number(v) for v in (sigma_v, k_eff)):
        resolve_k_sigma(targets[0], sigma_v, k_eff)  # refuses it, naming the parameter
    pairs: dict[tuple[Any, Any], Target] = {}
    for t in targets:
        spec = t.spectroscopy
        sv = sigma_v if sigma_v is not None else (spec.sigma_v_kms if spec else None)
        k = k_eff if k_eff is not None else (spec.k_for_tolerance if spec else None)
        pairs.setdefault((sv, k), t)
    for (sv, k), t in pairs.items():
        plain = type(sv) is float and type(k) is float
        if not (plain and 0.0 < sv <= 1e4 and 0.1 < k <= 1e4 and sv < k):
            resolve_k_sigma(t, sigma_v, k_eff)


def horizon_json(table: Table) -> str:
    """The JSON text ``ucbplan horizon --format json`` writes of a many-target table (one row per
    line; NaN as null), built by column (:func:`ucbplan.core.validity_batch.horizon_json`)."""
    from ucbplan.core.validity_batch import horizon_json as by_column

    return by_column(table)
