"""Spectrograph configurations (overheads, extinction, RV precision) and σ_v per exposure.

The bundled table is ``ucbplan/data/instruments.yaml`` (identical to ``configs/instruments.yaml``);
a user file with the same schema is read with :func:`load_instruments` ``(path)`` and searched
before the bundled table by :func:`get_instrument`. Every field the table could not confirm from a
citable source is left out and named under ``missing:``; it is ``None`` in :class:`Instrument`.

σ_v per exposure is photon-limited (:func:`sigma_v_kms`):

    σ_v = σ_ref · 10^{0.2 (m − m_ref)} · (t / t_ref)^{−1/2} · 10^{0.2 k (X − 1)}

with (σ_ref, m_ref, t_ref) the instrument's reference (``sigma_ref``), m the target's magnitude in
the reference band, t the exposure time, X the airmass and k the extinction [mag/airmass]: the
flux falls as 10^{−0.4(m + kX)}, the photon noise of a velocity as flux^{−1/2}.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ucbplan.core.constants import HOUR_S
from ucbplan.errors import InputError, InputFileError, shorten
from ucbplan.inputs import load_yaml

#: Where the bundled table lives inside the package.
BUNDLED = "ucbplan/data/instruments.yaml"

#: Fields that are either given or named under ``missing:``.
#: The shortest exposure the σ_v law is evaluated for [s]: a millisecond, below any spectrograph's
#: shutter (a subnormal exposure time would overflow the law's √(t_ref/t)).
MIN_EXPOSURE_S = 1e-3
OPTIONAL_NUMBERS = ("acquisition_s", "readout_s", "min_exptime_s", "extinction_k")
#: Open physical ranges (lo, hi) of the numeric fields.
RANGES = {
    "acquisition_s": (0.0, HOUR_S),
    "readout_s": (0.0, 600.0),
    "min_exptime_s": (0.0, HOUR_S),
    "extinction_k": (0.0, 1.0),
}
SIGMA_REF_RANGES = {"sigma_v_kms": (0.0, 200.0), "mag": (10.0, 25.0), "exptime_s": (0.0, 36000.0)}
KNOWN_KEYS = frozenset(
    {
        *OPTIONAL_NUMBERS,
        "telescope",
        "sites",
        "readout_mode",
        "extinction_band",
        "sigma_ref",
        "missing",
        "notes",
        "sources",
        "exptime_step_s",
    }
)
#: Range of the optional exposure-time granularity ``exptime_step_s`` (exposure times the
#: instrument accepts are its multiples; 1 s when absent) [s].
EXPTIME_STEP_RANGE = (0.0, 600.0)
#: Largest airmass σ_v is scaled to (beyond, the plane-parallel extinction law is meaningless).
MAX_AIRMASS = 40.0
#: Open range of target magnitudes accepted [mag].
MAG_RANGE = (-30.0, 40.0)
MISSABLE = frozenset({*OPTIONAL_NUMBERS, "sigma_ref"})

F64 = NDArray[np.float64]


@dataclass(frozen=True)
class SigmaRef:
    """RV precision reference: σ_v [km/s] of one ``exptime_s`` exposure at ``mag`` in ``band``."""

    sigma_v_kms: float
    mag: float
    band: str
    exptime_s: float


@dataclass(frozen=True)
class Instrument:
    """One spectrograph configuration; ``None`` = not confirmed (named in ``missing``)."""

    name: str
    telescope: str
    sites: tuple[str, ...]
    acquisition_s: float | None
    readout_s: float | None
    min_exptime_s: float | None
    extinction_k: float | None
    sigma_ref: SigmaRef | None
    extinction_band: str | None = None
    readout_mode: str | None = None
    missing: tuple[str, ...] = ()
    sources: Mapping[str, str] = field(default_factory=dict, hash=False, compare=False)
    exptime_step_s: float | None = None


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


def _number(where: str, key: str, value: Any, lo: float, hi: float, unit: str) -> float:
    if not _is_number(value) or not lo < value < hi:
        raise InputFileError(
            f"{where}: {key}: expected a number in ({lo:g}, {hi:g}) {unit}, "
            f"got {shorten(value, 60)}"
        )
    return float(value)


def _sigma_ref(where: str, value: Any) -> SigmaRef:
    where = f"{where}: sigma_ref"
    if not isinstance(value, dict):
        raise InputFileError(
            f"{where}: expected a mapping {{sigma_v_kms, mag, band, exptime_s}}, "
            f"got {shorten(value, 60)}"
        )
    extra = sorted(set(value) - {*SIGMA_REF_RANGES, "band"})
    if extra:
        raise InputFileError(
            f"{where}: unknown field {shorten(extra[0], 40)}; "
            "expected sigma_v_kms, mag, band, exptime_s"
        )
    units = {"sigma_v_kms": "km/s", "mag": "mag", "exptime_s": "s"}
    nums = {}
    for key, (lo, hi) in SIGMA_REF_RANGES.items():
        if key not in value:
            raise InputFileError(f"{where}: {key}: expected a number ({units[key]}), got nothing")
        nums[key] = _number(where, key, value[key], lo, hi, units[key])
    band = value.get("band")
    if not isinstance(band, str) or not band.strip():
        raise InputFileError(
            f"{where}: band: expected a photometric band name such as V, got {shorten(band, 40)}"
        )
    return SigmaRef(nums["sigma_v_kms"], nums["mag"], band.strip(), nums["exptime_s"])


def _instrument(name: Any, entry: Any, source: str) -> Instrument:
    where = f"{source}: instruments.{name}"
    if not isinstance(name, str) or not name:
        raise InputFileError(f"{source}: instruments: expected names as keys, got {shorten(name)}")
    if not isinstance(entry, dict):
        raise InputFileError(f"{where}: expected a mapping of fields, got {shorten(entry, 60)}")
    unknown = sorted(str(k) for k in set(entry) - KNOWN_KEYS)
    if unknown:
        raise InputFileError(
            f"{where}: unknown field {shorten(unknown[0], 40)}; known fields: "
            f"{', '.join(sorted(KNOWN_KEYS))}"
        )
    telescope, sites = _telescope_sites(where, entry)
    missing = _missing(where, entry)
    nums: dict[str, float | None] = {}  # the values given first: a bad one is the news
    for key in OPTIONAL_NUMBERS:
        lo, hi = RANGES[key]
        unit = "mag/airmass" if key == "extinction_k" else "s"
        nums[key] = _number(where, key, entry[key], lo, hi, unit) if key in entry else None
    ref = _sigma_ref(where, entry["sigma_ref"]) if "sigma_ref" in entry else None
    _check_missable(where, entry, missing)
    sources = entry.get("sources", {})
    if not isinstance(sources, dict) or not all(isinstance(v, str) for v in sources.values()):
        raise InputFileError(f"{where}: sources: expected a mapping field: text")
    band, mode = entry.get("extinction_band"), entry.get("readout_mode")
    step = entry.get("exptime_step_s")
    if step is not None:
        step = _number(where, "exptime_step_s", step, *EXPTIME_STEP_RANGE, "s")
    return Instrument(
        name=name,
        telescope=telescope,
        sites=sites,
        acquisition_s=nums["acquisition_s"],
        readout_s=nums["readout_s"],
        min_exptime_s=nums["min_exptime_s"],
        extinction_k=nums["extinction_k"],
        sigma_ref=ref,
        extinction_band=str(band) if band is not None else None,
        readout_mode=str(mode) if mode is not None else None,
        missing=missing,
        sources=MappingProxyType({str(k): v for k, v in sources.items()}),
        exptime_step_s=step,
    )


def _telescope_sites(where: str, entry: dict[str, Any]) -> tuple[str, tuple[str, ...]]:
    """The entry's telescope name (stripped) and its site names."""
    telescope = entry.get("telescope")
    if not isinstance(telescope, str) or not telescope.strip():
        raise InputFileError(f"{where}: telescope: expected a name, got {shorten(telescope, 60)}")
    sites = entry.get("sites")
    if not isinstance(sites, list) or not sites or not all(isinstance(s, str) and s for s in sites):
        raise InputFileError(
            f"{where}: sites: expected a list of site names such as [paranal], "
            f"got {shorten(sites, 60)}"
        )
    return telescope.strip(), tuple(sites)


def _missing(where: str, entry: dict[str, Any]) -> tuple[str, ...]:
    """The fields the entry names under ``missing`` (each one of :data:`MISSABLE`)."""
    missing = entry.get("missing", [])
    if not isinstance(missing, list) or not all(isinstance(m, str) for m in missing):
        raise InputFileError(f"{where}: missing: expected a list of field names")
    bad = sorted(set(missing) - MISSABLE)
    if bad:
        raise InputFileError(
            f"{where}: missing: expected names among {', '.join(sorted(MISSABLE))}, "
            f"got {shorten(bad[0], 40)}"
        )
    return tuple(missing)


def _check_missable(where: str, entry: dict[str, Any], missing: tuple[str, ...]) -> None:
    """Each missable field is given or listed under ``missing``, never both, never neither."""
    for key in sorted(MISSABLE):
        if (key in entry) == (key in missing):
            state = "both given and" if key in entry else "neither given nor"
            raise InputFileError(
                f"{where}: {key}: {state} listed under missing; give it (with its source) "
                "or name it under missing"
            )


def _parse(doc: Any, source: str) -> dict[str, Instrument]:
    if not isinstance(doc, dict) or not isinstance(doc.get("instruments"), dict):
        raise InputFileError(
            f"{source}: instruments: expected a top-level mapping 'instruments:' of "
            "name: {telescope, sites, ...}"
        )
    if not doc["instruments"]:
        raise InputFileError(f"{source}: instruments: expected at least one instrument, got none")
    extra = sorted(str(k) for k in set(doc) - {"instruments"})
    if extra:
        raise InputFileError(f"{source}: unknown top-level field {shorten(extra[0], 40)}")
    return {
        str(name): _instrument(name, entry, source) for name, entry in doc["instruments"].items()
    }


def load_instruments(path: Path | str | None = None) -> dict[str, Instrument]:
    """Load an instrument table: the bundled one (default) or a user YAML file (same schema).

    Raises
    ------
    InputFileError
        Unreadable or malformed file; one line naming the file and field.
    """
    if path is None:
        text = resources.files("ucbplan").joinpath("data/instruments.yaml").read_text("utf-8")
        return _parse(load_yaml(Path(BUNDLED), "instrument table", text=text), BUNDLED)
    path = Path(path)
    return _parse(load_yaml(path, "instrument table"), str(path))


def instrument_or_none(
    name: str | None, instruments_file: Path | str | None = None
) -> Instrument | None:
    """:func:`get_instrument` of ``--instrument NAME``, or None without a name.

    Raises
    ------
    InputError
        An instruments file without a name (it would be silently ignored), or as
        :func:`get_instrument`.
    """
    if name is None:
        if instruments_file is not None:
            raise InputError(
                f"instruments_file {shorten(str(instruments_file), 60)}: read only with "
                "`instrument` NAME; add `instrument` or drop the file"
            )
        return None
    return get_instrument(name, instruments_file)


def get_instrument(name: str, instruments_file: Path | str | None = None) -> Instrument:
    """Look an instrument up by name (case-insensitive); a user file is searched first.

    Raises
    ------
    InputError
        Unknown name: one line listing the known names, with a did-you-mean.
    """
    table = {
        **load_instruments(),
        **(load_instruments(instruments_file) if instruments_file else {}),
    }
    key = str(name).strip().lower()
    if key in table:
        return table[key]
    known = sorted(table)
    close = difflib.get_close_matches(key, known, n=1, cutoff=0.5)
    hint = f"did you mean {close[0]!r}? " if close else ""
    raise InputError(
        f"instrument: unknown instrument {shorten(name, 40)}; {hint}known: {', '.join(known)}; "
        "or give `instruments_file` FILE"
    )


def instrument_magnitude(instrument: Instrument, magnitudes: Mapping[str, float]) -> float:
    """The target's magnitude in the band of the instrument's σ_ref.

    Raises
    ------
    InputError
        No σ_ref (pass --sigma-v), or the target has no magnitude in that band.
    """
    ref = _require_ref(instrument)
    for band, mag in magnitudes.items():
        if band.strip().lower() == ref.band.lower():
            return float(mag)
    have = ", ".join(magnitudes) or "none"
    raise InputError(
        f"magnitudes: expected a {ref.band} magnitude (the band of {instrument.name}'s σ_ref), "
        f"got {have}; add magnitudes: {{{ref.band}: ...}} to the target file or pass `sigma_v`"
    )


def _require_ref(instrument: Instrument) -> SigmaRef:
    if instrument.sigma_ref is None:
        raise InputError(
            f"instrument {instrument.name}: no confirmed RV-precision reference (sigma_ref) "
            "in the instrument table; pass `sigma_v` KM_S (σ_v per exposure)"
        )
    return instrument.sigma_ref


def sigma_v_kms(
    instrument: Instrument,
    mag: float,
    exptime_s: ArrayLike,
    airmass: ArrayLike = 1.0,
    *,
    override_kms: float | None = None,
) -> F64:
    """σ_v per exposure [km/s], photon-limited (module notes); vectorised over time and airmass.

    ``override_kms`` (``--sigma-v``) replaces the scaling: returned, broadcast, as it is.

    Raises
    ------
    InputError
        No σ_ref and no override (pass --sigma-v); no extinction_k while an airmass > 1 is
        asked for; non-positive exposure time or airmass < 1.
    """
    t = np.asarray(exptime_s, dtype=np.float64)
    x = np.asarray(airmass, dtype=np.float64)
    if override_kms is not None:
        if not _is_number(override_kms) or override_kms <= 0:
            raise InputError(f"sigma_v: expected a positive number [km/s], got {override_kms!r}")
        return np.broadcast_to(np.float64(override_kms), np.broadcast(t, x).shape).copy()
    ref = _require_ref(instrument)
    if not np.all(np.isfinite(t)) or np.any(t <= 0):
        raise InputError(f"exptime: expected positive seconds, got {shorten(t.tolist(), 60)}")
    if np.any(t < MIN_EXPOSURE_S):
        raise InputError(
            f"exptime: expected seconds ≥ {MIN_EXPOSURE_S:g} (no spectrograph exposes shorter), "
            f"got {shorten(t.tolist(), 60)}"
        )
    if not np.all(np.isfinite(x)) or np.any(x < 1.0) or np.any(x > MAX_AIRMASS):
        raise InputError(
            f"airmass: expected a number in [1, {MAX_AIRMASS:g}], got {shorten(x.tolist(), 60)}"
        )
    if not _is_number(mag) or not MAG_RANGE[0] < mag < MAG_RANGE[1]:
        raise InputError(
            f"magnitude: expected a number in ({MAG_RANGE[0]:g}, {MAG_RANGE[1]:g}) mag, "
            f"got {shorten(mag, 40)}"
        )
    k = instrument.extinction_k
    if k is None:
        if np.any(x > 1.0):
            raise InputError(
                f"instrument {instrument.name}: extinction_k is not in the instrument table, so "
                "σ_v cannot be scaled with airmass; add it in an `instruments_file` or pass "
                "`sigma_v`"
            )
        k = 0.0
    return np.asarray(
        ref.sigma_v_kms
        * 10.0 ** (0.2 * (float(mag) - ref.mag))
        * np.sqrt(ref.exptime_s / t)
        * 10.0 ** (0.2 * k * (x - 1.0)),
        dtype=np.float64,
    )


@dataclass(frozen=True)
class Overheads:
    """Acquisition per visit and readout per exposure [s] in force, and where each came from."""

    acquisition_s: float
    readout_s: float
    acquisition_from: str
    readout_from: str


def instrument_overheads(
    instrument: Instrument | None,
    *,
    acquisition_s: float | None = None,
    readout_s: float | None = None,
) -> Overheads:
    """Overheads in force: an option the user gave (``--overhead``, ``--readout``) wins, else the
    instrument's number.

    Raises
    ------
    InputError
        The instrument table has no confirmed number (named under ``missing``) and the user gave
        none: one line naming the option to pass.
    """

    def pick(value: float | None, key: str, option: str) -> tuple[float, str]:
        if value is not None:
            if not _is_number(value) or value < 0:
                raise InputError(f"{option}: expected seconds >= 0, got {shorten(value, 40)}")
            return float(value), option
        table = getattr(instrument, key) if instrument is not None else None
        if table is None:
            if instrument is None:
                raise InputError(f"{option}: expected seconds (no `instrument` given), got none")
            raise InputError(
                f"instrument {instrument.name}: {key} is not confirmed in the instrument table; "
                f"pass `{option}` SECONDS"
            )
        return float(table), f"instrument {instrument.name}" if instrument else option

    acq, acq_from = pick(acquisition_s, "acquisition_s", "overhead")
    ro, ro_from = pick(readout_s, "readout_s", "readout")
    return Overheads(acq, ro, acq_from, ro_from)


def check_exptime(instrument: Instrument, exptime_s: float) -> None:
    """Refuse an exposure shorter than the instrument's minimum (when the table has one).

    Raises
    ------
    InputError
        One line naming the minimum.
    """
    low = instrument.min_exptime_s
    if low is not None and exptime_s < low:
        raise InputError(
            f"exptime: expected at least {low:g} s (minimum of {instrument.name}), "
            f"got {exptime_s:g} s"
        )
