"""Population visibility: hours and nights against astropy AltAz, epoch counts, CLI, resume."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from ucbplan.errors import InputError
from ucbplan.observing.observatory.sites import get_site
from ucbplan.observing.schedule.settings import PlanSettings
from ucbplan.population.catalog import Catalog, read_catalog
from ucbplan.population.runner import RunControl, run_visibility
from ucbplan.population.tables import write_table
from ucbplan.population.visibility import VisibilityOptions

ROOT = Path(__file__).resolve().parents[2]
CATALOG = ROOT / "catalogs" / "population" / "ldc-200.ecsv"
#: Moon and zenith hole off, so that astropy's Sun and target altitudes alone decide.
PLAIN = PlanSettings(moon_sep_deg=0.0, zenith_hole_deg=0.0)


def _subset(idx: list[int]) -> Catalog:
    cat = read_catalog(CATALOG)
    return dataclasses.replace(cat, sources=tuple(cat.sources[i] for i in idx))


@pytest.fixture(scope="module")
def vis(tmp_path_factory: pytest.TempPathFactory) -> tuple[object, bytes]:
    tmp = tmp_path_factory.mktemp("vis")
    opts = VisibilityOptions(site=get_site("paranal"), semester="P145", settings=PLAIN)
    run = run_visibility(_subset([0, 2, 3]), opts, RunControl(tmp / "p", chunk=2))
    write_table(run.table, tmp / "v.ecsv", overwrite=False)
    return run.table, (tmp / "v.ecsv").read_bytes()


def _astropy_hours(ra: float, dec: float, step_s: float = 1200.0) -> float:
    """Hours of P145 (2040-04-01 .. 2040-10-01 nights) with Sun <= -12 deg and airmass <= 2."""
    import warnings

    import astropy.units as u
    from astropy.coordinates import AltAz, SkyCoord, get_sun
    from astropy.time import Time

    site = get_site("paranal")
    with warnings.catch_warnings():  # ERFA's "dubious year" for dates past the leap-second table
        warnings.simplefilter("ignore")
        # local noon of 2040-04-01 (UTC-4) to local noon of 2040-10-01 (UTC-3)
        t0 = Time("2040-04-01T16:00:00", scale="utc")
        n = round((Time("2040-10-01T15:00:00", scale="utc") - t0).to_value(u.s) / step_s)
        t = t0 + (np.arange(n) + 0.5) * step_s * u.s
        frame = AltAz(obstime=t, location=site.location)
        sun = get_sun(t).transform_to(frame).alt.deg
        alt = SkyCoord(ra * u.deg, dec * u.deg).transform_to(frame).alt.deg
    airmass_2_alt = math.degrees(math.asin(0.5))
    return float(np.count_nonzero((sun <= -12.0) & (alt >= airmass_2_alt)) * step_s / 3600.0)


@pytest.mark.slow
def test_usable_hours_match_astropy_altaz(vis: tuple[object, bytes]) -> None:
    tab = vis[0]
    for row in tab:  # type: ignore[attr-defined]
        ref = _astropy_hours(float(row["ra"]), float(row["dec"]))
        # two grids (5 and 20 min) sample each night's edges differently: ~0.5 % over a semester
        assert row["usable_hours"] == pytest.approx(ref, rel=0.02), row["source_id"]
        assert 0 <= row["usable_nights"] <= 183


@pytest.mark.slow
def test_epoch_counts_follow_the_anchor_rate(vis: tuple[object, bytes]) -> None:
    """Quadratures come every P_orb/2 = 1/f: observable ≈ usable seconds × f (60 s blocks)."""
    tab = vis[0]
    cat = _subset([0, 2, 3])
    for row, src in zip(tab, cat.sources, strict=True):  # type: ignore[call-overload]
        if row["status"] != "ok":
            assert row["epochs_quadrature"] == -1 and row["valid_until_quadrature"] == ""
            continue
        expect = row["usable_hours"] * 3600.0 * src.f_hz
        assert row["observable_quadrature"] == pytest.approx(expect, rel=0.02)
        assert 0 <= row["epochs_quadrature"] <= row["observable_quadrature"]
        # inside T_valid: all of them when validity ends after the semester, none before it
        until = row["valid_until_quadrature"]
        if until > "2040-10-02":
            assert row["epochs_quadrature"] == row["observable_quadrature"]
        elif until < "2040-04-01":
            assert row["epochs_quadrature"] == 0


@pytest.mark.slow
def test_table_meta_and_resume(tmp_path: Path, vis: tuple[object, bytes]) -> None:
    text = vis[1].decode()
    for key in ("semester: P145", "Paranal", "airmass <= 2", "min_hours: 1.0", "catalog_sha256"):
        assert key in text
    opts = VisibilityOptions(site=get_site("paranal"), semester="P145", settings=PLAIN)
    parts = tmp_path / "p"
    cat = _subset([0, 2, 3])
    run_visibility(cat, opts, RunControl(parts, chunk=2))
    (parts / "part-000001.json").unlink()
    again = run_visibility(cat, opts, RunControl(parts, chunk=2, resume=True))
    assert again.reused == 1
    write_table(again.table, tmp_path / "r.ecsv", overwrite=False)
    assert (tmp_path / "r.ecsv").read_bytes() == vis[1]


def test_options_are_checked() -> None:
    site = get_site("paranal")
    with pytest.raises(InputError, match=r"^semester: "):
        VisibilityOptions(site=site, semester="2041C")
    with pytest.raises(InputError, match=r"^min_hours: "):
        VisibilityOptions(site=site, semester="2041A", min_hours=30.0)
    dates = VisibilityOptions(site=site, semester="2041B").dates()
    assert str(dates[0]) == "2041-08-01" and str(dates[-1]) == "2042-01-31"


def run_main(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str], *args: str
) -> tuple[int, str]:
    """``ucbplan ARGS`` through the console entry point: (exit code, stderr)."""
    import sys

    from ucbplan.cli import app as app_module

    monkeypatch.setattr(sys, "argv", ["ucbplan", *args])
    with pytest.raises(SystemExit) as exc:
        app_module.main()
    code = exc.value.code
    return (code if isinstance(code, int) else 0), capsys.readouterr().err


def test_cli_bad_options_are_one_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    base = ["population", "visibility", str(CATALOG), "-o", str(tmp_path / "v.ecsv")]
    cases = [
        (["--site", "paranal", "--semester", "2041X"], "--semester"),
        (["--site", "nowhere-at-all", "--semester", "2041A"], "nowhere"),
        (["--site", "paranal", "--semester", "2041A", "--airmass-max", "0.5"], "--airmass-max"),
    ]
    for extra, needle in cases:
        code, err = run_main(monkeypatch, capsys, *base, *extra)
        assert code == 2, err
        assert needle in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
        assert not (tmp_path / "v.ecsv").exists()
