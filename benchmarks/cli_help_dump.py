"""Dump the ``--help`` text of every ucbplan command and sub-command, to diff two versions.

Usage: ``python benchmarks/cli_help_dump.py OUT_DIR [--tree DIR]`` on each version, then
``diff -r BEFORE AFTER``. Each command's help, rendered at 100 columns without colour, goes to
``OUT_DIR/<command path>.txt`` (``plan.txt``, ``ephemeris-fit.txt``, ``__root__.txt``).
``--tree`` runs another checkout's package (e.g. a ``git worktree`` of an older commit).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

_LIST = """
import json, typer.main
from ucbplan.cli.app import app
cmd = typer.main.get_command(app)
def walk(c, path):
    yield path
    if hasattr(c, "commands"):
        for name in sorted(c.commands):
            yield from walk(c.commands[name], [*path, name])
print(json.dumps(list(walk(cmd, []))))
"""


def dump(out: Path, tree: Path) -> int:
    """Write every command's help under ``out``; the number of commands."""
    env = {**os.environ, "COLUMNS": "100", "PYTHONPATH": str(tree), "NO_COLOR": "1", "TERM": "dumb"}
    listed = subprocess.run(
        [sys.executable, "-c", _LIST], env=env, capture_output=True, text=True, check=True
    )
    out.mkdir(parents=True)
    paths = json.loads(listed.stdout)
    for path in paths:
        done = subprocess.run(
            [sys.executable, "-m", "ucbplan", *path, "--help"],
            env=env,
            capture_output=True,
            text=True,
            timeout=120,
        )
        name = "-".join(path) or "__root__"
        (out / f"{name}.txt").write_text(
            done.stdout + done.stderr + f"\n[rc={done.returncode}]\n", encoding="utf-8"
        )
    return len(paths)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", type=Path, help="a new folder")
    ap.add_argument("--tree", type=Path, default=ROOT, help="the checkout whose package runs")
    args = ap.parse_args()
    print(f"{dump(args.out, args.tree.resolve())} commands dumped to {args.out}")


if __name__ == "__main__":
    main()
