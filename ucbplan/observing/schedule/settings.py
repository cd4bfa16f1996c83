"""Planning settings: the planning modes and what a run needs besides targets, site and nights."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

from ucbplan.errors import UcbplanError
from ucbplan.observing.blocks import ExposurePlan
from ucbplan.observing.constraints import (
    AirmassConstraint,
    ConstraintSet,
    MoonIlluminationConstraint,
    MoonSeparationConstraint,
    NightConstraint,
    ZenithHoleConstraint,
)
from ucbplan.observing.sites import Site

__all__ = ["MODES", "ModeSpec", "PlanSettings", "parse_mode"]

#: The planning modes, as ``--mode`` spells them.
MODES = ("quadrature", "conjunction", "zero-crossing", "fixed-u-pairs", "u=VALUE")


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
    """The number of ``u=VALUE`` (radians), or None if ``text`` is not of that form."""
    m = re.fullmatch(r"u\s*=\s*([-+0-9.eE]+)", text)
    if not m:
        return None
    try:
        value = float(m.group(1))
    except ValueError:
        return None
    return value if math.isfinite(value) else None


def parse_mode(text: str) -> ModeSpec:
    """``--mode`` → :class:`ModeSpec`.

    Raises
    ------
    UcbplanError
        For an unknown mode (lists the valid ones).
    """
    t = text.strip().lower()
    half_pi = (math.pi / 2, 3 * math.pi / 2)
    if t == "quadrature":
        return ModeSpec("quadrature", "quadrature", (0.0, math.pi), "quadrature", True)
    if t == "conjunction":
        return ModeSpec("conjunction", "conjunction", half_pi, "conjunction", False)
    if t in ("zero-crossing", "zero_crossing"):
        return ModeSpec("zero-crossing", "zero-crossing", half_pi, "conjunction", True)
    if t in ("fixed-u-pairs", "fixed-u", "pairs"):
        return ModeSpec("fixed-u-pairs", 0.0, (0.0,), "quadrature", False)
    value = _u_value(t)
    if value is not None:
        return ModeSpec(f"u={value:g}", value, (value,), "generic", False)
    raise UcbplanError(
        f"--mode: unknown mode {text!r}; expected quadrature, conjunction, zero-crossing, "
        "fixed-u-pairs or u=VALUE (radians, e.g. u=0.785)"
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
        RV precision σ_v and semi-amplitude K_eff [km/s]; None takes the target file's.
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

    Raises
    ------
    UcbplanError
        If ``alpha`` is not positive or ``sessions_per_night`` < 1.
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
    k_eff_kms: float | None = None
    max_smear: str | None = None
    max_bin_fraction: float | None = None
    overhead_s: float = 300.0
    sessions_per_night: int = 1
    max_pair_baseline_days: float = 365.0
    star: int = 1

    def __post_init__(self) -> None:
        if not (self.alpha > 0 and math.isfinite(self.alpha)):
            raise UcbplanError(f"--alpha must be positive, got {self.alpha}")
        if self.sessions_per_night < 1:
            raise UcbplanError(f"--sessions must be >= 1, got {self.sessions_per_night}")

    @property
    def spec(self) -> ModeSpec:
        """The parsed planning mode."""
        return parse_mode(self.mode)

    def constraints(self, site: Site) -> ConstraintSet:
        """The constraints of a run at ``site``, by name."""
        hole = self.zenith_hole_deg if self.zenith_hole_deg is not None else site.zenith_hole_deg
        moon_illum = self.moon_illum_max
        return ConstraintSet(
            night=NightConstraint(twilight=self.twilight),
            airmass=AirmassConstraint(max_airmass=self.airmass_max),
            zenith_hole=ZenithHoleConstraint(radius_deg=hole) if hole else None,
            moon_sep=(
                MoonSeparationConstraint(min_deg=self.moon_sep_deg)
                if self.moon_sep_deg > 0
                else None
            ),
            moon_illum=(
                MoonIlluminationConstraint(max_fraction=moon_illum)
                if moon_illum is not None
                else None
            ),
        )
