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

import importlib.util
from pathlib import Path

import pytest
from support.screen import WIDTH, run_at_100, too_wide

ROOT = Path(__file__).resolve().parents[2]
_SPEC = importlib.util.spec_from_file_location(
    "readme_outputs", ROOT / "benchmarks" / "readme_outputs.py"
)
assert _SPEC is not None and _SPEC.loader is not None
_README = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(_README)
#: The README's ``ucbplan`` examples, parsed once (benchmarks/readme_outputs.py runs them all).
readme_commands = _README.readme_commands

#: Command families not run here (minutes each, or a network service).
SLOW = {"simulate", "fisher", "waveform", "population"}
#: Input-file suffixes (a positional argument with one must exist before the example runs).
INPUTS = (".yaml", ".csv", ".ecsv", ".h5", ".json")


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
