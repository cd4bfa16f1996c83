"""Timing ephemerides fitted to eclipse times: :func:`fit_ephemeris` and its :class:`TimingFit`.

The options are declared once (:data:`FIT_FLAGS`); ``ucbplan ephemeris fit`` derives its flags,
defaults and help from them and from the function's signature. See docs/timing.md.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ucbplan.api._convert import as_float, scope
from ucbplan.api.flagspec import Flag
from ucbplan.api.targets import TargetLike
from ucbplan.errors import InputError, shorten

if TYPE_CHECKING:
    from astropy.time import Time
    from matplotlib.figure import Figure

    from ucbplan.targets import Target
    from ucbplan.timing import EclipseTimes, EphemerisFit, PeriodGuess

#: The options of :func:`fit_ephemeris` (and of :meth:`TimingFit.to_target`) as
#: ``ucbplan ephemeris fit`` spells them.
FIT_FLAGS: dict[str, Flag] = {
    "times": Flag(
        (), "Eclipse times: CSV or ECSV with bjd_tdb (or bmjd_tdb), sigma_s [, kind, cycle]."
    ),
    "terms": Flag(("--terms",), "2: T0, P; 3: + Pdot; 4: + Pddot."),
    "period": Flag(
        ("--period",),
        "First period guess for counting cycles, e.g. '414.79 s' (trusted to its last digit); "
        "default: from the best-covered night's eclipses.",
    ),
    "initial": Flag(
        ("--initial",), "Earlier ephemeris (target YAML with timing: t0, period[, pdot])."
    ),
    "clip": Flag(("--clip",), "Drop times more than K (rescaled) sigma from the fit; reported."),
    "like": Flag(
        ("--like",), "Copy name, sky, masses, spectroscopy, magnitudes from this target YAML."
    ),
    "name": Flag(("--name",), "Target name (overrides --like)."),
    "ra": Flag(("--ra",), "ICRS right ascension, e.g. 15h39m32.16s."),
    "dec": Flag(("--dec",), "ICRS declination, e.g. +50d27m38.8s."),
}


@dataclass(frozen=True, slots=True)
class TimingFit:
    """A fitted timing ephemeris t(n) = T0 + P·n + ½·P·Ṗ·n² (+ ⅙·P²·P̈·n³).

    Attributes
    ----------
    fit : ucbplan.timing.EphemerisFit
        The least-squares solution: values, covariance, O − C, χ², outliers, clipped rows.
    times : ucbplan.timing.EclipseTimes
        The eclipse times it was fitted to.
    notes : tuple of str
        What the fit decided (σ's rescaled, outliers kept, rows clipped, a guess ignored).

    Examples
    --------
    T0, P and Ṗ of six eclipses of a 400 s binary (times written to 10⁻⁷ d), as a timing target
    (``terms=2`` holds Ṗ at 0, and the target says so):

    >>> from astropy import units as u
    >>> from astropy.table import Table
    >>> import ucbplan
    >>> cycles = [0, 1000, 2000, 3000, 4000, 5000]
    >>> period_d = (400 * u.s).to_value(u.day)
    >>> bjd = [f"{2461000.5 + n * period_d:.7f}" for n in cycles]
    >>> times = Table({"cycle": cycles, "bjd_tdb": bjd, "sigma_s": [1.0] * 6})
    >>> fit = ucbplan.fit_ephemeris(times, terms=3)
    >>> fit.t0_text, fit.period, fit.units
    ('BJD_TDB 2461012.074074087500', <Quantity 399.99999941 s>, ('s', 's', 's/s'))
    >>> fit.to_target(name="Demo", ra="15h39m32.16s", dec="+50d27m38.8s")
    <Target 'Demo' (timing): P=399.9999994 s, RA=234.88400°, Dec=+50.46078°,
    T0=2025-12-02T13:46:40.001 TDB>
    """

    fit: EphemerisFit
    times: EclipseTimes
    notes: tuple[str, ...] = ()

    def __repr__(self) -> str:
        f, sig = self.fit, self.fit.sigmas
        pdot = f", Ṗ={f.values[2]:.4g}±{sig[2]:.2g}" if f.terms > 2 else ""
        ratio = f"{f.chi2 / f.dof:.3g}" if f.dof > 0 else "n/a"
        return (
            f"<TimingFit {f.source}: T0=BJD_TDB {float(f.t0_jd):.7f}±{sig[0]:.3g} s, "
            f"P={f.period_s:.10g}±{sig[1]:.2g} s{pdot}; {f.n_used} times, chi2/dof={ratio}>"
        )

    @property
    def t0(self) -> Time:
        """T0, the primary eclipse nearest the weighted mean epoch (TDB, full precision)."""
        from astropy.time import Time

        whole = int(self.fit.t0_jd)
        return Time(float(whole), float(self.fit.t0_jd - whole), format="jd", scale="tdb")

    @property
    def t0_text(self) -> str:
        """T0 as the target file writes it, with every digit (``"BJD_TDB 2458305.6827886…"``)."""
        from ucbplan.core.timing_epochs import format_bjd

        return format_bjd(self.fit.t0_jd)

    @property
    def units(self) -> tuple[str, ...]:
        """The unit of each fitted parameter's value (s, s, s/s, 1/s)."""
        from ucbplan.timing.fit import UNITS

        return UNITS[: self.fit.terms]

    @property
    def period(self) -> Any:
        """P at T0 (Quantity, s)."""
        from astropy import units as u

        return self.fit.period_s * u.s

    @property
    def pdot(self) -> float | None:
        """Ṗ [s/s] (None when only T0 and P were fitted)."""
        return float(self.fit.values[2]) if self.fit.terms > 2 else None

    @property
    def sigmas(self) -> dict[str, float]:
        """1σ of each fitted parameter (t0, period [s], pdot [1], pddot [1/s])."""
        return dict(zip(self.fit.names, map(float, self.fit.sigmas), strict=True))

    def to_dict(self) -> dict[str, Any]:
        """The report ``ucbplan ephemeris fit --format json`` writes, as Python values.

        Returns
        -------
        dict
            Parameters with σ and units, covariance, χ², outliers, clipped rows, notes and every
            point's O − C.
        """
        from ucbplan.timing.document import fit_report

        return fit_report(self.fit, self.times)

    def target_document(
        self,
        name: str | None = None,
        ra: str | None = None,
        dec: str | None = None,
        like: TargetLike | None = None,
    ) -> dict[str, Any]:
        """The timing target file as a mapping (see :func:`target_identity`).

        Parameters
        ----------
        name : str, optional
            The target name (overrides ``like``'s).
        ra, dec : str, optional
            ICRS position (``"15h39m32.16s"``, ``"+50d27m38.8s"``), both or neither.
        like : str, Path, dict or Target, optional
            A target file (or document) to copy name, sky, masses, spectroscopy, magnitudes from.

        Returns
        -------
        dict
            The target document: name, sky, this ephemeris (T0 with every digit, P, Ṗ … and
            their covariance) and what ``like`` adds.

        Raises
        ------
        InputError
            No name or sky position, or an unreadable one.
        """
        from ucbplan.timing.document import target_document

        ident = target_identity(like, name, ra, dec)
        return target_document(self.fit, ident, self.times.label())

    def target_yaml(
        self,
        name: str | None = None,
        ra: str | None = None,
        dec: str | None = None,
        like: TargetLike | None = None,
    ) -> str:
        """The timing target file's text (``ucbplan ephemeris fit -o target.yaml``).

        Parameters
        ----------
        name, ra, dec, like
            As :meth:`target_document`.

        Returns
        -------
        str
            The YAML text.

        Raises
        ------
        InputError
            As :meth:`target_document`.
        """
        import io

        from ucbplan.timing.document import write_yaml

        buf = io.StringIO()
        write_yaml(self.target_document(name, ra, dec, like), buf)
        return buf.getvalue()

    def to_target(
        self,
        name: str | None = None,
        ra: str | None = None,
        dec: str | None = None,
        like: TargetLike | None = None,
    ) -> Target:
        """This ephemeris as a timing target (``ucbplan.write_target`` writes it).

        Parameters
        ----------
        name, ra, dec, like : str or None; like also Path, dict or Target
            Its name and sky position, and a target file to copy them (and masses,
            spectroscopy, magnitudes) from, as for :meth:`target_document`.

        Returns
        -------
        ucbplan.targets.Target
            The target :func:`ucbplan.load_target` reads from :meth:`target_yaml`'s text.

        Raises
        ------
        InputError
            As :meth:`target_document`.
        TargetFileError
            A target that fails the target-file checks (as :func:`load_target`).
        """
        from ucbplan.targets import target_from_dict

        with scope():
            return target_from_dict(self.target_document(name, ra, dec, like))

    def figure(self) -> Figure:
        """The O − C figure.

        Returns
        -------
        matplotlib.figure.Figure
            O − C against the linear ephemeris [s] with the fitted curve, and the residuals
            below, against cycle since T0 (``.savefig(path)`` writes it).
        """
        from ucbplan.timing.plots import oc_figure

        return oc_figure(self.fit, self.times)

    def write(
        self, text: str | None, output: Path | None, plot: Path | None, overwrite: bool = False
    ) -> list[Path]:
        """Write ``text`` to ``output`` and the O − C figure to ``plot`` as a unit (both or
        neither).

        Parameters
        ----------
        text : str or None
            The report or target file's text (None: none written).
        output : Path or None
            Its file (None: none written).
        plot : Path or None
            The figure's file, ``.png``, ``.pdf`` or ``.svg`` (None: no figure).
        overwrite : bool
            Replace existing files.

        Returns
        -------
        list of Path
            The files written.

        Raises
        ------
        InputError
            ``plot`` is not a ``.png``, ``.pdf`` or ``.svg`` file name.
        OutputExistsError
            A file exists and ``overwrite`` is false (nothing is written).
        """
        from ucbplan.io import write_file_set
        from ucbplan.plotting import figure_format, pyplot

        files: dict[Path, Any] = {}
        if text is not None and output is not None:
            data = text.encode("utf-8")
            files[output] = lambda handle: handle.write(data)
        if plot is None:
            if files:
                write_file_set(files, overwrite=overwrite, binary=True)
            return list(files)
        kind, fig = figure_format(plot), self.figure()
        files[plot] = lambda handle: fig.savefig(handle, format=kind, dpi=120)
        try:
            write_file_set(files, overwrite=overwrite, binary=True)
        finally:
            pyplot().close(fig)
        return list(files)


def target_identity(
    like: TargetLike | None = None,
    name: str | None = None,
    ra: str | None = None,
    dec: str | None = None,
) -> dict[str, Any]:
    """Name, sky (and masses, spectroscopy, magnitudes) of a timing target to write.

    Parameters
    ----------
    like : str, Path, dict or Target, optional
        A target file (or document) to copy name, sky, masses, spectroscopy, magnitudes from.
    name : str, optional
        The target name (overrides ``like``'s).
    ra, dec : str, optional
        ICRS position (``"15h39m32.16s"``, ``"+50d27m38.8s"``), both or neither.

    Raises
    ------
    InputError
        No name or sky position, or an unreadable one.
    """
    from ucbplan.timing.document import identity

    for parameter, value, example in (
        ("name", name, "'ZTF J1539+5027'"),
        ("ra", ra, "'15h39m32.16s'"),
        ("dec", dec, "'+50d27m38.8s'"),
    ):
        if value is not None and not isinstance(value, str):
            raise InputError(
                f"{parameter}: expected text like {example}, got {shorten(value, 40)}", parameter
            )
    if like is None or isinstance(like, str | Path):
        return identity(Path(like) if like is not None else None, name, ra, dec)
    if not isinstance(like, Mapping):
        from ucbplan.api.targets import load_as
        from ucbplan.targets import target_to_dict

        like = target_to_dict(load_as(like, "like"))
    return identity(like, name, ra, dec)


def fit_ephemeris(
    times: Any,
    period: Any = None,
    initial: TargetLike | None = None,
    terms: int = 3,
    clip: float | None = None,
) -> TimingFit:
    """Fit T0, P, Ṗ (and P̈ with ``terms=4``) to eclipse times (``ucbplan ephemeris fit``).

    Parameters
    ----------
    times : str, Path or astropy.table.Table
        Eclipse-time table (docs/timing.md): ``bjd_tdb`` (or ``bmjd_tdb``; text keeps every
        digit, a ``Time`` column in TDB too), ``sigma_s`` [s], optional ``kind`` and ``cycle``.
    period : str, float or Quantity, optional
        First period guess (``"0.0595 d"``, seconds, or a time Quantity) to count cycles,
        trusted to its last digit.
    initial : str, Path, dict or Target, optional
        An earlier timing ephemeris (a target with ``timing``: t0, period[, pdot]) to count
        cycles from.
    terms : int
        2 (T0, P), 3 (+Ṗ) or 4 (+P̈).
    clip : float, optional
        Drop times more than ``clip`` (rescaled) σ from the fit [σ, ≥ 1]; reported.

    Returns
    -------
    TimingFit
        The fitted parameters, their covariance and ``notes`` (what the fit decided);
        ``.to_target(...)`` turns it into a target, ``.to_dict()`` is the JSON report.

    Raises
    ------
    InputError
        Bad table, ambiguous cycle count, too few times (one line each, naming the row).

    Examples
    --------
    Five eclipses of a 400 s binary, 1000 cycles apart (times as text keep every digit):

    >>> from astropy.table import Table
    >>> import ucbplan
    >>> times = Table(
    ...     {
    ...         "cycle": [0, 1000, 2000, 3000, 4000],
    ...         "bjd_tdb": [
    ...             "2461000.5000000",
    ...             "2461005.1296296",
    ...             "2461009.7592593",
    ...             "2461014.3888889",
    ...             "2461019.0185185",
    ...         ],
    ...         "sigma_s": [1.0] * 5,
    ...     }
    ... )
    >>> ucbplan.fit_ephemeris(times, terms=2)
    <TimingFit <Table>: T0=BJD_TDB 2461009.7592593±0.447 s, P=400±0.00032 s; 5 times,
    chi2/dof=...>
    """
    from ucbplan.timing import fit_times

    guess = _first_ephemeris(period, initial, terms, clip)
    with scope():
        table = _times(times)
        notes: tuple[str, ...] = ()
        if table.cycle is not None and guess is not None:
            notes = (f"{guess.origin} ignored: the table has a cycle column",)
        fit = fit_times(table, guess, int(terms), None if clip is None else float(clip))
    return TimingFit(fit, table, notes + tuple(fit.notes))


def _first_ephemeris(period: Any, initial: Any, terms: Any, clip: Any) -> PeriodGuess | None:
    """The checked options and the first ephemeris that counts cycles (``period``/``initial``)."""
    from ucbplan.inputs import check_number, is_number
    from ucbplan.timing import period_guess, read_initial

    if not (is_number(terms) and terms in (2, 3, 4)):
        raise InputError(f"terms: expected 2, 3 or 4, got {shorten(terms)}", parameter="terms")
    check_number("clip", clip, 1.0, 1e6, "σ", "times within 1σ are never outliers")
    if period is not None and initial is not None:
        raise InputError("period, initial: give one first ephemeris, not both", "period")
    if isinstance(initial, str | Path):
        return read_initial(_existing(initial, "initial"))
    if initial is not None:
        return _guess_of(initial)
    if period is None:
        return None
    p = as_float(period, "s", "period")
    return period_guess(f"{p!r} s" if isinstance(p, float) else p, "period")


def _existing(path: str | Path, parameter: str) -> str | Path:
    """``path`` if it names a file; else one line naming ``parameter`` and the path as given."""
    from ucbplan.api.targets import is_path

    is_path(path, parameter)
    if not Path(path).is_file():
        raise InputError(
            f"{parameter}: {shorten(str(path), 80)}: file not found; check the path", parameter
        )
    return path


def _guess_of(initial: Any) -> PeriodGuess:
    """The first ephemeris of a target in memory (a ``Target`` or a document)."""
    from ucbplan.timing.initial import guess_from_document

    if isinstance(initial, Mapping):
        return guess_from_document(initial, "<dict>")
    from ucbplan.api.targets import load_as
    from ucbplan.targets import target_to_dict

    t = load_as(initial, "initial")
    return guess_from_document(target_to_dict(t), t.name)


def _times(times: Any) -> EclipseTimes:
    """The eclipse times of a file or an astropy ``Table``."""
    from astropy.table import Table

    from ucbplan.api.targets import is_path
    from ucbplan.timing import read_times
    from ucbplan.timing.eclipse_table import read_times_table

    if isinstance(times, Table):
        return read_times_table(times)
    if not is_path(times, "times"):
        raise InputError(
            f"times: expected a table file (CSV or ECSV) or an astropy Table, got "
            f"{shorten(times, 60)}",
            parameter="times",
        )
    return read_times(times)
