"""Population rank: the figure of merit against closed forms, order, target files for plan."""

from __future__ import annotations

import datetime as dt
import math
from pathlib import Path

import numpy as np
import pytest
from astropy.table import Table

from ucbplan.population.catalog import read_catalog
from ucbplan.targets import load_target

ROOT = Path(__file__).resolve().parents[2]
CATALOG = ROOT / "catalogs" / "population" / "ldc-200.ecsv"
SIGMA_REF = (10.0, 20.0, 600.0)  # σ_v = 10 km/s in 600 s at V = 20


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


@pytest.fixture(scope="module")
def small(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("cat") / "ldc-20.ecsv"
    Table.read(CATALOG)[:20].write(path, format="ascii.ecsv")
    return path


def _rank(monkeypatch, capsys, out: Path, *args: str) -> Table:  # type: ignore[no-untyped-def]
    code, err = run_main(monkeypatch, capsys, "population", "rank", *args, "--out-dir", str(out))
    assert code == 0, err
    return Table.read(out / "ranked.ecsv", format="ascii.ecsv")


def test_goal_hours_merit_matches_closed_form(
    tmp_path: Path, small: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture
) -> None:
    ref = ",".join(f"{x:g}" for x in SIGMA_REF)
    tab = _rank(monkeypatch, capsys, tmp_path, str(small), "--top", "2", "--sigma-ref", ref)
    assert tab.meta["figure_of_merit"] == "goal_hours"
    merit = np.asarray(tab["merit"], dtype=float)
    finite = np.isfinite(merit)
    assert np.all(np.diff(merit[finite]) >= 0) and list(finite) == sorted(finite, reverse=True)
    assert list(tab["rank"]) == list(range(1, len(tab) + 1))
    cat = {s.source_id: s for s in read_catalog(small).sources}
    for row in tab[finite][:5]:
        s = cat[row["source_id"]]
        # independent: σ_v scaling, Λ_K = sinc of one exposure, quadrature pair σ_K = σ_v/(Λ√2)
        sv = SIGMA_REF[0] * 10 ** (0.2 * (s.vmag - SIGMA_REF[1])) * math.sqrt(SIGMA_REF[2] / 60.0)
        assert row["sigma_v_exposure"] == pytest.approx(sv, rel=1e-12)
        x = math.pi * s.f_hz * 60.0 / 2.0
        lam = math.sin(x) / x
        g, c, ms = 6.6743e-11, math.pi * s.f_hz, (s.m1_msun + s.m2_msun) * 1.98840987e30
        ktot = (g * ms * c) ** (1 / 3) * math.sin(s.inclination_rad) / 1e3
        k1 = ktot * s.m2_msun / (s.m1_msun + s.m2_msun)
        cycles = math.ceil((sv / (lam * math.sqrt(2.0)) / (0.05 * k1)) ** 2 * (1 - 1e-12))
        assert row["n_spectra"] == 2 * cycles
    files = [f for f in tab["target_file"] if f]
    assert len(files) == 2 and all(Path(f).is_absolute() and Path(f).is_file() for f in files)
    assert [f for f in tab["target_file"][:2]] == files


def test_t_valid_merit_and_a_ranked_target_plans(
    tmp_path: Path, small: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture
) -> None:
    out = tmp_path / "ranked"
    tab = _rank(monkeypatch, capsys, out, str(small), "--top", "1")
    assert (
        tab.meta["figure_of_merit"] == "t_valid" and "T_valid" in tab.meta["figure_of_merit_text"]
    )
    tv = np.asarray(tab["merit"], dtype=float)
    ok = np.isfinite(tv)
    assert np.all(np.diff(tv[ok]) <= 0)
    assert set(tab["status"][~ok]) <= {"unconstrained", "below-threshold"} or not np.any(~ok)
    target_file = Path(tab["target_file"][0])
    t = load_target(target_file)
    assert t.name == tab["source_id"][0] and t.spectroscopy is not None
    assert t.spectroscopy.sigma_v_kms == 15.0
    # a night in 2039 (after LISA) when the target crosses the meridian near local midnight
    day = dt.date(2039, 3, 21) + dt.timedelta(days=round((t.ra_deg - 180.0) % 360.0 / 0.9856))
    code, err = run_main(
        monkeypatch,
        capsys,
        "plan",
        str(target_file),
        "--site",
        "paranal",
        "--night",
        day.isoformat(),
        "--airmass-max",
        "3",
    )
    assert code == 0, err


def test_forecast_table_input_and_catalog_check(
    tmp_path: Path, small: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture
) -> None:
    fc = tmp_path / "f.ecsv"
    code, err = run_main(monkeypatch, capsys, "population", "forecast", str(small), "-o", str(fc))
    assert code == 0, err
    from_fc = _rank(monkeypatch, capsys, tmp_path / "a", str(fc), "--top", "0")
    from_cat = _rank(monkeypatch, capsys, tmp_path / "b", str(small), "--top", "0")
    assert list(from_fc["source_id"]) == list(from_cat["source_id"])
    other = tmp_path / "other.ecsv"
    Table.read(CATALOG)[:21].write(other, format="ascii.ecsv")
    code, err = run_main(
        monkeypatch,
        capsys,
        "population",
        "rank",
        str(fc),
        "--catalog",
        str(other),
        "--out-dir",
        str(tmp_path / "c"),
    )
    assert code == 2 and "sha256" in err and len(err.strip().splitlines()) == 1


def test_bad_options_and_existing_files(
    tmp_path: Path, small: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture
) -> None:
    base = ["population", "rank", str(small), "--out-dir", str(tmp_path)]
    for extra, needle in (
        (["--sigma-ref", "10,20"], "--sigma-ref"),
        (["--instrument", "xshooter-uvb"], "--sigma-ref"),
        (["--goal", "K9=3%"], "--goal"),
        (["--top", "-1"], "--top"),
    ):
        code, err = run_main(monkeypatch, capsys, *base, *extra)
        assert code == 2 and needle in err and "Traceback" not in err, err
    assert not (tmp_path / "ranked.ecsv").exists()
    code, _ = run_main(monkeypatch, capsys, *base, "--top", "1")
    before = {p: p.read_bytes() for p in tmp_path.iterdir()}
    code, err = run_main(monkeypatch, capsys, *base, "--top", "1")
    assert code == 2 and "--overwrite" in err
    assert {p: p.read_bytes() for p in tmp_path.iterdir()} == before
