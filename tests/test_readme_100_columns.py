"""The README's examples fit a 100-column terminal (issue 24).

Every ``ucbplan …`` line in the README's code blocks (continuation lines joined, comments cut)
runs in a fresh process with ``COLUMNS=100`` in a scratch folder that holds the bundled
``catalogs/``, in README order, so that a later example finds the files an earlier one wrote.
Skipped: usage synopses (placeholders such as ``TARGET.yaml…`` or ``[--force]``), the LISA
simulation and population examples (minutes each; their own tests cover them), the ESO p2
upload and examples whose inputs no earlier example writes. No line of their output (stdout or
stderr) may be wider than 100 terminal cells.
"""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest
from test_screen_100_columns import WIDTH, run_at_100, too_wide

ROOT = Path(__file__).resolve().parents[1]

#: Command families not run here (minutes each, or a network service).
SLOW = {"simulate", "fisher", "waveform", "population"}
#: Input-file suffixes (a positional argument with one must exist before the example runs).
INPUTS = (".yaml", ".csv", ".ecsv", ".h5", ".json")


def readme_commands() -> list[list[str]]:
    """The ``ucbplan`` examples of README.md, as argument lists, in order."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    out: list[list[str]] = []
    for block in re.findall(r"```[a-z]*\n(.*?)```", text, flags=re.S):
        joined = re.sub(r"\\\n\s*", " ", block)
        for line in joined.splitlines():
            line = line.split("&& ", 1)[-1].strip()
            if not line.startswith("ucbplan "):
                continue
            line = re.sub(r"\s#\s.*$", "", line)
            if "…" in line or "[" in line or re.search(r"\b[A-Z]{3,}\b", line):
                continue  # a usage synopsis, not an example
            out.append(shlex.split(line)[1:])
    return out


def _inputs(args: list[str]) -> list[str]:
    values = {"-o", "--plot", "--plots", "--sheet", "--em-prior", "--out-dir"}
    return [
        a
        for k, a in enumerate(args)
        if a.endswith(INPUTS) and (k == 0 or args[k - 1] not in values)
    ]


@pytest.mark.slow
def test_readme_examples_fit_100_columns(tmp_path: Path) -> None:
    (tmp_path / "catalogs").symlink_to(ROOT / "catalogs")
    (tmp_path / "figs").mkdir()
    ran = []
    for args in readme_commands():
        if args[0] in SLOW or "--create" in args:
            continue
        if not all((tmp_path / f).exists() for f in _inputs(args)):
            continue
        out = run_at_100(args, tmp_path)
        assert out.returncode == 0, (args, out.stderr[-600:])
        wide = too_wide(out.stdout) + too_wide(out.stderr)
        assert not wide, f"{' '.join(args)}: lines wider than {WIDTH}:\n" + "\n".join(wide[:5])
        ran.append(args[0])
    # the floor: the examples this issue is about did run
    assert {"plan", "now", "export", "reduce", "horizon", "ephemeris"} <= set(ran), ran
