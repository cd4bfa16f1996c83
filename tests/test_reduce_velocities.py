"""Velocity-table reader: accepted formats and one-line errors naming row and column."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from test_reduce_synth import make_target

from ucbplan.errors import VelocityFileError
from ucbplan.offline import configure_offline
from ucbplan.reduce.velocities import check_validity, read_velocities

HEADER = "bjd_tdb,exptime_s,v1,sigma_v1,v2,sigma_v2,session\n"
JD = 2465800.0  # 2039-12 TDB: after the fiducial LISA observation (ends 2039-01-01)


@pytest.fixture(autouse=True, scope="module")
def _offline() -> None:
    configure_offline()


def _write(tmp_path: Path, text: str, name: str = "v.csv") -> Path:
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    return p


def test_reads_sb2_csv_with_comments_and_sessions(tmp_path: Path) -> None:
    """SB2 CSV: TDB times to 1e-9 d, windows, velocities and session labels read exactly."""
    p = _write(
        tmp_path,
        "# comment\n" + HEADER + f"{JD + 0.1},30,100.5,15,-80,14,A\n"
        f"{JD + 0.2},30,-100,15,90,14,B\n",
    )
    tab = read_velocities(p)
    assert tab.lines == "SB2" and tab.n == 2
    assert tab.time.scale == "tdb"
    assert abs(tab.time[0].jd - (JD + 0.1)) < 1e-9
    np.testing.assert_array_equal(tab.v[0], [100.5, -100.0])
    np.testing.assert_array_equal(tab.sigma[1], [14.0, 14.0])
    assert tab.session == ("A", "B")
    assert np.all(np.isnan(tab.lambda_k))


def test_reads_sb1_mjd_and_lambda_k_and_auto_sessions(tmp_path: Path) -> None:
    """SB1 with mjd_tdb and lambda_k; sessions split at gaps > 0.5 d."""
    mjd = JD - 2400000.5
    p = _write(
        tmp_path,
        f"mjd_tdb,lambda_k,v,sigma_v\n{mjd},0.97,1,2\n{mjd + 0.01},0.97,1,2\n{mjd + 3},0.97,1,2\n",
    )
    tab = read_velocities(p)
    assert tab.lines == "SB1"
    assert tab.session == ("S1", "S1", "S2")
    assert abs(tab.time[0].jd - JD) < 1e-9
    assert np.all(np.isnan(tab.window_s))


def test_reads_ecsv_with_units(tmp_path: Path) -> None:
    """ECSV velocities in m/s and windows in min are converted to km/s and s."""
    from astropy import units as u
    from astropy.table import Table

    tab = Table()
    tab["bjd_tdb"] = [JD, JD + 0.01]
    tab["exptime_s"] = [0.5, 0.5] * u.min
    tab["v"] = [1000.0, -2000.0] * u.m / u.s
    tab["sigma_v"] = [15000.0, 15000.0] * u.m / u.s
    path = tmp_path / "v.ecsv"
    tab.write(path, format="ascii.ecsv")
    out = read_velocities(path)
    np.testing.assert_allclose(out.v[0], [1.0, -2.0])
    np.testing.assert_allclose(out.sigma[0], [15.0, 15.0])
    np.testing.assert_allclose(out.window_s, [30.0, 30.0])


@pytest.mark.parametrize(
    "text, needle",
    [
        (HEADER + f"{JD},30,abc,15,1,15,A\n", "row 1, column 'v1'"),
        (HEADER + f"{JD},30,1,15,1,15,A\n{JD},30,1,0,1,15,A\n", "row 2, column 'sigma_v1'"),
        (HEADER + f"{JD},30,1,15,1,-3,A\n", "row 1, column 'sigma_v2'"),
        (HEADER + f"{JD},30,nan,15,1,15,A\n", "row 1, column 'v1'"),
        (HEADER + f"{JD},30,1,15,1,A\n", "row 1 (line 2)"),
        (HEADER + f"{JD},-5,1,15,1,15,A\n", "row 1, column 'exptime_s'"),
        ("bjd_tdb,exptime_s,v1,sigma_v1,v2,sigma_v2,colour\n", "column 'colour'"),
        ("bjd_utc,exptime_s,v,sigma_v\n", "column 'bjd_utc'"),
        ("bjd_tdb,exptime_s,v1,v2,sigma_v2\n", "sigma_v1"),
        ("bjd_tdb,v,sigma_v\n", "exptime_s"),
        (HEADER, "no data rows"),
        ("", "empty velocity file"),
    ],
)
def test_malformed_tables_raise_one_line_errors(tmp_path: Path, text: str, needle: str) -> None:
    """Each malformed table raises VelocityFileError naming the file and the row/column."""
    p = _write(tmp_path, text)
    with pytest.raises(VelocityFileError) as exc:
        read_velocities(p)
    msg = str(exc.value)
    assert needle in msg and str(p) in msg and "\n" not in msg


def test_validity_window(tmp_path: Path) -> None:
    """Times before the LISA start or > 20 yr after its end are rejected with the row number."""
    t = make_target()
    start_jd = t.t_start.tdb.jd
    ok = _write(tmp_path, HEADER + f"{JD},30,1,15,1,15,A\n", "ok.csv")
    tau = check_validity(read_velocities(ok), t)
    assert tau[0] > 0.5 * t.t_obs_s
    early = _write(
        tmp_path, HEADER + f"{JD},30,1,15,1,15,A\n{start_jd - 1},30,1,15,1,15,A\n", "early.csv"
    )
    with pytest.raises(VelocityFileError, match=r"row 2: .*before the LISA observation start"):
        check_validity(read_velocities(early), t)
    late = _write(tmp_path, HEADER + f"{JD + 365.25 * 25},30,1,15,1,15,A\n", "late.csv")
    with pytest.raises(VelocityFileError, match=r"row 1: .*more than 20 yr"):
        check_validity(read_velocities(late), t)
