"""Targets, sites, epochs, horizons and timing fits: the forecast half of the public API."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ucbplan._version import __version__
from ucbplan.api._convert import as_float, as_tdb, scope
from ucbplan.errors import EphemerisRangeWarning, InputError, UcbplanError, emit, shorten

if TYPE_CHECKING:
    from astropy.table import Table

    from ucbplan.core.ephemeris import EpochSet
    from ucbplan.observing.sites import Site
    from ucbplan.target import Target
    from ucbplan.timing import EphemerisFit

__all__ = [
    "ephemeris",
    "epoch_table",
    "epoch_window",
    "fit_ephemeris",
    "get_site",
    "horizon",
    "horizon_warnings",
    "load_target",
    "resolve_k_sigma",
]

TargetLike = Any  # a Target, a path, or a target document (dict)


def load_target(target: TargetLike) -> Target:
    """A target from a YAML file, a parsed target document (``dict``) or a ``Target``.

    Parameters
    ----------
    target : str, Path, dict or Target
        Path of a target YAML file, the same document as a mapping, or a loaded target.

    Returns
    -------
    Target

    Raises
    ------
    TargetFileError
        One line naming the file (or ``<dict>``), the field, what was expected and how to fix it.
    """
    from ucbplan.target import Target
    from ucbplan.target import load_target as _load
    from ucbplan.target.parse import target_from_dict

    if isinstance(target, Target):
        return target
    if isinstance(target, Mapping):
        return target_from_dict(dict(target))
    if isinstance(target, str | Path):
        return _load(target)
    raise InputError(
        f"target: expected a target file path, a target document (dict) or a Target, got "
        f"{shorten(target, 60)}",
        parameter="target",
    )


def get_site(site: Any, timezone: str | None = None) -> Site:
    """An observatory from a name of the bundled table, an ``EarthLocation`` or an astroplan
    ``Observer``.

    Parameters
    ----------
    site : str, Site, astropy.coordinates.EarthLocation or astroplan.Observer
        ``"paranal"``, ``"La Palma"`` …, a location (its IANA zone is looked up offline), or an
        observer (its location; its time zone unless that is UTC).
    timezone : str, optional
        IANA time zone replacing the site's (e.g. ``America/Santiago``).

    Returns
    -------
    Site

    Raises
    ------
    SiteError
        Unknown name (with the closest known ones), or coordinates out of range.
    """
    from ucbplan.observing.sites import Site, resolve_site, site_from_lonlat

    if isinstance(site, Site):
        return resolve_site(site.name, timezone=timezone) if timezone else site
    location = getattr(site, "location", None) if _is_observer(site) else site
    if hasattr(location, "geodetic"):
        if timezone is None and _is_observer(site) and str(site.timezone) != "UTC":
            timezone = str(site.timezone)
        geo = location.geodetic  # type: ignore[union-attr]
        numbers = (geo.lon.deg, geo.lat.deg, geo.height.to_value("m"))
        text = ",".join(repr(float(v)) for v in numbers)
        return site_from_lonlat(text, timezone)
    if isinstance(site, str):
        return resolve_site(site, timezone=timezone)
    raise InputError(
        f"site: expected a site name (e.g. 'paranal'), an EarthLocation or an astroplan "
        f"Observer, got {shorten(site, 60)}",
        parameter="site",
    )


def _is_observer(obj: Any) -> bool:
    return type(obj).__name__ == "Observer" and type(obj).__module__.startswith("astroplan")


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
    """
    from ucbplan.core.ephemeris import find_epochs

    if star not in (1, 2) or isinstance(star, bool):
        raise InputError(f"star: expected 1 or 2, got {shorten(star)}", parameter="star")
    with scope():
        t = load_target(target)
        tau0, tau1 = epoch_window(t, start, end, anchor, max_epochs)
        es = find_epochs(t, tau0, tau1, anchor, star)
        lines = horizon_warnings(t, tau0, tau1)
        table = epoch_table(t, es)
    emit(lines, EphemerisRangeWarning)
    return table


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
        Each a path, a target document or a ``Target`` (see :func:`load_target`).
    sigma_v, k_eff : float or Quantity, optional
        RV precision σ_v and semi-amplitude K_eff [km/s]; None takes each target file's.
    alpha : float or sequence of float
        Planning margins α of T_valid.
    n_epochs : int
        Number of epochs the tolerance is shared between.
    anchors : sequence of str
        Anchors (``conjunction``, ``quadrature`` …).

    Returns
    -------
    astropy.table.Table
        One row per target × anchor × α, the columns of ``ucbplan horizon --format json``
        (``anchor``, ``alpha``, ``tolerance_rad`` [rad], ``t_valid_days`` [d], ``dt_u_s`` [s],
        ``sigma_u_end_rad`` [rad] …, and ``target``).

    Raises
    ------
    InputError
        A bad α, σ_v or K (naming the parameter); TargetFileError for a target.

    Notes
    -----
    Eq. tol_quad and Eq. tol_conj for the tolerances; T_valid is the first root of
    σ_u(τ) = α·δu_tol (docs/method.md).
    """
    from astropy.table import Table

    from ucbplan.core.forecast import horizon_table
    from ucbplan.inputs import check_alpha, check_int

    alphas = [alpha] if isinstance(alpha, int | float) else list(alpha)
    for a in alphas:
        check_alpha(a)
    check_int("n_epochs", n_epochs, 1, 10**6, "epochs sharing the tolerance")
    many = isinstance(targets, Sequence) and not isinstance(targets, str)
    items = list(targets) if many else [targets]
    rows: list[dict[str, Any]] = []
    with scope():
        for item in items:
            t = load_target(item)
            sv, k = resolve_k_sigma(t, sigma_v, k_eff)
            got = horizon_table(t, sv, k, alphas=alphas, anchors=list(anchors), n_epochs=n_epochs)
            rows.extend(r.as_dict() | {"target": t.name} for r in got)
    if not rows:
        raise UcbplanError("targets: expected at least one target")
    return Table(rows=rows)


def fit_ephemeris(
    times: Any,
    period: Any = None,
    initial: TargetLike | None = None,
    terms: int = 3,
    clip: float | None = None,
) -> EphemerisFit:
    """Fit T0, P, Ṗ (and P̈ with ``terms=4``) to eclipse times (``ucbplan ephemeris fit``).

    Parameters
    ----------
    times : str or Path
        Eclipse-time table (see docs/timing.md).
    period : str, float or Quantity, optional
        First period guess (``"0.0595 d"``, seconds, or a time Quantity) to count cycles.
    initial : str or Path, optional
        An earlier ephemeris (a target file) to count cycles from.
    terms : int
        2 (T0, P), 3 (+Ṗ) or 4 (+P̈).
    clip : float, optional
        Outlier threshold [σ].

    Returns
    -------
    EphemerisFit
        The fitted parameters, their covariance and ``notes`` (what the fit decided).

    Raises
    ------
    InputError
        Bad table, ambiguous cycle count, too few times (one line each).
    """
    from ucbplan.timing import fit_times, period_guess, read_initial, read_times

    if terms not in (2, 3, 4) or isinstance(terms, bool):
        raise InputError(f"terms: expected 2, 3 or 4, got {shorten(terms)}", parameter="terms")
    if period is not None and initial is not None:
        raise InputError("period, initial: give one first ephemeris, not both", "period")
    with scope():
        guess = read_initial(initial) if initial is not None else None
        if period is not None:
            p = as_float(period, "s", "period")
            guess = period_guess(f"{p!r} s" if isinstance(p, float) else str(p))
        return fit_times(read_times(times), guess, terms, clip)
