"""Screen tests (issues 15 and 24): at 100 columns nothing is cut, no line is wider, and file
names are printed literally.

Rich marks a cell it had to cut with "…"; each command runs in a fresh process with
``COLUMNS=100`` (the terminal width rich reads), as a user's terminal would run it. Widths are
counted in terminal cells (``rich.cells.cell_len``: a wide character takes two).
"""

from __future__ import annotations

from pathlib import Path

import pytest
from support.screen import run_at_100, too_wide

CAT = Path(__file__).resolve().parents[2] / "catalogs"
HM, ECC = str(CAT / "hm-cnc-simulated.yaml"), str(CAT / "fiducial-eccentric.yaml")
SYN = str(CAT / "examples" / "synthetic-eclipsing.yaml")


COMMANDS = [
    ["validate", HM],
    ["horizon", HM],
    ["ephemeris", HM, "--start", "2040-02-16T03:00", "--end", "2040-02-16T03:10"],
    ["ephemeris", SYN, "--start", "2026-11-24", "--end", "2026-11-24T01:00", "--anchor", "eclipse"],
    ["feasibility", ECC],
    ["reduce", ECC, str(CAT / "fiducial-eccentric-velocities.csv"), "--samples", "2000"],
    ["plan", HM, "--site", "paranal", "--night", "2040-02-15"],
    [
        "plan",
        HM,
        ECC,
        "--site",
        "paranal",
        "--night",
        "2040-02-15",
        "--visit",
        "1h",
        "--sigma-v",
        "5",
        "--nights",
        "5",
    ],
]


@pytest.mark.parametrize("args", COMMANDS, ids=lambda a: " ".join(Path(x).name for x in a)[:60])
def test_default_output_fits_100_columns(args: list[str], tmp_path: Path) -> None:
    out = run_at_100(args, tmp_path)
    assert out.returncode == 0, out.stderr[-800:]
    cut = [line for line in out.stderr.splitlines() if "…" in line and "│" in line]
    assert not cut, "\n".join(cut[:5])
    wide = too_wide(out.stderr) + too_wide(out.stdout)
    assert not wide, "\n".join(wide[:5])


def test_warnings_wrap_with_a_hanging_indent(tmp_path: Path) -> None:
    """The planner's warnings (IERS, leap seconds, smearing) are longer than 100 columns in a
    run past 2027: each wraps at a word, its continuation lines indented under the first."""
    out = run_at_100(["plan", HM, ECC, "--site", "paranal", "--night", "2040-02-15"], tmp_path)
    assert out.returncode == 0, out.stderr[-800:]
    lines = out.stderr.splitlines()
    starts = [k for k, line in enumerate(lines) if line.startswith("warning: ")]
    assert len(starts) >= 3  # smearing, IERS-A, leap seconds
    assert not too_wide(out.stderr)
    assert any(lines[k + 1].startswith("  ") and lines[k + 1].strip() for k in starts)
    assert any("astropy-iers-data" in line for line in lines)


NAMES = ["hmcnc[draft].yaml", "a [b] \\[c] ~$x.yaml", "[bold]x :x: [red].y"]


@pytest.mark.parametrize("name", NAMES)
def test_file_names_are_printed_literally(name: str, tmp_path: Path) -> None:
    """Rich markup (and emoji codes) in a file name is text: an error names the file exactly as
    it is spelled (the one-line error, wrapped at 100 columns, is joined back)."""
    (tmp_path / name).write_text("bad: [\n", encoding="utf-8")
    out = run_at_100(["validate", name], tmp_path)
    assert out.returncode == 2
    line = " ".join(part.strip() for part in out.stderr.splitlines())
    assert line.startswith(f"error: {name}: not valid YAML")
    assert line.count("\\") == name.count("\\")  # no escape added


def test_written_file_names_are_printed_literally(tmp_path: Path) -> None:
    """The "wrote FILE" line of a command names a bracketed file as it is spelled."""
    out = run_at_100(["feasibility", ECC, "--plot", "aps[x].png"], tmp_path)
    assert out.returncode == 0, out.stderr[-800:]
    assert "wrote aps[x].png" in out.stderr.splitlines()
    assert (tmp_path / "aps[x].png").is_file()
