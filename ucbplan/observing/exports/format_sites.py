"""Which observatory sites each export format serves, and the check that a plan was made for one.

A file for Keck written from a Paranal plan has every time wrong by the hours between the sites'
nights, so :func:`check_site` refuses it unless the user passes ``--force`` (docs/exports.md,
"Sites"). A plan's site matches a format when its position (``meta['site']`` ``lon_deg`` and
``lat_deg``) lies within :data:`SITE_MATCH_KM` of one of the format's sites, or, for a table
without a position, when its name is one of them (looked up in the bundled sites table).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

from ucbplan.errors import SiteError, UcbplanError, shorten
from ucbplan.inputs import is_number
from ucbplan.observing.observatory.sites import get_site

#: Largest distance between a plan's site and an observatory that still counts as that
#: observatory [km]: a mountain's telescopes lie within ~2 km; the closest distinct sites in the
#: tables below (Cerro Tololo and Cerro Pachon) are ~10 km apart.
SITE_MATCH_KM = 5.0
#: Mean Earth radius [km] (the distance test needs a few percent accuracy only).
_EARTH_RADIUS_KM = 6371.0


@dataclass(frozen=True, slots=True)
class ObservatorySite:
    """A site an observatory's scheduler serves: display name, geodetic position [deg]."""

    name: str
    lon_deg: float
    lat_deg: float


def _bundled(name: str) -> ObservatorySite:
    site = get_site(name)
    return ObservatorySite(site.name, site.lon_deg, site.lat_deg)


#: Las Cumbres Observatory network sites not in the bundled sites table (positions of the
#: network's 1-m/2-m enclosures as the LCO observation portal lists them, rounded to 0.001°).
_LCO_EXTRA = (
    ObservatorySite("Cerro Tololo (LCO lsc)", -70.805, -30.167),
    ObservatorySite("Teide (LCO tfn)", -16.512, 28.300),
    ObservatorySite("McDonald (LCO elp)", -104.015, 30.680),
    ObservatorySite("Haleakala (LCO ogg)", -156.258, 20.707),
    ObservatorySite("Wise (LCO tlv)", 34.763, 30.596),
)

#: Bundled site names each format serves (formats not listed take any site).
_FORMAT_SITE_NAMES: dict[str, tuple[str, ...]] = {
    "eso-p2": ("Paranal", "La Silla", "Armazones"),
    "keck-starlist": ("Mauna Kea",),
    "ing-cat": ("La Palma (ORM)",),
    "lco": ("Siding Spring", "Sutherland", "Cerro Pachon"),
    "gemini": ("Mauna Kea", "Cerro Pachon"),
}


def _format_sites(to: str) -> tuple[ObservatorySite, ...] | None:
    names = _FORMAT_SITE_NAMES.get(to)
    if names is None:
        return None
    sites = tuple(_bundled(n) for n in names)
    return (*sites, *_LCO_EXTRA) if to == "lco" else sites


#: Export format → the observatory sites its files are for; formats not listed take any site.
FORMAT_SITES: Mapping[str, tuple[ObservatorySite, ...]] = {
    to: sites for to in _FORMAT_SITE_NAMES if (sites := _format_sites(to)) is not None
}


def _distance_km(lon1: float, lat1: float, lon2: float, lat2: float) -> float:
    """Great-circle distance on a sphere (haversine) [km]."""
    p1, p2 = math.radians(lat1), math.radians(lat2)
    dlat, dlon = p2 - p1, math.radians(lon2 - lon1)
    h = math.sin(dlat / 2) ** 2 + math.cos(p1) * math.cos(p2) * math.sin(dlon / 2) ** 2
    return 2 * _EARTH_RADIUS_KM * math.asin(min(1.0, math.sqrt(h)))


def _plan_site(site: object) -> tuple[str, float, float] | None:
    """(name, lon, lat) of a table's ``meta['site']``; None when neither position nor a known
    name is given."""
    if isinstance(site, Mapping):
        name = str(site.get("name") or "unnamed site")
        lon, lat = site.get("lon_deg"), site.get("lat_deg")
        if is_number(lon) and is_number(lat):
            return name, float(lon), float(lat)
    elif isinstance(site, str) and site:
        name = site
    else:
        return None
    try:
        known = get_site(name)
    except UcbplanError:
        return None
    return name, known.lon_deg, known.lat_deg


def _matches(plan: tuple[str, float, float], sites: tuple[ObservatorySite, ...]) -> bool:
    _, lon, lat = plan
    return any(_distance_km(lon, lat, s.lon_deg, s.lat_deg) <= SITE_MATCH_KM for s in sites)


def serves_site(site: object, to: str) -> bool:
    """Whether the format ``to`` has an observatory at the plan's site (``meta['site']``)."""
    sites, plan = FORMAT_SITES.get(to), _plan_site(site)
    return sites is not None and plan is not None and _matches(plan, sites)


def check_site(site: object, to: str, force: bool) -> list[str]:
    """Check that a plan's site (``meta['site']``) is one the format ``to`` serves.

    Returns
    -------
    list of str
        Notes: the site could not be checked (no site in the table), or ``force`` let a foreign
        site through.

    Raises
    ------
    SiteError
        The site is none of the format's observatory sites and ``force`` is False.
    """
    sites = FORMAT_SITES.get(to)
    if sites is None:
        return []
    plan = _plan_site(site)
    where = ", ".join(s.name for s in sites)
    if plan is None:
        return [f"{to}: the table names no known site; check that it was planned for: {where}"]
    if _matches(plan, sites):
        return []
    name, lon, lat = plan
    label = f"{shorten(name, 40)} (lon {lon:.3f}, lat {lat:.3f} deg)"
    if force:
        return [f"{to}: written for site {label}, none of {where}, because of --force"]
    raise SiteError(
        f"{to}: the plan's site {label} is none of this format's observatory sites ({where}); "
        "re-plan with `site` for one of them, or pass `force` to write it anyway"
    )
