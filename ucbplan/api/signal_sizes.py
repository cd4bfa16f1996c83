"""Expected signal sizes before observing (paper Sec. 3): :func:`feasibility` and its report.

The options are declared once (:data:`FEASIBILITY_FLAGS`); ``ucbplan feasibility`` derives its
flags, defaults and help from them and from the function's signature.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ucbplan.api._convert import as_float, scope
from ucbplan.api.ephemeris import parse_epoch
from ucbplan.api.flagspec import Flag
from ucbplan.api.plan_options import PLAN_FLAGS
from ucbplan.api.targets import TargetLike, load_target
from ucbplan.core.constants import DAY_S, YEAR_S  # also the command's table columns
from ucbplan.core.constants import MONTH_S as MONTH_S
from ucbplan.errors import InputError, shorten

if TYPE_CHECKING:
    from ucbplan.feasibility import FeasibilityReport
    from ucbplan.targets import Target

#: The options of :func:`feasibility` as ``ucbplan feasibility`` spells them. ``sigma_v``,
#: ``sigma_floor``, ``extinction`` and ``max_visit`` are the plan's options too (one Flag each
#: once the plan's table is merged).
FEASIBILITY_FLAGS: dict[str, Flag] = {
    "m1": Flag(("--m1",), "Mass of star 1 (M_sun) (else file).", "M_sun"),
    "m2": Flag(("--m2",), "Mass of star 2 (M_sun) (else file).", "M_sun"),
    "sigma_v": Flag(
        ("--sigma-v",),
        "RV precision: km/s fixed per exposure (30), or of one spectrum of T_ref seconds "
        "(30km/s@600s; ,V=20.0 at that magnitude): then exposure time and cadence are chosen.",
    ),
    "n_spectra": Flag(("--n-spectra",), "Spectra co-added per epoch."),
    "baseline": Flag(("--baseline",), "Baseline ΔT ('30 d', '1 yr', days)."),
    "m3": Flag(("--m3",), "Tertiary mass (M_sun) for Δv_CM.", "M_sun"),
    "a_out": Flag(("--a-out",), "Tertiary separation (AU) for Δv_CM.", "AU"),
    "optical_sigma_phase": Flag(
        ("--optical-sigma-phase",), "Optical ephemeris σ(φ0) (cycles).", "cycles"
    ),
    "optical_sigma_f_rel": Flag(("--optical-sigma-f-rel",), "σ_f/f (1)."),
    "optical_sigma_fdot_rel": Flag(("--optical-sigma-fdot-rel",), "σ_ḟ/f (1/s).", "1/s"),
    "optical_sigma_p": Flag(("--optical-sigma-p",), "σ(P_orb) (s).", "s"),
    "optical_sigma_pdot": Flag(("--optical-sigma-pdot",), "σ(Ṗ_orb) (s/s)."),
    "optical_sigma_t0": Flag(("--optical-sigma-t0",), "σ(T0) (s).", "s"),
    "optical_epoch": Flag(
        ("--optical-epoch",),
        "Optical ephemeris reference epoch: ISO (TDB unless labelled UTC) or BJD_TDB; "
        "default: the target's reference epoch (LISA midpoint or timing T0).",
    ),
    # the σ_v law's floor and extinction as plan declares them
    "sigma_floor": PLAN_FLAGS["sigma_floor"],
    "extinction": PLAN_FLAGS["extinction"],
    "readout": Flag(("--readout",), "Readout per exposure (s).", "s"),
    "overhead": Flag(("--overhead",), "Acquisition per visit (s).", "s"),
    "visit": Flag(("--visit",), "Visit length (1h); default --max-visit."),
    "max_visit": Flag(("--max-visit",), "Longest visit a --goal plans (default 2h)."),
    "goal": Flag(("--goal",), "Precision goal (sigma_K=2km/s, K1=1%, q=1%): hours to reach it."),
    "min_lambda_k": Flag(("--min-lambda-k",), "Smallest Λ_K of an exposure (0.9)."),
    "allow_smeared": Flag(("--allow-smeared",), "Allow exposures below the Λ_K floor."),
    "compare_strategies": Flag(
        ("--compare-strategies",),
        "Compare targeted, phase-locked and untargeted exposures (implied by a law "
        "--sigma-v T@REF or --goal).",
    ),
}

#: What the JSON document says of its units.
UNITS_NOTE = "SI (m/s, s, rad, rad/s); masses M_sun"


@dataclass(frozen=True, slots=True)
class Feasibility:
    """The expected signal sizes of one binary (paper Sec. 3) and, when asked for, the
    comparison of exposure strategies.

    Attributes
    ----------
    target : Target
    report : ucbplan.feasibility.FeasibilityReport
        Every Sec. 3 magnitude, SI (K_j [m/s], ω̇ [rad/s], Δv_aps [m/s], Δv_CM, timing errors).
    strategies : ucbplan.observing.schedule.compare.StrategyComparison or None
        Targeted, phase-locked and untargeted exposures compared (a σ_v law or a goal).
    """

    target: Target
    report: FeasibilityReport
    strategies: Any = None

    def __repr__(self) -> str:
        r = self.report
        k1 = "—" if r.k1_m_s is None else f"{r.k1_m_s / 1e3:.1f} km/s"
        more = ", strategies compared" if self.strategies is not None else ""
        return f"<Feasibility {r.name}: P_b={r.period_s / 60:.4f} min, K1={k1}, e={r.e:.3g}{more}>"

    def to_dict(self) -> dict[str, Any]:
        """The document ``ucbplan feasibility --format json`` writes (SI units; None for
        infinite or undefined values)."""
        doc = {"units": UNITS_NOTE, **self.report.to_dict()}
        if self.strategies is not None:
            doc["strategies"] = self.strategies.to_dict()
        return doc

    def plot(self, path: str | Path, overwrite: bool = False) -> Path:
        """Draw Δv_aps against the baseline to ``path`` (PNG/PDF/SVG); returns it."""
        from ucbplan.feasibility import plot_report

        plot_report(self.report, Path(path), overwrite=overwrite)
        return Path(path)


def feasibility(
    target: TargetLike,
    m1: Any = None,
    m2: Any = None,
    sigma_v: Any = None,
    n_spectra: int = 1,
    baseline: Any = "1 yr",
    m3: Any = 1.0,
    a_out: Any = 5.0,
    optical_sigma_phase: float | None = None,
    optical_sigma_f_rel: float | None = None,
    optical_sigma_fdot_rel: float | None = None,
    optical_sigma_p: Any = None,
    optical_sigma_pdot: float | None = None,
    optical_sigma_t0: Any = None,
    optical_epoch: Any = None,
    sigma_floor: Any = 0.0,
    extinction: float | None = None,
    readout: Any = 0.0,
    overhead: Any = 300.0,
    visit: Any = None,
    max_visit: Any = None,
    goal: str | None = None,
    min_lambda_k: float | None = None,
    allow_smeared: bool = False,
    compare_strategies: bool = False,
    plot: str | Path | None = None,
    overwrite: bool = False,
) -> Feasibility:
    """Expected signal sizes (paper Section 3): K_j, apsidal rates, ΔK, Δv_aps, e floor, Δv_CM,
    and GW vs optical timing errors (``ucbplan feasibility``).

    Parameters
    ----------
    target : str, Path, dict or Target
        The binary (see :func:`load_target`).
    m1, m2 : float or Quantity, optional
        Component masses [M_sun] (default: the target file's).
    sigma_v : float, str or Quantity, optional
        RV precision per exposure [km/s], or a law ``"30km/s@600s[,V=20.0]"`` (then exposure time
        and cadence are chosen and strategies compared).
    n_spectra : int
        Spectra co-added per epoch.
    baseline : str, float or Quantity
        Baseline ΔT (``"30 d"``, ``"1 yr"``, bare days).
    m3 : float or Quantity
        Tertiary mass [M_sun] for Δv_CM.
    a_out : float or Quantity
        Tertiary separation [AU] for Δv_CM.
    optical_sigma_phase, optical_sigma_f_rel, optical_sigma_fdot_rel : float, optional
        Optical ephemeris σ(φ0) [cycles], σ_f/f [1], σ_ḟ/f [1/s].
    optical_sigma_p, optical_sigma_pdot, optical_sigma_t0 : float, optional
        Optical ephemeris σ(P_orb) [s], σ(Ṗ_orb) [s/s], σ(T0) [s].
    optical_epoch : str, float or Time, optional
        The optical ephemeris' reference epoch (ISO, ``"BJD_TDB …"``, a bare BJD_TDB or a Time);
        default the target's reference epoch.
    sigma_floor, extinction, readout, overhead, visit, max_visit, goal, min_lambda_k,
    allow_smeared :
        As :func:`ucbplan.plan` (km/s, mag/airmass, s, s, durations, a precision goal …).
    compare_strategies : bool
        Compare targeted, phase-locked and untargeted exposures (implied by a law or a goal).
    plot : str or Path, optional
        Draw Δv_aps against the baseline here (refused before any work if it exists, unless
        ``overwrite``).
    overwrite : bool
        Replace an existing ``plot``.

    Returns
    -------
    Feasibility

    Raises
    ------
    InputError
        A bad value (one line naming the parameter), before the target is read.

    Examples
    --------
    >>> import ucbplan
    >>> ucbplan.feasibility("catalogs/hm-cnc-simulated.yaml", sigma_v=15, n_spectra=100)
    <Feasibility HM Cnc (simulated): P_b=5.3586 min, K1=156.2 km/s, e=0>
    """
    from ucbplan.observing.schedule.options import plan_settings

    settings = plan_settings(
        sigma_v_kms=as_float(sigma_v, "km/s", "sigma_v"),
        sigma_floor_kms=as_float(sigma_floor, "km/s", "sigma_floor"),
        extinction_k=extinction,
        readout_s=as_float(readout, "s", "readout"),
        overhead_s=as_float(overhead, "s", "overhead"),
        visit=visit,
        max_visit=max_visit,
        goal=goal,
        min_lambda_k=min_lambda_k,
        allow_smeared=allow_smeared,
    )
    masses = _masses(m1, m2, m3, a_out)
    sigma_ref = _checked(settings, n_spectra, masses)
    if plot is not None:
        from ucbplan.plotting import check_figure_path

        check_figure_path(Path(plot), overwrite)
    with scope():
        tgt = load_target(target)
        law = settings.sigma_model
        compare = compare_strategies or goal is not None or bool(law and law.follows_exposure)
        optical = _optical(
            tgt,
            optical_sigma_phase,
            optical_sigma_f_rel,
            optical_sigma_fdot_rel,
            as_float(optical_sigma_p, "s", "optical_sigma_p"),
            optical_sigma_pdot,
            as_float(optical_sigma_t0, "s", "optical_sigma_t0"),
        )
        given = optical_epoch is not None and not (
            isinstance(optical_epoch, str) and not optical_epoch
        )
        offset = _optical_offset(optical_epoch, tgt.t_ref) if given else 0.0
        report = _report(tgt, masses, sigma_ref, n_spectra, baseline, optical, offset)
        result = Feasibility(tgt, report, _comparison(tgt, settings) if compare else None)
        if plot is not None:
            result.plot(plot, overwrite)
    return result


def _masses(m1: Any, m2: Any, m3: Any, a_out: Any) -> tuple[Any, Any, Any, Any]:
    """The masses [M_sun] and the tertiary separation [AU] as numbers."""
    return (
        as_float(m1, "solMass", "m1"),
        as_float(m2, "solMass", "m2"),
        as_float(m3, "solMass", "m3"),
        as_float(a_out, "AU", "a_out"),
    )


def _checked(settings: Any, n_spectra: Any, masses: tuple[Any, ...]) -> float | None:
    """Reject bad values with the parameter's name (before any file is read).

    Returns the reference σ_v [km/s]: the σ_v law's at its reference exposure, else sigma_v.
    """
    from ucbplan.inputs import check_number, check_range

    m1, m2, m3, a_out = masses
    law = settings.sigma_model
    sigma_v = law.sigma_kms if law is not None else settings.sigma_v_kms
    check_range("n_spectra", n_spectra, 0, 1e9, "spectra", low_open=True)
    if int(n_spectra) != n_spectra:
        raise InputError(f"n_spectra: expected a whole number of spectra, got {n_spectra!r}")
    wd = "white dwarfs weigh between ~0.05 M_sun and the Chandrasekhar mass"
    check_number("m1", m1, 0.05, 1.5, "M_sun", wd)
    check_number("m2", m2, 0.05, 1.5, "M_sun", wd)
    check_number("sigma_v", sigma_v, 0.0, 1e4, "km/s")
    check_range("m3", m3, 0.0, 1e3, "M_sun", low_open=True)  # required: None refused
    outside = "a tertiary orbits outside the binary (~1e-4 AU)"
    check_range("a_out", a_out, 1e-6, 1e6, "AU", outside, low_open=True)
    return sigma_v


def _optical(
    tgt: Target,
    sigma_phase: float | None,
    sigma_f_rel: float | None,
    sigma_fdot_rel: float | None,
    sigma_p: float | None,
    sigma_pdot: float | None,
    sigma_t0: float | None,
) -> Any:
    """The optical ephemeris of the ``optical_sigma_*`` parameters, at the target's period."""
    from ucbplan.feasibility import optical_ephemeris

    return optical_ephemeris(
        tgt.params.nodal_period_s,
        sigma_phase_cycles=sigma_phase,
        sigma_f_rel=sigma_f_rel,
        sigma_fdot_rel_s=sigma_fdot_rel,
        sigma_p_s=sigma_p,
        sigma_pdot=sigma_pdot,
        sigma_t0_s=sigma_t0,
    )


def _report(
    tgt: Target,
    masses: tuple[Any, ...],
    sigma_kms: float | None,
    n_spectra: int,
    baseline: Any,
    optical: Any,
    offset_s: float,
) -> FeasibilityReport:
    """:func:`ucbplan.feasibility.report_for_target` in SI units."""
    from ucbplan.feasibility import report_for_target

    m1, m2, m3, a_out = masses
    return report_for_target(
        tgt,
        m1_msun=m1,
        m2_msun=m2,
        sigma_v_m_s=sigma_kms * 1e3 if sigma_kms is not None else None,
        n_spectra=n_spectra,
        baseline_s=_baseline_s(baseline),
        m3_msun=m3,
        a_out_au=a_out,
        optical=optical,
        optical_offset_s=offset_s,
    )


def _comparison(target: Target, settings: Any) -> Any:
    """The strategies compared; one that no strategy fits is refused here, before anything is
    shown (issue 33: the report used to print before the error)."""
    from ucbplan.observing.schedule.compare import compare_target_strategies

    comparison = compare_target_strategies(target, settings)
    _ = comparison.best  # raises InputError when no strategy fits a visit
    return comparison


def _baseline_s(value: Any) -> float:
    """Baseline as a time Quantity, its text (``"30 d"``, ``"1 yr"``) or bare days → seconds."""
    from ucbplan.inputs import check_number

    seconds = _seconds(value)
    if seconds is None:
        raise InputError(
            f"baseline: got {shorten(value, 40)}, expected a time like '30 d', '1 yr' or bare days",
            parameter="baseline",
        )
    check_number("baseline", seconds / YEAR_S, 0.0, 100.0, "yr", "at most a century")
    return seconds


def _seconds(value: Any) -> float | None:
    """A duration in seconds (a bare number: days), or None for what is not one."""
    import astropy.units as u

    from ucbplan.inputs import is_number

    if hasattr(value, "unit"):
        return float(as_float(value, "s", "baseline"))
    if is_number(value):
        return float(value) * DAY_S
    if not isinstance(value, str):
        return None
    try:
        return float(value) * DAY_S
    except ValueError:
        pass
    try:
        return float(u.Quantity(value).to_value(u.s))
    except (ValueError, TypeError, u.UnitsError):
        return None


def _optical_offset(value: Any, t_ref: Any) -> float:
    """Seconds from the optical reference epoch (a bare number = BJD_TDB) to the target's
    reference epoch."""
    from astropy.time import Time

    from ucbplan.inputs import check_number, is_number

    try:
        jd = float(value) if is_number(value) or isinstance(value, str) else None
    except ValueError:
        jd = None
    if jd is None:
        epoch = parse_epoch(value, "optical_epoch")
    else:
        # a bare number is a BJD_TDB between the years 1000 and 3000
        check_number("optical_epoch", jd, 2086302.5, 2816787.5, "BJD_TDB")
        epoch = Time(jd, format="jd", scale="tdb")
    return float((t_ref - epoch).to_value("s"))
