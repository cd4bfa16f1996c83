"""A file for one observatory is written only from a plan made for one of its sites.

Independent check of the distance test: astropy's geocentric positions of the sites (the chord
between two points on the ellipsoid equals the great-circle distance to < 0.1 % at < 1000 km).
"""

from __future__ import annotations

import math
from pathlib import Path

import astropy.units as u
import numpy as np
import pytest
from astropy.coordinates import EarthLocation
from astropy.table import Table
from support.cli import run_cli
from support.exports import fixture_table

from ucbplan.errors import SiteError
from ucbplan.observing.exports import EXPORT_FORMATS, ExportOptions, export_blocks
from ucbplan.observing.exports.format_sites import (
    FORMAT_SITES,
    SITE_MATCH_KM,
    _distance_km,
    check_site,
)
from ucbplan.observing.observatory.sites import get_site

OPTS = ExportOptions(acquisition_s=600.0)


def _at(site: str | dict[str, object] | None) -> Table:
    table = fixture_table()
    if site is None:
        del table.meta["site"]
    else:
        table.meta["site"] = get_site(site).as_dict() if isinstance(site, str) else site
    return table


@pytest.mark.parametrize(
    ("to", "site"),
    [
        ("eso-p2", "paranal"),
        ("eso-p2", "la silla"),
        ("eso-p2", "armazones"),
        ("keck-starlist", "mauna kea"),
        ("ing-cat", "wht"),
        ("lco", "siding spring"),
        ("lco", "soar"),
        ("lco", "saao"),
    ],
)
def test_a_plan_for_the_observatory_exports_without_a_note(to: str, site: str) -> None:
    res = export_blocks(_at(site), to, OPTS)
    assert not any("site" in n for n in res.notes)


@pytest.mark.parametrize(
    ("to", "site", "expected"),
    [
        ("keck-starlist", "paranal", "Mauna Kea"),
        ("ing-cat", "paranal", "La Palma (ORM)"),
        ("lco", "paranal", "Cerro Tololo"),
        ("eso-p2", "mauna kea", "La Silla"),
        ("eso-p2", "las campanas", "Armazones"),  # 27 km from La Silla: not ESO
    ],
)
def test_a_foreign_site_is_a_one_line_error(to: str, site: str, expected: str) -> None:
    with pytest.raises(SiteError) as info:
        export_blocks(_at(site), to, OPTS)
    text = str(info.value)
    assert "\n" not in text and len(text) < 400
    assert get_site(site).name in text and expected in text and "`force`" in text


def test_force_writes_and_says_so() -> None:
    forced = export_blocks(_at("paranal"), "keck-starlist", ExportOptions(force=True))
    assert any("because of --force" in n for n in forced.notes)
    plain = export_blocks(_at("mauna kea"), "keck-starlist", ExportOptions())
    assert forced.content.splitlines()[1:] == plain.content.splitlines()[1:]  # site line aside


def test_formats_without_an_observatory_take_any_site() -> None:
    for to in sorted(set(EXPORT_FORMATS) - set(FORMAT_SITES)):
        export_blocks(_at("kitt peak"), to, OPTS)


def test_a_table_without_a_site_is_exported_with_a_note() -> None:
    res = export_blocks(_at(None), "keck-starlist", OPTS)
    assert any("names no known site" in n for n in res.notes)


def test_lonlat_site_near_the_observatory_matches() -> None:
    kea = get_site("mauna kea")
    near = {"name": "lon-155.47 lat+19.82", "lon_deg": kea.lon_deg + 0.02, "lat_deg": kea.lat_deg}
    assert check_site(near, "keck-starlist", False) == []  # ~2 km east
    far = dict(near, lon_deg=kea.lon_deg + 0.1)  # ~10 km
    with pytest.raises(SiteError):
        check_site(far, "keck-starlist", False)


def test_a_site_by_name_only_is_looked_up() -> None:
    assert check_site("Paranal", "eso-p2", False) == []
    with pytest.raises(SiteError):
        check_site("Paranal", "ing-cat", False)


def _chord_km(a: tuple[float, float], b: tuple[float, float]) -> float:
    pa, pb = (EarthLocation.from_geodetic(lon * u.deg, lat * u.deg, 0 * u.m) for lon, lat in (a, b))
    diff = np.array([(pa.x - pb.x).to_value(u.km), (pa.y - pb.y).to_value(u.km)])
    return float(math.hypot(*diff, (pa.z - pb.z).to_value(u.km)))


@pytest.mark.parametrize(
    ("a", "b"), [("paranal", "la silla"), ("la silla", "las campanas"), ("soar", "paranal")]
)
def test_distance_against_astropy_geocentric_chord(a: str, b: str) -> None:
    sa, sb = get_site(a), get_site(b)
    ours = _distance_km(sa.lon_deg, sa.lat_deg, sb.lon_deg, sb.lat_deg)
    ref = _chord_km((sa.lon_deg, sa.lat_deg), (sb.lon_deg, sb.lat_deg))
    assert ours == pytest.approx(ref, rel=0.006)  # sphere vs ellipsoid: < 0.5 %


def test_observatory_sites_are_further_apart_than_the_match_radius() -> None:
    sites = [s for group in FORMAT_SITES.values() for s in group]
    for i, a in enumerate(sites):
        for b in sites[i + 1 :]:
            if a.name != b.name:
                assert _distance_km(a.lon_deg, a.lat_deg, b.lon_deg, b.lat_deg) > SITE_MATCH_KM


def test_cli_refuses_a_foreign_site_with_exit_2(tmp_path: Path) -> None:
    blocks = tmp_path / "blocks.ecsv"
    _at("paranal").write(blocks, format="ascii.ecsv")
    out = tmp_path / "keck.txt"
    code, err = run_cli(["export", str(blocks), "--to", "keck-starlist", "-o", str(out)])
    assert code == 2 and "Mauna Kea" in err and "Traceback" not in err and not out.exists()
    code, err = run_cli(["export", str(blocks), "--to", "keck-starlist", "--force", "-o", str(out)])
    assert code == 0 and out.exists() and "--force" in err
