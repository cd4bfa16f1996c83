"""The core commands end to end: JSON contract, one-line errors, no partial or clobbered files."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from support.cli import run_main
from typer.testing import CliRunner

from ucbplan.cli.app import app

runner = CliRunner()


def _run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "ucbplan", *args], capture_output=True, text=True, timeout=120
    )


def test_horizon_json_contract(hm_cnc_path: Path) -> None:
    res = runner.invoke(app, ["horizon", str(hm_cnc_path), "--format", "json"])
    assert res.exit_code == 0, res.output
    rows = json.loads(res.stdout)
    assert {"anchor", "alpha", "tolerance_rad", "t_valid_days", "dt_u_s"} <= set(rows[0])
    quad1 = next(r for r in rows if r["anchor"] == "quadrature" and r["alpha"] == 1.0)
    assert quad1["t_valid_days"] == pytest.approx(6036, rel=0.03)
    assert quad1["tolerance_rad"] == pytest.approx(0.452911, rel=1e-4)


def test_horizon_options_and_plot(tmp_path: Path, eccentric_path: Path) -> None:
    png = tmp_path / "h.png"
    res = runner.invoke(
        app,
        [
            "horizon",
            str(eccentric_path),
            "--alpha",
            "1",
            "--epochs",
            "1",
            "--sigma-v",
            "10",
            "--k-eff",
            "1000",
            "--plot",
            str(png),
            "--format",
            "csv",
        ],
    )
    assert res.exit_code == 0, res.output
    assert png.stat().st_size > 10_000
    assert res.stdout.splitlines()[0].startswith("anchor,alpha,tolerance_rad")


def test_ephemeris_round_trip_from_json(eccentric_path: Path) -> None:
    """Printed epochs (TDB ISO, µs) converted back give u = u★ to the µs time grid (~3e-8 rad)."""
    from astropy.time import Time

    from ucbplan.core.ephemeris import arg_latitude
    from ucbplan.targets import load_target

    res = runner.invoke(
        app,
        [
            "ephemeris",
            str(eccentric_path),
            "--start",
            "2040-03-01T00:00:00",
            "--end",
            "2040-03-01T01:00:00",
            "--anchor",
            "conjunction",
            "--format",
            "json",
        ],
    )
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout)
    assert doc["meta"]["time_scale"].startswith("TDB")
    t = load_target(eccentric_path)
    times = Time([r["t_star_tdb"] for r in doc["rows"]], scale="tdb")
    u = arg_latitude(t.params, t.tau(times))
    import numpy as np

    us = np.array([r["u_star_rad"] for r in doc["rows"]])
    err = np.angle(np.exp(1j * (u - us)))
    assert np.max(np.abs(err)) < 0.0264 * 1e-6  # u̇ × 1 µs rounding
    assert len(doc["rows"]) == pytest.approx(3600 / 238 * 2, abs=2)


def test_validate_summary(hm_cnc_path: Path, eccentric_path: Path) -> None:
    res = runner.invoke(
        app, ["validate", str(hm_cnc_path), str(eccentric_path), "--format", "json"]
    )
    assert res.exit_code == 0, res.output
    s = json.loads(res.stdout)
    assert s[0]["period_s"] == pytest.approx(2 / 6.2204944286e-3)
    assert s[1]["eccentricity"] == pytest.approx(9.41e-3, rel=1e-3)


def test_error_is_one_line_without_traceback(tmp_path: Path) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text(
        'name: X\nsky: {ra: 1, dec: 2}\nlisa: {t_ref: "2037-01-01T00:00:00", t_obs: "1 yr", '
        'phase: 1, f_gw: "6e-3 Hz", fdot: "7.07e-16 Hz"}\n'
    )
    proc = _run("validate", str(bad))
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr
    lines = [ln for ln in proc.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1
    assert 'bad.yaml: lisa.fdot: expected a frequency derivative like "7.07e-16 Hz / s"' in lines[0]


def test_no_overwrite_and_no_partial_file(tmp_path: Path, hm_cnc_path: Path) -> None:
    out = tmp_path / "h.json"
    out.write_text("keep me")
    proc = _run("horizon", str(hm_cnc_path), "--format", "json", "-o", str(out))
    assert proc.returncode == 2 and "--overwrite" in proc.stderr
    assert out.read_text() == "keep me"
    proc = _run("horizon", str(hm_cnc_path), "--format", "json", "-o", str(out), "--overwrite")
    assert proc.returncode == 0
    assert json.loads(out.read_text())[0]["anchor"] == "conjunction"
    # a failing run leaves no file behind
    out2 = tmp_path / "never.json"
    proc = _run("horizon", str(hm_cnc_path), "--sigma-v", "-1", "--format", "json", "-o", str(out2))
    assert proc.returncode == 2
    assert not out2.exists()
    assert not list(tmp_path.glob(".never.json*"))


def test_missing_sigma_tells_what_to_pass(tmp_path: Path) -> None:
    t = tmp_path / "t.yaml"
    t.write_text(
        'name: X\nsky: {ra: 1, dec: 2}\nlisa: {t_ref: "2037-01-01T00:00:00", t_obs: "1 yr", '
        'phase: 1, f_gw: "6e-3 Hz", fdot: "7e-16 Hz / s"}\n'
    )
    proc = _run("horizon", str(t))
    assert proc.returncode == 2
    assert "--sigma-v" in proc.stderr


def test_bad_anchor_and_window(hm_cnc_path: Path) -> None:
    proc = _run(
        "ephemeris",
        str(hm_cnc_path),
        "--start",
        "2040-01-01",
        "--end",
        "2040-01-02",
        "--anchor",
        "periastron",
    )
    assert proc.returncode == 2 and "unknown anchor" in proc.stderr
    proc = _run("ephemeris", str(hm_cnc_path), "--start", "2040-01-02", "--end", "2040-01-01")
    assert proc.returncode == 2 and "must be after" in proc.stderr


def test_usage_error_has_no_traceback(hm_cnc_path: Path) -> None:
    """A missing required option is a usage message (exit 2), never a traceback."""
    proc = _run("plan", str(hm_cnc_path), "--site", "paranal")
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr
    assert "--night" in proc.stderr


def test_all_commands_registered() -> None:
    res = runner.invoke(app, ["--help"])
    for cmd in (
        "validate",
        "ephemeris",
        "horizon",
        "plan",
        "export",
        "feasibility",
        "reduce",
        "simulate",
        "fisher",
        "waveform",
    ):
        assert cmd in res.stdout


# ------------------------------------------------------------------ the ephemeris group


def test_ephemeris_without_sub_command_is_predict(hm_cnc_path: Path) -> None:
    """`ephemeris TARGET …` (as before the group existed) and `ephemeris predict TARGET …` give
    the same output, with options before or after the target."""
    window = ["--start", "2040-01-01T00:00:00", "--end", "2040-01-01T01:00:00"]
    outs = []
    for args in (
        ["ephemeris", str(hm_cnc_path), *window, "--format", "json"],
        ["ephemeris", "predict", str(hm_cnc_path), *window, "--format", "json"],
        ["ephemeris", "--format", "json", *window, str(hm_cnc_path)],
    ):
        res = runner.invoke(app, args)
        assert res.exit_code == 0, res.output
        outs.append(json.loads(res.stdout))
    assert outs[0] == outs[1] == outs[2]
    assert "t_alt_tdb" in outs[0]["rows"][0]  # a LISA posterior keeps its π mode


def test_ephemeris_group_help_and_no_arguments() -> None:
    res = runner.invoke(app, ["ephemeris", "--help"])
    assert res.exit_code == 0
    assert "predict" in res.stdout and "compare" in res.stdout
    proc = _run("ephemeris")
    assert "Traceback" not in proc.stderr and "predict" in proc.stdout + proc.stderr
    proc = _run("ephemeris", "compare")
    assert proc.returncode == 2 and "Traceback" not in proc.stderr


def test_ephemeris_sub_commands_are_mountable() -> None:
    """The lead mounts `fit` on the same group (cli/core.py, register): a new sub-command is
    reachable by name and does not change the default routing."""
    import typer

    from ucbplan.cli.ephemeris import EphemerisGroup

    sub = typer.Typer(cls=EphemerisGroup, add_completion=False)
    seen: list[str] = []

    @sub.command("predict")
    def _predict(target: str) -> None:
        seen.append(f"predict {target}")

    @sub.command("fit")
    def _fit(times: str) -> None:
        seen.append(f"fit {times}")

    assert runner.invoke(sub, ["fit", "t.csv"]).exit_code == 0
    assert runner.invoke(sub, ["a.yaml"]).exit_code == 0
    assert seen == ["fit t.csv", "predict a.yaml"]


def test_horizon_many_targets_match_single(
    tmp_path: Path, hm_cnc_path: Path, eccentric_path: Path
) -> None:
    """A directory of targets gives the long table, a row per target × anchor × α, each equal
    to the one-target command's row (every number, to 1e-12: the same vectorised search)."""
    import shutil

    from astropy.table import Table

    for p in (hm_cnc_path, eccentric_path):
        shutil.copy(p, tmp_path / p.name)
    out = tmp_path / "h.ecsv"
    res = runner.invoke(
        app, ["horizon", str(tmp_path), "--sigma-v", "15", "--k-eff", "400", "-o", str(out)]
    )
    assert res.exit_code == 0, res.output
    tab = Table.read(out)
    assert len(tab) == 2 * 2 * 2
    assert tab["t_valid_days"].unit == "d" and tab["sigma_v_kms"].unit == "km / s"
    for src in (hm_cnc_path, eccentric_path):
        one = runner.invoke(
            app, ["horizon", str(src), "--sigma-v", "15", "--k-eff", "400", "--format", "json"]
        )
        single = json.loads(one.stdout)
        mine = tab[tab["file"] == str(tmp_path / src.name)]
        assert len(mine) == len(single) == 4
        for row, r in zip(mine, single, strict=True):
            assert (row["anchor"], row["alpha"]) == (r["anchor"], r["alpha"])
            assert row["target"] == r["target"] and row["kind"] == "lisa"
            for key in ("tolerance_rad", "t_valid_days", "dt_u_s", "sigma_u_end_rad"):
                assert row[key] == pytest.approx(r[key], rel=1e-12), key


def test_horizon_catalog_folder_and_files_agree(
    tmp_path: Path, hm_cnc_path: Path, eccentric_path: Path
) -> None:
    """A catalog (one YAML file, target documents separated by ---) gives the same rows as the
    files given one by one, in every format; a bad document is named in a one-line error."""
    text = [p.read_text(encoding="utf-8") for p in (hm_cnc_path, eccentric_path)]
    cat = tmp_path / "catalog.yaml"
    cat.write_text(text[0] + "\n---\n" + text[1], encoding="utf-8")
    files = [str(hm_cnc_path), str(eccentric_path)]
    by_files = json.loads(runner.invoke(app, ["horizon", *files, "--format", "json"]).stdout)
    by_cat = json.loads(runner.invoke(app, ["horizon", str(cat), "--format", "json"]).stdout)
    assert len(by_cat) == len(by_files) == 8
    for a, b in zip(by_cat, by_files, strict=True):
        assert a.pop("file") == str(cat)
        b.pop("file")
        assert a == b
    csv = runner.invoke(app, ["horizon", str(cat), "--format", "csv"])
    assert csv.exit_code == 0 and len(csv.stdout.strip().splitlines()) == 1 + 8
    table = runner.invoke(app, ["horizon", str(cat)])
    assert table.exit_code == 0 and "horizons of 2 targets" in table.output
    cat.write_text(text[0] + "\n---\nname: broken\n", encoding="utf-8")
    res = _run("horizon", str(cat), "--format", "json")
    assert res.returncode == 2 and not res.stdout
    assert "(document 2)" in res.stderr and len(res.stderr.strip().splitlines()) == 1


def test_horizon_many_targets_refuse_plot(
    tmp_path: Path, hm_cnc_path: Path, eccentric_path: Path
) -> None:
    res = _run("horizon", str(hm_cnc_path), str(eccentric_path), "--plot", str(tmp_path / "x.png"))
    assert res.returncode == 2
    assert "--plot: takes one target" in res.stderr  # the library names plot, the CLI the flag
    assert not (tmp_path / "x.png").exists()


def test_horizon_empty_directory(tmp_path: Path) -> None:
    res = _run("horizon", str(tmp_path))
    assert res.returncode == 2
    assert "no *.yaml target files" in res.stderr


@pytest.mark.parametrize("alpha", ["2.556621066963388e+77", "0", "-1", "nan", "11"])
def test_horizon_alpha_outside_its_range_is_one_line_exit_2(hm_cnc_path: Path, alpha: str) -> None:
    """Regression (found by the CLI fuzz test): --alpha 2.6e77 overflowed inside the root
    finder and ended as an internal error; horizon now checks --alpha like plan does."""
    res = _run("horizon", str(hm_cnc_path), "--alpha", alpha)
    assert res.returncode == 2, res.stderr
    assert "--alpha: expected a number in (0, 10]" in res.stderr
    assert "Traceback" not in res.stderr and len(res.stderr.strip().splitlines()) == 1


def test_horizon_many_targets_json_with_a_timing_target(hm_cnc_path: Path) -> None:
    """Regression (issue 23): several targets with --format json ended in an internal error
    ("Out of range float values are not JSON compliant: nan"): a LISA posterior has no horizon
    before its reference, and the wide per-target table carried NaN there."""
    timing = hm_cnc_path.parent / "examples" / "synthetic-eclipsing.yaml"
    res = _run("horizon", str(hm_cnc_path), str(timing), "--format", "json")
    assert res.returncode == 0, res.stderr
    assert "NaN" not in res.stdout
    rows = json.loads(res.stdout)
    assert len(rows) == 2 * 2 * 2  # targets × anchors × α
    lisa = [r for r in rows if r["kind"] == "lisa"]
    timed = [r for r in rows if r["kind"] == "timing"]
    assert len(lisa) == len(timed) == 4
    assert all("t_valid_before_days" not in r for r in lisa)
    assert all(r["t_valid_before_days"] > 0 for r in timed)


def test_horizon_many_targets_name_the_first_that_fails_sigma_k(
    tmp_path: Path, hm_cnc_path: Path
) -> None:
    """σ_v and K are checked once per distinct pair: the error still names the first target in
    the given order that fails, and the option it needs (issue 23)."""
    text = hm_cnc_path.read_text(encoding="utf-8")
    bare = tmp_path / "bare.yaml"
    bare.write_text(text.split("\nspectroscopy:")[0].replace("HM Cnc (simulated)", "bare") + "\n")
    big = tmp_path / "big.yaml"
    big.write_text(text.replace('"390 km/s"', '"50 km/s"').replace("HM Cnc (simulated)", "big"))
    good = str(hm_cnc_path)
    code, _, err = run_main(["horizon", good, str(bare), str(big), "--format", "json"])
    assert code == 2 and err.startswith("error: --sigma-v: bare has no RV precision")
    code, _, err = run_main(["horizon", good, str(big), str(bare), "--format", "json"])
    assert code == 2 and "(56.5685 km/s) must be smaller than k_eff (50 km/s)" in err
    code, _, err = run_main(["horizon", good, str(bare), "--sigma-v", "20", "--format", "json"])
    assert code == 2 and err.startswith("error: --k-eff: bare has no semi-amplitude")
    ok = ["horizon", good, str(bare), str(big), "--sigma-v", "20", "--k-eff", "300"]
    code, out, err = run_main([*ok, "--format", "json"])
    assert code == 0 and len(json.loads(out)) == 3 * 2 * 2, err
