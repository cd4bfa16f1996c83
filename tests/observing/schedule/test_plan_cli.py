"""`ucbplan plan` end to end: files, formats, overwrite protection, one-line errors."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from ucbplan.cli.app import app
from ucbplan.errors import OutputExistsError
from ucbplan.observing.blocks.make import file_sha256
from ucbplan.observing.blocks.read import read_blocks
from ucbplan.observing.blocks.schema import REQUIRED_COLUMNS

pytestmark = [
    pytest.mark.filterwarnings("ignore::erfa.ErfaWarning"),
    pytest.mark.filterwarnings("ignore::astropy.utils.exceptions.AstropyWarning"),
]

REPO = Path(__file__).resolve().parents[3]
HM = str(REPO / "catalogs" / "hm-cnc-simulated.yaml")
BASE = ["plan", HM, "--site", "paranal", "--night", "2040-02-15"]


def test_plan_writes_ecsv_and_plot(tmp_path: Path) -> None:
    out, png = tmp_path / "blocks.ecsv", tmp_path / "night.png"
    res = CliRunner().invoke(app, [*BASE, "-o", str(out), "--plot", str(png)])
    assert res.exit_code == 0, res.output
    table = read_blocks(out)
    assert tuple(table.colnames[: len(REQUIRED_COLUMNS)]) == REQUIRED_COLUMNS
    assert len(table) == 2 and set(table["anchor"]) == {"quadrature"}
    assert table.meta["site"]["name"] == "Paranal"
    assert table.meta["targets"][0]["sha256"] == file_sha256(Path(HM))
    assert "nautical night (Sun altitude <= -12 deg)" in table.meta["constraints"]
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # Overwrite protection (the CLI's one-line error path is exercised below by subprocess).
    again = CliRunner().invoke(app, [*BASE, "-o", str(out)])
    assert isinstance(again.exception, OutputExistsError)
    ok = CliRunner().invoke(app, [*BASE, "-o", str(out), "--overwrite", "--mode", "conjunction"])
    assert ok.exit_code == 0, ok.output


def test_plan_json_to_stdout() -> None:
    res = CliRunner().invoke(app, [*BASE, "--format", "json", "--exptime", "20", "--n-exp", "3"])
    assert res.exit_code == 0
    rows = json.loads(res.stdout)["rows"]
    assert [r["n_exp"] for r in rows] == [3, 3]
    assert rows[0]["t_mid_utc"].startswith("2040-02-16T")


def _run(args: list[str]) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "ucbplan", *args], capture_output=True, text=True, timeout=120
    )


def test_errors_are_one_line_without_traceback(tmp_path: Path) -> None:
    doc = yaml.safe_load(Path(HM).read_text())
    doc["sky"]["dec"] = "+80d00m00s"
    doc["name"] = "Far North"
    north = tmp_path / "north.yaml"
    north.write_text(yaml.safe_dump(doc))
    proc = _run(["plan", str(north), "--site", "paranal", "--night", "2040-02-15"])
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr
    assert "error: no block could be planned at Paranal: Far North (2040-02-15): never at" in (
        " ".join(proc.stderr.split())
    )
    proc = _run(["plan", HM, "--site", "atlantis", "--night", "2040-02-15"])
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert "known sites: Paranal" in " ".join(proc.stderr.split())


def test_site_lonlat_and_sites_file(tmp_path: Path) -> None:
    # Paranal by coordinates gives the same blocks as by name (zone only changes local times).
    by_name = CliRunner().invoke(app, [*BASE, "--format", "json"])
    lonlat = [
        "plan",
        HM,
        "--site-lonlat",
        "-70.4042,-24.6272,2635",
        "--night",
        "2040-02-15",
        "--format",
        "json",
    ]
    by_coords = CliRunner().invoke(app, lonlat)
    assert by_coords.exit_code == 0, by_coords.output
    a, b = json.loads(by_name.stdout)["rows"], json.loads(by_coords.stdout)["rows"]
    assert [r["t_mid_utc"] for r in a] == [r["t_mid_utc"] for r in b]
    sites = tmp_path / "sites.yaml"
    sites.write_text(
        "sites:\n  - name: My Dome\n    lon_deg: -70.4042\n    lat_deg: -24.6272\n"
        "    height_m: 2635\n    timezone: America/Santiago\n"
    )
    mine = CliRunner().invoke(
        app,
        [
            "plan",
            HM,
            "--site",
            "my dome",
            "--sites-file",
            str(sites),
            "--night",
            "2040-02-15",
            "--format",
            "json",
        ],
    )
    assert mine.exit_code == 0, mine.output
    assert [r["t_mid_utc"] for r in json.loads(mine.stdout)["rows"]] == [r["t_mid_utc"] for r in a]


def test_night_chart_axes() -> None:
    from datetime import date

    from ucbplan.observing.night.chart import plot_night
    from ucbplan.observing.observatory.sites import get_site
    from ucbplan.plotting import pyplot
    from ucbplan.targets import load_target

    fig = plot_night([load_target(Path(HM))], get_site("paranal"), date(2040, 2, 15), [], 2.0)
    ax = fig.axes[0]
    assert ax.get_ylabel() == "altitude [deg]"
    assert ax.get_xlabel().startswith("UTC [hh:mm]")
    assert {t.get_text() for t in ax.get_legend().get_texts()} >= {
        "HM Cnc (simulated)",
        "Moon",
        "airmass 2",
    }
    pyplot().close(fig)


def test_priority_option_orders_the_schedule() -> None:
    fid = str(REPO / "catalogs" / "fiducial-eccentric.yaml")
    args = [
        "plan",
        HM,
        fid,
        "--site",
        "paranal",
        "--night",
        "2040-02-15",
        "--format",
        "json",
        "--overhead",
        "7200",
    ]
    # With a 2-h overhead the two transits (~02:13 and ~03:06 UTC) cannot both be used: HM Cnc
    # (listed first) gets its transit at equal priority, the fiducial source when boosted.
    base = json.loads(CliRunner().invoke(app, args).stdout)["rows"]
    boosted = json.loads(
        CliRunner().invoke(app, [*args, "--priority", "Fiducial eccentric dWD=5"]).stdout
    )["rows"]

    def best(rows: list[dict], name: str) -> float:
        return min(r["airmass"] for r in rows if r["target"] == name)

    # Measured: fiducial 1.203 -> 1.168 (its transit), HM Cnc 1.305 (transit) -> 1.379.
    assert best(boosted, "Fiducial eccentric dWD") < best(base, "Fiducial eccentric dWD") - 0.02
    assert best(boosted, "HM Cnc (simulated)") > best(base, "HM Cnc (simulated)") + 0.05
    bad = CliRunner().invoke(app, [*args, "--priority", "nobody=3"])
    assert "no target named 'nobody'" in str(bad.exception)
