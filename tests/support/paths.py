"""Where the repository's files are, for tests in any folder under tests/."""

from __future__ import annotations

from pathlib import Path

#: The repository's root (this file is tests/support/paths.py).
REPO = Path(__file__).resolve().parents[2]
#: The bundled catalogs (target files, velocity tables) the tests read.
CATALOGS = REPO / "catalogs"
#: Golden output files, compared byte for byte.
GOLDEN = REPO / "tests" / "golden"
