"""Site table: packaged copy, lookups, user files, --site-lonlat and error messages."""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest

from ucbplan.errors import SiteError
from ucbplan.observing.observatory.sites import get_site, load_sites, site_from_lonlat

REPO = Path(__file__).resolve().parents[3]
REQUIRED = (
    "Paranal",
    "La Silla",
    "Armazones",
    "Mauna Kea",
    "La Palma (ORM)",
    "Cerro Pachon",
    "Las Campanas",
    "Kitt Peak",
    "Sutherland",
    "Siding Spring",
    "Calar Alto",
)


def test_packaged_copy_identical_to_configs() -> None:
    # The package loads ucbplan/data/sites.yaml (installed wheels have no configs/): keep in sync.
    assert (REPO / "configs" / "sites.yaml").read_bytes() == (
        REPO / "ucbplan" / "data" / "sites.yaml"
    ).read_bytes()


def test_all_required_sites_present_and_plausible() -> None:
    sites = {s.name: s for s in load_sites()}
    assert set(REQUIRED) <= set(sites)
    for site in sites.values():
        # All bundled sites are mountain observatories: 1000-4300 m.
        assert 1000.0 < site.height_m < 4300.0
        assert site.zone is not None
    # Independent sanity: the Chilean sites lie within 100 km (~1 deg) of each other.
    chile = [sites[n] for n in ("Paranal", "La Silla", "Armazones", "Cerro Pachon", "Las Campanas")]
    assert max(s.lon_deg for s in chile) - min(s.lon_deg for s in chile) < 1.0


@pytest.mark.parametrize(
    ("query", "expected"),
    [
        ("paranal", "Paranal"),
        ("PARANAL", "Paranal"),
        ("vlt", "Paranal"),
        ("la palma", "La Palma (ORM)"),
        ("La_Palma", "La Palma (ORM)"),
        ("orm", "La Palma (ORM)"),
        ("keck", "Mauna Kea"),
        ("cerro pachón".replace("ó", "o"), "Cerro Pachon"),
        ("SALT", "Sutherland"),
    ],
)
def test_lookup_by_name_and_alias(query: str, expected: str) -> None:
    assert get_site(query).name == expected


def test_unknown_site_lists_known_names() -> None:
    with pytest.raises(SiteError, match=r"unknown site 'atlantis'.*Paranal.*Calar Alto"):
        get_site("atlantis")


def test_user_site_file_first(tmp_path: Path) -> None:
    path = tmp_path / "mysites.yaml"
    path.write_text(
        "sites:\n  - name: Pole\n    lon_deg: 0\n    lat_deg: -89.99\n    height_m: 2835\n"
        "    timezone: Antarctica/McMurdo\n"
    )
    assert get_site("pole", path).lat_deg == -89.99
    assert get_site("paranal", path).name == "Paranal"  # bundled table still searched
    bad = tmp_path / "bad.yaml"
    bad.write_text(
        "sites:\n  - name: X\n    lon_deg: 0\n    lat_deg: 95\n    height_m: 0\n    timezone: UTC\n"
    )
    with pytest.raises(SiteError, match=r"lat_deg: expected a number in \[-90, 90\] deg.*got 95"):
        get_site("x", bad)
    with pytest.raises(SiteError, match=r"^sites_file .*missing.yaml: file not found"):
        get_site("x", tmp_path / "missing.yaml")


def test_site_from_lonlat() -> None:
    site = site_from_lonlat("-70.4,-24.6,2635")
    assert (site.lon_deg, site.lat_deg, site.height_m) == (-70.4, -24.6, 2635.0)
    # Regression (issue 15): the zone was the nautical one of the longitude (Etc/GMT+5, UTC-5),
    # four or five hours off Chile's civil time, so local columns were wrong.
    assert site.timezone == "America/Santiago"
    assert site_from_lonlat("-3.7,40.4,650").timezone == "Europe/Madrid"
    assert site_from_lonlat("-30,0,0").timezone == "Etc/GMT+2"  # open ocean: nautical zone
    assert site_from_lonlat("-70.4,-24.6,2635", timezone="UTC").timezone == "UTC"
    with pytest.raises(SiteError, match="expected LON,LAT,HEIGHT"):
        site_from_lonlat("1,2")
    with pytest.raises(SiteError, match="expected three numbers"):
        site_from_lonlat("a,b,c")


GOOD_SITE = (
    "sites:\n  - name: Pole\n    lon_deg: 0\n    lat_deg: -89.99\n    height_m: 2835\n"
    "    timezone: Antarctica/McMurdo\n"
)


@pytest.mark.parametrize(
    ("text", "pattern"),
    [
        (GOOD_SITE.replace("lat_deg", "latitude"), r"latitude: unknown field; did you mean"),
        (
            GOOD_SITE.replace("lon_deg", "lon_dge"),
            r"lon_dge: unknown field; did you mean 'lon_deg'",
        ),
        (GOOD_SITE.replace("sites:", "site:"), r"expected a top-level 'sites:' list"),
        (GOOD_SITE + "extra: 1\n", r"extra: unknown top-level key"),
        (GOOD_SITE.replace("    timezone: Antarctica/McMurdo\n", ""), r"timezone: missing"),
        (GOOD_SITE.replace("Antarctica/McMurdo", "Mars/Olympus"), r"timezone: expected an IANA"),
        (GOOD_SITE.replace("Antarctica/McMurdo", "antarctica/mcmurdo"), r"did you mean"),
        (GOOD_SITE.replace("Antarctica/McMurdo", "../../etc/passwd"), r"timezone: expected"),
        (GOOD_SITE.replace("Antarctica/McMurdo", "'" + "x" * 5000 + "'"), r"timezone: expected"),
        (GOOD_SITE.replace("2835", "true"), r"height_m: expected a number"),
        (GOOD_SITE.replace("2835", "'2835 m'"), r"height_m: expected a number"),
        (GOOD_SITE.replace("2835", ".nan"), r"height_m: expected a number"),
        (GOOD_SITE.replace("-89.99", "-91"), r"lat_deg: expected a number in \[-90, 90\]"),
        (
            GOOD_SITE + "    zenith_hole_deg: 90\n",
            r"zenith_hole_deg: expected a number in \[0, 45\]",
        ),
        (GOOD_SITE + "    aliases: spole\n", r"aliases: expected a list"),
        (GOOD_SITE + "    aliases: [[1]]\n", r"aliases\[0\]: expected a name"),
        (GOOD_SITE.replace("name: Pole", 'name: "Po\\x07le"'), r"name: expected the site name"),
        (GOOD_SITE.replace("name: Pole", "name: ''"), r"name: expected the site name"),
        (GOOD_SITE + "    lat_deg: -89\n", r"duplicate key 'lat_deg'"),
        (GOOD_SITE + GOOD_SITE.replace("sites:\n", ""), r"both answer to 'Pole'"),
        (
            GOOD_SITE
            + GOOD_SITE.replace("sites:\n", "").replace("Pole", "X")
            + "    aliases: [po-le]\n",
            r"sites\[0\] \('Pole'\) and sites\[1\] \('X'\) both answer to 'po-le'",
        ),
        ("sites: []\n", r"sites: expected a list of site mappings"),
        ("sites:\n  - [1, 2]\n", r"sites\[0\]: expected a mapping"),
        ("a: &a [1]\n" + "b: [" + ", ".join(["*a"] * 60) + "]\n", r"more than 50 aliases"),
        ("", r"expected a top-level 'sites:' list"),
    ],
)
def test_site_file_is_read_strictly(tmp_path: Path, text: str, pattern: str) -> None:
    path = tmp_path / "sites.yaml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(SiteError) as info:
        load_sites(path)
    message = str(info.value)
    assert "\n" not in message and len(message) < 400, message
    assert re.search(pattern, message), message


def test_site_file_encodings_and_non_files(tmp_path: Path) -> None:
    bom = tmp_path / "bom.yaml"
    bom.write_bytes(b"\xef\xbb\xbf" + GOOD_SITE.encode())
    assert load_sites(bom)[0].name == "Pole"
    latin = tmp_path / "latin.yaml"
    latin.write_bytes(GOOD_SITE.replace("Pole", "Pôle").encode("latin-1"))
    with pytest.raises(SiteError, match="not UTF-8"):
        load_sites(latin)
    with pytest.raises(SiteError, match=r"is a folder|not a regular file"):
        load_sites(tmp_path)
    fifo = tmp_path / "fifo.yaml"
    os.mkfifo(fifo)
    with pytest.raises(SiteError, match="not a regular file"):
        load_sites(fifo)  # must not block waiting for a writer


def test_bundled_names_and_aliases_are_unique() -> None:
    keys = [
        key
        for s in load_sites()
        for key in {re.sub(r"[^a-z0-9.]", "", label.lower()) for label in (s.name, *s.aliases)}
    ]
    assert len(keys) == len(set(keys))


def test_lonlat_zone_matches_every_bundled_site() -> None:
    """Independent check: the zone looked up from each bundled site's coordinates is the zone
    the hand-curated site table declares (or one with the same UTC offsets all year)."""
    from datetime import datetime
    from zoneinfo import ZoneInfo

    for site in load_sites():
        found = site_from_lonlat(f"{site.lon_deg},{site.lat_deg},{site.height_m}").timezone
        days = [datetime(2031, m, 1, 12) for m in range(1, 13)]
        offsets = {
            z: [d.replace(tzinfo=ZoneInfo(z)).utcoffset() for d in days]
            for z in (found, site.timezone)
        }
        assert offsets[found] == offsets[site.timezone], (site.name, found, site.timezone)


def test_tz_option_replaces_zone_and_refuses_unknown() -> None:
    from ucbplan.observing.observatory.sites import resolve_site

    assert resolve_site("paranal", timezone="UTC").timezone == "UTC"
    assert resolve_site("paranal").timezone == "America/Santiago"
    with pytest.raises(SiteError, match=r"^tz: timezone: .*IANA"):
        resolve_site("paranal", timezone="Mars/Olympus")
