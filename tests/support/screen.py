"""Run the CLI at a 100-column terminal and find lines that are too wide."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from rich.cells import cell_len

#: The terminal width of these tests [columns].
WIDTH = 100


def run_at_100(args: list[str], cwd: Path) -> subprocess.CompletedProcess[str]:
    """``python -m ucbplan ARGS`` in a fresh process whose terminal is ``WIDTH`` columns."""
    env = {**os.environ, "COLUMNS": str(WIDTH), "LINES": "50"}
    cmd = [sys.executable, "-m", "ucbplan", *args]
    return subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=cwd, timeout=120)


def too_wide(text: str) -> list[str]:
    """Lines of ``text`` wider than ``WIDTH`` terminal cells."""
    return [line for line in text.splitlines() if cell_len(line) > WIDTH]
