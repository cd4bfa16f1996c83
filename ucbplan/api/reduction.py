"""``ucbplan.reduce``: measured velocities → K_j, γ_j, masses, Δκ and Δv_CM, the library
behind ``ucbplan reduce`` (its options declared once, in :data:`REDUCE_FLAGS`)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

from ucbplan.api._convert import scope
from ucbplan.api.ephemeris import TargetLike, get_site, load_target
from ucbplan.api.flagspec import Flag
from ucbplan.errors import InputError, ReduceWarning, emit, shorten

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from ucbplan.reduce.pipeline import ReduceOptions, Reduction

#: Fewest Monte-Carlo samples (fewer give no usable quantiles).
MIN_SAMPLES = 100
#: Most Monte-Carlo samples: above 250 000 they run in chunks; 10⁷ take ~0.65 GB peak resident
#: memory and ~20 s (benchmarks/reduce_scaling.py).
MAX_SAMPLES = 10_000_000

#: How ``ucbplan reduce`` spells the parameters of :func:`reduce`.
REDUCE_FLAGS: dict[str, Flag] = {
    "target": Flag((), "Target YAML file (LISA ephemeris and posterior)."),
    "velocities": Flag(
        (), "Velocity table (CSV or ECSV): bjd_tdb, exptime_s, v1, sigma_v1, v2, sigma_v2."
    ),
    "samples": Flag(("--samples",), "Monte-Carlo samples.", min=MIN_SAMPLES, max=MAX_SAMPLES),
    "seed": Flag(("--seed",), "Random seed (reported).", min=0),
    "light_time": Flag(("--light-time",), "Correct for the light travel time across the orbit."),
    "mass_radius": Flag(
        ("--mass-radius",),
        "WD mass–radius relation for the redshift check: "
        "eggleton (Verbunt & Rappaport 1988) | nauenberg (Nauenberg 1972).",
    ),
    "cos_i_sigma": Flag(
        ("--cos-i-sigma",),
        "1σ of cos ι if neither covariance nor samples carry it (default: held fixed).",
        min=0.0,
    ),
    "site": Flag(("--site",), "Observatory (bundled site table) for jd_utc/mjd_utc time columns."),
}


def check_count(parameter: str, value: Any, low: int, high: int, why: str = "") -> int:
    """``value`` as an int: a whole number (not a bool) in [low, high].

    Raises
    ------
    InputError
        One line naming ``parameter``: what was expected and what was given.
    """
    from ucbplan.inputs import check_int

    return check_int(parameter, value, low, high, why)


def check_seed(value: Any, parameter: str = "seed", optional: bool = False) -> int | None:
    """A random seed: a whole number >= 0 (None too, with ``optional``: fresh entropy).

    Raises
    ------
    InputError
        One line naming ``parameter``.
    """
    from ucbplan.inputs import is_number

    if value is None and optional:
        return None
    whole = is_number(value) and math.isfinite(float(value)) and float(value) == int(value)
    if whole and int(value) >= 0:
        return int(value)
    expected = "a whole number >= 0" + (" or None (fresh entropy)" if optional else "")
    raise InputError(
        f"{parameter}: expected {expected}, got {shorten(value, 40)}", parameter=parameter
    )


@dataclass(frozen=True, slots=True)
class Measurement:
    """One reported quantity: value and 1σ in ``unit`` (None where not measurable)."""

    value: float | None
    sigma: float | None
    unit: str

    def __repr__(self) -> str:
        value = "nan" if self.value is None else f"{self.value:.6g}"
        sigma = "nan" if self.sigma is None else f"{self.sigma:.2g}"
        return f"{value} ± {sigma}" + (f" {self.unit}" if self.unit else "")

    @property
    def quantity(self) -> Any:
        """The value as an astropy ``Quantity`` (NaN where not measurable)."""
        import astropy.units as u

        return (float("nan") if self.value is None else self.value) * u.Unit(self.unit or "")


#: The headline quantities of a report, in its order.
_HEADLINE = ("K1", "K2", "gamma1", "gamma2", "q", "M1", "M2", "M_tot")


@dataclass(frozen=True)
class Report:
    """A finished reduction: K_j, γ_j, masses, Δκ and Δv_CM with their uncertainties.

    Attributes
    ----------
    reduction : Reduction
        Everything the reduction found (fits, Monte-Carlo samples …).

    Examples
    --------
    The bundled fiducial eccentric binary's velocities (truth K1 = 585.293 km/s):

    >>> import ucbplan
    >>> report = ucbplan.reduce(
    ...     "catalogs/fiducial-eccentric.yaml",
    ...     "catalogs/fiducial-eccentric-velocities.csv",
    ...     seed=1,
    ...     samples=2000,
    ...     warn=False,
    ... )
    >>> report.K1, report["M_tot"]
    (586.476 ± 1 km / s, 0.632644 ± 0.0021 solMass)
    >>> report.to_dict()["K1"]["unit"]
    'km / s'
    >>> list(report.em_prior()["em_prior"])
    ['target', 'source', 'q', 'M_tot', 'M1', 'M2', 'M_c', 'K1', 'K2', 'a_los']
    """

    reduction: Reduction

    @cached_property
    def _doc(self) -> dict[str, Any]:
        from ucbplan.reduce.report import build_report

        return build_report(self.reduction)

    def __repr__(self) -> str:
        shown = [f"{k} = {m!r}" for k in _HEADLINE[:2] if (m := self[k]) is not None]
        return (
            f"<Report {self.target}: {self.n_spectra} spectra, {', '.join(shown)}, "
            f"seed {self.seed}>"
        )

    def __getitem__(self, key: str) -> Measurement | None:
        """A reported quantity by its report key (``"K1"``, ``"M_tot"``, ``"dkappa"`` …)."""
        entry = self._doc.get(key)
        if not isinstance(entry, dict) or "value" not in entry:
            return None
        return Measurement(entry["value"], entry["sigma"], str(entry.get("unit", "")))

    @property
    def target(self) -> str:
        """The target's name."""
        return str(self._doc["target"])

    @property
    def seed(self) -> int:
        """The seed of the Monte-Carlo draws (reported; rerun with it to repeat them)."""
        return int(self._doc["seed"])

    @property
    def n_spectra(self) -> int:
        """Spectra reduced."""
        return int(self._doc["n_spectra"])

    @property
    def K1(self) -> Measurement | None:
        """K_1 [km/s] (σ: statistical ⊕ phase ⊕ attenuation)."""
        return self["K1"]

    @property
    def K2(self) -> Measurement | None:
        """K_2 [km/s]; None for a single-lined binary."""
        return self["K2"]

    @property
    def quantities(self) -> dict[str, Measurement]:
        """Every reported quantity with a value and σ, by report key, in the report's order."""
        return {k: m for k in self._doc if (m := self[k]) is not None}

    def to_dict(self) -> dict[str, Any]:
        """The report exactly as ``ucbplan reduce --format json`` writes it, as Python values.

        Returns
        -------
        dict
            By report key (``"K1"``, ``"M_tot"`` …): plain floats (km/s, M_sun …, the unit named
            in each entry's ``unit``), lists and dicts; NaN as None.
        """
        from ucbplan.io import json_plain

        return dict(json_plain(self._doc))

    @property
    def warnings(self) -> list[str]:
        """What the reduction warns about (also emitted as :class:`ucbplan.ReduceWarning`)."""
        return [str(w) for w in self._doc.get("warnings", [])]

    def dump(self, handle: IO[str], fmt: str = "json") -> None:
        """Write the report to an open text ``handle`` (what ``reduce -o`` writes).

        Parameters
        ----------
        handle : file-like
            An open text stream.
        fmt : str
            ``json`` (indented, NaN-free); any other value writes block-style YAML.
        """
        from ucbplan.reduce.report import write_json, write_yaml

        (write_json if fmt == "json" else write_yaml)(self._doc, handle)

    def print(self, console: Any) -> None:
        """The report as rich tables on ``console`` (what ``ucbplan reduce`` shows).

        Parameters
        ----------
        console : rich.console.Console
            Where to print (the command line's prints to stderr).
        """
        from ucbplan.reduce.report import print_report

        print_report(self._doc, console)

    def write(
        self,
        path: str | Path | None,
        fmt: str = "json",
        *,
        em_prior: str | Path | None = None,
        overwrite: bool = False,
    ) -> None:
        """Write the report and the EM prior (YAML) atomically: both or neither.

        Parameters
        ----------
        path : str, Path or None
            The report's file (None: no report file).
        fmt : str
            ``json``; any other value writes YAML (as :meth:`dump`).
        em_prior : str or Path, optional
            The EM prior's file (``reduce --em-prior``; :meth:`em_prior`).
        overwrite : bool
            Replace existing files.

        Raises
        ------
        OutputExistsError
            A file exists and ``overwrite`` is false (nothing is written).
        """
        from ucbplan.io import write_file_set
        from ucbplan.reduce.report import em_prior as em_prior_doc
        from ucbplan.reduce.report import write_yaml

        files: dict[Path, Any] = {}
        if path is not None:
            files[Path(path)] = lambda h: self.dump(h, fmt)
        if em_prior is not None:
            prior = em_prior_doc(self.reduction)
            files[Path(em_prior)] = lambda h: write_yaml(prior, h)
        if files:
            write_file_set(files, overwrite=overwrite)

    def em_prior(self) -> dict[str, Any]:
        """The EM prior for a later LISA analysis or ``ucbplan simulate`` (``reduce --em-prior``).

        Returns
        -------
        dict
            ``{"em_prior": {"target", "source", <name>: {value, sigma, unit}}}`` for q, M_tot,
            M1, M2, M_c, K1, K2 (when measured) and a_los (value and σ, or an upper limit).
        """
        from ucbplan.reduce.report import em_prior

        return em_prior(self.reduction)

    def plot(self, ax: Any = None, overwrite: bool = False) -> Any:
        """The velocities against the orbital factor F̄ with the fitted lines.

        Parameters
        ----------
        ax : matplotlib Axes, str, Path or None
            Draw on this Axes; None: a new figure, with the residuals below; a folder (str or
            Path): write every figure of ``reduce --plots`` there (as :meth:`save_plots`).
        overwrite : bool
            With a folder: replace existing figures.

        Returns
        -------
        Axes or list of Path
            The ``Axes`` drawn on (``.figure.savefig`` to keep it), or the figures written.

        Raises
        ------
        InputError
            ``ax`` is none of these.
        OutputExistsError
            With a folder: a figure exists and ``overwrite`` is false (none is written).
        """
        if isinstance(ax, str | Path):
            return self.save_plots(ax, overwrite=overwrite)
        from ucbplan.reduce.plots import draw_rv, fig_rv

        if ax is None:
            axes: Axes = fig_rv(self.reduction).axes[0]
            return axes
        if not callable(getattr(ax, "errorbar", None)):
            raise InputError(
                f"ax: expected a matplotlib Axes, None or a folder, got {shorten(ax, 40)}", "ax"
            )
        draw_rv(self.reduction, ax)
        return ax

    def _repr_html_(self) -> str:
        from html import escape

        rows = "".join(
            f"<tr><td>{escape(k)}</td><td>{escape(repr(m))}</td></tr>"
            for k, m in self.quantities.items()
        )
        head = f"<b>{escape(self.target)}</b>: {self.n_spectra} spectra, seed {self.seed}"
        return f"<p>{head}</p><table>{rows}</table>"

    def save_plots(self, folder: str | Path, overwrite: bool = False) -> list[Path]:
        """Write the reduction's PNG figures in ``folder`` (``reduce --plots``).

        Parameters
        ----------
        folder : str or Path
            Where the figures go (file names :data:`ucbplan.reduce.plots.PLOT_NAMES`).
        overwrite : bool
            Replace existing figures.

        Returns
        -------
        list of Path
            The figures written (the Δv and mass–mass figures only where they apply).

        Raises
        ------
        OutputExistsError
            A figure exists and ``overwrite`` is false (checked for all before writing any).
        """
        from ucbplan.reduce.plots import plot_all

        return list(plot_all(self.reduction, Path(folder), overwrite=overwrite))


def reduce(
    target: TargetLike,
    velocities: Any,
    seed: int | None = None,
    *,
    samples: int = 20_000,
    light_time: bool = False,
    mass_radius: str | None = None,
    cos_i_sigma: float = 0.0,
    site: Any = None,
    warn: bool = True,
) -> Report:
    """Reduce measured velocities against a target (``ucbplan reduce``; paper Secs. 3–5).

    Parameters
    ----------
    target : str, Path, dict or Target
        LISA ephemeris and posterior (see :func:`ucbplan.load_target`).
    velocities : str, Path, astropy Table or VelocityTable
        Velocity table (CSV or ECSV file, or a table with its columns): ``bjd_tdb``,
        ``exptime_s``, ``v1``, ``sigma_v1`` … [km/s].
    seed, samples : int, optional
        Seed (>= 0) of the Monte-Carlo draws (None: fresh entropy, reported in the report);
        their number, from :data:`MIN_SAMPLES` to :data:`MAX_SAMPLES`.
    light_time, mass_radius, cos_i_sigma : bool, str, float, optional
        Correct for the light travel time across the orbit; WD mass–radius relation for the
        redshift check (``eggleton``, ``nauenberg``); 1σ of cos ι [1] in [0, 2] if neither the
        covariance nor the samples carry it.
    site : str, EarthLocation or astroplan Observer, optional
        Telescope, when the table's times are UTC at the site.
    warn : bool
        Emit the report's warnings as :class:`ucbplan.ReduceWarning` (the CLI prints them).

    Returns
    -------
    Report
        K_j, γ_j [km/s], masses [M_sun], Δκ, Δv_CM, and the warnings.

    Raises
    ------
    InputError
        Bad options (naming the parameter); VelocityFileError, TargetFileError for the files.

    Examples
    --------
    The bundled exact-Keplerian velocities of the fiducial eccentric binary (truth K1 = 585.293,
    K2 = 712.620 km/s):

    >>> import ucbplan
    >>> ucbplan.reduce(
    ...     "catalogs/fiducial-eccentric.yaml",
    ...     "catalogs/fiducial-eccentric-velocities.csv",
    ...     seed=1,
    ...     samples=2000,
    ... )
    <Report Fiducial eccentric dWD: 480 spectra, K1 = 586.476 ± 1 km / s,
    K2 = 711.893 ± 0.99 km / s, seed 1>
    """
    from ucbplan.reduce.pipeline import reduce as _reduce

    checked = reduce_options(
        seed=seed,
        samples=samples,
        light_time=light_time,
        mass_radius=mass_radius,
        cos_i_sigma=cos_i_sigma,
    )
    with scope():
        tgt = load_target(target)
        table = _velocity_table(velocities, tgt, site)
        report = Report(_reduce(tgt, table, checked))
        _ = report._doc  # the report's numbers, built inside the astropy scope
    if warn:
        emit(report.warnings, ReduceWarning)
    return report


def reduce_options(
    *,
    seed: Any,
    samples: Any,
    light_time: Any,
    mass_radius: Any,
    cos_i_sigma: Any,
) -> ReduceOptions:
    """The checked options of :func:`reduce` (one line naming the parameter at fault)."""
    from ucbplan.inputs import check_range
    from ucbplan.reduce.pipeline import reduce_options as _options

    if not isinstance(light_time, bool):
        raise InputError(
            f"light_time: expected True or False, got {shorten(light_time)}", "light_time"
        )
    if mass_radius is not None and not isinstance(mass_radius, str):
        raise InputError(
            f"mass_radius: expected a name or None, got {shorten(mass_radius)}", "mass_radius"
        )
    return _options(
        samples=check_count("samples", samples, MIN_SAMPLES, MAX_SAMPLES),
        seed=check_seed(seed, optional=True),
        light_time=light_time,
        mass_radius=mass_radius,
        cos_i_sigma=check_range("cos_i_sigma", cos_i_sigma, 0.0, 2.0, why="1σ of cos ι"),
    )


def _velocity_table(velocities: Any, tgt: Any, site: Any) -> Any:
    """The velocity table, site-UTC times converted to barycentric TDB at ``site``."""
    from ucbplan.reduce.velocities import (
        VelocityTable,
        read_velocities,
        to_barycentric,
        velocities_from_table,
    )

    if isinstance(velocities, VelocityTable):
        table = velocities
    elif isinstance(velocities, str | Path):
        table = read_velocities(velocities)
    elif hasattr(velocities, "colnames"):
        table = velocities_from_table(velocities, Path("velocities"))
    else:
        raise InputError(
            "velocities: expected a file (str or Path) or an astropy Table, got "
            f"{shorten(velocities, 40)}",
            parameter="velocities",
        )
    if table.site_utc:
        if site is None:
            raise InputError(
                f"site: {table.source}: times are UTC at the telescope; pass site=NAME to "
                "convert them",
                parameter="site",
            )
        table = to_barycentric(table, tgt.coord, get_site(site).location)
    return table
