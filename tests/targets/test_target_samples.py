"""Posterior-samples files: the one reader (read_samples_file) and load_samples on a target."""

from __future__ import annotations

import math
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
import yaml
from astropy.table import Table

from ucbplan.errors import InputFileError, TargetFileError
from ucbplan.targets import load_samples, load_target, read_samples_file, write_target
from ucbplan.targets import samples as samples_module

RNG = np.random.default_rng(12)


def _table(n: int = 50) -> Table:
    return Table(
        {
            "phase": RNG.uniform(0, 2 * math.pi, n),
            "f_gw": 6.2204944286e-3 + 1e-11 * RNG.standard_normal(n),
            "fdot": 7.07e-16 + 1e-19 * RNG.standard_normal(n),
            "cos_inclination": RNG.uniform(-1, 1, n),
        }
    )


def _no_astropy_fallback(monkeypatch: pytest.MonkeyPatch) -> None:
    def fail(path: Path) -> None:
        raise AssertionError(f"{path}: fell back to astropy")

    monkeypatch.setattr(samples_module, "_read_with_astropy", fail)


def test_reads_astropy_ecsv_exactly_by_the_fast_path(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A numeric ECSV written by astropy is parsed by numpy alone, values bit-identical."""
    tab = _table()
    path = tmp_path / "post.ecsv"
    tab.write(path, format="ascii.ecsv")
    _no_astropy_fallback(monkeypatch)
    cols = read_samples_file(path)
    assert list(cols) == tab.colnames
    for name in tab.colnames:
        np.testing.assert_array_equal(cols[name], np.asarray(tab[name]))


def test_non_default_delimiter(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """ECSV's ``delimiter: ','`` header is honoured (still without astropy)."""
    tab = _table()
    path = tmp_path / "post.ecsv"
    tab.write(path, format="ascii.ecsv", delimiter=",")
    assert "# delimiter: ','" in path.read_text()
    _no_astropy_fallback(monkeypatch)
    cols = read_samples_file(path)
    np.testing.assert_array_equal(cols["f_gw"], np.asarray(tab["f_gw"]))
    np.testing.assert_array_equal(cols["phase"], np.asarray(tab["phase"]))


def test_text_columns_fall_back_to_astropy_and_are_dropped(tmp_path: Path) -> None:
    tab = _table(5)
    tab["chain"] = ["a b", "c", "d", "e", "f"]
    tab["step"] = np.arange(5)
    path = tmp_path / "post.ecsv"
    tab.write(path, format="ascii.ecsv")
    cols = read_samples_file(path)
    assert "chain" not in cols
    np.testing.assert_array_equal(cols["fdot"], np.asarray(tab["fdot"]))
    np.testing.assert_array_equal(cols["step"], np.arange(5.0))


def test_empty_and_header_only_files_are_errors(tmp_path: Path) -> None:
    empty = tmp_path / "empty.ecsv"
    empty.write_text("")
    with pytest.raises(InputFileError, match=r"empty\.ecsv: cannot read posterior samples \("):
        read_samples_file(empty)
    header_only = tmp_path / "none.ecsv"
    _table(0).write(header_only, format="ascii.ecsv")
    with pytest.raises(InputFileError, match=r"none\.ecsv: posterior samples file has no rows"):
        read_samples_file(header_only)
    with pytest.raises(InputFileError, match="cannot read posterior samples"):
        read_samples_file(tmp_path / "missing.ecsv")


# ---------------------------------------------------------------------------------------------
# load_samples
# ---------------------------------------------------------------------------------------------

START = "2035-01-01T00:00:00"
T_OBS = 126232599.05
F0, FDOT, FDDOT = 6.2e-3, 7.0e-16, 1.0e-26


def _target(tmp_path: Path, t_ref_is: str, samples: str = "post.ecsv") -> Path:
    doc = {
        "name": "S",
        "sky": {"ra": 120.0, "dec": 15.0},
        "lisa": {
            "t_ref": START,
            "t_obs": f"{T_OBS} s",
            "t_ref_is": t_ref_is,
            "phase": 1.0,
            "f_gw": f"{F0} Hz",
            "fdot": f"{FDOT} Hz / s",
            "fddot": f"{FDDOT} Hz / s2",
            "samples": samples,
        },
    }
    path = tmp_path / "t.yaml"
    path.write_text(yaml.safe_dump(doc))
    return path


def test_load_samples_moves_start_referenced_samples_to_the_midpoint(tmp_path: Path) -> None:
    """Samples at the start, f = f0 + δ: at the midpoint f = f0 + δ + ḟT/2 + f̈(T/2)²/2 and
    φ = φ0 + 2π(f T/2 + ḟ(T/2)²/2 + f̈(T/2)³/6) (Sec. 4.1, exact rational arithmetic here);
    the unsampled f̈ comes from the target and non-parameter columns are dropped."""
    n = 20
    delta = 1e-11 * RNG.standard_normal(n)
    delta[0] = 0.0
    Table(
        {
            "phase": np.full(n, 1.0),
            "f_gw": F0 + delta,
            "fdot": np.full(n, FDOT),
            "log_likelihood": RNG.standard_normal(n),
        }
    ).write(tmp_path / "post.ecsv", format="ascii.ecsv")
    t = load_target(_target(tmp_path, "start"))
    cols = load_samples(t)
    assert "log_likelihood" not in cols
    half = T_OBS / 2
    f_mid = F0 + delta + FDOT * half + FDDOT * half**2 / 2
    np.testing.assert_allclose(cols["f_gw"], f_mid, rtol=1e-13, atol=0)
    h = Fraction(half)
    for k in range(n):
        cycles = (
            Fraction(F0 + delta[k]) * h + Fraction(FDOT) * h**2 / 2 + Fraction(FDDOT) * h**3 / 6
        )
        phase = (1.0 + 2 * math.pi * float(cycles % 1)) % (2 * math.pi)
        assert math.remainder(cols["phase"][k] - phase, 2 * math.pi) == pytest.approx(0, abs=1e-8)
    # the sample at the target's own values lands on the target's (shifted) midpoint phase
    assert math.remainder(cols["phase"][0] - t.params.phase, 2 * math.pi) == pytest.approx(
        0, abs=1e-8
    )


def test_load_samples_of_a_midpoint_file_are_returned_as_read(tmp_path: Path) -> None:
    tab = _table(10)
    tab.write(tmp_path / "post.ecsv", format="ascii.ecsv")
    t = load_target(_target(tmp_path, "midpoint"))
    cols = load_samples(t)
    assert list(cols) == tab.colnames
    np.testing.assert_array_equal(cols["f_gw"], np.asarray(tab["f_gw"]))


def test_load_samples_errors(tmp_path: Path) -> None:
    Table({"x": [1.0, 2.0]}).write(tmp_path / "post.ecsv", format="ascii.ecsv")
    # the target has no lisa.covariance: its covariance comes from the samples, read at load
    with pytest.raises(TargetFileError, match=r"post\.ecsv: no parameter columns"):
        load_target(_target(tmp_path, "midpoint"))
    (tmp_path / "post.ecsv").write_text("%ECSV 1.0\n# ---\nnot: [a table\n")
    with pytest.raises(TargetFileError, match="cannot read posterior samples"):
        load_target(_target(tmp_path, "midpoint"))
    Table({"f_gw": [F0]}).write(tmp_path / "post.ecsv", format="ascii.ecsv", overwrite=True)
    with pytest.raises(TargetFileError, match=r"post\.ecsv: 1 row; a covariance needs at least 2"):
        load_target(_target(tmp_path, "midpoint"))
    Table({"f_gw": [F0, np.nan]}).write(tmp_path / "post.ecsv", format="ascii.ecsv", overwrite=True)
    with pytest.raises(TargetFileError, match=r"post\.ecsv: column f_gw: data row 2 is nan"):
        load_target(_target(tmp_path, "midpoint"))


def test_samples_path_survives_writing_elsewhere(tmp_path: Path) -> None:
    """write_target records the samples file relative to the new file when it lies below it,
    else absolute; either way the copy finds the same file."""
    _table(5).write(tmp_path / "post.ecsv", format="ascii.ecsv")
    t = load_target(_target(tmp_path, "midpoint"))
    same_dir = tmp_path / "copy.yaml"
    write_target(t, same_dir)
    assert yaml.safe_load(same_dir.read_text())["lisa"]["samples"] == "post.ecsv"
    (tmp_path / "sub").mkdir()
    other_dir = tmp_path / "sub" / "copy.yaml"
    write_target(t, other_dir)
    assert yaml.safe_load(other_dir.read_text())["lisa"]["samples"] == str(t.samples)
    assert Path(str(t.samples)).is_absolute()
    assert load_target(same_dir).samples == load_target(other_dir).samples == t.samples


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_non_finite_samples_are_refused_naming_column_and_row(tmp_path: Path, bad: float) -> None:
    tab = _table(10)
    tab["phase"][3] = bad
    tab["phase"][7] = bad
    tab.write(tmp_path / "post.ecsv", format="ascii.ecsv")
    with pytest.raises(
        TargetFileError, match=r"post\.ecsv: column phase: data row 4 is .*\(2 such"
    ):
        load_samples(load_target(_target(tmp_path, "midpoint")))  # the target reads them too


def test_horizon_says_the_covariance_came_from_the_samples(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """Issue 26 item 4: the command says which covariance it used (one line)."""
    import sys

    from ucbplan.cli import app as app_module

    _table(40).write(tmp_path / "post.ecsv", format="ascii.ecsv")
    path = _target(tmp_path, "midpoint")
    argv = ["ucbplan", "horizon", str(path), "--sigma-v", "15", "--k-eff", "500"]
    monkeypatch.setattr(sys, "argv", argv)
    with pytest.raises(SystemExit) as exit_:
        app_module.main()
    err = capsys.readouterr().err
    assert exit_.value.code == 0, err
    assert "S: covariance from the samples file post.ecsv" in err
