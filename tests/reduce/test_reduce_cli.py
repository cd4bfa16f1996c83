"""``ucbplan reduce`` command: JSON/YAML reports, EM prior, plots, overwrite rules, error format."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from ucbplan.cli._flags import cli_message
from ucbplan.cli.app import app

ROOT = Path(__file__).resolve().parents[2]
TARGET = ROOT / "catalogs" / "fiducial-eccentric.yaml"
VELS = ROOT / "catalogs" / "fiducial-eccentric-velocities.csv"
TRUTH = {"K1": 585.293, "K2": 712.620, "gamma1": 41.640, "gamma2": 39.197}


def _run(*args: str) -> object:
    return CliRunner().invoke(app, ["reduce", str(TARGET), str(VELS), *args])


def test_json_report_keys_and_truth(tmp_path: Path) -> None:
    """JSON on stdout: required top-level keys as {value, sigma, unit} (+lo/hi for MC); the
    example file (exact Kepler, seed 20370101) recovers its header truth within 3σ."""
    res = _run("--format", "json", "--seed", "1", "--samples", "2000")
    assert res.exit_code == 0, res.output  # type: ignore[attr-defined]
    doc = json.loads(res.stdout)  # type: ignore[attr-defined]
    for key in ("K1", "K2", "gamma1", "gamma2", "q", "M1", "M2", "M_tot"):
        q = doc[key]
        assert set(q) >= {"value", "sigma", "unit"}, key
        assert q["sigma"] > 0
    for key in ("q", "M1", "M2", "M_tot", "M_c"):
        assert doc[key]["lo"] < doc[key]["value"] < doc[key]["hi"]
    assert doc["K1"]["unit"] == "km / s" and doc["M1"]["unit"] == "solMass"
    for key, val in TRUTH.items():
        assert abs(doc[key]["value"] - val) < 3 * doc[key]["sigma"], key
    assert abs(doc["M1"]["value"] - 0.347) < 3 * doc["M1"]["sigma"]
    assert doc["drifts"]["pairs"] and "a_los" in doc["drifts"]
    assert doc["seed"] == 1


def test_yaml_output_em_prior_plots_and_overwrite(tmp_path: Path) -> None:
    """-o YAML, --em-prior and --plots write files; a second run without --overwrite fails and
    leaves them untouched; with --overwrite it succeeds."""
    out, prior, plots = tmp_path / "r.yaml", tmp_path / "prior.yaml", tmp_path / "figs"
    plots.mkdir()
    args = (
        "-o",
        str(out),
        "--em-prior",
        str(prior),
        "--plots",
        str(plots),
        "--seed",
        "2",
        "--samples",
        "500",
        "--mass-radius",
        "eggleton",
    )
    res = _run(*args)
    assert res.exit_code == 0, res.output  # type: ignore[attr-defined]
    doc = yaml.safe_load(out.read_text())
    assert doc["redshift_grav_model"]["unit"] == "km / s"
    # the example's γ_j contain the Eggleton surface redshifts + 3G(M2−M1)/(2ac) split: the
    # measured G(M1/R1 − M2/R2)/c must agree with the model within 3σ (truth 3.26 km/s)
    diff = doc["redshift_grav_minus_model"]
    assert abs(diff["value"]) < 3 * diff["sigma"]
    assert abs(doc["redshift_grav"]["value"] - 3.265) < 3 * doc["redshift_grav"]["sigma"]
    pr = yaml.safe_load(prior.read_text())["em_prior"]
    assert {"q", "M_tot", "a_los"} <= set(pr)
    assert sorted(p.name for p in plots.iterdir()) == [
        "dv1_vs_dv2.png",
        "mass_mass.png",
        "rv_vs_F.png",
    ]
    before = out.read_bytes()
    res2 = _run(*args)
    assert res2.exit_code != 0
    assert "overwrite" in str(res2.exception)  # type: ignore[attr-defined]
    assert out.read_bytes() == before
    assert _run(*args, "--overwrite").exit_code == 0


def test_bad_options_and_files_exit_2_with_one_line(tmp_path: Path) -> None:
    """End to end (python -m ucbplan): a malformed velocity row → exit 2, one line naming it."""
    bad = tmp_path / "bad.csv"
    bad.write_text("bjd_tdb,exptime_s,v,sigma_v\n2465800.1,30,oops,15\n")
    proc = subprocess.run(
        [sys.executable, "-m", "ucbplan", "reduce", str(TARGET), str(bad)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 2
    err = proc.stderr.strip()
    assert "row 1, column 'v'" in err and len(err.splitlines()) == 1
    res = _run("--mass-radius", "unknown")
    assert res.exit_code != 0 and "eggleton" in str(res.exception)  # type: ignore[attr-defined]


def test_site_utc_times_are_converted(tmp_path: Path) -> None:
    """mjd_utc columns + --site: the barycentric times of the example file are recovered after a
    round trip through site UTC (|Δ| < 1 ms ⇒ phase error < 3e-5 rad), so K1 is identical to
    0.01 km/s; without --site the run fails with a one-line hint."""
    import numpy as np
    from astropy.time import Time

    from ucbplan.observing.observatory.barycentric import bary_tdb_to_site_utc
    from ucbplan.observing.observatory.sites import get_site
    from ucbplan.targets import load_target

    t = load_target(TARGET)
    lines = [ln for ln in VELS.read_text().splitlines() if not ln.startswith("#")]
    rows = [ln.split(",") for ln in lines[1:]]
    jd = np.array([float(r[0]) for r in rows])
    bary = Time(np.floor(jd), jd - np.floor(jd), format="jd", scale="tdb")
    utc = bary_tdb_to_site_utc(bary, t.coord, get_site("Paranal").location)
    out = tmp_path / "utc.csv"
    body = [f"{m:.10f}," + ",".join(r[1:]) for m, r in zip(utc.utc.mjd, rows, strict=True)]
    out.write_text("mjd_utc," + lines[0].split(",", 1)[1] + "\n" + "\n".join(body) + "\n")
    res = CliRunner().invoke(
        app,
        [
            "reduce",
            str(TARGET),
            str(out),
            "--format",
            "json",
            "--site",
            "Paranal",
            "--samples",
            "200",
            "--seed",
            "1",
        ],
    )
    assert res.exit_code == 0, res.output
    ref = CliRunner().invoke(
        app,
        ["reduce", str(TARGET), str(VELS), "--format", "json", "--samples", "200", "--seed", "1"],
    )
    assert json.loads(res.stdout)["K1"]["value"] == pytest.approx(
        json.loads(ref.stdout)["K1"]["value"], abs=0.01
    )
    bad = CliRunner().invoke(app, ["reduce", str(TARGET), str(out)])
    assert bad.exit_code != 0 and "--site" in cli_message(str(bad.exception))


# --- issue 11: one -o rule, option values, outputs as a unit ---


@pytest.mark.parametrize(
    ("args", "fmt"),
    [
        (["-o", "{tmp}/r.json"], "json"),
        (["-o", "{tmp}/r.yaml"], "yaml"),
        (["-o", "{tmp}/r.YML"], "yaml"),
        (["-o", "{tmp}/report"], "json"),  # no suffix: the first machine format
        (["-o", "{tmp}/r.yaml", "--format", "yaml"], "yaml"),
    ],
)
def test_output_format_follows_the_one_rule(tmp_path: Path, args: list[str], fmt: str) -> None:
    """--format, else the -o suffix, else JSON for a file; the file holds that format."""
    argv = [a.replace("{tmp}", str(tmp_path)) for a in args]
    res = _run(*argv, "--samples", "200", "--seed", "1")
    assert res.exit_code == 0, res.output  # type: ignore[attr-defined]
    text = Path(argv[1]).read_text()
    if fmt == "json":
        assert json.loads(text)["seed"] == 1
    else:
        assert not text.lstrip().startswith("{") and yaml.safe_load(text)["seed"] == 1


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["--format", "json", "-o", "{tmp}/x.yaml"], "suffix says yaml but --format says json"),
        (["--format", "table", "-o", "{tmp}/x.json"], "--format table"),
        (["--format", "xml"], "--format"),
        (["-o", "{tmp}/x.json", "--em-prior", "{tmp}/x.json"], "same file"),
        (["--em-prior", "{tmp}/prior.json"], "EM prior is YAML"),
        (["--cos-i-sigma", "1e300"], "--cos-i-sigma"),
        (["-o", "{tmp}"], "folder"),
        (["-o", "{tmp}/missing/x.json"], "does not exist"),
        (["--plots", "{tmp}/nope"], "--plots"),
        (["--mass-radius", "x" * 3000], "--mass-radius"),
        (["--site", "atlantis"], ""),
    ],
)
def test_bad_output_and_option_values(tmp_path: Path, args: list[str], needle: str) -> None:
    """One UcbplanError line naming the option as the command line prints it (library parameter
    names become flags there, ucbplan.cli._flags); the folder is left as it was."""
    from ucbplan.cli._flags import cli_message
    from ucbplan.errors import UcbplanError

    (tmp_path / "keep.txt").write_text("x")
    argv = [a.replace("{tmp}", str(tmp_path)) for a in args]
    res = _run(*argv, "--samples", "200")
    exc = res.exception  # type: ignore[attr-defined]
    if "--site" in args:  # a barycentric table needs no site: the option is unused
        assert res.exit_code == 0  # type: ignore[attr-defined]
        return
    assert isinstance(exc, UcbplanError), (exc, res.output)  # type: ignore[attr-defined]
    msg = cli_message(str(exc))
    assert needle in msg and "\n" not in msg and len(msg) < 400, msg
    assert [p.name for p in tmp_path.iterdir()] == ["keep.txt"]


@pytest.mark.parametrize(
    "args",
    [
        ["--samples", "5"],
        ["--samples", "-5"],
        ["--samples", "10000000000"],
        ["--seed", "-1"],
        ["--samples", "abc"],
        ["--cos-i-sigma", "-1"],
        ["--cos-i-sigma", "nan"],
    ],
)
def test_out_of_range_numbers_are_usage_errors(tmp_path: Path, args: list[str]) -> None:
    """Values typer checks (ranges, integers): exit 2 naming the option, nothing written."""
    res = _run("-o", str(tmp_path / "r.json"), *args)
    assert res.exit_code == 2  # type: ignore[attr-defined]
    assert args[0] in res.output and "Traceback" not in res.output  # type: ignore[attr-defined]
    assert list(tmp_path.iterdir()) == []


def test_report_and_em_prior_are_written_together(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """If writing the EM prior fails, the report is not left behind either."""
    from ucbplan.reduce import report as rep

    def fail(doc: object, handle: object) -> None:
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(rep, "write_yaml", fail)
    out, prior = tmp_path / "r.json", tmp_path / "prior.yaml"
    res = _run("-o", str(out), "--em-prior", str(prior), "--samples", "200")
    assert res.exit_code != 0  # type: ignore[attr-defined]
    assert "no space left" in str(res.exception)  # type: ignore[attr-defined]
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    ("kwargs", "parameter", "flag"),
    [
        ({"mass_radius": "x"}, "mass_radius", "--mass-radius"),
        ({"cos_i_sigma": 2.5}, "cos_i_sigma", "--cos-i-sigma"),
    ],
)
def test_reduce_options_name_the_parameter_and_the_flag(
    kwargs: dict[str, object], parameter: str, flag: str
) -> None:
    """One check for the command and ucbplan.reduce: the library error names the parameter,
    the command line prints its flag; a valid relation is stored lower case."""
    from ucbplan.cli._flags import cli_message
    from ucbplan.errors import InputError
    from ucbplan.reduce.pipeline import reduce_options

    with pytest.raises(InputError) as info:
        reduce_options(**kwargs)  # type: ignore[arg-type]
    assert info.value.parameter == parameter
    assert str(info.value).startswith(f"{parameter}: ")
    assert cli_message(str(info.value)).startswith(f"{flag}: ")
    assert reduce_options(mass_radius="Eggleton", cos_i_sigma=2.0).mass_radius == "eggleton"
