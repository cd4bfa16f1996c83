"""The ``plan`` options as :class:`~ucbplan.observing.schedule.PlanSettings`: instrument,
overheads, exposure, visits and goal resolved in one place.

Overheads: an option the user gives (``--overhead`` = acquisition per visit or session,
``--readout`` per exposure) wins; else the instrument's number (``--instrument``); else the
defaults of the ``plan`` command before instruments existed (300 s acquisition, no readout;
when the exposure time is chosen, the shortest readout of the bundled spectrographs, said in a
note).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from ucbplan.errors import InputError
from ucbplan.observing.blocks.block import ExposurePlan
from ucbplan.observing.precision.instruments import (
    Instrument,
    check_exptime,
    instrument_or_none,
    instrument_overheads,
)
from ucbplan.observing.precision.sigma_v import SigmaVModel, parse_sigma_v
from ucbplan.observing.schedule.settings import (
    DEFAULT_MAX_VISIT_S,
    PlanSettings,
    parse_budgets,
    parse_duration,
)

#: Exposure time without ``--exptime`` [s].
DEFAULT_EXPTIME_S = 60.0
#: Acquisition without ``--overhead`` or ``--instrument`` [s].
DEFAULT_OVERHEAD_S = 300.0
#: Readout without ``--readout`` or ``--instrument`` [s].
DEFAULT_READOUT_S = 0.0
#: Readout assumed when the exposure time is chosen (σ_v follows it, ``30km/s@600s``) and
#: neither ``--readout`` nor ``--instrument`` gives one [s]: the shortest confirmed readout of
#: the bundled spectrographs (GMOS, 2×2 binning). With no readout the shortest exposure always
#: wins (the law has no read noise): 1-s exposures, thousands per visit (issue 33).
DEFAULT_LAW_READOUT_S = 24.0


def plan_settings(
    *,
    instrument: str | None = None,
    instruments_file: Path | str | None = None,
    exptime_s: float | None = None,
    n_exp: int = 1,
    readout_s: float | None = None,
    overhead_s: float | None = None,
    visit: str | float | None = None,
    max_visit: str | float | None = None,
    sigma_v_kms: str | float | None = None,
    sigma_floor_kms: float = 0.0,
    extinction_k: float | None = None,
    budgets: Sequence[str] = (),
    **options: Any,
) -> PlanSettings:
    """:class:`PlanSettings` from the ``plan`` options (module notes).

    ``instrument`` (``--instrument NAME``) is looked up in the bundled table, a user's
    ``instruments_file`` first. ``exptime_s``, ``n_exp``, ``readout_s``, ``overhead_s``: exposure
    time, exposures per block, readout and acquisition [s] (None: the instrument's, else the
    default). ``visit``, ``max_visit``: ``--visit`` and ``--max-visit`` durations (``1h``,
    ``45min``, ``3600s`` or seconds; a goal's longest visit defaults to 2 h). ``sigma_v_kms``:
    a number (km/s per exposure) or a law ``30km/s@600s[,V=20.0]``
    (:func:`~ucbplan.observing.precision.sigma_v.parse_sigma_v`), required with an instrument
    without a σ reference; ``sigma_floor_kms``: a floor in quadrature [km/s]; ``extinction_k``
    [mag/airmass]: the instrument's, else 0. ``budgets``: ``NAME=DURATION`` wall time per target.
    Every other :class:`PlanSettings` field comes by name in ``options``.

    Raises :class:`InputError` (one line each) for an unknown instrument, an instrument without
    σ_ref and no ``--sigma-v``, an overhead the instrument does not confirm and the user did not
    give, an exposure below the instrument's minimum, or a malformed duration.
    """
    inst = instrument_or_none(instrument, instruments_file)
    fixed, model = _sigma_v(sigma_v_kms, sigma_floor_kms, extinction_k, inst)
    if inst is not None and sigma_v_kms is None and inst.sigma_ref is None:
        raise InputError(
            f"instrument {inst.name}: the instrument table has no confirmed RV-precision "
            "reference (sigma_ref); pass `sigma_v` KM_S (sigma_v per exposure)"
        )
    assumed = model is not None and inst is None and readout_s is None
    acq, readout = _overheads(inst, overhead_s, DEFAULT_LAW_READOUT_S if assumed else readout_s)
    exptime = DEFAULT_EXPTIME_S if exptime_s is None else exptime_s
    if inst is not None:
        check_exptime(inst, exptime)
    visit_s, max_visit_s = _visits(visit, max_visit)
    return PlanSettings(
        exposure=ExposurePlan(exptime_s=exptime, n_exp=n_exp, readout_s=readout),
        overhead_s=acq,
        exptime_explicit=exptime_s is not None,
        readout_assumed=assumed,
        instrument=inst,
        visit_s=visit_s,
        max_visit_s=max_visit_s,
        sigma_v_kms=fixed,
        sigma_model=model,
        budgets=parse_budgets(list(budgets)),
        **options,
    )


def check_max_visit(max_visit: Any, goal: Any, *, compared: bool = False) -> None:
    """Refuse a ``max_visit`` nothing would use: it is the longest visit a goal plans (or, with
    ``compared``, a strategy comparison assumes); without either it would be ignored.

    Raises
    ------
    InputError
        One line naming ``max_visit``.
    """
    if max_visit is not None and goal is None and not compared:
        raise InputError(
            "max_visit: the longest visit a goal plans, and no goal is given: add a goal "
            "or leave it out",
            parameter="max_visit",
        )


def _visits(visit: str | float | None, max_visit: str | float | None) -> tuple[float | None, float]:
    """``visit`` and ``max_visit`` [s] (a goal's longest visit: 2 h unless given).

    Raises
    ------
    InputError
        For a malformed duration (an empty one too: it is not the default), or a maximum
        shorter than the visit (it would be dropped without a word).
    """
    visit_s = parse_duration(visit) if visit is not None else None
    if max_visit is None:
        return visit_s, DEFAULT_MAX_VISIT_S
    max_visit_s = parse_duration(max_visit, "max_visit")
    if visit_s is not None and max_visit_s < visit_s:
        raise InputError(
            f"max_visit: {max_visit_s:g} s is shorter than the visit ({visit_s:g} s), which "
            "sets every visit's length: give a longer maximum or leave it out"
        )
    return visit_s, max_visit_s


def _overheads(
    inst: Instrument | None, overhead_s: float | None, readout_s: float | None
) -> tuple[float, float]:
    """Acquisition and readout [s]: the given ones, else the instrument's, else the defaults."""
    if inst is not None:
        over = instrument_overheads(inst, acquisition_s=overhead_s, readout_s=readout_s)
        return over.acquisition_s, over.readout_s
    acq = DEFAULT_OVERHEAD_S if overhead_s is None else overhead_s
    return acq, DEFAULT_READOUT_S if readout_s is None else readout_s


def _sigma_v(
    text: str | float | None, floor_kms: float, extinction_k: float | None, inst: Instrument | None
) -> tuple[float | None, SigmaVModel | None]:
    """``--sigma-v`` as (fixed σ_v [km/s], exposure-time law): a bare number is the fixed σ_v it
    always was (with a floor in quadrature); a law is a :class:`SigmaVModel`."""
    if text is None:
        if floor_kms:
            raise InputError("sigma_floor: expected `sigma_v` as well (a floor of what?)")
        if extinction_k is not None:
            raise InputError("extinction: expected `sigma_v` 30km/s@600s as well")
        return None, None
    k = extinction_k
    if k is None:
        k = inst.extinction_k if inst is not None and inst.extinction_k is not None else 0.0
    model = parse_sigma_v(text, floor_kms=floor_kms, extinction_k=k)
    if not model.follows_exposure:
        if extinction_k is not None:
            raise InputError(
                "extinction: a fixed `sigma_v` does not scale with airmass; give a reference "
                "exposure (30km/s@600s)"
            )
        return float(model.sigma(1.0)), None  # (σ_v² + σ_sys²)^½, fixed per exposure
    return None, model
