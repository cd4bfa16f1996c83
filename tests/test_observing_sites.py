"""Site table: packaged copy, lookups, user files, --site-lonlat and error messages."""

from __future__ import annotations

from pathlib import Path

import pytest

from ucbplan.errors import SiteError
from ucbplan.observing.sites import get_site, load_sites, site_from_lonlat

REPO = Path(__file__).resolve().parents[1]
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
    bad.write_text("sites:\n  - name: X\n    lon_deg: 0\n    lat_deg: 95\n    height_m: 0\n")
    with pytest.raises(SiteError, match=r"lat_deg: expected -90\.0 <= value <= 90\.0, got 95"):
        get_site("x", bad)
    with pytest.raises(SiteError, match="cannot read site file"):
        get_site("x", tmp_path / "missing.yaml")


def test_site_from_lonlat() -> None:
    site = site_from_lonlat("-70.4,-24.6,2635")
    assert (site.lon_deg, site.lat_deg, site.height_m) == (-70.4, -24.6, 2635.0)
    assert site.timezone == "Etc/GMT+5"  # POSIX sign: UTC-5 for 70.4 W
    assert site_from_lonlat("2.5,40,0").timezone == "Etc/UTC"
    with pytest.raises(SiteError, match="expected LON,LAT,HEIGHT"):
        site_from_lonlat("1,2")
    with pytest.raises(SiteError, match="expected three numbers"):
        site_from_lonlat("a,b,c")
