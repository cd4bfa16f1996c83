"""Observatory sites: the bundled table, user site files and ``--site-lonlat``.

Never ``EarthLocation.of_site`` (it needs the network): sites come from ``ucbplan/data/sites.yaml``
(a copy of ``configs/sites.yaml``) or a user YAML file with the same schema.
"""

from __future__ import annotations

import functools
import re
from dataclasses import dataclass, field, replace
from importlib import resources
from pathlib import Path
from typing import Any
from zoneinfo import ZoneInfo, ZoneInfoNotFoundError, available_timezones

from astropy import units as u
from astropy.coordinates import EarthLocation

from ucbplan.errors import InputError, SiteError, UcbplanError, shorten
from ucbplan.inputs import check_range, load_yaml
from ucbplan.targets.values import did_you_mean


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


#: Fields of one site entry: required ones first.
SITE_FIELDS = ("name", "lon_deg", "lat_deg", "height_m", "timezone", "zenith_hole_deg", "aliases")
_REQUIRED = ("name", "lon_deg", "lat_deg", "height_m", "timezone")
#: Ranges of the numeric fields: (low, high, unit, why).
_RANGES = {
    "lon_deg": (-180.0, 360.0, "deg", "east longitude"),
    "lat_deg": (-90.0, 90.0, "deg", "geodetic latitude"),
    "height_m": (-500.0, 10000.0, "m", "height above the WGS84 ellipsoid"),
    "zenith_hole_deg": (0.0, 45.0, "deg", "radius around the zenith; omit when unknown"),
}
#: Longest site name or alias [characters].
_MAX_NAME_CHARS = 100
#: Most aliases of one site.
_MAX_ALIASES = 100


def east_longitude(lon_deg: float) -> float:
    """The one longitude rule: any east longitude in [−180, 360] deg as its value in [−180, 180).

    Site files and ``--site-lonlat`` accept both conventions (0…360 and ±180); every consumer
    (the time-zone lookup, astropy's ``EarthLocation``, the local-time columns) then sees the
    same normalised value.
    """
    return (lon_deg + 180.0) % 360.0 - 180.0


@functools.lru_cache(maxsize=1)
def _zone_names() -> frozenset[str]:
    return frozenset(available_timezones())


def _check_zone(zone: Any, where: str) -> str:
    """``zone`` if it is an IANA time-zone name this Python knows."""
    names = _zone_names()
    if isinstance(zone, str) and len(zone) <= 100 and (not names or zone in names):
        try:
            ZoneInfo(zone)
            return zone
        except (ZoneInfoNotFoundError, ValueError, OSError):
            pass
    hint = did_you_mean(zone, sorted(names)) if isinstance(zone, str) else ""
    raise SiteError(
        f"{where}: timezone: {hint}expected an IANA time-zone name like 'America/Santiago', "
        f"got {shorten(zone, 60)}"
    )


def _text(value: Any, where: str, what: str) -> str:
    """A non-empty printable name of at most :data:`_MAX_NAME_CHARS` characters."""
    ok = isinstance(value, str) and 0 < len(value.strip()) and len(value) <= _MAX_NAME_CHARS
    if not ok or not value.isprintable():
        raise SiteError(
            f"{where}: expected {what} (printable text of 1-{_MAX_NAME_CHARS} characters), "
            f"got {shorten(value, 60)}"
        )
    return str(value).strip()


def _check_keys(entry: dict[Any, Any], where: str) -> None:
    for key in entry:
        if key not in SITE_FIELDS:
            hint = did_you_mean(key, SITE_FIELDS) if isinstance(key, str) else ""
            raise SiteError(
                f"{where}: {_label(key)}: unknown field; {hint}fields are {', '.join(SITE_FIELDS)}"
            )
    for key in _REQUIRED:
        if key not in entry:
            raise SiteError(
                f"{where}: {key}: missing; every site needs {', '.join(_REQUIRED)} "
                "(degrees, metres, IANA time zone)"
            )


def _aliases(value: Any, where: str) -> tuple[str, ...]:
    if value is None:
        return ()
    if not isinstance(value, list) or len(value) > _MAX_ALIASES:
        raise SiteError(
            f"{where}: aliases: expected a list of at most {_MAX_ALIASES} names, "
            f"got {shorten(value, 60)}"
        )
    return tuple(_text(a, f"{where}: aliases[{k}]", "a name") for k, a in enumerate(value))


def _parse_site(entry: Any, where: str) -> Site:
    if not isinstance(entry, dict):
        raise SiteError(f"{where}: expected a mapping of site fields, got {shorten(entry, 60)}")
    name = _text(entry.get("name"), f"{where}: name", "the site name")
    where = f"{where} ({shorten(name, 40)})"
    _check_keys(entry, where)
    num = {
        k: check_range(f"{where}: {k}", entry[k], *_RANGES[k], error=SiteError)
        for k in _RANGES
        if entry.get(k) is not None or k in _REQUIRED
    }
    return Site(
        name=name,
        lon_deg=east_longitude(num["lon_deg"]),
        lat_deg=num["lat_deg"],
        height_m=num["height_m"],
        timezone=_check_zone(entry["timezone"], where),
        zenith_hole_deg=num.get("zenith_hole_deg"),
        aliases=_aliases(entry.get("aliases"), where),
    )


def _unique(sites: list[Site], where: str) -> list[Site]:
    """Refuse two sites of one table sharing a name or alias (lookups would be ambiguous)."""
    owner: dict[str, int] = {}
    for i, site in enumerate(sites):
        for label in (site.name, *site.aliases):
            key = _key(label)
            if owner.setdefault(key, i) != i:
                raise SiteError(
                    f"{where}: sites[{owner[key]}] ({shorten(sites[owner[key]].name, 40)}) and "
                    f"sites[{i}] ({shorten(site.name, 40)}) both answer to {shorten(label, 40)}; "
                    "rename one or drop the alias"
                )
    return sites


def _label(key: Any) -> str:
    """A mapping key as messages show it: plain when it is a short printable name."""
    if isinstance(key, str) and key.isprintable() and 0 < len(key) <= 40:
        return key
    return shorten(key, 40)


def _read_yaml(path: Path, text: str | None = None) -> list[Site]:
    doc = load_yaml(path, "site table", text=text)
    where = str(path)
    if not isinstance(doc, dict) or "sites" not in doc:
        raise SiteError(f"{where}: expected a top-level 'sites:' list of site mappings")
    for key in doc:
        if key != "sites":
            hint = did_you_mean(key, ["sites"]) if isinstance(key, str) else ""
            raise SiteError(
                f"{where}: {_label(key)}: unknown top-level key; {hint}the file holds "
                "one 'sites:' list"
            )
    entries = doc["sites"]
    if not isinstance(entries, list) or not entries:
        raise SiteError(
            f"{where}: sites: expected a list of site mappings, got {shorten(entries, 60)}"
        )
    return _unique([_parse_site(e, f"{where}: sites[{i}]") for i, e in enumerate(entries)], where)


@functools.lru_cache(maxsize=1)
def _bundled() -> tuple[Site, ...]:
    text = resources.files("ucbplan").joinpath("data/sites.yaml").read_text(encoding="utf-8")
    return tuple(_read_yaml(Path("ucbplan/data/sites.yaml"), text))


def load_sites(path: Path | None = None) -> list[Site]:
    """Load a site table: the bundled one (default) or a user YAML file with the same schema.

    The file is read by :func:`ucbplan.inputs.load_yaml` (UTF-8, size limit, no duplicate keys,
    alias budget). Every entry needs ``name``, ``lon_deg``, ``lat_deg``, ``height_m`` and an
    IANA ``timezone``; ``zenith_hole_deg`` and ``aliases`` are optional; other keys are refused
    with the closest field name.

    Raises
    ------
    SiteError
        If the file is missing, unreadable or malformed (one line naming the field).
    """
    if path is None:
        return list(_bundled())
    try:
        return _read_yaml(Path(path))
    except SiteError:
        raise
    except InputError as exc:  # unreadable, not UTF-8, not YAML: say it is the site file
        raise SiteError(f"sites_file {exc}") from None


def get_site(name: str, sites_file: Path | None = None) -> Site:
    """Look a site up by name or alias (case-, space- and punctuation-insensitive).

    A user ``sites_file`` is searched first, then the bundled table.

    Raises
    ------
    SiteError
        If no site matches; the message lists the known names.
    """
    tables = ([*load_sites(sites_file)] if sites_file is not None else []) + load_sites()
    key = _key(name) if isinstance(name, str) and len(name) <= _MAX_NAME_CHARS else None
    for site in tables:
        if key in {_key(site.name), *(_key(a) for a in site.aliases)}:
            return site
    known = shorten(", ".join(dict.fromkeys(s.name for s in tables)), 200).strip("'\"")
    raise SiteError(
        f"site: unknown site {shorten(name, 60)}; known sites: {known}; or give "
        "`site_lonlat` LON,LAT,HEIGHT or `sites_file` FILE"
    )


def site_from_lonlat(text: str, timezone: str | None = None) -> Site:
    """Site from ``"LON,LAT,HEIGHT"`` (degrees east, degrees north, metres).

    Without ``timezone`` (``--tz``) the IANA zone is looked up from the coordinates with
    ``timezonefinder`` (offline, its boundary data ship with the package); over open sea it is
    the nautical zone ``Etc/GMT±N``. The zone sets the local evening of ``--night`` and the
    local-time columns.

    Raises
    ------
    SiteError
        If the text is not three numbers in range.
    """
    form = "LON,LAT,HEIGHT (deg east, deg north, m)"
    parts = [p.strip() for p in text.split(",")] if len(text) <= 200 else []
    if len(parts) != 3:
        raise SiteError(f"site_lonlat: expected {form}, got {shorten(text, 60)}")
    try:
        numbers = [float(p) for p in parts]
    except ValueError:
        raise SiteError(
            f"site_lonlat: expected three numbers {form}, got {shorten(text, 60)}"
        ) from None
    lon, lat, height = (
        check_range(f"site_lonlat: {k}", v, *_RANGES[k], error=SiteError)
        for k, v in zip(("lon_deg", "lat_deg", "height_m"), numbers, strict=True)
    )
    lon = east_longitude(lon)
    entry: dict[str, Any] = {"name": f"lon{lon:+.4f} lat{lat:+.4f}", "lon_deg": lon}
    entry.update(lat_deg=lat, height_m=height)
    entry["timezone"] = _zone_at(lon, lat) if timezone is None else timezone
    return _parse_site(entry, "site_lonlat" if timezone is None else "tz")


def _zone_at(lon: float, lat: float) -> str:
    """IANA zone at a longitude/latitude [deg]; the nautical zone over open sea."""
    from timezonefinder import TimezoneFinder  # imported here: ~0.1 s, only for --site-lonlat

    zone = TimezoneFinder().timezone_at(lng=lon, lat=lat)
    if zone is None:  # not expected (the data cover the oceans); keep the nautical rule
        offset = round(east_longitude(lon) / 15.0)
        # Etc/GMT signs are inverted (POSIX): Etc/GMT+5 is UTC-5.
        zone = "Etc/UTC" if offset == 0 else f"Etc/GMT{-offset:+d}"
    return str(zone)


def resolve_site(
    name: str | None = None,
    lonlat: str | None = None,
    sites_file: Path | None = None,
    timezone: str | None = None,
) -> Site:
    """The site named by ``--site NAME`` (looked up, ``sites_file`` first) or given by
    ``--site-lonlat LON,LAT,HEIGHT``; ``timezone`` (``--tz``) replaces the site's zone.

    Raises
    ------
    UcbplanError
        If neither or both are given, or the name or coordinates are not valid.
    """
    if lonlat and name:
        raise SiteError(
            f"site {shorten(name, 40)}, `site_lonlat` {shorten(lonlat, 40)}: give one site, "
            "not both"
        )
    if lonlat:
        return site_from_lonlat(lonlat, timezone)
    if not name:
        raise UcbplanError("no site: pass `site` NAME (e.g. paranal) or `site_lonlat` LON,LAT,H")
    site = get_site(name, sites_file)
    if timezone is None:
        return site
    return replace(site, timezone=_check_zone(timezone, "tz"))
