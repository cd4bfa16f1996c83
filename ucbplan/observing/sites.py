"""Observatory sites: the bundled table, user site files and ``--site-lonlat``.

Never ``EarthLocation.of_site`` (it needs the network): sites come from ``ucbplan/data/sites.yaml``
(a copy of ``configs/sites.yaml``) or a user YAML file with the same schema.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any
from zoneinfo import ZoneInfo, ZoneInfoNotFoundError

import yaml
from astropy import units as u
from astropy.coordinates import EarthLocation

from ucbplan.errors import SiteError, UcbplanError

__all__ = ["Site", "get_site", "load_sites", "resolve_site", "site_from_lonlat"]


@dataclass(frozen=True, slots=True)
class Site:
    """An observatory: geodetic WGS84 position, IANA time zone, optional zenith hole.

    Attributes
    ----------
    name : str
        Display name.
    lon_deg, lat_deg : float
        East longitude and latitude [deg].
    height_m : float
        Height above the WGS84 ellipsoid [m].
    timezone : str
        IANA time zone (e.g. ``America/Santiago``).
    zenith_hole_deg : float or None
        Radius of the region around the zenith that cannot be observed [deg].
    aliases : tuple of str
        Alternative names accepted by :func:`get_site`.
    """

    name: str
    lon_deg: float
    lat_deg: float
    height_m: float
    timezone: str
    zenith_hole_deg: float | None = None
    aliases: tuple[str, ...] = field(default_factory=tuple)

    @property
    def location(self) -> EarthLocation:
        """The site as an astropy ``EarthLocation`` (geodetic WGS84)."""
        return EarthLocation.from_geodetic(
            self.lon_deg * u.deg, self.lat_deg * u.deg, self.height_m * u.m
        )

    @property
    def zone(self) -> ZoneInfo:
        """The site's time zone."""
        return ZoneInfo(self.timezone)

    def as_dict(self) -> dict[str, Any]:
        """Plain dict for provenance metadata."""
        return {
            "name": self.name,
            "lon_deg": self.lon_deg,
            "lat_deg": self.lat_deg,
            "height_m": self.height_m,
            "timezone": self.timezone,
            "zenith_hole_deg": self.zenith_hole_deg,
        }


def _key(name: str) -> str:
    """Normalised lookup key: case-, space-, hyphen- and bracket-insensitive."""
    return re.sub(r"[^a-z0-9.]", "", name.lower())


def _number(entry: dict[str, Any], key: str, where: str, lo: float, hi: float) -> float:
    try:
        value = float(entry[key])
    except KeyError as exc:
        raise SiteError(f"{where}: field {key!r} is missing; add it (degrees/metres)") from exc
    except (TypeError, ValueError) as exc:
        raise SiteError(f"{where}: {key}: expected a number, got {entry[key]!r}") from exc
    if not lo <= value <= hi:
        raise SiteError(f"{where}: {key}: expected {lo} <= value <= {hi}, got {value}")
    return value


def _check_zone(zone: str, where: str) -> str:
    try:
        ZoneInfo(zone)
    except (ZoneInfoNotFoundError, ValueError) as exc:
        raise SiteError(
            f"{where}: timezone: unknown IANA time zone {zone!r}; use e.g. 'America/Santiago'"
        ) from exc
    return zone


def _parse_site(entry: Any, where: str) -> Site:
    if not isinstance(entry, dict) or "name" not in entry:
        raise SiteError(f"{where}: expected a mapping with 'name', got {entry!r}")
    where = f"{where} ({entry['name']})"
    hole = entry.get("zenith_hole_deg")
    aliases = entry.get("aliases") or []
    if not isinstance(aliases, list):
        raise SiteError(f"{where}: aliases: expected a list of names, got {aliases!r}")
    return Site(
        name=str(entry["name"]),
        lon_deg=_number(entry, "lon_deg", where, -180.0, 360.0),
        lat_deg=_number(entry, "lat_deg", where, -90.0, 90.0),
        height_m=_number(entry, "height_m", where, -500.0, 10000.0),
        timezone=_check_zone(str(entry.get("timezone", "UTC")), where),
        zenith_hole_deg=None if hole is None else _number(entry, "zenith_hole_deg", where, 0, 45),
        aliases=tuple(str(a) for a in aliases),
    )


def _read_yaml(text: str, where: str) -> list[Site]:
    try:
        doc = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise SiteError(f"{where}: not valid YAML ({exc})".replace("\n", " ")) from exc
    if not isinstance(doc, dict) or not isinstance(doc.get("sites"), list):
        raise SiteError(f"{where}: expected a top-level 'sites:' list of site mappings")
    return [_parse_site(e, f"{where}: sites[{i}]") for i, e in enumerate(doc["sites"])]


def load_sites(path: Path | None = None) -> list[Site]:
    """Load a site table: the bundled one (default) or a user YAML file with the same schema.

    Raises
    ------
    SiteError
        If the file is missing or malformed.
    """
    if path is None:
        text = resources.files("ucbplan").joinpath("data/sites.yaml").read_text(encoding="utf-8")
        return _read_yaml(text, "ucbplan/data/sites.yaml")
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise SiteError(f"{path}: cannot read site file ({exc.strerror}); check the path") from exc
    return _read_yaml(text, str(path))


def get_site(name: str, sites_file: Path | None = None) -> Site:
    """Look a site up by name or alias (case-, space- and punctuation-insensitive).

    A user ``sites_file`` is searched first, then the bundled table.

    Raises
    ------
    SiteError
        If no site matches; the message lists the known names.
    """
    tables = ([*load_sites(sites_file)] if sites_file is not None else []) + load_sites()
    key = _key(name)
    for site in tables:
        if key in {_key(site.name), *(_key(a) for a in site.aliases)}:
            return site
    known = ", ".join(dict.fromkeys(s.name for s in tables))
    raise SiteError(
        f"unknown site {name!r}; known sites: {known}; or give --site-lonlat LON,LAT,HEIGHT "
        "or --sites-file FILE"
    )


def site_from_lonlat(text: str, timezone: str | None = None) -> Site:
    """Site from ``"LON,LAT,HEIGHT"`` (degrees east, degrees north, metres).

    Without ``timezone`` the zone is the nautical one of the longitude (``Etc/GMT±N``), which is
    only used to interpret ``--night`` as a local date.

    Raises
    ------
    SiteError
        If the text is not three numbers in range.
    """
    parts = [p.strip() for p in text.split(",")]
    if len(parts) != 3:
        raise SiteError(
            f"--site-lonlat: expected LON,LAT,HEIGHT (deg east, deg north, m), got {text!r}"
        )
    try:
        lon, lat, height = (float(p) for p in parts)
    except ValueError as exc:
        raise SiteError(f"--site-lonlat: expected three numbers, got {text!r}") from exc
    entry = {"name": f"lon{lon:+.4f} lat{lat:+.4f}", "lon_deg": lon, "lat_deg": lat}
    entry["height_m"] = height
    if timezone is None:
        offset = round(((lon + 180.0) % 360.0 - 180.0) / 15.0)
        # Etc/GMT signs are inverted (POSIX): Etc/GMT+5 is UTC-5.
        timezone = "Etc/UTC" if offset == 0 else f"Etc/GMT{-offset:+d}"
    entry["timezone"] = timezone
    return _parse_site(entry, "--site-lonlat")


def resolve_site(
    name: str | None = None, lonlat: str | None = None, sites_file: Path | None = None
) -> Site:
    """The site named by ``--site NAME`` (looked up, ``sites_file`` first) or given by
    ``--site-lonlat LON,LAT,HEIGHT`` (which wins when both are given).

    Raises
    ------
    UcbplanError
        If neither is given, or the name or coordinates are not valid.
    """
    if lonlat:
        return site_from_lonlat(lonlat)
    if not name:
        raise UcbplanError("no site: pass --site NAME (e.g. paranal) or --site-lonlat LON,LAT,H")
    return get_site(name, sites_file)
