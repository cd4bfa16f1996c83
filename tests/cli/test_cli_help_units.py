"""Every ``--help`` shows its units (issue 15): help text is printed verbatim, not as markup.

Rich markup read ``[deg]`` as a tag and dropped it ("Smallest Moon separation ."). The check walks
every command and option of the CLI and asserts that each bracketed unit in an option's help text
appears in that command's rendered ``--help``.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import typer
from typer.testing import CliRunner

from ucbplan.cli.app import app

_BRACKET = re.compile(r"\[[^\[\]]{1,20}\]")


def _commands(cmd: Any, path: tuple[str, ...]) -> list[tuple[tuple[str, ...], Any]]:
    """Every command under ``cmd`` with its argument path (typer may vendor its own click, so
    groups are recognised by their ``commands`` mapping, not by class)."""
    out = [(path, cmd)]
    for name, sub in getattr(cmd, "commands", {}).items():
        out += _commands(sub, (*path, name))
    return out


def test_every_bracketed_unit_is_shown_in_help() -> None:
    root = typer.main.get_command(app)
    checked = 0
    for path, cmd in _commands(root, ()):
        result = CliRunner().invoke(app, [*path, "--help"], env={"COLUMNS": "200"})
        assert result.exit_code == 0, (path, result.output)
        text = " ".join(result.output.split())
        for param in cmd.params:
            for unit in _BRACKET.findall(getattr(param, "help", None) or ""):
                assert unit in text, (path, param.name, unit)
                checked += 1
    assert checked >= 10  # the CLI has many options with bracketed units; the walk must reach them


def test_completion_is_offered() -> None:
    result = CliRunner().invoke(app, ["--help"], env={"COLUMNS": "100"})
    assert "--show-completion" in result.output


def test_help_does_not_import_the_science_stack() -> None:
    """Start-up (issue 14): ``ucbplan --help`` must not import astropy or numpy (the commands
    import them when they run). Checked structurally in a fresh interpreter, not timed."""
    import subprocess
    import sys

    code = (
        "import sys\n"
        "from ucbplan.cli.app import main\n"
        "sys.argv = ['ucbplan', '--help']\n"
        "try:\n    main()\nexcept SystemExit:\n    pass\n"
        "stack = ('astropy', 'numpy', 'scipy', 'matplotlib')\n"
        "heavy = sorted(m for m in stack if m in sys.modules)\n"
        "print('HEAVY', heavy)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert "HEAVY []" in out.stdout, out.stdout[-300:]


def test_quiet_prints_only_warnings_and_errors(tmp_path: Path) -> None:
    """``ucbplan --quiet`` (issue 15): no tables or notes; warnings and errors still shown; the
    output file is written as without it."""
    import subprocess
    import sys

    hm = Path(__file__).resolve().parents[2] / "catalogs" / "hm-cnc-simulated.yaml"
    base = [sys.executable, "-m", "ucbplan", "--quiet", "plan", str(hm), "--night", "2040-02-15"]
    ok = subprocess.run(
        [*base, "--site", "paranal", "-o", str(tmp_path / "q.ecsv")], capture_output=True, text=True
    )
    assert ok.returncode == 0 and (tmp_path / "q.ecsv").exists()
    lines = ok.stderr.strip().splitlines()
    assert lines and all(line.startswith("warning:") for line in lines), lines  # 2040: data age
    bad = subprocess.run([*base, "--site", "nowhere"], capture_output=True, text=True)
    assert bad.returncode == 2 and bad.stderr.strip().startswith("error: --site")
