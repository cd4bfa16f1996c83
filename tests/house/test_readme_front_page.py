"""The README is a front page (issue 35): short, its links live, its outputs real, its numbers
each named with the command that reproduces it.

The reference the README used to hold lives in the docs site (docs/commands.md,
docs/benchmarks.md); ``benchmarks/readme_outputs.py`` runs the README's examples and then those
pages' (``EXAMPLE_PAGES``), so the before/after comparison and the 100-column test follow them.
"""

from __future__ import annotations

import importlib.util
import itertools
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
README = ROOT / "README.md"
#: The front page's length limit (issue 35: "a README that is a front page, ≤ 250 lines").
MAX_LINES = 250
WIDTH = 100
_SPEC = importlib.util.spec_from_file_location(
    "readme_outputs", ROOT / "benchmarks" / "readme_outputs.py"
)
assert _SPEC is not None and _SPEC.loader is not None
_OUTPUTS = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(_OUTPUTS)


def _text() -> str:
    return README.read_text(encoding="utf-8")


def _section(title: str) -> str:
    return _text().split(f"\n## {title}\n", 1)[1].split("\n## ", 1)[0]


def test_readme_is_short_and_fits_100_columns() -> None:
    lines = _text().splitlines()
    assert len(lines) <= MAX_LINES, f"README.md has {len(lines)} lines (at most {MAX_LINES})"
    wide = [f"{k}: {line[:40]}…" for k, line in enumerate(lines, 1) if len(line) > WIDTH]
    assert not wide, "\n".join(wide)


def test_quick_start_holds_the_two_commands_ci_runs() -> None:
    """.ci/run takes each command from between its <!-- quickstart-N --> markers."""
    for n, head in ((1, "pip install . && ucbplan plan "), (2, "pip install '.[test]' && ")):
        block = _text().split(f"<!-- quickstart-{n} -->", 1)[1].split(f"<!-- /quickstart-{n}", 1)[0]
        commands = [ln for ln in block.splitlines() if ln.strip() and not ln.startswith("```")]
        assert len(commands) == 1 and commands[0].startswith(head), commands


def test_readme_links_point_to_files_that_exist() -> None:
    targets = re.findall(r"\]\(([^)#]+)(?:#[^)]*)?\)", _text())
    local = [t for t in targets if not t.startswith(("http://", "https://"))]
    assert len(local) >= 10  # the floor: the front page links into the docs
    missing = [t for t in local if not (ROOT / t).exists()]
    assert not missing, missing


def test_example_pages_exist_and_are_in_the_docs_nav() -> None:
    nav = (ROOT / "mkdocs.yml").read_text(encoding="utf-8")
    for page in _OUTPUTS.EXAMPLE_PAGES:
        assert page.is_file(), page
        assert f": {page.relative_to(ROOT / 'docs').as_posix()}\n" in nav, page
    assert ": benchmarks.md\n" in nav


def test_every_number_names_the_command_that_reproduces_it() -> None:
    items = re.findall(r"^- (.*?)(?=^- |\Z)", _section("The numbers that matter"), re.M | re.S)
    assert len(items) >= 6, items
    for item in items:
        assert re.search(r"\*\*[^*]*\d[^*]*\*\*", item), f"no number in bold: {item!r}"
        commands = re.findall(r"`((?:ucbplan|python -m benchmarks)[^`]*)`", item)
        assert commands, f"no command named: {item!r}"
        for module in re.findall(r"--only (\w+)", " ".join(commands)):
            assert (ROOT / "benchmarks" / f"{module}.py").is_file(), module
        for module in re.findall(r"python -m benchmarks\.(\w+)", " ".join(commands)):
            assert (ROOT / "benchmarks" / f"{module}.py").is_file(), module


def _examples_with_outputs() -> list[tuple[list[list[str]], list[str]]]:
    """(commands of a block, lines of the output block right after it), in README order."""
    blocks = re.findall(r"```([a-z]*)\n(.*?)```", _text(), flags=re.S)
    pairs = []
    for (lang, body), (next_lang, out) in itertools.pairwise(blocks):
        if lang or next_lang or "ucbplan " not in body or "ucbplan " in out or "pip " in body:
            continue  # not a command block followed by its output (the quick start has none)
        commands = _OUTPUTS.block_commands(body)
        pairs.append((commands, [ln for ln in out.splitlines() if "…" not in ln]))
    return pairs


@pytest.mark.slow
def test_readme_outputs_are_real(tmp_path: Path) -> None:
    """Every line the README shows as output (but excerpt marks) is a line its command printed."""
    (tmp_path / "catalogs").symlink_to(ROOT / "catalogs")
    env = {**os.environ, "COLUMNS": "100", "PYTHONPATH": str(ROOT), "SOURCE_DATE_EPOCH": "0"}
    checked = 0
    for commands, shown in _examples_with_outputs():
        printed: set[str] = set()
        for args in commands:
            done = subprocess.run(
                [sys.executable, "-m", "ucbplan", *args],
                cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300,
            )  # fmt: skip
            assert done.returncode == 0, (args, done.stderr[-600:])
            printed |= {ln.rstrip() for ln in (done.stdout + done.stderr).splitlines()}
        invented = [ln for ln in shown if ln.rstrip() not in printed]
        assert not invented, f"{commands}: not printed:\n" + "\n".join(invented)
        checked += 1
    assert checked >= 8, checked  # the floor: one example per main command
