"""Epochs t★ of a target (``ucbplan ephemeris predict``) and two ephemerides compared
(``ucbplan ephemeris compare``), with their options declared once (:data:`EPHEMERIS_FLAGS`,
:data:`COMPARE_FLAGS`)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from ucbplan._version import __version__
from ucbplan.api._convert import as_tdb, scope
from ucbplan.api.flagspec import Flag
from ucbplan.api.targets import TargetLike, load_target
from ucbplan.api.targets import get_site as get_site
from ucbplan.errors import EphemerisRangeWarning, InputError, emit, shorten

if TYPE_CHECKING:
    from astropy.table import Table

    from ucbplan.core.ephemeris import EpochSet
    from ucbplan.targets import Target

#: The options of :func:`ephemeris` as ``ucbplan ephemeris predict`` spells them.
EPHEMERIS_FLAGS: dict[str, Flag] = {
    "start": Flag(("--start",), "Window start, ISO, TDB at the barycentre."),
    "end": Flag(("--end",), "Window end, ISO, TDB at the barycentre."),
    "anchor": Flag(
        ("--anchor",),
        "quadrature | conjunction | eclipse (primary and secondary) | zero-crossing | U_RAD",
    ),
    "star": Flag(("--star",), "Component whose argument of latitude (1 or 2)."),
    "max_epochs": Flag(("--max-epochs",), "Refuse windows with more epochs than this."),
}
#: The options of :func:`compare_ephemerides` as ``ucbplan ephemeris compare`` spells them.
COMPARE_FLAGS: dict[str, Flag] = {
    "a": Flag((), "Target YAML file A (e.g. a LISA posterior)."),
    "b": Flag((), "Target YAML file B (e.g. a timing ephemeris)."),
    "at": Flag(
        ("--at",),
        'Epoch, "BJD_TDB …" or ISO TDB (default: midway between the two reference epochs).',
    ),
}


def epoch_window(
    t: Target, start: Any, end: Any, anchor: str, max_epochs: int
) -> tuple[float, float]:
    """``start``/``end`` as TDB seconds since the target's t_ref; refuse empty or huge windows.

    Raises
    ------
    InputError
        An epoch that does not parse, ``end`` not after ``start``, more than ``max_epochs``.
    """
    t0, t1 = as_tdb(start, "start"), as_tdb(end, "end")
    tau0, tau1 = float(t.tau(t0)), float(t.tau(t1))
    if tau1 <= tau0:
        raise InputError(
            f"end ({shorten(str(end), 60)}) must be after start ({shorten(str(start), 60)})",
            parameter="end",
        )
    expected = (tau1 - tau0) / t.period_s * (2 if anchor != "u" else 1)
    if expected > max_epochs:
        raise InputError(
            f"max_epochs: the window holds ~{expected:.3g} epochs (> {max_epochs}); shorten it",
            parameter="max_epochs",
        )
    return tau0, tau1


def horizon_warnings(t: Target, tau0: float, tau1: float) -> list[str]:
    """Warning lines for epochs past T_valid(quadrature, α = 1) of the target file's σ_v, K."""
    from ucbplan.core.constants import DAY_S
    from ucbplan.core.forecast import horizon_s, tolerance, valid_window_s

    spec = t.spectroscopy
    if spec is None or spec.sigma_v_kms is None or spec.k_for_tolerance is None:
        return []
    if t.kind != "timing":
        if tau1 <= t.t_obs_s / 2:
            return []
        tv = horizon_s(t, spec.sigma_v_kms, spec.k_for_tolerance, "quadrature")
        if tau1 <= t.t_obs_s / 2 + tv:
            return []
        return [
            f"epochs after T_valid(quadrature, α=1) = {tv / DAY_S:.0f} d past the LISA "
            "observation have σ_u above the phase tolerance; check σ_t before scheduling them "
            "(see `ucbplan horizon`)"
        ]
    tol = tolerance("quadrature", spec.sigma_v_kms, spec.k_for_tolerance)
    lo, hi = valid_window_s(t, tol, (0.0, math.pi))
    return [
        f"epochs more than T_valid(quadrature, α=1) = {span / DAY_S:.0f} d {side} T0 have σ_u "
        "above the phase tolerance; check σ_t before scheduling them (see `ucbplan horizon`)"
        for outside, side, span in ((tau0 < lo, "before", -lo), (tau1 > hi, "after", hi))
        if outside
    ]


def ephemeris(
    target: TargetLike,
    start: Any,
    end: Any,
    anchor: str = "quadrature",
    star: int = 1,
    max_epochs: int = 2_000_000,
) -> Table:
    """Barycentric epochs t★ (TDB) where u = u★, with σ_t and the φ_ref π-mode alternative.

    Parameters
    ----------
    target : str, Path, dict or Target
        The target (see :func:`load_target`).
    start, end : str or astropy.time.Time
        The window: ``Time`` in any scale, or text as ``ucbplan ephemeris --start`` takes it
        (unlabelled text is TDB).
    anchor : str
        ``quadrature``, ``conjunction``, ``eclipse``, ``zero-crossing`` … (as ``--anchor``).
    star : int
        Component whose argument of latitude is targeted (1 or 2).
    max_epochs : int
        Largest number of epochs the window may hold.

    Returns
    -------
    astropy.table.Table
        The columns of ``ucbplan ephemeris --format ecsv`` (``t_star_tdb`` ISO TDB, ``tau_s`` [s],
        ``sigma_t_s`` [s], ``sigma_u_rad`` [rad] …) and its metadata.

    Raises
    ------
    InputError
        A bad window, anchor or star (naming the parameter); TargetFileError for the target.

    Warns
    -----
    EphemerisRangeWarning
        Epochs past T_valid(quadrature, α = 1) (also printed by the command line); a
        :class:`~ucbplan.errors.PlanWarning`.

    Examples
    --------
    >>> import ucbplan
    >>> table = ucbplan.ephemeris(
    ...     "catalogs/hm-cnc-simulated.yaml", "2040-02-15T00:00", "2040-02-15T00:30"
    ... )
    >>> len(table)
    11
    >>> table["k", "anchor", "t_star_tdb"][:2]
    <Table length=2>
      k      anchor           t_star_tdb
    int64    str10              str26
    ------ ---------- --------------------------
    306349 quadrature 2040-02-15T00:02:20.767885
    306350 quadrature 2040-02-15T00:05:01.525011
    """
    found = predict(target, start, end, anchor, star, max_epochs)
    emit(list(found.warnings), EphemerisRangeWarning)
    return found.table


@dataclass(frozen=True, slots=True)
class EpochPrediction:
    """What ``ucbplan ephemeris predict`` shows: the target, its epoch table and the warning
    lines for epochs past the phase-coherence horizon."""

    target: Target
    table: Table
    warnings: tuple[str, ...] = ()

    def __repr__(self) -> str:
        return f"<EpochPrediction: {self.target.name}, {len(self.table)} epochs>"


def predict(
    target: TargetLike, start: Any, end: Any, anchor: str, star: int, max_epochs: int
) -> EpochPrediction:
    """:func:`ephemeris` with its warnings returned, not emitted (parameters and their defaults
    as there: declared once, in :func:`ephemeris`)."""
    from ucbplan.core.ephemeris import find_epochs
    from ucbplan.inputs import check_int, is_number

    if not (is_number(star) and star in (1, 2)):
        raise InputError(f"star: expected 1 or 2, got {shorten(star)}", parameter="star")
    check_int("max_epochs", max_epochs, 1, 10**12, "epochs a window may hold")
    check_anchor(anchor, "anchor")
    with scope():
        t = load_target(target)
        tau0, tau1 = epoch_window(t, start, end, anchor, int(max_epochs))
        es = find_epochs(t, tau0, tau1, anchor, int(star))
        lines = horizon_warnings(t, tau0, tau1)
        table = epoch_table(t, es)
    return EpochPrediction(t, table, tuple(lines))


def check_anchor(anchor: Any, parameter: str) -> None:
    """An anchor is a name or a finite number u★ [rad] (a name's spelling is checked where
    used).

    Raises
    ------
    InputError
        Anything else (one line naming ``parameter``).
    """
    from ucbplan.inputs import is_number

    if isinstance(anchor, str) or (is_number(anchor) and math.isfinite(anchor)):
        return
    raise InputError(
        f"{parameter}: expected quadrature, conjunction, eclipse, zero-crossing or a finite "
        f"number u★ in radians, got {shorten(anchor, 60)}",
        parameter=parameter,
    )


def epoch_table(t: Target, es: EpochSet) -> Table:
    """The epochs of ``es`` as the ``ephemeris`` table (columns, units and provenance)."""
    from astropy.table import Table
    from astropy.time import TimeDelta

    from ucbplan.core.ephemeris import eclipse_kind

    t_star = t.t_ref + TimeDelta(es.origin_s, format="sec") + TimeDelta(es.dt_s, format="sec")
    tab = Table()
    tab["k"] = es.k
    if t.kind == "timing":
        tab["cycle"] = _cycles(t, es)
    tab["anchor"] = [es.anchor] * len(es)
    if es.anchor == "eclipse":
        tab["eclipse"] = eclipse_kind(es.u_star_rad, es.star) if len(es) else []
    tab["u_star_rad"] = es.u_star_rad
    tab["t_star_tdb"] = _iso_us(t_star)
    if t.kind == "timing":
        from ucbplan.core.timing_epochs import bjd_tdb_numbers

        tab["t_star_bjd_tdb"] = bjd_tdb_numbers(t_star)
    tab["tau_s"] = es.tau_s
    tab["sigma_t_s"] = es.sigma_t_s
    tab["sigma_u_rad"] = es.sigma_u_rad
    units = [("u_star_rad", "rad"), ("tau_s", "s"), ("sigma_t_s", "s"), ("sigma_u_rad", "rad")]
    if t.has_pi_mode:
        t_alt = t.t_ref + TimeDelta(es.tau_alt_s, format="sec")
        tab["t_alt_tdb"] = _iso_us(t_alt)
        tab["tau_alt_s"] = es.tau_alt_s
        units.append(("tau_alt_s", "s"))
    for col, unit in units:
        tab[col].unit = unit
    tab.meta.update(_epoch_meta(t, es))
    return tab


def _epoch_meta(t: Target, es: EpochSet) -> dict[str, Any]:
    """Provenance of an epoch table."""
    meta: dict[str, Any] = {
        "ucbplan_version": __version__,
        "target": t.name,
        "target_file": str(t.source) if t.source else "",
        "target_sha256": t.sha256 or "",
        "time_scale": "TDB at the solar-system barycentre",
        "t_ref_tdb": t.t_ref.tdb.isot,
        "tau_origin": "seconds since t_ref (TDB)",
        "phase_convention": (
            "u = Phi_GW/2 + eps_j + 2 kappa sin Phi_asc - 2 eta cos Phi_asc; "
            "eps_1=0, eps_2=pi; u=0 ascending node (max recession of star 1)"
        ),
        "star": es.star,
    }
    if t.has_pi_mode:
        meta["alt_epoch"] = "solution of the phi_ref + pi posterior mode (about P_b/4 earlier)"
    if t.kind == "timing" and t.timing is not None:
        from ucbplan.core.timing_epochs import format_bjd_tdb

        meta.update(
            {
                "ephemeris": "timing",
                "t0_bjd_tdb": format_bjd_tdb(t.t_ref).split()[1],
                "t0_marks": t.timing.ephemeris.mark,
                "cycle": "ephemeris cycle n of t(n) = T0 + P n + P Pdot n^2/2 (+ P^2 Pddot n^3/6)"
                " for star 1: (u_1 - u_1(T0))/2pi, half-integer at the other conjunction",
                "source": t.timing.source,
            }
        )
    return meta


def _cycles(t: Target, es: EpochSet) -> Any:
    """Ephemeris cycle number n of each epoch: (u₁ − u₁(T0))/2π (u₁ = u★ − ε of the star)."""
    import numpy as np

    from ucbplan.core.phase import u_cycles

    m0, g0 = u_cycles(t.params, np.array([0.0]))
    eps = 0.0 if es.star == 1 else 0.5
    cycles = es.k + (es.u_star_rad / (2 * math.pi) - eps) - (m0[0] + g0[0])
    return np.round(cycles, 9)


def _iso_us(t: Any) -> list[str]:
    """TDB ISO strings with microseconds."""
    import numpy as np

    tdb = t.tdb
    tdb.precision = 6
    return [str(x) for x in np.atleast_1d(tdb.isot)]


def parse_epoch(text: Any, parameter: str) -> Any:
    """An epoch as an astropy ``Time`` (TDB): a ``Time``, or text as the command line takes it.

    ``"BJD_TDB …"``/``"BMJD_TDB …"`` keep full precision (two-part JD; HJD and UTC-based words
    are refused with how to convert); anything else is ISO/MJD/JD TDB, or UTC when labelled so
    (:func:`ucbplan.core.epochs.parse_tdb`).

    Raises
    ------
    InputError
        Text that is not an epoch (naming ``parameter``).
    """
    from astropy.time import Time

    from ucbplan.core.timing_epochs import TIMING_EPOCH_WORDS, parse_timing_epoch

    if isinstance(text, Time) or not isinstance(text, str):
        return as_tdb(text, parameter)
    word = text.strip().split(" ", 1)[0].upper().replace("-", "_")
    if word in TIMING_EPOCH_WORDS or word.startswith(("BJD", "BMJD", "HJD", "HMJD")):
        try:
            return parse_timing_epoch(text)
        except ValueError as exc:
            raise InputError(f"{parameter}: {exc}", parameter) from None
    return as_tdb(text, parameter)


@dataclass(frozen=True, slots=True)
class EphemerisComparison:
    """Two ephemerides of one system compared at an epoch (``ucbplan ephemeris compare``).

    ``doc`` is the JSON document the command writes (offsets in rad and s, significance, cycle
    counts, π-mode alternatives, the convention); ``warnings`` says when the two look like
    different binaries.
    """

    a: Target
    b: Target
    doc: dict[str, Any]
    warnings: tuple[str, ...] = ()

    def __repr__(self) -> str:
        d = self.doc
        return (
            f"<EphemerisComparison: {self.a.name} − {self.b.name} at {d['epoch_tdb']} TDB: "
            f"{d['time_offset_s']:.4g} ± {d['sigma_time_offset_s']:.3g} s>"
        )

    def to_dict(self) -> dict[str, Any]:
        """The JSON document (a copy)."""
        return dict(self.doc)


def compare_ephemerides(a: TargetLike, b: TargetLike, at: Any = None) -> EphemerisComparison:
    """Phase and time offset of two ephemerides of one system (A − B, star 1) at an epoch.

    Parameters
    ----------
    a, b : str, Path, dict or Target
        The two ephemerides (see :func:`load_target`), e.g. a LISA posterior and a timing one.
    at : str or astropy.time.Time, optional
        The epoch (``"BJD_TDB …"``, ISO TDB or a ``Time``); default midway between the two
        reference epochs.

    Returns
    -------
    EphemerisComparison
        With σ from both covariances, the significance, and the cycles from A's reference epoch
        to B's as each counts them (a whole-cycle disagreement the wrapped offset hides).

    Raises
    ------
    UcbplanError
        A target that does not load, or an ``at`` that is not an epoch: one line naming it.

    Examples
    --------
    >>> import ucbplan
    >>> ucbplan.compare_ephemerides(
    ...     "catalogs/hm-cnc-simulated.yaml", "catalogs/hm-cnc-simulated.yaml"
    ... )
    <EphemerisComparison: HM Cnc (simulated) − HM Cnc (simulated)
    at 2037-01-01T00:00:00.000 TDB: -0 ± 0.832 s>
    """
    from ucbplan.core.timing import compare_sources

    with scope():
        ta, tb = load_target(a), load_target(b)
        epoch = parse_epoch(at, "at") if at is not None else None
        lines = _different_systems(ta, tb)
        report = compare_sources(ta, tb, epoch)
        doc = _comparison_doc(ta, tb, report)
    return EphemerisComparison(ta, tb, doc, lines)


def _different_systems(ta: Target, tb: Target) -> tuple[str, ...]:
    """A warning when the two files look like different binaries (sky position, period)."""
    sep = float(ta.coord.separation(tb.coord).arcsec)
    dp = abs(ta.period_s - tb.period_s) / ta.period_s
    if sep <= 5.0 and dp <= 1e-3:
        return ()
    return (
        f"{ta.name} and {tb.name} are {sep:.1f}″ apart and their periods differ by "
        f"{100 * dp:.3g} %: compare two ephemerides of one system",
    )


def _comparison_doc(ta: Target, tb: Target, report: Any) -> dict[str, Any]:
    """JSON-ready comparison: the two files, the epoch, the offset (and π-mode alternatives)."""
    from ucbplan.core.timing_epochs import format_bjd_tdb

    def side(t: Target) -> dict[str, Any]:
        return {
            "name": t.name,
            "file": str(t.source) if t.source else "",
            "kind": t.kind,
            "t_ref_tdb": t.t_ref.tdb.isot,
        }

    r = report.result
    return {
        "a": side(ta),
        "b": side(tb),
        "epoch_tdb": report.epoch.tdb.isot,
        "epoch_bjd_tdb": format_bjd_tdb(report.epoch).split()[1],
        **r.offsets(),
        "cycles_a": r.cycles_a,
        "cycles_b": r.cycles_b,
        "cycle_count_difference": r.cycle_difference,
        "sigma_cycle_count_difference": r.sigma_cycle_difference,
        "whole_cycle_difference": round(r.cycle_difference),
        "pi_mode": [{"side": s, **c.offsets()} for s, c in report.alternatives],
        "convention": (
            "A - B for star 1: phase offset u1_A - u1_B at the epoch wrapped to (-pi, pi]; time "
            "offset t_A - t_B of the same orbital phase (negative: A predicts it earlier); "
            "cycles_a/cycles_b: orbits from A's reference epoch to B's as counted by A and by B; "
            "pi_mode: the same with that side's phi_ref + pi (LISA posteriors)"
        ),
    }
