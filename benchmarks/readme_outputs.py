"""Run every README and docs example in order, keeping what it printed and wrote, to diff versions.

Usage: ``python benchmarks/readme_outputs.py OUT_DIR [--quick] [--tree DIR]`` on each version
(``--tree``: another checkout's package and catalogs, e.g. a ``git worktree`` of an older
commit, run with this README's examples), then
``diff -r -I created_utc -I DTSTAMP -I '^# ucbplan ' BEFORE AFTER`` (the creation stamps differ
between any two runs). The examples are the ``ucbplan …`` lines (continuation lines joined,
comments cut, usage synopses skipped) of the README and then of the docs pages that hold the
examples moved out of it (``EXAMPLE_PAGES``), run in that order in OUT_DIR, which holds a
link to the bundled ``catalogs/``, so that a later example finds the files an earlier one wrote.
Each example's standard output, standard error and exit code go to ``NN-command.out|err|rc``;
the files it writes stay where it wrote them. ``--quick`` skips the LISA simulation and the
population examples (minutes each).
"""

from __future__ import annotations

import argparse
import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: Command families that take minutes (skipped by --quick).
SLOW = {"simulate", "fisher", "waveform", "population"}
#: Pages whose examples run after the README's, in this order (the README is the front page; the
#: worked examples of every command live in the docs site).
EXAMPLE_PAGES = (ROOT / "docs" / "commands.md",)


def readme_commands(readme: Path | None = None) -> list[list[str]]:
    """The ``ucbplan`` examples, as argument lists (``ucbplan`` cut), in order.

    ``readme`` given: that file's examples; else the README's, then those of ``EXAMPLE_PAGES``.
    """
    if readme is None:
        return [c for page in (ROOT / "README.md", *EXAMPLE_PAGES) for c in readme_commands(page)]
    text = readme.read_text(encoding="utf-8")
    blocks = re.findall(r"```[a-z]*\n(.*?)```", text, flags=re.S)
    return [args for block in blocks for args in block_commands(block)]


def block_commands(block: str) -> list[list[str]]:
    """The ``ucbplan`` examples of one code block's text, as argument lists (``ucbplan`` cut)."""
    out: list[list[str]] = []
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


def run_all(out: Path, quick: bool, tree: Path = ROOT) -> int:
    """Run the examples in ``out`` with the package of ``tree``; the number run."""
    out.mkdir(parents=True)
    (out / "catalogs").symlink_to(tree / "catalogs")
    for sub in ("figs", "simfigs"):
        (out / sub).mkdir()
    # SOURCE_DATE_EPOCH: matplotlib stamps PDFs with it instead of the clock, so two runs compare
    env = {**os.environ, "COLUMNS": "100", "PYTHONPATH": str(tree), "SOURCE_DATE_EPOCH": "0"}
    n = 0
    for k, args in enumerate(readme_commands(), start=1):
        if (quick and args[0] in SLOW) or "--create" in args or "--live" in args:
            continue
        cmd = [sys.executable, "-m", "ucbplan", *args]
        done = subprocess.run(cmd, cwd=out, env=env, capture_output=True, text=True, timeout=900)
        stem = out / f"{k:02d}-{args[0]}"
        stem.with_suffix(".out").write_text(done.stdout, encoding="utf-8")
        stem.with_suffix(".err").write_text(done.stderr, encoding="utf-8")
        stem.with_suffix(".rc").write_text(f"{done.returncode}\n", encoding="utf-8")
        n += 1
    return n


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", type=Path, help="a new folder")
    ap.add_argument("--quick", action="store_true", help="skip the minutes-long examples")
    ap.add_argument("--tree", type=Path, default=ROOT, help="the checkout whose package runs")
    a = ap.parse_args()
    if a.out.exists():
        sys.exit(f"{a.out} exists; give a new folder")
    print(f"{run_all(a.out, a.quick, a.tree.resolve())} README examples run into {a.out}")


if __name__ == "__main__":
    main()
