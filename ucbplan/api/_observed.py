"""``plan(observed=FILE)``: the spectra already taken, read for the goal planning.

FILE is a velocities file as ``reduce`` takes it (:func:`ucbplan.reduce.velocities.read_velocities`:
epochs, exposure times or Λ_K, and the measured σ_v; the velocities are not used) of the one
target planned, a blocks table as ``plan -o`` writes it with a ``status`` column (``taken``,
``missed`` or ``skipped``: only ``taken`` rows count; their ``sigma_v_kms`` is taken as the σ_v
measured), or an observing log as the night sheet and ``now --log`` write it
(:mod:`ucbplan.observing.night.observing_log`: one row per exposure, read the same way). The spectra
become :class:`~ucbplan.observing.precision.observed.ObservedSpectra` in the planner's settings, and
the median of measured / predicted σ_v rescales the σ_v law (:func:`observed_settings`).
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ucbplan.errors import InputError, shorten

if TYPE_CHECKING:
    from ucbplan.observing.observatory.sites import Site
    from ucbplan.observing.precision.observed import ObservedSpectra
    from ucbplan.observing.schedule import PlanSettings
    from ucbplan.targets import Target


def observed_settings(
    path: Any, scale: Any, targets: list[Target], site: Site, settings: PlanSettings
) -> PlanSettings:
    """``settings`` with the spectra of ``path`` (None: none) and the σ_v scale: ``scale`` if
    given, else the measured / predicted ratio when it differs from 1 by more than
    :data:`~ucbplan.observing.precision.observed.SIGMA_V_RATIO_TOL`, else 1.

    Raises
    ------
    InputError
        Observed spectra without a goal; a file of another target or site; a bad status; an
        unreadable file (one line naming the file).
    """
    from ucbplan.observing.precision.observed import SIGMA_V_RATIO_TOL, sigma_v_ratio

    given = _scale(scale)
    if path is None:
        return dataclasses.replace(settings, sigma_v_scale=1.0 if given is None else given)
    if settings.goal is None:
        raise InputError(
            "observed: the spectra already taken count toward a goal; give `goal` too (e.g. "
            "sigma_K=2km/s)",
            parameter="observed",
        )
    if _is_table(path):
        label = str(path.meta.get(SOURCE_KEY, "a table in memory"))
        spectra = _from_blocks(label, path, targets, site, settings)
    else:
        spectra = _read(Path(_text(path)), targets, site, settings)
    ratio = sigma_v_ratio(  # a log of only missed exposures has no spectra
        np.concatenate([s.sigma_v_kms for s in spectra] or [np.zeros(0)]),
        np.concatenate([s.predicted_kms for s in spectra] or [np.zeros(0)]),
    )
    if given is None:
        given = ratio if math.isfinite(ratio) and abs(ratio - 1) > SIGMA_V_RATIO_TOL else 1.0
    return dataclasses.replace(settings, observed=tuple(spectra), sigma_v_scale=given)


#: The key of a table's meta that names it in messages and in the plan's meta (a table in memory
#: has no file name: a replan names its kept rows so).
SOURCE_KEY = "observed_source"


def _is_table(value: Any) -> bool:
    """Whether ``value`` is an astropy table (a blocks table in memory, with its status column)."""
    return hasattr(value, "colnames") and hasattr(value, "meta")


def _text(value: Any) -> str | Path:
    if isinstance(value, str | Path):
        return value
    raise InputError(
        f"observed: expected a file path or a blocks table with a status column, got "
        f"{shorten(value, 40)}",
        parameter="observed",
    )


def _scale(value: Any) -> float | None:
    """``sigma_v_scale``: None, or a positive number."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise InputError(
            f"sigma_v_scale: expected a positive number (1 keeps the σ_v law), got "
            f"{shorten(value, 40)}",
            parameter="sigma_v_scale",
        )
    return float(value)


def _spectra_text(path: Path) -> str:
    """The text of a spectra file (read once, to tell a log, a blocks table and velocities)."""
    from ucbplan.inputs import read_text

    try:
        return read_text(path, "spectra file")
    except InputError as exc:
        raise InputError(f"observed: {exc}", parameter="observed") from None


def _is_blocks(text: str) -> bool:
    """Whether ``text`` holds a blocks table (a ``block_id`` column) rather than velocities."""
    head = text.lstrip()
    if head.startswith(("[", "{")):
        return True
    lines = [ln for ln in text.splitlines() if ln.strip()]
    header = [ln for ln in lines if ln.lstrip().startswith("#")]
    first = next((ln for ln in lines if not ln.lstrip().startswith("#")), "")
    return "block_id" in first.split(",") or any("name: block_id" in ln for ln in header)


def _read(
    path: Path, targets: list[Target], site: Site, settings: PlanSettings
) -> list[ObservedSpectra]:
    """The spectra of ``path``, one :class:`ObservedSpectra` per target it names: an observing
    log (the night sheet's or ``now --log``'s CSV), a blocks table, else velocities."""
    from ucbplan.observing.night.observing_log import is_log

    text = _spectra_text(path)
    if is_log(text):
        from ucbplan.observing.night.observing_log import read_log

        return _from_blocks(path, read_log(path), targets, site, settings)
    if _is_blocks(text):
        from ucbplan.observing.blocks.read import read_blocks

        return _from_blocks(path, read_blocks(path), targets, site, settings)
    return [_from_velocities(path, targets, site, settings)]


def _predicted(
    target: Target, settings: PlanSettings, exptime_s: np.ndarray, airmass: np.ndarray
) -> np.ndarray:
    """σ_v the plan's law predicts for each spectrum [km/s] (NaN without an exposure time)."""
    from ucbplan.observing.schedule.exposure import exposure_sigma_v

    out = np.full(exptime_s.shape, np.nan)
    for i, (t, x) in enumerate(zip(exptime_s, airmass, strict=True)):
        if math.isfinite(t) and t > 0:
            out[i] = float(exposure_sigma_v(target, settings, float(t), max(1.0, float(x))))
    return out


def _from_velocities(
    path: Path, targets: list[Target], site: Site, settings: PlanSettings
) -> ObservedSpectra:
    """A velocities file: the spectra of the one target planned."""
    from ucbplan.observing.precision.observed import ObservedSpectra, window_lambda_k
    from ucbplan.reduce.velocities import check_validity, read_velocities, to_barycentric

    if len(targets) != 1:
        names = ", ".join(t.name for t in targets)
        raise InputError(
            f"observed {path}: a velocities file names no target, and {len(targets)} are "
            f"planned ({shorten(names, 80)}); plan its target alone, or give a blocks table",
            parameter="observed",
        )
    target = targets[0]
    table = to_barycentric(read_velocities(path), target.coord, site.location)
    tau = check_validity(table, target)
    lam = np.where(
        np.isfinite(table.lambda_k),
        table.lambda_k,
        window_lambda_k(np.nan_to_num(table.window_s), target.params.n_bar),
    )
    airmass = _airmass(target, site, table.time)
    predicted = _predicted(target, settings, table.window_s, airmass)
    return ObservedSpectra(target.name, tau, lam, table.sigma[0], predicted, str(path))


def _airmass(target: Target, site: Site, time: Any) -> np.ndarray:
    """Airmass of ``target`` at ``site`` at each time (the light time, ≤ 8.3 min, neglected)."""
    from astropy.coordinates import AltAz

    from ucbplan.observing.observatory.sky import airmass_from_alt

    alt = target.coord.transform_to(AltAz(obstime=time.utc, location=site.location)).alt.deg
    return np.asarray(airmass_from_alt(np.asarray(alt, dtype=np.float64)), dtype=np.float64)


def _from_blocks(
    path: Path | str, table: Any, targets: list[Target], site: Site, settings: PlanSettings
) -> list[ObservedSpectra]:
    """A blocks table with a status column, or an observing log (one row per exposure,
    :data:`~ucbplan.observing.night.observing_log.LOG_COLUMNS`): its ``taken`` rows, per target."""
    where = f"observed {path}"
    _check_site(table.meta, site, where)
    taken = _taken_rows(table, where)
    by_name = {t.name: t for t in targets}
    names = [str(n) for n in np.asarray(table["target"])[taken]]
    for name in dict.fromkeys(names):
        if name not in by_name:
            known = ", ".join(by_name)
            raise InputError(
                f"{where}: target {shorten(name, 60)} is not planned (targets: "
                f"{shorten(known, 120)}); give the file of a planned target",
                parameter="observed",
            )
    return [
        _target_rows(table, taken & (np.asarray(table["target"]) == n), by_name[n], settings, path)
        for n in dict.fromkeys(names)
    ]


def _check_site(meta: Any, site: Site, where: str) -> None:
    """The table's site (ECSV/JSON meta; a CSV has none) is the plan's."""
    theirs = (meta.get("site") or {}) if hasattr(meta, "get") else {}
    name = theirs.get("name") if hasattr(theirs, "get") else None
    if name is not None and str(name).strip().lower() != site.name.strip().lower():
        raise InputError(
            f"{where}: observed at {shorten(str(name), 40)}, but the plan is for {site.name}; "
            "give the file of this site's run",
            parameter="observed",
        )


def _taken_rows(table: Any, where: str) -> np.ndarray:
    """Rows whose ``status`` is ``taken`` (every status one of :data:`STATUSES`)."""
    # here, not at the top: a plan without observed spectra need not import the night tools
    from ucbplan.observing.night.observing_log import STATUSES

    if "status" not in table.colnames:
        raise InputError(
            f"{where}: expected a status column ({', '.join(STATUSES)} per row), got none; "
            "add it, or give a velocities file",
            parameter="observed",
        )
    status = [str(s).strip().lower() for s in table["status"]]
    for i, s in enumerate(status):
        if s not in STATUSES:
            raise InputError(
                f"{where}: row {i + 1}, column status: expected one of {', '.join(STATUSES)}, "
                f"got {shorten(table['status'][i], 40)}",
                parameter="observed",
            )
    return np.array([s == "taken" for s in status], dtype=bool)


def _target_rows(
    table: Any, rows: np.ndarray, target: Target, settings: PlanSettings, path: Path | str
) -> ObservedSpectra:
    """The ``rows`` of one target as :class:`ObservedSpectra` (σ_v: the ``sigma_v_kms``)."""
    from astropy.time import Time

    from ucbplan.observing.precision.observed import ObservedSpectra

    def column(name: str) -> np.ndarray:
        return np.asarray(table[name], dtype=np.float64)[rows]

    t_mid = Time([str(t) for t in np.asarray(table["t_mid_tdb_bary"])[rows]], scale="tdb")
    tau = np.asarray((t_mid - target.t_ref).to_value("s"), dtype=np.float64)
    exptime = column("exptime_s")
    predicted = _predicted(target, settings, exptime, column("airmass"))
    sigma = column("sigma_v_kms")
    bad = np.flatnonzero(~(sigma > 0))
    if bad.size:
        row = int(np.flatnonzero(rows)[bad[0]]) + 1
        raise InputError(
            f"observed {path}: row {row}, column sigma_v_kms: expected the measured σ_v of the "
            f"spectrum taken (km/s, > 0), got {sigma[bad[0]]:g}; fill it in",
            parameter="observed",
        )
    return ObservedSpectra(target.name, tau, column("lambda_k"), sigma, predicted, str(path))


def sigma_v_note(settings: PlanSettings) -> str | None:
    """The measured σ_v of the spectra taken against the law's, and the factor the remainder
    is planned with, in one line (None without observed spectra)."""
    from ucbplan.observing.precision.observed import SIGMA_V_RATIO_TOL, sigma_v_ratio

    spectra = settings.observed
    if not spectra:
        return None
    measured = np.concatenate([s.sigma_v_kms for s in spectra])
    predicted = np.concatenate([s.predicted_kms for s in spectra])
    ratio = sigma_v_ratio(measured, predicted)
    scale = settings.sigma_v_scale
    if scale == 1.0 and _as_planned(measured, predicted):
        return (
            f"{measured.size} spectra carry the plan's σ_v, not measured ones: the law is kept "
            "(fill in sigma_v_kms)"
        )
    if not math.isfinite(ratio):
        text = "no σ_v law prediction to compare with (no exposure times)"
    else:
        text = f"median measured/predicted σ_v = {ratio:.3g} over {measured.size} spectra"
    if scale == 1.0 and math.isfinite(ratio) and abs(ratio - 1) <= SIGMA_V_RATIO_TOL:
        plan = f"within {SIGMA_V_RATIO_TOL:.0%} of the law: the law is kept"
    elif scale == ratio:
        plan = f"the remainder is planned with the σ_v law × {scale:.3g}"
    else:
        plan = f"`sigma_v_scale={scale:g}`: the remainder is planned with the σ_v law × {scale:g}"
    return f"{text}; {plan}"


#: Relative difference below which a σ_v read back equals the law's prediction: the spectra carry
#: the plan's own σ_v (a blocks table or an observing log), not measured ones.
_AS_PLANNED_RTOL = 1e-6


def _as_planned(measured: np.ndarray, predicted: np.ndarray) -> bool:
    """Whether every σ_v read equals the law's prediction for its spectrum (none measured)."""
    known = np.isfinite(predicted)
    return bool(known.all()) and bool(
        np.all(np.abs(measured - predicted) <= _AS_PLANNED_RTOL * predicted)
    )
