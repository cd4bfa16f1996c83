"""Velocity-table reader: accepted formats and one-line errors naming row and column."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from support.reduce import (
    HEADER,
    JD,
    assert_same_velocities,
    write_velocity_ecsv,
    write_velocity_file,
)
from support.reduce_synth import make_target

from ucbplan.errors import VelocityFileError
from ucbplan.reduce.velocities import check_validity, read_velocities


def test_reads_sb2_csv_with_comments_and_sessions(tmp_path: Path) -> None:
    """SB2 CSV: TDB times to 1e-9 d, windows, velocities and session labels read exactly."""
    p = write_velocity_file(
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
    p = write_velocity_file(
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


def test_validity_window(tmp_path: Path) -> None:
    """Times before the LISA start or > 20 yr after its end are rejected with the row number."""
    t = make_target()
    start_jd = t.t_start.tdb.jd
    ok = write_velocity_file(tmp_path, HEADER + f"{JD},30,1,15,1,15,A\n", "ok.csv")
    tau = check_validity(read_velocities(ok), t)
    assert tau[0] > 0.5 * t.t_obs_s
    early = write_velocity_file(
        tmp_path, HEADER + f"{JD},30,1,15,1,15,A\n{start_jd - 1},30,1,15,1,15,A\n", "early.csv"
    )
    with pytest.raises(VelocityFileError, match=r"row 2: .*before the LISA observation start"):
        check_validity(read_velocities(early), t)
    late = write_velocity_file(
        tmp_path, HEADER + f"{JD + 365.25 * 25},30,1,15,1,15,A\n", "late.csv"
    )
    with pytest.raises(VelocityFileError, match=r"row 1: .*more than 20 yr"):
        check_validity(read_velocities(late), t)


# --- issue 11: encodings, blank cells, ranges, too few rows, windows as long as the orbit ---

ROOT = Path(__file__).resolve().parents[2]
FIDUCIAL = ROOT / "catalogs" / "fiducial-eccentric.yaml"
ROWS = [
    f"{JD + 0.0003 * k:.10f},30,{100 * np.cos(k):.3f},15,{-120 * np.cos(k):.3f},15,A\n"
    for k in range(8)
]


def test_utf8_bom_and_crlf_are_read(tmp_path: Path) -> None:
    """Excel's UTF-8 with a byte-order mark and CRLF line ends read like plain UTF-8."""
    p = tmp_path / "bom.csv"
    p.write_bytes(b"\xef\xbb\xbf" + (HEADER + "".join(ROWS)).replace("\n", "\r\n").encode())
    tab = read_velocities(p)
    assert tab.n == 8 and tab.session[0] == "A"


def test_latin1_is_refused_with_the_fix(tmp_path: Path) -> None:
    p = tmp_path / "latin.csv"
    p.write_bytes(("# observer: Müller\n" + HEADER + "".join(ROWS)).encode("latin-1"))
    with pytest.raises(VelocityFileError, match=r"not UTF-8 text .*iconv") as exc:
        read_velocities(p)
    assert str(p) in str(exc.value) and "\n" not in str(exc.value)


def test_duplicate_ecsv_columns_differing_in_case_are_refused(tmp_path: Path) -> None:
    p = write_velocity_ecsv(tmp_path, [f"{JD} 1 15 30 2"], "bjd_tdb v sigma_v exptime_s V")
    with pytest.raises(VelocityFileError, match="column 'v': appears twice"):
        read_velocities(p)


def _reduce(path: Path) -> object:
    from ucbplan.reduce import ReduceOptions, reduce
    from ucbplan.targets import load_target

    return reduce(load_target(FIDUCIAL), read_velocities(path), ReduceOptions(200, seed=1))


@pytest.mark.parametrize("n_rows", [1])
def test_too_few_spectra_is_one_line_error(tmp_path: Path, n_rows: int) -> None:
    """One spectrum cannot fit γ and K (it was a ValueError traceback)."""
    p = write_velocity_file(tmp_path, HEADER + "".join(ROWS[:n_rows]))
    with pytest.raises(VelocityFileError, match="at least 2 spectra") as exc:
        _reduce(p)
    assert str(p) in str(exc.value)


def test_spectra_at_one_phase_are_one_line_error(tmp_path: Path) -> None:
    """Three spectra at the same time: F̄ does not vary, K is undetermined."""
    p = write_velocity_file(tmp_path, HEADER + "".join(ROWS[0] for _ in range(3)))
    with pytest.raises(VelocityFileError, match="same orbital phase"):
        _reduce(p)


@pytest.mark.parametrize("window", ["238", "300", "1000"])
def test_window_as_long_as_the_orbit_is_refused(tmp_path: Path, window: str) -> None:
    """exptime_s ≥ P_b (238 s) makes Λ_K ≤ 0: K1 came out as −1e7 km/s with exit 0."""
    rows = [r.replace(",30,", f",{window},", 1) if k == 2 else r for k, r in enumerate(ROWS)]
    p = write_velocity_file(tmp_path, HEADER + "".join(rows))
    with pytest.raises(VelocityFileError, match=r"row 3, column 'exptime_s'.*orbital period"):
        _reduce(p)


def test_two_spectra_at_different_phases_reduce(tmp_path: Path) -> None:
    """Two spectra are the minimum (the two-spectrum quadrature technique): a result, no error."""
    p = write_velocity_file(tmp_path, HEADER + "".join(ROWS[:2]))
    red = _reduce(p)
    assert np.isfinite(red.fits[0].K)  # type: ignore[attr-defined]


def test_swapped_star_gives_warning_not_nan_masses(tmp_path: Path) -> None:
    """SB2 with K ≤ 0 for one star: masses are not computed and a warning says why."""
    rows = [r.replace(",A\n", ",A\n") for r in ROWS]
    flipped = []
    for r in rows:
        c = r.split(",")
        c[4] = f"{-float(c[4]):.3f}"  # star 2 moving like star 1
        flipped.append(",".join(c))
    red = _reduce(write_velocity_file(tmp_path, HEADER + "".join(flipped)))
    assert "M1" not in red.summaries  # type: ignore[attr-defined]
    assert any("K =" in w and "not computed" in w for w in red.warnings)  # type: ignore[attr-defined]


def _both_readers(path: Path, monkeypatch: pytest.MonkeyPatch) -> tuple[object, object]:
    """The table read by the columnar reader and by the strict per-cell reader (the reference)."""
    from ucbplan.reduce import velocities as vel

    fast = read_velocities(path)
    with monkeypatch.context() as m:
        m.setattr(vel, "_fast_csv", lambda p: None)
        strict = read_velocities(path)
    return fast, strict


def test_columnar_reader_equals_the_strict_reader(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Issue 23: CSVs are read column by column by astropy's C reader with its exact converter;
    every value must be the strict reader's bit for bit (comments, blank lines, a byte-order
    mark, CRLF, session labels, auto sessions, SB1 and SB2)."""
    from ucbplan.reduce import velocities as vel

    rng = np.random.default_rng(3)
    n = 500
    jd = JD + np.sort(rng.integers(0, 5, n) + rng.uniform(0, 0.3, n))  # five nights
    cells = np.column_stack(
        [jd, rng.uniform(10, 60, n), rng.normal(0, 300, n), rng.uniform(5, 20, n)]
    )
    body = "".join(
        f"{float(a)!r},{b:.3f},{c:.17g},{d:.4e},{'AB'[k % 2]}x\n"
        for k, (a, b, c, d) in enumerate(cells)
    )
    p = tmp_path / "sb1.csv"
    p.write_bytes(
        ("\ufeff# measured\n\nbjd_tdb,exptime_s,v,sigma_v,session\n" + body)
        .replace("\n", "\r\n")
        .encode()
    )
    assert vel._fast_csv(p) is not None  # the columnar path is the one taken
    assert_same_velocities(*_both_readers(p, monkeypatch))
    auto = write_velocity_file(
        tmp_path,
        HEADER.replace(",session", "")
        + "".join(
            f"{float(j)!r},30,{v},15,{-v},14\n" for j, v in zip(jd, cells[:, 2], strict=True)
        ),
    )
    fast, strict = _both_readers(auto, monkeypatch)
    assert_same_velocities(fast, strict)
    assert len(set(fast.session)) > 1  # type: ignore[attr-defined]


@pytest.mark.parametrize(
    ("body", "needle"),
    [
        (f"{JD},30,1,15,2,,A\n", "row 1, column 'sigma_v2': blank cell"),
        (f"{JD},30,1,15,2,14,A\n{JD},30,x,15,2,14,B\n", "row 2, column 'v1': got 'x'"),
        (f"{JD},30,1,15,2,14,A\n{JD},30,nan,15,2,14,B\n", "row 2, column 'v1'"),
        (f"{JD},30,1,15,2,14,A\n{JD},30,1,15\n", "row 2 (line 3): has 4 fields, expected 7"),
        (f"{JD},30,1,15,2,14,01\n{JD + 1},30,1,15,2,14,1\n", None),
    ],
)
def test_columnar_reader_leaves_bad_files_to_the_strict_reader(
    tmp_path: Path, body: str, needle: str | None
) -> None:
    """A file the columnar reader cannot take whole goes to the strict reader: its one-line
    message names the row and column, and a numeric-looking session label stays text."""
    p = write_velocity_file(tmp_path, HEADER + body)
    if needle is None:
        assert read_velocities(p).session == ("01", "1")
        return
    with pytest.raises(VelocityFileError, match=needle.replace("(", r"\(").replace(")", r"\)")):
        read_velocities(p)
