"""Population catalogs (ECSV, CSV, HDF5, column maps, bad rows), semesters and the CLI."""

from __future__ import annotations

import datetime as dt
import sys
from pathlib import Path

import pytest
import typer
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from ucbplan.errors import InputError, InputFileError, UcbplanError
from ucbplan.observing.observatory.semesters import semester_dates
from ucbplan.population.catalog import parse_column_map, read_catalog

ROOT = Path(__file__).resolve().parents[2]
CATALOG = ROOT / "catalogs" / "population" / "ldc-200.ecsv"
HEADER = (
    "Frequency,FrequencyDerivative,Amplitude,EclipticLatitude,EclipticLongitude,"
    "Inclination,Polarization,InitialPhase"
)
GOOD = "0.01,1e-16,1e-22,0.1,1.0,1.0,0.3,2.0"


def _csv(tmp: Path, *rows: str, header: str = HEADER) -> Path:
    p = tmp / "cat.csv"
    p.write_text("\n".join([header, *rows]) + "\n", encoding="utf-8")
    return p


def test_ecsv_example_catalog() -> None:
    cat = read_catalog(CATALOG)
    assert len(cat.sources) == 200 and cat.bad == ()
    assert cat.sources[0].source_id == "GB13-00001" and cat.sources[0].row == 1
    assert {"Magnitude", "Distance", "Mass1", "Mass2"} <= set(cat.optional)
    assert len(cat.sha256) == 64


def test_csv_and_units(tmp_path: Path) -> None:
    cat = read_catalog(_csv(tmp_path, GOOD, GOOD))
    assert [s.source_id for s in cat.sources] == ["1", "2"]
    assert cat.sources[0].f_hz == 0.01 and cat.sources[0].vmag is None


def test_ecsv_units_are_converted(tmp_path: Path) -> None:
    from astropy.table import Table

    tab = Table.read(CATALOG, format="ascii.ecsv")[:3]
    tab["Frequency"] = tab["Frequency"].to("mHz")
    tab["EclipticLatitude"] = tab["EclipticLatitude"].to("deg")
    p = tmp_path / "c.ecsv"
    tab.write(p, format="ascii.ecsv")
    a, b = read_catalog(p).sources[1], read_catalog(CATALOG).sources[1]
    assert a.f_hz == pytest.approx(b.f_hz, rel=1e-15)
    assert a.ecl_lat_rad == pytest.approx(b.ecl_lat_rad, rel=1e-15)


def test_bad_rows_named_by_number_or_skipped(tmp_path: Path) -> None:
    bad = "0.01,1e-16,1e-22,3.0,1.0,1.0,0.3,2.0"  # latitude out of range
    missing = "0.01,,1e-22,0.1,1.0,1.0,0.3,2.0"
    p = _csv(tmp_path, GOOD, bad, GOOD, missing)
    with pytest.raises(InputFileError, match=r"row 2: EclipticLatitude.*`skip_bad`"):
        read_catalog(p)
    cat = read_catalog(p, skip_bad=True)
    assert [s.row for s in cat.sources] == [1, 3]
    assert [r for r, _ in cat.bad] == [2, 4]
    assert "FrequencyDerivative" in cat.bad[1][1]


def test_column_map(tmp_path: Path) -> None:
    header = HEADER.replace("Frequency,", "f0,", 1).replace("Polarization", "psi")
    p = _csv(tmp_path, GOOD, header=header)
    with pytest.raises(InputFileError, match=r"missing column.*Frequency.*`columns`"):
        read_catalog(p)
    cat = read_catalog(p, parse_column_map("f0=Frequency, psi=Polarization"))
    assert cat.sources[0].f_hz == 0.01
    with pytest.raises(InputFileError, match=r"^columns: unknown catalog column"):
        parse_column_map("f0=Freq")
    with pytest.raises(InputFileError, match=r"^columns: expected old=new"):
        parse_column_map("f0")
    with pytest.raises(InputFileError, match=": `columns`: no column"):
        read_catalog(p, {"nope": "Frequency"})


def test_hdf5_compound_table(tmp_path: Path) -> None:
    pytest.importorskip("h5py")
    sys.path.insert(0, str(ROOT / "benchmarks"))
    import make_population_catalog as mk

    p = tmp_path / "c.h5"
    mk.main(["-n", "5", "--seed", "13", "-o", str(p), "--hdf5"])
    cat = read_catalog(p)
    ref = read_catalog(CATALOG)
    assert [s.source_id for s in cat.sources] == [s.source_id for s in ref.sources[:5]]
    assert cat.sources[3].f_hz == ref.sources[3].f_hz


def test_hdf5_without_h5py_says_how_to_install(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    p = tmp_path / "c.h5"
    p.write_bytes(b"\x89HDF\r\n")
    monkeypatch.setitem(sys.modules, "h5py", None)
    with pytest.raises(InputFileError, match=r"pip install 'ucbplan\[hdf5\]'"):
        read_catalog(p)


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    cells=st.lists(
        st.one_of(
            st.sampled_from(["", "nan", "inf", "-1", "0", "1e300", "abc", '"', "0.01", "1e-22"]),
            st.floats(allow_nan=True),
            st.text(max_size=8),
        ),
        min_size=8,
        max_size=8,
    )
)
def test_fuzzed_rows_are_one_line_errors(tmp_path: Path, cells: list[object]) -> None:
    row = ",".join(str(c).replace("\n", " ").replace(",", ";") for c in cells)
    p = _csv(tmp_path, GOOD, row)
    try:
        read_catalog(p)
    except UcbplanError as exc:
        msg = str(exc)
        assert "\n" not in msg and len(msg) < 400


def test_semesters() -> None:
    assert semester_dates("2041A") == (dt.date(2041, 2, 1), dt.date(2041, 8, 1))
    assert semester_dates("2041b") == (dt.date(2041, 8, 1), dt.date(2042, 2, 1))
    assert semester_dates("P110") == (dt.date(2022, 10, 1), dt.date(2023, 4, 1))
    assert semester_dates("P111") == (dt.date(2023, 4, 1), dt.date(2023, 10, 1))
    assert semester_dates("P147") == (dt.date(2041, 4, 1), dt.date(2041, 10, 1))
    assert semester_dates("P1") == (dt.date(1968, 4, 1), dt.date(1968, 10, 1))
    for n in range(1, 300):  # consecutive, six months, alternating 1 Apr / 1 Oct
        a, b = semester_dates(f"P{n}")
        assert b == semester_dates(f"P{n + 1}")[0] and a.day == 1
        assert a.month == (4 if n % 2 else 10)
    for bad in ("2041C", "P0", "41A", "", "P-3"):
        with pytest.raises(InputError, match=r"^semester: "):
            semester_dates(bad)


def _app() -> typer.Typer:
    from ucbplan.cli import population

    app = typer.Typer()

    @app.callback()
    def _root() -> None:
        pass

    population.register(app)
    return app


def test_cli_forecast_with_plots(tmp_path: Path) -> None:
    from astropy.table import Table

    src = Table.read(CATALOG, format="ascii.ecsv")[:12]
    cat = tmp_path / "c.ecsv"
    src.write(cat, format="ascii.ecsv")
    out, plots = tmp_path / "f.ecsv", tmp_path / "plots"
    plots.mkdir()
    res = CliRunner().invoke(
        _app(), ["population", "forecast", str(cat), "-o", str(out), "--plots", str(plots)]
    )
    assert res.exit_code == 0, res.output
    assert Table.read(out, format="ascii.ecsv").meta["n_ok"] >= 8
    assert sorted(p.name for p in plots.iterdir()) == [
        "tvalid_cumulative.png",
        "tvalid_vs_f.png",
        "tvalid_vs_snr.png",
    ]
    assert not (tmp_path / "f.ecsv.parts").exists()
    res = CliRunner().invoke(_app(), ["population", "forecast", str(cat), "-o", str(out)])
    assert res.exit_code != 0  # exists, no --overwrite


def test_cli_semester() -> None:
    res = CliRunner().invoke(_app(), ["population", "semester", "P147"])
    assert res.exit_code == 0 and "2041-04-01 .. 2041-10-01" in res.output
