"""A first ephemeris for counting cycles: ``--period P`` or ``--initial TARGET.yaml``.

Only the period (and, from a target file, T0 and Ṗ if given) is read. How well the guess is known
is taken from how it is written: one unit in its last written digit (``414.79 s`` → ±0.01 s,
``BJD_TDB 2458305.6827886`` → ±1e-7 d), so a guess with few digits is trusted over a short span
only and a count across a longer gap is refused as ambiguous rather than guessed. ``--period``
is taken as the period near the densest group of times (the counting starts there); a value with
more digits than hold there is caught when the counted times disagree with it. Without a Ṗ
(``--period``, or a file without ``pdot``) Ṗ = 0 ± :data:`PDOT_PRIOR_SIGMA` while counting.

The target file is read tolerantly: of its ``timing:`` block only ``t0``, ``period`` and ``pdot``
are used; every other field of the file is ignored here (the target's own reader checks them).
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from dataclasses import dataclass
from decimal import Decimal
from pathlib import Path
from typing import Any

from ucbplan.core.constants import DAY_S, HOUR_S
from ucbplan.core.timing_epochs import parse_decimal, parse_epoch_label
from ucbplan.errors import InputError, InputFileError, shorten
from ucbplan.inputs import load_yaml

#: Width of the Ṗ prior while counting cycles [s/s]: GW-driven |Ṗ| of a double white dwarf with
#: P > 5 min and chirp mass < 1 M☉ is < 3e-10, so 1e-9 is generous. Used only to count cycles.
PDOT_PRIOR_SIGMA = 1e-9
#: Accepted period range [s].
PERIOD_RANGE = (1e-3, 1e9)

_PERIOD_RE = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d{1,4})?)\s*([A-Za-z]*)\s*$")
_UNITS_S = {"": 1.0, "s": 1.0, "sec": 1.0, "min": 60.0, "h": HOUR_S, "hr": HOUR_S, "d": DAY_S}


@dataclass(frozen=True)
class PeriodGuess:
    """A first ephemeris: P (and T0, Ṗ) with the uncertainty implied by their digits.

    Attributes
    ----------
    period_s, sigma_period_s : float
        Period and its uncertainty [s].
    t0_jd : Decimal or None
        Primary eclipse epoch (exact JD, TDB), or None.
    sigma_t0_s : float
        Uncertainty of ``t0_jd`` [s] (0 without T0).
    pdot, sigma_pdot : float
        Ṗ [s/s] (0 if not given) and the width of its prior.
    origin : str
        Where the guess came from, for messages (``--period`` or ``--initial FILE``).
    """

    period_s: float
    sigma_period_s: float
    t0_jd: Decimal | None = None
    sigma_t0_s: float = 0.0
    pdot: float = 0.0
    sigma_pdot: float = PDOT_PRIOR_SIGMA
    origin: str = "--period"


def _last_digit(d: Decimal) -> Decimal:
    """One unit in the last written digit of ``d`` (``414.79`` → 0.01)."""
    return Decimal(1).scaleb(int(d.as_tuple().exponent))


def parse_period(value: Any, what: str = "period") -> tuple[float, float]:
    """A period text (``"414.7915404 s"``, ``"6.9 min"``, ``0.0048 d``, a bare number: seconds)
    as (P [s], σ_P [s] = one unit in the last digit).

    Raises
    ------
    InputError
        Not a positive time in (1e-3, 1e9] s.
    """
    if isinstance(value, bool) or not isinstance(value, str | int | float):
        raise InputError(
            f'{what}: expected a period like "414.7915404 s", got {shorten(value, 60)}'
        )
    text = repr(value) if isinstance(value, float) else str(value)
    m = _PERIOD_RE.match(text)
    unit = m.group(2).lower() if m else ""
    if m is None or unit not in _UNITS_S:
        raise InputError(
            f'{what}: expected a period like "414.7915404 s" (units s, min, h, d), got '
            f"{shorten(value, 60)}"
        )
    num = parse_decimal(m.group(1))
    period = float(num) * _UNITS_S[unit]
    if not (math.isfinite(period) and PERIOD_RANGE[0] < period <= PERIOD_RANGE[1]):
        raise InputError(
            f"{what}: expected a positive period in ({PERIOD_RANGE[0]:g}, {PERIOD_RANGE[1]:g}] s, "
            f"got {shorten(value, 60)}"
        )
    return period, float(_last_digit(num)) * _UNITS_S[unit]


def period_guess(value: str, what: str = "period") -> PeriodGuess:
    """A :class:`PeriodGuess` from a ``--period`` text (errors name ``what``)."""
    p, sp = parse_period(value, what)
    return PeriodGuess(period_s=p, sigma_period_s=sp, origin="--period")


def read_initial(path: Path | str) -> PeriodGuess:
    """P (and T0, Ṗ) from the ``timing:`` block of a target file.

    Raises
    ------
    InputFileError
        No ``timing:`` block or period, or a malformed t0/period/pdot (the field named).
    """
    path = Path(path)
    return guess_from_document(load_yaml(path, "target file"), path.name)


def guess_from_document(doc: Any, label: str) -> PeriodGuess:
    """P (and T0, Ṗ) from the ``timing:`` block of a target document named ``label``.

    Raises
    ------
    InputFileError
        As :func:`read_initial`.
    """
    timing = doc.get("timing") if isinstance(doc, Mapping) else None
    if not isinstance(timing, Mapping):
        raise InputFileError(
            f"{label}: timing: missing; `initial` needs a target file with a timing: block "
            "(t0, period[, pdot]), or give `period`"
        )
    if "period" not in timing:
        raise InputFileError(f'{label}: timing.period: missing; add e.g. period: "414.79 s"')
    try:
        period, sigma_p = parse_period(timing["period"], f"{label}: timing.period")
    except InputError as exc:
        raise InputFileError(str(exc)) from None
    t0_jd, sigma_t0 = _initial_t0(timing.get("t0"), label)
    pdot, sigma_pdot = _initial_pdot(timing.get("pdot"), label)
    return PeriodGuess(
        period_s=period,
        sigma_period_s=sigma_p,
        t0_jd=t0_jd,
        sigma_t0_s=sigma_t0,
        pdot=pdot,
        sigma_pdot=sigma_pdot,
        origin=f"--initial {label}",
    )


def _initial_t0(raw_t0: Any, label: str) -> tuple[Decimal | None, float]:
    """T0 [JD, exact] and one unit in its last digit [s] of ``timing.t0`` (None, 0 if absent).

    Raises
    ------
    InputFileError
        ``timing.t0`` is not a labelled epoch.
    """
    if raw_t0 is None:
        return None, 0.0
    if not isinstance(raw_t0, str):
        raise InputFileError(
            f'{label}: timing.t0: expected a labelled epoch like "BJD_TDB 2458305.6827886", '
            f"got {shorten(raw_t0, 60)}"
        )
    try:
        t0_jd = parse_epoch_label(raw_t0, f"{label}: timing.t0")
    except InputError as exc:
        raise InputFileError(str(exc)) from None
    return t0_jd, _t0_digits_s(raw_t0)


def _initial_pdot(raw_pdot: Any, label: str) -> tuple[float, float]:
    """Ṗ and one unit in its last digit of ``timing.pdot`` (0 and the prior σ if absent).

    Raises
    ------
    InputFileError
        ``timing.pdot`` is not a number, or |Ṗ| ≥ 1e-3 s/s.
    """
    if raw_pdot is None:
        return 0.0, PDOT_PRIOR_SIGMA
    try:
        if isinstance(raw_pdot, bool):
            raise ValueError
        pdot_dec = parse_decimal(repr(raw_pdot) if isinstance(raw_pdot, float) else str(raw_pdot))
        pdot, sigma_pdot = float(pdot_dec), float(_last_digit(pdot_dec))
    except (ValueError, ArithmeticError):
        raise InputFileError(
            f"{label}: timing.pdot: expected a number (s/s) like -2.373e-11, got "
            f"{shorten(raw_pdot, 60)}"
        ) from None
    if not (math.isfinite(pdot) and abs(pdot) < 1e-3):
        raise InputFileError(
            f"{label}: timing.pdot: expected |Ṗ| < 1e-3 s/s, got {shorten(raw_pdot, 60)}"
        )
    return pdot, sigma_pdot


def _t0_digits_s(text: str) -> float:
    """One unit in the last digit of a labelled epoch, in seconds."""
    parts = text.split()
    if len(parts) == 2 and not re.match(r"^\d{4}-", parts[0]):
        return float(_last_digit(parse_decimal(parts[1]))) * DAY_S
    m = re.search(r"\d\d:\d\d(:\d\d(\.(\d+))?)?", text)  # ISO: the last digit of its clock
    if m is None:
        return float(DAY_S)
    if m.group(3):
        return 10.0 ** -len(m.group(3))
    return 1.0 if m.group(1) else 60.0
