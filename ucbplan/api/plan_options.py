"""The options of :func:`ucbplan.plan`, declared once: their flags and help (:data:`PLAN_FLAGS`),
their old names, and their conversion into the planner's settings.

The defaults and units are in :func:`ucbplan.plan`'s signature and numpydoc; the command line
derives its ``plan`` options from both (:mod:`ucbplan.cli._derive`). This module imports
nothing heavy at module level: the command line reads it at start-up.
"""

from __future__ import annotations

import functools
import inspect
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

from ucbplan.api._convert import as_float
from ucbplan.api.flagspec import Flag
from ucbplan.errors import InputError, shorten

if TYPE_CHECKING:
    from ucbplan.observing.schedule import PlanSettings

F = TypeVar("F", bound=Callable[..., Any])


class PlanDefault(float):
    """A number left at its default: equal to the default, but not the same object as a
    caller's equal number (``exptime=60.0`` given is the user's choice; left out, ucbplan's)."""

    __slots__ = ()


#: The exposure time ``plan`` takes when none is given [s] (capped at the smearing floor, or
#: chosen for information per hour when σ_v follows the exposure time); equal to the planner's
#: ``DEFAULT_EXPTIME_S`` (a test keeps them equal: the planner is not imported at start-up).
DEFAULT_EXPTIME = PlanDefault(60.0)

_DEG, _S, _KMS = "deg", "s", "km/s"

#: ``plan``'s options as the command line spells them: flag and ``--help`` text.
PLAN_FLAGS: dict[str, Flag] = {
    "targets": Flag((), "Target YAML files."),
    "site": Flag(("--site",), "Site name or alias (e.g. paranal)."),
    "site_lonlat": Flag(
        ("--site-lonlat",), "LON,LAT,HEIGHT (deg east, deg north, m) instead of --site."
    ),
    "sites_file": Flag(("--sites-file",), "YAML site table searched before the bundled one."),
    "night": Flag(("--night",), "Local date of the first evening, YYYY-MM-DD."),
    "nights": Flag(("--nights",), "Number of consecutive nights."),
    "mode": Flag(
        ("--mode",),
        "quadrature | conjunction | zero-crossing | fixed-u-pairs | quadrature+conjunction "
        "| u=VALUE [rad].",
    ),
    "twilight": Flag(("--twilight",), "civil | nautical | astronomical"),
    "airmass_max": Flag(("--airmass-max",), "Largest airmass (sec z)."),
    "moon_sep": Flag(("--moon-sep",), "Smallest Moon separation [deg].", _DEG),
    "moon_illum": Flag(
        ("--moon-illum",), "Largest Moon illuminated fraction (0-1) while the Moon is up."
    ),
    "zenith_hole": Flag(
        ("--zenith-hole",), "Zenith-hole radius [deg] (default: the site's; 0 = none).", _DEG
    ),
    "exptime": Flag(("--exptime",), "Single-exposure time [s].", _S),
    "n_exp": Flag(("--n-exp",), "Exposures per block (co-added)."),
    "readout": Flag(
        ("--readout",),
        "Readout after each exposure [s] (default: the instrument's, else 0; 24 when the "
        "--sigma-v law chooses the exposure time).",
        _S,
    ),
    "alpha": Flag(("--alpha",), "Planning margin α of T_valid."),
    "sigma_v": Flag(
        ("--sigma-v",),
        "RV precision: km/s fixed per exposure (30), or of one spectrum of T_ref seconds "
        "(30km/s@600s; ,V=20.0 at that magnitude): then exposure time and cadence are chosen.",
        _KMS,
    ),
    "sigma_floor": Flag(
        ("--sigma-floor",), "Systematic σ_v floor added in quadrature [km/s].", _KMS
    ),
    "extinction": Flag(
        ("--extinction",),
        "Extinction k [mag/airmass] of the σ_v law (default: the instrument's, else 0).",
    ),
    "k_eff": Flag(("--k-eff",), "Semi-amplitude K_eff [km/s].", _KMS),
    "max_smear": Flag(
        ("--max-smear",), "Smearing budget: '0.5*sigma_v' or km/s; exceeded = error.", _KMS
    ),
    "max_bin_fraction": Flag(("--max-bin-fraction",), "Largest block span as a fraction of P_b."),
    "overhead": Flag(
        ("--overhead",),
        "Slew + acquisition before each visit or session [s] (default: the instrument's, "
        "else 300).",
        _S,
    ),
    "sessions": Flag(("--sessions",), "Sessions per target and night."),
    "visit": Flag(
        ("--visit",),
        "Plan visits of this length (1h, 45min, 3600s; acquisition included): one "
        "acquisition, then exposures each centred on an anchor.",
        _S,
    ),
    "max_visit": Flag(("--max-visit",), "Longest visit a --goal plans (default 2h).", _S),
    "cadence": Flag(
        ("--cadence",),
        "auto (most information per visit) | targeted (each exposure on an anchor) | "
        "phase-locked (exposure + readout = anchor spacing) | untargeted (back to back).",
    ),
    "service_mode": Flag(
        ("--service-mode",),
        "Plan only what a service-mode queue executes: visits of back-to-back exposures "
        "(phase-locked or untargeted cadence).",
    ),
    "instrument": Flag(
        ("--instrument",), "Spectrograph (e.g. xshooter-vis, uves, esi): overheads."
    ),
    "instruments_file": Flag(
        ("--instruments-file",), "YAML instrument table searched before the bundled."
    ),
    "goal": Flag(
        ("--goal",), "Precision goal (sigma_K=2km/s, K1=1%, q=1%): plan the spectra it needs."
    ),
    "observed": Flag(
        ("--observed",),
        "Spectra already taken: a velocities file (epochs, exposure times, measured σ_v) or a "
        "blocks table with a status column (taken | missed | skipped); the goal plans the rest.",
    ),
    "sigma_v_scale": Flag(
        ("--sigma-v-scale",),
        "Factor on the σ_v law (default: the measured/predicted σ_v of --observed when it "
        "differs by more than 5 %; 1 keeps the law).",
    ),
    "min_lambda_k": Flag(
        ("--min-lambda-k",),
        "Smallest smearing factor Λ_K of an exposure (default 0.9 with --visit).",
    ),
    "allow_smeared": Flag(("--allow-smeared",), "Plan exposures below the Λ_K floor."),
    "budgets": Flag(
        ("--budget",), "NAME=DURATION: wall time a target may get over all nights (e.g. 2h)."
    ),
    "priorities": Flag(
        ("--priority",), "NAME=P overrides a target file's priority (higher first)."
    ),
    "timezone": Flag(("--tz",), "IANA time zone replacing the site's (e.g. America/Santiago)."),
}

#: Names the options had before issue 30 (``**options`` of the planner's settings) → the
#: keyword of :func:`ucbplan.plan` that replaces each; the number means the same (unit
#: included), so the old name keeps working.
OLD_NAMES = {
    "exptime_s": "exptime",
    "readout_s": "readout",
    "overhead_s": "overhead",
    "max_visit_s": "max_visit",
    "visit_s": "visit",
    "sigma_v_kms": "sigma_v",
    "sigma_floor_kms": "sigma_floor",
    "extinction_k": "extinction",
    "k_eff_kms": "k_eff",
    "moon_sep_deg": "moon_sep",
    "moon_illum_max": "moon_illum",
    "zenith_hole_deg": "zenith_hole",
    "sessions_per_night": "sessions",
}


def accept_old_names(func: F) -> F:
    """``func`` taking :data:`OLD_NAMES` as aliases of its keywords; an unknown keyword (or a
    keyword given under both names) is one :class:`InputError` naming it, not a TypeError."""
    known = list(inspect.signature(func).parameters)

    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        return func(*args, **renamed(kwargs, known, func.__name__))

    return wrapper  # type: ignore[return-value]


def renamed(kwargs: dict[str, Any], known: Sequence[str], where: str) -> dict[str, Any]:
    """``kwargs`` with old names replaced by the new ones (see :func:`accept_old_names`)."""
    from ucbplan.targets.values import did_you_mean

    out: dict[str, Any] = {}
    for key, value in kwargs.items():
        new = OLD_NAMES.get(key, key)
        if new not in known:
            hint = did_you_mean(key, [*known, *(k for k, v in OLD_NAMES.items() if v in known)])
            raise InputError(
                f"{key}: not an option of ucbplan.{where}; {hint}see help(ucbplan.{where})",
                parameter=key,
            )
        if new in out or (new != key and new in kwargs):
            raise InputError(
                f"{key}, {new}: one option under two names; give {new} only", parameter=new
            )
        out[new] = value
    return out


def _duration(value: Any, parameter: str) -> Any:
    """A duration as the planner takes it: text (``1h``) unchanged, a Quantity in seconds."""
    return as_float(value, _S, parameter)


def checked_text(value: Any, parameter: str, what: str) -> str | None:
    """``value`` if it is None or text, else one line naming ``parameter``."""
    if value is None or isinstance(value, str):
        return value
    raise InputError(f"{parameter}: expected {what}, got {shorten(value, 40)}", parameter=parameter)


def _path(value: Any, parameter: str) -> Path | None:
    """``value`` (None, text or a path) as a path."""
    if value is None or isinstance(value, Path):
        return value
    return Path(checked_text(value, parameter, "a file path") or "")


def _budgets(value: Any) -> list[Any]:
    """``budgets`` as the planner's items: ``NAME=DURATION`` text or (name, duration) pairs."""
    if value is None:
        return []
    if isinstance(value, Mapping):
        return [(k, _duration(v, "budgets")) for k, v in value.items()]
    if isinstance(value, str) or not isinstance(value, Sequence):
        raise InputError(
            "budgets: expected NAME=DURATION items or a {name: duration} mapping, got "
            f"{shorten(value, 60)}",
            parameter="budgets",
        )
    return list(value)


def checked_flag(value: Any, parameter: str) -> bool:
    """``value`` if it is True or False, else one line naming ``parameter``."""
    if not isinstance(value, bool):
        raise InputError(
            f"{parameter}: expected True or False, got {shorten(value, 40)}", parameter
        )
    return value


def _sigma_v(value: Any) -> Any:
    """``sigma_v``: a law's text unchanged, a Quantity in km/s, a number as it is."""
    return as_float(value, _KMS, "sigma_v")


def _max_smear(value: Any) -> Any:
    """``max_smear``: text unchanged; a speed (Quantity, or a number of km/s) as its text."""
    value = as_float(value, _KMS, "max_smear")
    if isinstance(value, int | float) and not isinstance(value, bool):
        return f"{float(value)!r} km/s"
    return value


def settings_from(o: Mapping[str, Any], constraints: tuple[Any, ...] | None) -> PlanSettings:
    """The planner's settings from ``plan``'s keywords ``o`` (units converted, types checked),
    and ``constraints`` (already checked) replacing the constraint options.

    Raises
    ------
    InputError
        One line naming the keyword at fault (as ``plan`` spells it, not as the planner does).
    """
    try:
        return _settings(o, constraints)
    except InputError as exc:
        _rename_parameter(exc)
        raise


def _rename_parameter(exc: InputError) -> None:
    """``exc`` naming the planner's field (``sigma_v_kms: …``) made to name ``plan``'s keyword
    (``sigma_v: …``), in place."""
    text = str(exc)
    old, sep, rest = text.partition(":")
    if sep and old in OLD_NAMES and len(exc.args) == 1:
        exc.args = (f"{OLD_NAMES[old]}:{rest}",)
        exc.parameter = OLD_NAMES[old]


def _settings(o: Mapping[str, Any], constraints: tuple[Any, ...] | None) -> PlanSettings:
    from ucbplan.observing.schedule import check_max_visit, plan_settings

    check_max_visit(o["max_visit"], o["goal"])
    exptime = o["exptime"]
    return plan_settings(
        instrument=checked_text(o["instrument"], "instrument", "an instrument name"),
        instruments_file=_path(o["instruments_file"], "instruments_file"),
        # left at its default, the exposure time is capped at the smearing floor (or chosen);
        # given, it is refused below it
        exptime_s=None if exptime is DEFAULT_EXPTIME else as_float(exptime, _S, "exptime"),
        n_exp=o["n_exp"],
        readout_s=as_float(o["readout"], _S, "readout"),
        overhead_s=as_float(o["overhead"], _S, "overhead"),
        visit=_duration(o["visit"], "visit"),
        max_visit=_duration(o["max_visit"], "max_visit"),
        sigma_v_kms=_sigma_v(o["sigma_v"]),
        sigma_floor_kms=as_float(o["sigma_floor"], _KMS, "sigma_floor"),
        extinction_k=o["extinction"],
        cadence=o["cadence"],
        service_mode=checked_flag(o["service_mode"], "service_mode"),
        goal=checked_text(o["goal"], "goal", "a goal such as sigma_K=2km/s"),
        min_lambda_k=o["min_lambda_k"],
        allow_smeared=checked_flag(o["allow_smeared"], "allow_smeared"),
        budgets=_budgets(o["budgets"]),
        mode=o["mode"],
        alpha=o["alpha"],
        k_eff_kms=as_float(o["k_eff"], _KMS, "k_eff"),
        max_smear=_max_smear(o["max_smear"]),
        max_bin_fraction=o["max_bin_fraction"],
        sessions_per_night=o["sessions"],
        custom_constraints=constraints,
        **(_limits(o) if constraints is None else {}),
    )


def _limits(o: Mapping[str, Any]) -> dict[str, Any]:
    """The constraint options as the planner's settings name them."""
    return {
        "twilight": o["twilight"],
        "airmass_max": o["airmass_max"],
        "moon_sep_deg": as_float(o["moon_sep"], _DEG, "moon_sep"),
        "moon_illum_max": o["moon_illum"],
        "zenith_hole_deg": as_float(o["zenith_hole"], _DEG, "zenith_hole"),
    }


#: The plan options a replan takes from the plan's meta instead (site, nights, targets).
_FROM_META = frozenset(
    {"targets", "site", "site_lonlat", "sites_file", "timezone", "night", "nights"}
)


def recorded_options(o: Mapping[str, Any], plan_func: Any) -> dict[str, Any]:
    """The options of a :func:`ucbplan.plan` call ``o`` that differ from its defaults, as the
    meta records them: text, numbers and lists of text; anything else (objects) by its type
    under ``unrecorded`` (a replan then refuses)."""
    defaults = inspect.signature(plan_func).parameters
    out: dict[str, Any] = {}
    unrecorded: list[str] = []
    for name, value in o.items():
        if name in _FROM_META or name not in defaults or value is defaults[name].default:
            continue
        if isinstance(value, Path):
            value = str(value)
        plain = value is None or isinstance(value, str | int | float | bool)
        if isinstance(value, list | tuple) and all(isinstance(v, str) for v in value):
            value, plain = list(value), True
        if plain:
            out[name] = value if not isinstance(value, float) else float(value)
        else:
            unrecorded.append(name)
    if unrecorded:
        out["unrecorded"] = unrecorded
    return out
