"""Planning settings: the planning modes and what a run needs besides targets, site and nights."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from typing import Any

from ucbplan.core.constants import DAY_S, HOUR_S
from ucbplan.core.smearing import parse_smear_budget
from ucbplan.errors import InputError, UcbplanError, shorten
from ucbplan.inputs import check_alpha, check_int, check_range
from ucbplan.observing.blocks.block import MAX_BLOCK_S, ExposurePlan
from ucbplan.observing.constraints import ConstraintSet
from ucbplan.observing.constraints.objects import constraint_set, default_constraints
from ucbplan.observing.observatory.sites import Site
from ucbplan.observing.precision.goals import parse_goal
from ucbplan.observing.precision.instruments import Instrument
from ucbplan.observing.precision.observed import ObservedSpectra
from ucbplan.observing.precision.sigma_v import SigmaVModel

#: Exposure cadences inside a visit (``--cadence``): ``auto`` takes the strategy with the most
#: information per visit when σ_v follows the exposure time
#: (:mod:`ucbplan.observing.precision.strategy`), else ``targeted``; ``targeted`` (or ``anchor``)
#: centres every exposure on an anchor and waits for the next one it can reach; ``phase-locked``
#: sets exposure + readout to the anchor spacing, so consecutive exposures centre on consecutive
#: anchors without waiting; ``untargeted`` takes back-to-back exposures at whatever phase they fall.
CADENCES = ("auto", "targeted", "anchor", "phase-locked", "untargeted")
#: The cadences a service-mode queue executes (``--service-mode``): exposures back to back after
#: one acquisition, no wait between them for an orbital phase.
QUEUE_CADENCES = ("phase-locked", "untargeted")
#: Longest wait after a readout a service-mode queue is taken to absorb [s]: a visit whose
#: exposures wait longer for their phases runs as planned only in visitor mode (the plan notes a
#: phase-locked wait above it; the queue exports note such a visit).
QUEUE_WAIT_S = 1.0
#: Default smallest smearing factor Λ_K of a planned exposure (``--min-lambda-k``), in every mode.
DEFAULT_MIN_LAMBDA_K = 0.9
#: Longest visit a goal plans without ``--visit`` (``--max-visit``) [s].
DEFAULT_MAX_VISIT_S = 7200.0
#: Longest per-target time budget [s] (a year of nights).
MAX_BUDGET_S = 366 * DAY_S
#: Seconds per unit of a ``--visit`` duration.
_DURATION_UNITS = {
    "s": 1.0,
    "sec": 1.0,
    "min": 60.0,
    "m": 60.0,
    "h": HOUR_S,
    "hr": HOUR_S,
}

#: The planning modes, as ``--mode`` spells them.
MODES = (
    "quadrature",
    "conjunction",
    "zero-crossing",
    "fixed-u-pairs",
    "quadrature+conjunction",
    "u=VALUE",
)

#: Largest |u★| of ``--mode u=VALUE`` [rad] (two turns; the anchor is taken modulo 2π).
MAX_ABS_U_RAD = 4.0 * math.pi
#: Largest RV precision or semi-amplitude [km/s] (white-dwarf binaries have K < 3000 km/s).
MAX_SPEED_KMS = 1.0e4
#: Most sessions per target and night (a 5-min binary has ~100 u = 0 / π pairs in a night).
MAX_SESSIONS = 1000
#: Largest factor on the σ_v law (``--sigma-v-scale``).
MAX_SIGMA_V_SCALE = 100.0
#: Longest ``--max-smear`` text [characters].
_MAX_SMEAR_CHARS = 60


def parse_duration(
    text: str | float, option: str = "visit", longest_s: float = MAX_BLOCK_S
) -> float:
    """A duration such as ``1h``, ``45min``, ``3600s`` or ``1.5h`` → seconds.

    Raises
    ------
    InputError
        For any other form, or a duration outside (0, ``longest_s``].
    """
    if isinstance(text, int | float) and not isinstance(text, bool):
        value, unit = float(text), "s"
    else:
        m = re.fullmatch(r"\s*([0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)\s*([a-z]*)\s*", str(text)[:40])
        if not m or m.group(2) not in _DURATION_UNITS:
            raise InputError(
                f"{option}: expected a duration such as 1h, 45min or 3600s, got {shorten(text, 40)}"
            )
        value, unit = float(m.group(1)), m.group(2)
    seconds = value * _DURATION_UNITS[unit]
    why = "a visit (acquisition included) must fit in one night"
    if longest_s != MAX_BLOCK_S:
        why = "a time budget over the nights planned"
    return check_range(option, seconds, 0.0, longest_s, "s", why, low_open=True)


def parse_budgets(items: object) -> tuple[tuple[str, float], ...]:
    """``NAME=DURATION`` items (``--budget 'HM Cnc=2h'``) → ((lower-case name, seconds), ...).

    Raises
    ------
    InputError
        For an item that is not ``NAME=DURATION``, or a name given twice.
    """
    if not isinstance(items, list | tuple):
        raise InputError(f"budget: expected NAME=DURATION items, got {shorten(items, 60)}")
    out: dict[str, float] = {}
    for item in items:
        if isinstance(item, tuple) and len(item) == 2:
            name, text = str(item[0]), item[1]
        else:
            name, sep, text = str(item).rpartition("=")
            if not sep or not name.strip():
                raise InputError(
                    "budget: expected NAME=DURATION (a target name and e.g. 2h or 90min), "
                    f"got {shorten(item, 80)}"
                )
        key = name.strip().lower()
        if key in out:
            raise InputError(f"budget: target {shorten(name.strip(), 40)} is given twice")
        out[key] = parse_duration(text, f"budget {shorten(name.strip(), 40)}", MAX_BUDGET_S)
    return tuple(out.items())


@dataclass(frozen=True, slots=True)
class ModeSpec:
    """What a planning mode means for epochs, tolerances and sessions.

    Attributes
    ----------
    label : str
        Name written into the ``anchor`` column.
    anchor : str or float
        Anchor passed to :func:`ucbplan.core.ephemeris.find_epochs` (a name or u★ [rad]).
    u_values : tuple of float
        Anchor phases u★ [rad] whose σ_u sets T_valid.
    tol_kind : str
        Tolerance formula (``quadrature``, ``conjunction`` or ``generic``).
    paired : bool
        Sessions of two blocks at alternating anchors (u = 0 then π, or both zero crossings).
    """

    label: str
    anchor: str | float
    u_values: tuple[float, ...]
    tol_kind: str
    paired: bool


def _u_value(text: str) -> float | None:
    """The number of ``u=VALUE`` (radians), or None if ``text`` is not of that form.

    Raises
    ------
    InputError
        For a number outside ±:data:`MAX_ABS_U_RAD`.
    """
    m = re.fullmatch(r"u\s*=\s*([-+0-9.eE]+)", text)
    if not m:
        return None
    try:
        value = float(m.group(1))
    except ValueError:
        return None
    why = "argument of latitude; the anchor is taken modulo 2 pi"
    return check_range("mode u=VALUE", value, -MAX_ABS_U_RAD, MAX_ABS_U_RAD, "rad", why)


def parse_mode(text: str) -> ModeSpec:
    """``--mode`` → :class:`ModeSpec`.

    Raises
    ------
    InputError
        For an unknown mode (lists the valid ones) or a ``u=VALUE`` out of range.
    """
    if not isinstance(text, str) or len(text) > 60:
        t = ""
    else:
        t = text.strip().lower()
    half_pi = (math.pi / 2, 3 * math.pi / 2)
    if t == "quadrature":
        return ModeSpec("quadrature", "quadrature", (0.0, math.pi), "quadrature", True)
    if t in ("quadrature+conjunction", "quad+conj"):
        quarter = (0.0, math.pi / 2, math.pi, 3 * math.pi / 2)
        label = "quadrature+conjunction"
        return ModeSpec(label, label, quarter, "quadrature", False)
    if t == "conjunction":
        return ModeSpec("conjunction", "conjunction", half_pi, "conjunction", False)
    if t in ("zero-crossing", "zero_crossing"):
        return ModeSpec("zero-crossing", "zero-crossing", half_pi, "conjunction", True)
    if t in ("fixed-u-pairs", "fixed-u", "pairs"):
        return ModeSpec("fixed-u-pairs", 0.0, (0.0,), "quadrature", False)
    value = _u_value(t)
    if value is not None:
        return ModeSpec(f"u={value:g}", value, (value,), "generic", False)
    raise InputError(
        f"mode: unknown mode {shorten(text, 60)}; expected quadrature, conjunction, "
        "zero-crossing, fixed-u-pairs, quadrature+conjunction or u=VALUE (radians, e.g. u=0.785)"
    )


@dataclass(frozen=True, slots=True)
class PlanSettings:
    """Everything the planner needs besides targets, site and nights (the ``plan`` options).

    Attributes
    ----------
    mode : str
        Planning mode (see :data:`MODES`); checked by :func:`parse_mode` when planning.
    twilight : str
        ``civil``, ``nautical`` or ``astronomical`` night.
    airmass_max : float
        Largest airmass (sec z).
    moon_sep_deg : float
        Smallest Moon separation [deg]; 0 switches the constraint off.
    moon_illum_max : float or None
        Largest illuminated fraction of the Moon while it is up (None: no limit).
    zenith_hole_deg : float or None
        Zenith-hole radius [deg]; None takes the site's, 0 switches it off.
    exposure : ExposurePlan
        Exposures of each block.
    alpha : float
        Planning margin α of T_valid (> 0).
    n_epochs : int
        Number of epochs the tolerance is shared between.
    sigma_v_kms, k_eff_kms : float or None
        RV precision σ_v of every exposure and semi-amplitude K_eff [km/s]; None takes the
        target file's.
    sigma_model : SigmaVModel or None
        σ_v that follows the exposure time, magnitude and airmass (``--sigma-v 30km/s@600s``);
        the exposure time and cadence are then chosen for information per hour.
    max_smear : str or None
        Smearing budget (``0.5*sigma_v`` or km/s); exceeding it is an error.
    max_bin_fraction : float or None
        Largest block span as a fraction of the orbit.
    overhead_s : float
        Slew + acquisition before each session [s].
    sessions_per_night : int
        Sessions per target and night (≥ 1).
    max_pair_baseline_days : float
        Longest baseline searched for the second epoch of a fixed-u pair [d].
    star : int
        Component whose argument of latitude is targeted (1 or 2).
    visit_s : float or None
        Visit length, acquisition included [s] (``--visit``); None plans sessions (or, with a
        goal, visits of up to ``max_visit_s``).
    max_visit_s : float
        Longest visit a goal plans (``--max-visit``) [s]; visits are balanced below it.
    cadence : str
        Exposure cadence inside a visit (see :data:`CADENCES`).
    service_mode : bool
        Plan only what a service-mode queue executes (``--service-mode``): visits whose
        exposures run back to back after one acquisition, i.e. the cadences of
        :data:`QUEUE_CADENCES` (``auto`` picks the better of them; ``targeted`` is refused).
    min_lambda_k : float or None
        Smallest smearing factor Λ_K of a planned block (``--min-lambda-k``). None: 0.9
        (:data:`DEFAULT_MIN_LAMBDA_K`), in every mode.
    allow_smeared : bool
        Plan exposures below ``min_lambda_k`` (``--allow-smeared``).
    exptime_explicit : bool or None
        The exposure time was chosen by the user: below the floor it is refused, not capped,
        and it is not optimised. None (library calls): chosen unless ``exposure`` keeps the
        default 60 s. The CLI sets it from whether ``--exptime`` was given.
    readout_assumed : bool
        The readout is ``DEFAULT_LAW_READOUT_S``, assumed because the exposure time is chosen
        and no readout was given (the plan says so in a note).
    instrument : Instrument or None
        Spectrograph whose σ_ref scales σ_v per exposure (overheads are resolved already).
    goal : str or None
        Precision goal (``--goal``, e.g. ``sigma_K=2km/s``): plans the spectra that reach it.
    budgets : tuple of (str, float)
        Wall-time budget per target (lower-case name, seconds) over all nights (``--budget``).
    custom_constraints : tuple or None
        Constraint objects (ucbplan's, a user's or astroplan's) replacing the set built from
        ``twilight``, ``airmass_max``, ``moon_sep_deg``, ``moon_illum_max`` and
        ``zenith_hole_deg`` (see :func:`~ucbplan.observing.constraints.objects.constraint_set`).
    observed : tuple of ObservedSpectra
        Spectra already taken (``--observed``): their information counts toward the goal.
    sigma_v_scale : float
        Factor on every σ_v the law predicts (``--sigma-v-scale``, or the ratio the observed
        spectra measured).
    short_goals : bool
        A goal the nights cannot reach is planned as far as they go and its shortfall stated
        (``replan``), not refused.
    goal_slack : float
        Fraction of each goal's information the plan may leave uncollected (a replan that
        changes the plan: ``REPLAN_INFO_SLACK``; 0 otherwise).
    pinned : tuple of (str, tuple of str)
        Visits a replan keeps (:mod:`.pinning`): per visit, its target's name and the UTC
        starts (ISO) of its exposures.

    Raises
    ------
    InputError
        For any value outside its physical range (one line naming the option, the range and
        why), before any planning work.
    """

    mode: str = "quadrature"
    twilight: str = "nautical"
    airmass_max: float = 2.0
    moon_sep_deg: float = 30.0
    moon_illum_max: float | None = None
    zenith_hole_deg: float | None = None
    exposure: ExposurePlan = field(default_factory=ExposurePlan)
    alpha: float = 1.0
    n_epochs: int = 2
    sigma_v_kms: float | None = None
    sigma_model: SigmaVModel | None = None
    k_eff_kms: float | None = None
    max_smear: str | None = None
    max_bin_fraction: float | None = None
    overhead_s: float = 300.0
    sessions_per_night: int = 1
    max_pair_baseline_days: float = 365.0
    star: int = 1
    visit_s: float | None = None
    max_visit_s: float = DEFAULT_MAX_VISIT_S
    cadence: str = "auto"
    service_mode: bool = False
    min_lambda_k: float | None = None
    allow_smeared: bool = False
    exptime_explicit: bool | None = None
    readout_assumed: bool = False
    instrument: Instrument | None = None
    goal: str | None = None
    budgets: tuple[tuple[str, float], ...] = ()
    custom_constraints: tuple[Any, ...] | None = None
    observed: tuple[ObservedSpectra, ...] = ()
    sigma_v_scale: float = 1.0
    short_goals: bool = False
    goal_slack: float = 0.0
    pinned: tuple[tuple[str, tuple[str, ...]], ...] = ()

    def __post_init__(self) -> None:
        parse_mode(self.mode)
        self.constraints(None)  # twilight, airmass, Moon and zenith-hole limits
        if not isinstance(self.exposure, ExposurePlan):
            raise InputError(f"exposure: expected an ExposurePlan, got {shorten(self.exposure)}")
        check_alpha(self.alpha)
        check_int("n_epochs", self.n_epochs, 1, 10**6, "epochs sharing the tolerance")
        for name, value in (("sigma_v_kms", self.sigma_v_kms), ("k_eff_kms", self.k_eff_kms)):
            if value is not None:
                check_range(name, value, 0.0, MAX_SPEED_KMS, "km/s", "", low_open=True)
        self._check_budgets()
        why = "factor on the σ_v law"
        check_range(
            "sigma_v_scale", self.sigma_v_scale, 0.0, MAX_SIGMA_V_SCALE, "", why, low_open=True
        )
        why = "slew + acquisition before each session; a block must fit in one night"
        check_range("overhead_s", self.overhead_s, 0.0, MAX_BLOCK_S, "s", why)
        check_int(
            "sessions_per_night", self.sessions_per_night, 1, MAX_SESSIONS, "per target and night"
        )
        why = "longest baseline of a fixed-u pair: a century at most"
        check_range("max_pair_baseline_days", self.max_pair_baseline_days, 0.0, 36525.0, "d", why)
        if self.star not in (1, 2) or isinstance(self.star, bool):
            raise InputError(f"star: expected 1 or 2, got {shorten(self.star)}")
        self._check_visits()

    def _check_visits(self) -> None:
        """``--visit``, ``--cadence``, ``--min-lambda-k`` and ``--goal``."""
        if self.visit_s is not None:
            parse_duration(self.visit_s)
            if self.spec.label == "fixed-u-pairs":
                raise InputError(
                    "visit: fixed-u pairs are single blocks at two epochs; drop `visit` or "
                    "use `mode` quadrature"
                )
            if self.exposure.n_exp != 1:
                raise InputError(
                    f"n_exp: expected 1 with `visit` (each exposure of a visit is centred on "
                    f"its own anchor), got {self.exposure.n_exp}; drop `n_exp`"
                )
        parse_duration(self.max_visit_s, "max_visit_s")
        if self.cadence not in CADENCES:
            raise InputError(
                f"cadence: expected {', '.join(CADENCES)}, got {shorten(self.cadence, 40)}"
            )
        if self.cadence in ("phase-locked", "untargeted"):
            if self.visit_s is None and self.goal is None:
                raise InputError(
                    f"cadence {self.cadence}: expected `visit` DURATION (or `goal`) as well"
                )
            if self.spec.label == "fixed-u-pairs":
                raise InputError(
                    f"cadence {self.cadence}: fixed-u pairs are single blocks; drop `cadence`"
                )
        self._check_service_mode()
        if self.cadence == "phase-locked":
            if self.exptime_given:
                raise InputError(
                    "cadence phase-locked sets exposure + readout to the anchor spacing; "
                    "drop `exptime` (or use `cadence` anchor)"
                )
        why = "smallest smearing factor of an exposure: 0 = none, 1 = no smearing at all"
        if self.min_lambda_k is not None:
            check_range("min_lambda_k", self.min_lambda_k, 0.0, 1.0, "", why)
        parse_budgets(list(self.budgets))
        if self.goal is not None:
            parse_goal(self.goal)
            if self.spec.label == "fixed-u-pairs":
                raise InputError("goal: fixed-u pairs plan two blocks each; drop `goal`")

    def _check_service_mode(self) -> None:
        """``--service-mode``: visits (or a goal's), and no cadence that waits."""
        if not self.service_mode:
            return
        if self.cadence in ("targeted", "anchor"):
            raise InputError(
                f"service_mode: `cadence={self.cadence}` waits between exposures for their "
                "phases, which a service-mode queue cannot; use `cadence=phase-locked`, "
                "untargeted or auto"
            )
        if self.visit_s is None and self.goal is None:
            raise InputError(
                "service_mode: expected `visit=DURATION` (or `goal`): a queue executes one "
                "acquisition, then exposures back to back"
            )

    def _check_budgets(self) -> None:
        """``--max-smear`` (its form, and a positive budget) and ``--max-bin-fraction``."""
        if self.max_bin_fraction is not None:
            why = "largest block span as a fraction of the orbital period"
            check_range("max_bin_fraction", self.max_bin_fraction, 0.0, 1.0, "", why, low_open=True)
        if self.max_smear is None:
            return
        if not isinstance(self.max_smear, str) or len(self.max_smear) > _MAX_SMEAR_CHARS:
            raise InputError(
                "max_smear: expected e.g. '0.5*sigma_v' or '2 km/s', got "
                f"{shorten(self.max_smear, 40)}"
            )
        # the form and sign now; a sigma_v budget is scaled by each target's sigma_v later
        try:
            budget = parse_smear_budget(self.max_smear, 1.0)
        except UcbplanError:
            raise
        except ValueError:  # a factor that is not a number, e.g. '..*sigma_v'
            raise InputError(
                "max_smear: expected e.g. '0.5*sigma_v' or '2 km/s', got "
                f"{shorten(self.max_smear, 40)}"
            ) from None
        why = "a velocity, or a multiple of sigma_v"
        check_range("max_smear", budget, 0.0, MAX_SPEED_KMS, "km/s", why, low_open=True)

    @property
    def lambda_k_floor(self) -> float:
        """The smearing floor in force (see ``min_lambda_k``)."""
        return DEFAULT_MIN_LAMBDA_K if self.min_lambda_k is None else self.min_lambda_k

    @property
    def plans_visits(self) -> bool:
        """Whether the run plans visits (``--visit``, or a goal, which chooses their length)."""
        return self.visit_s is not None or self.goal is not None

    @property
    def optimises_exposure(self) -> bool:
        """Whether the exposure time is chosen for information per hour: σ_v follows the
        exposure time and the user gave none."""
        law = self.sigma_model is not None and self.sigma_model.follows_exposure
        inst = self.instrument is not None and self.instrument.sigma_ref is not None
        fixed = self.sigma_v_kms is not None and self.sigma_model is None
        return (law or (inst and not fixed)) and not self.exptime_given

    @property
    def exptime_given(self) -> bool:
        """Whether the exposure time was chosen by the user (``exptime_explicit``; None: an
        ``exposure`` other than the default :class:`ExposurePlan`)."""
        if self.exptime_explicit is not None:
            return self.exptime_explicit
        return self.exposure.exptime_s != ExposurePlan().exptime_s

    @property
    def spec(self) -> ModeSpec:
        """The parsed planning mode."""
        return parse_mode(self.mode)

    def constraints(self, site: Site | None) -> ConstraintSet:
        """The constraints of a run at ``site`` (None: without the site's zenith hole), by name:
        ``custom_constraints`` when given, else the command line's
        (:func:`~ucbplan.observing.constraints.objects.default_constraints`)."""
        if self.custom_constraints is not None:
            return constraint_set(self.custom_constraints, site)
        return constraint_set(
            default_constraints(
                site,
                twilight=self.twilight,
                airmass_max=self.airmass_max,
                moon_sep_deg=self.moon_sep_deg,
                moon_illum_max=self.moon_illum_max,
                zenith_hole_deg=self.zenith_hole_deg,
            )
        )
