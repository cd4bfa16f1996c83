"""Targets and sites at the door of the public API: read, check, summarise, write.

:func:`load_target` takes what a notebook holds (a path, a parsed document, a ``Target``);
:func:`write_target` writes one back (never over a file unless asked); :func:`validate` is
``ucbplan validate``'s summary of each file; :func:`get_site` takes a name, an
``EarthLocation`` or an astroplan ``Observer``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ucbplan.errors import InputError, shorten

if TYPE_CHECKING:
    from ucbplan.observing.observatory.sites import Site
    from ucbplan.targets import Target

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

    Examples
    --------
    >>> import ucbplan
    >>> ucbplan.load_target("catalogs/hm-cnc-simulated.yaml")
    <Target 'HM Cnc (simulated)' (lisa): P=321.5178509 s, RA=121.59667°, Dec=+15.45833°, ...>
    """
    return load_as(target, "target")


def load_as(target: TargetLike, parameter: str) -> Target:
    """:func:`load_target` of the argument ``parameter`` (named by its errors)."""
    from ucbplan.targets import Target
    from ucbplan.targets import load_target as _load
    from ucbplan.targets.parse import target_from_dict

    if isinstance(target, Target):
        return target
    if isinstance(target, Mapping):
        return target_from_dict(dict(target))
    if is_path(target, parameter):
        return _load(target)
    raise InputError(
        f"{parameter}: expected a target file path, a target document (dict) or a Target, got "
        f"{shorten(target, 60)}",
        parameter=parameter,
    )


def write_target(target: TargetLike, path: str | Path, overwrite: bool = False) -> Path:
    """Write a target as a target YAML file that :func:`load_target` reads back.

    Parameters
    ----------
    target : Target, dict, str or Path
        The target (see :func:`load_target`), e.g. ``fit.to_target(...)``.
    path : str or Path
        The file to write.
    overwrite : bool
        Replace an existing file (else refuse it).

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    OutputExistsError
        ``path`` exists and ``overwrite`` is false (nothing is written).

    Examples
    --------
    >>> import pathlib, tempfile
    >>> import ucbplan
    >>> tmp = tempfile.TemporaryDirectory()
    >>> path = pathlib.Path(tmp.name) / "hm-cnc.yaml"
    >>> ucbplan.write_target("catalogs/hm-cnc-simulated.yaml", path).name
    'hm-cnc.yaml'
    >>> ucbplan.load_target(path).name
    'HM Cnc (simulated)'
    >>> tmp.cleanup()
    """
    from ucbplan.targets import write_target as _write

    if not isinstance(path, str | Path) or not str(path).strip():
        raise InputError(f"path: expected a file path, got {shorten(path, 60)}", "path")
    if not isinstance(overwrite, bool):
        raise InputError(
            f"overwrite: expected True or False, got {shorten(overwrite)}", "overwrite"
        )
    out = Path(path)
    _write(load_target(target), out, overwrite=overwrite)
    return out


def is_path(value: Any, parameter: str) -> bool:
    """Whether ``value`` is a path (text or ``Path``); a blank one, or one with a line break or
    another unprintable character (an error naming it would not be one line), is refused naming
    ``parameter``."""
    if not isinstance(value, str | Path):
        return False
    text = str(value)
    if not text.strip() or not text.isprintable():
        raise InputError(f"{parameter}: expected a file path, got {shorten(text, 60)}", parameter)
    return True


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
    InputError
        Anything else, or a location holding more than one place.

    Examples
    --------
    >>> import ucbplan
    >>> site = ucbplan.get_site("paranal")
    >>> site.name, site.timezone
    ('Paranal', 'America/Santiago')
    >>> site.lat_deg, site.height_m
    (-24.6272, 2635.0)
    """
    from ucbplan.observing.observatory.sites import Site, resolve_site, site_from_lonlat

    if timezone is not None and not isinstance(timezone, str):
        raise InputError(
            f"timezone: expected an IANA time zone name, got {shorten(timezone, 60)}", "timezone"
        )
    if isinstance(site, Site):
        return resolve_site(site.name, timezone=timezone) if timezone else site
    location = getattr(site, "location", None) if _is_observer(site) else site
    if hasattr(location, "geodetic"):
        if timezone is None and _is_observer(site) and str(site.timezone) != "UTC":
            timezone = str(site.timezone)
        return site_from_lonlat(_lonlat_text(location), timezone)
    if isinstance(site, str) and site.strip():
        return resolve_site(site, timezone=timezone)
    raise InputError(
        f"site: expected a site name (e.g. 'paranal'), an EarthLocation or an astroplan "
        f"Observer, got {shorten(site, 60)}",
        parameter="site",
    )


def _lonlat_text(location: Any) -> str:
    """``"LON,LAT,HEIGHT"`` of one ``EarthLocation`` (refusing an array of them)."""
    size = getattr(location, "size", 1)
    if size != 1:
        raise InputError(
            f"site: expected one location, got an EarthLocation of {size} places; pass one, "
            "e.g. location[0]",
            parameter="site",
        )
    geo = location.geodetic
    numbers = (geo.lon.deg, geo.lat.deg, geo.height.to_value("m"))
    return ",".join(repr(float(v)) for v in numbers)


def _is_observer(obj: Any) -> bool:
    return type(obj).__name__ == "Observer" and type(obj).__module__.startswith("astroplan")


def validate(targets: TargetLike | Sequence[TargetLike]) -> list[dict[str, Any]]:
    """Check target files and summarise each (``ucbplan validate``).

    Parameters
    ----------
    targets : target or list of targets
        Each a path, a target document or a ``Target`` (see :func:`load_target`).

    Returns
    -------
    list of dict
        One summary per target, as ``ucbplan validate --format json`` prints it: times as TDB ISO
        strings, the rest SI floats (period [s], ω [deg], σ_u [mrad] …; a timing ephemeris: T0,
        P, Ṗ with their σ, and σ_u, σ_t one year before and after T0).

    Raises
    ------
    TargetFileError
        The first file that is not a valid target (one line naming the field).

    Examples
    --------
    >>> import ucbplan
    >>> row = ucbplan.validate("catalogs/hm-cnc-simulated.yaml")[0]
    >>> row["name"], row["t_ref_tdb"], row["t_end_tdb"]
    ('HM Cnc (simulated)', '2037-01-01T00:00:00.000', '2039-01-01T12:18:19.525')
    """
    from ucbplan.api.target_summary import summary

    items = list(targets) if _is_sequence(targets) else [targets]
    return [summary(load_target(item)) for item in items]


def _is_sequence(value: Any) -> bool:
    return isinstance(value, Sequence) and not isinstance(value, str)
