"""Regression tests of issue 22: the new surfaces (timing, population, plan options, exports,
several targets per horizon) refuse bad input with one line and exit 2, write nothing on failure
and never crash on values JSON cannot spell."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from astropy.table import Table
from hypothesis import given, settings
from hypothesis import strategies as st
from support.cli import run_main
from typer.testing import CliRunner

from ucbplan.cli.app import app
from ucbplan.errors import shorten
from ucbplan.io import dumps_json, json_plain
from ucbplan.observing.observatory.sites import east_longitude, site_from_lonlat

runner = CliRunner()
ROOT = Path(__file__).resolve().parents[2]
CAT = ROOT / "catalogs"
HM = CAT / "hm-cnc-simulated.yaml"
INJ = CAT / "fiducial-injection.yaml"
POP = CAT / "population" / "ldc-200.ecsv"


def cli(*args: str) -> tuple[int, str, str]:
    """``ucbplan ARGS`` through the real entry point in this process: exit code, stdout, stderr."""
    return run_main(list(args))


def refused(*args: str) -> str:
    """Run ``ucbplan ARGS``, check it failed with exit 2 and one error line; return the line."""
    code, _, err = cli(*args)
    assert code == 2, err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    return lines[0]


def _strict_json(text: str) -> object:
    """Parse JSON as a strict reader does: the bare tokens NaN/Infinity are errors."""

    def _refuse(token: str) -> None:
        raise AssertionError(f"non-standard JSON token {token}")

    return json.loads(text, parse_constant=_refuse)


def test_json_plain_spells_non_finite_as_null() -> None:
    doc = {"a": float("nan"), "b": [np.float64("inf"), np.int64(3)], 4: (np.nan, "x")}
    assert json_plain(doc) == {"a": None, "b": [None, 3], "4": [None, "x"]}
    assert _strict_json(dumps_json(doc)) == {"a": None, "b": [None, 3], "4": [None, "x"]}


def test_horizon_of_two_lisa_targets_is_valid_json(tmp_path: Path) -> None:
    res = runner.invoke(app, ["horizon", str(INJ), str(HM), "--format", "json"])
    assert res.exit_code == 0, res.output
    doc = _strict_json(res.stdout)  # NaN "before" horizons once crashed the writer half-way
    assert isinstance(doc, list) and {r["target"] for r in doc} >= {"HM Cnc (simulated)"}
    out = tmp_path / "h.json"
    res = runner.invoke(app, ["horizon", str(INJ), str(HM), "-o", str(out)])
    assert res.exit_code == 0, res.output
    assert _strict_json(out.read_text()) == doc


ECC = CAT / "fiducial-eccentric.yaml"


def test_plot_and_existing_output_writes_neither(tmp_path: Path) -> None:
    (tmp_path / "f.json").write_text("keep me\n")
    args = ["feasibility", str(ECC), "--plot", str(tmp_path / "f.png")]
    refused(*args, "-o", str(tmp_path / "f.json"))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["f.json"]


@settings(max_examples=200, deadline=None)
@given(lon=st.floats(-180.0, 360.0))
def test_one_longitude_rule_keeps_the_meridian(lon: float) -> None:
    out = east_longitude(lon)
    assert -180.0 <= out < 180.0
    # the same meridian: differs by a whole number of turns (to float rounding, 1e-12 deg)
    turns = (lon - out) / 360.0
    assert abs(turns - round(turns)) < 1e-12


@pytest.mark.parametrize(("east", "west"), [("200", "-160"), ("360", "0"), ("180", "-180")])
def test_site_lonlat_above_180_is_the_same_site_as_below(east: str, west: str) -> None:
    a, b = site_from_lonlat(f"{east},10,0"), site_from_lonlat(f"{west},10,0")
    assert (a.lon_deg, a.timezone, a.name) == (b.lon_deg, b.timezone, b.name)


def test_plan_at_longitude_200_runs(tmp_path: Path) -> None:
    out = tmp_path / "b.ecsv"
    code, _, err = cli(
        "plan", str(HM), "--site-lonlat", "200,19.8,4200", "--night", "2040-02-15", "-o", str(out)
    )
    assert code == 0, err
    assert out.exists()


@pytest.mark.parametrize("command", ["plan", "population visibility"])
def test_site_and_site_lonlat_together_are_refused(tmp_path: Path, command: str) -> None:
    base = (
        ["plan", str(HM), "--night", "2040-02-15"]
        if command == "plan"
        else ["population", "visibility", str(POP), "--semester", "2041A"]
    )
    args = [*base, "--site", "paranal", "--site-lonlat", "-70,-24,2600", "-o", str(tmp_path / "x")]
    line = refused(*args)
    assert "--site" in line and "--site-lonlat" in line and "not both" in line
    assert list(tmp_path.iterdir()) == []


def test_instruments_file_without_instrument_is_refused(tmp_path: Path) -> None:
    line = refused(
        "plan", str(HM), "--site", "paranal", "--night", "2040-02-15",
        "--instruments-file", str(tmp_path / "mine.yaml"),
    )  # fmt: skip
    assert "--instruments-file" in line and "--instrument NAME" in line


def test_bad_value_in_an_instruments_file_is_named_before_a_missing_one(tmp_path: Path) -> None:
    path = tmp_path / "inst.yaml"
    path.write_text(
        "instruments:\n  myspec:\n    telescope: VLT\n    sites: [paranal]\n    readout_s: -5\n"
        "    acquisition_s: 300\n    missing: [extinction_k, sigma_ref]\n",
        encoding="utf-8",
    )
    line = refused(
        "plan", str(HM), "--site", "paranal", "--night", "2040-02-15", "--sigma-v", "10",
        "--instrument", "myspec", "--instruments-file", str(path),
    )  # fmt: skip
    assert "readout_s: expected a number" in line and "got -5" in line


def test_numbers_in_messages_are_written_as_users_write_them() -> None:
    assert shorten(np.float64(-1.0)) == "-1.0"
    assert shorten(np.str_("abc")) == "'abc'"
    assert shorten(np.int64(3)) == "3"
    assert shorten(np.array([1.0])) == repr(np.array([1.0]))  # arrays are not scalars


def _renamed(tmp_path: Path, file: str, name: str) -> Path:
    text = HM.read_text(encoding="utf-8")
    old = next(ln for ln in text.splitlines() if ln.startswith("name:"))
    path = tmp_path / file
    path.write_text(text.replace(old, f"name: {name!r}"), encoding="utf-8")
    return path


def test_plan_refuses_a_target_given_twice_naming_both_files(tmp_path: Path) -> None:
    copy = _renamed(tmp_path, "copy.yaml", "HM Cnc (simulated)")
    night = ["--site", "paranal", "--night", "2040-02-15", "-o", str(tmp_path / "b.ecsv")]
    line = refused("plan", str(HM), str(HM), *night)
    assert line.count(str(HM)) == 2 and "the same target file twice" in line
    alias = tmp_path / "sub" / ".." / "copy.yaml"
    (tmp_path / "sub").mkdir()
    line = refused("plan", str(copy), str(alias), *night)
    assert str(copy) in line and str(alias) in line and "same target file" in line
    line = refused("plan", str(HM), str(copy), *night)
    assert str(HM) in line and str(copy) in line and "both are target" in line
    # names that give the same block ids (HM Cnc / HM-Cnc) are the same target to the planner
    a, b = _renamed(tmp_path, "a.yaml", "HM Cnc"), _renamed(tmp_path, "b.yaml", "HM-Cnc")
    line = refused("plan", str(a), str(b), *night)
    assert "'HM Cnc' / 'HM-Cnc'" in line
    assert not (tmp_path / "b.ecsv").exists()


def test_plan_of_two_distinct_targets_still_runs(tmp_path: Path) -> None:
    other = _renamed(tmp_path, "other.yaml", "HM Cnc twin")
    out = tmp_path / "b.ecsv"
    code, _, err = cli(
        "plan", str(HM), str(other), "--site", "paranal", "--night", "2040-02-15", "-o", str(out)
    )
    assert code == 0, err
    ids = [ln for ln in out.read_text().splitlines() if not ln.startswith("#")][1:]
    assert len(ids) == len(set(ids)) > 0


def _small_catalog(tmp_path: Path, n: int = 3) -> Table:
    tab = Table.read(POP)[:n]
    return tab


@pytest.mark.parametrize("command", ["forecast", "visibility", "simulate", "rank"])
def test_catalog_problems_are_one_line_before_any_output(tmp_path: Path, command: str) -> None:
    empty = tmp_path / "empty.csv"
    empty.write_text("\n", encoding="utf-8")
    tab = _small_catalog(tmp_path)
    tab.write(tmp_path / "small.csv", format="ascii.csv")
    head, *rows = (tmp_path / "small.csv").read_text().splitlines()
    dup = tmp_path / "dup.csv"
    dup.write_text("\n".join([head.replace("Amplitude", "Frequency"), *rows]) + "\n")
    kg = tmp_path / "kg.ecsv"
    tab["Mass1"].unit = "kg"  # the numbers are solar masses: 0.44 kg is no star
    tab.write(kg)
    out = tmp_path / "out"
    out.mkdir()
    extra = {
        "forecast": ["-o", str(out / "f.ecsv")],
        "visibility": ["-o", str(out / "v.ecsv"), "--semester", "2041A", "--site", "paranal"],
        "simulate": ["-o", str(out / "s.ecsv"), "--out-dir", str(out / "sd")],
        "rank": ["--out-dir", str(out / "r")],
    }[command]
    expect = {
        empty: "the catalog is empty",
        dup: "column 'Frequency' appears twice",
        kg: "Mass1: expected 0.01..1.5 solMass, got",
    }
    for path, text in expect.items():
        line = refused("population", command, str(path), *extra)
        assert text in line, line
        assert "Errno" not in line
        assert list(out.iterdir()) == []


@pytest.fixture(scope="module")
def blocks_table(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("blocks") / "b.ecsv"
    code, _, err = cli(
        "plan", str(HM), "--site", "paranal", "--night", "2040-02-15", "-o", str(out)
    )
    assert code == 0, err
    return out


def test_phase_table_needs_the_period_and_names_the_rows(
    tmp_path: Path, blocks_table: Path
) -> None:
    tab = Table.read(blocks_table)
    assert len(tab) >= 2
    tab["period_s"][:] = np.nan
    bad = tmp_path / "nan.ecsv"
    tab.write(bad)
    line = refused("export", str(bad), "--to", "phase-table", "-o", str(tmp_path / "p.ecsv"))
    assert "column period_s" in line and "rows 1, 2" in line
    assert not (tmp_path / "p.ecsv").exists()


def test_an_empty_period_cell_is_estimated_and_the_note_says_so(
    tmp_path: Path, blocks_table: Path
) -> None:
    tab = Table.read(blocks_table)
    period = float(tab["period_s"][1])
    tab["period_s"][0] = np.nan
    one = tmp_path / "one.ecsv"
    tab.write(one)
    code, _, err = cli("export", str(one), "--to", "proposal", "-o", str(tmp_path / "p.csv"))
    assert code == 0, err
    assert f"period_s empty in 1 of {len(tab)} rows" in err and "no period_s column" not in err
    code, _, err = cli("export", str(one), "--to", "phase-table", "-o", str(tmp_path / "p.ecsv"))
    assert code == 0, err
    out = Table.read(tmp_path / "p.ecsv")
    # the median of the target's given periods (the estimate is not used by the phase table)
    assert float(out["period_s"][0]) == pytest.approx(period, rel=1e-12)


def test_nothing_planned_says_why_once(tmp_path: Path) -> None:
    # HM Cnc (dec +16) in July from Paranal: below airmass 2 all night
    code, _, err = cli(
        "plan", str(HM), "--site", "paranal", "--night", "2040-07-15", "-o", str(tmp_path / "b")
    )
    assert code == 2
    lines = [ln for ln in err.splitlines() if ln.strip() and not ln.startswith("warning:")]
    assert len(lines) == 1 and lines[0].startswith("error: no block could be planned"), err
    assert lines[0].count("never at airmass") == 1


def test_horizon_refuses_a_target_file_given_twice(tmp_path: Path) -> None:
    line = refused("horizon", str(HM), str(INJ), str(HM), "--format", "json")
    assert line.count(str(HM)) == 2 and "the same target file twice" in line
    folder = tmp_path / "targets"
    folder.mkdir()
    (folder / "hm.yaml").write_bytes(HM.read_bytes())
    line = refused("horizon", str(folder), str(folder / "hm.yaml"), "-o", str(tmp_path / "h.json"))
    assert "the same target file twice" in line
    assert not (tmp_path / "h.json").exists()
