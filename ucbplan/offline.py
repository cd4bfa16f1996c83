"""Offline astropy: the bundled IERS and leap-second tables, never the network.

Call :func:`configure_offline` before any time or coordinate work, in the CLI and in every worker
process. It changes astropy's configuration, once per process, and makes the IERS Earth-rotation
table load lazily from a parsed cache: astropy opens the table only when a conversion first needs
UT1 or polar motion (so ``--help`` or a horizon never pays for it), and that first open then reads
a pickle of the parsed table (~5 ms) instead of parsing the IERS-A and -B text files (~0.5 s).
The cache lives in ``$UCBPLAN_CACHE_DIR`` (default ``$XDG_CACHE_HOME/ucbplan`` or
``~/.cache/ucbplan``; an empty value disables it) and is keyed by the astropy and
astropy-iers-data versions and the bundled files' size and modification time, so an update of
either package is picked up. A missing, stale or unreadable cache falls back to astropy's parser.
"""

from __future__ import annotations

import hashlib
import os
import pickle
import tempfile
from pathlib import Path
from typing import Any

__all__ = ["configure_offline", "iers_cache_path"]

_OFFLINE_DONE = False


def configure_offline() -> None:
    """Configure astropy so that nothing ever touches the network (docs/method.md, time scales).

    Called once at CLI start, never on import. Uses the IERS-A/B tables and leap seconds bundled
    with ``astropy-iers-data``; nights past their coverage are warned about by the planner. The
    IERS table is loaded on first use, from the parsed cache when there is one (module docstring).
    """
    global _OFFLINE_DONE
    if _OFFLINE_DONE:
        return
    from astropy.utils import data, iers

    iers.conf.auto_download = False
    iers.conf.auto_max_age = None
    data.conf.allow_internet = False
    iers.IERS_Auto.open = classmethod(_open_cached)
    _OFFLINE_DONE = True


def iers_cache_path() -> Path | None:
    """Where the parsed IERS table is cached for the installed astropy data (None: disabled)."""
    import astropy
    from astropy.utils import iers

    root = os.environ.get("UCBPLAN_CACHE_DIR")
    if root is None:
        base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
        root = str(Path(base) / "ucbplan")
    if not root:
        return None
    key = [astropy.__version__]
    for name in (iers.IERS_A_FILE, iers.IERS_B_FILE):
        st = os.stat(name)
        key += [str(name), str(st.st_size), str(st.st_mtime_ns)]
    digest = hashlib.sha256("\0".join(key).encode()).hexdigest()[:16]
    return Path(root) / f"iers-auto-{digest}.pickle"


def _open_cached(cls: Any) -> Any:
    """``IERS_Auto.open`` that reads the parsed table from the cache (and fills the cache)."""
    if cls.iers_table is not None:
        return cls.iers_table
    try:
        path = iers_cache_path()
    except OSError:
        path = None
    table = _read_cache(path, cls) if path is not None else None
    if table is None:
        table = cls.read()
        if path is not None:
            _write_cache(path, table)
    cls.iers_table = table
    return table


def _read_cache(path: Path, cls: type) -> Any:
    try:
        with path.open("rb") as fh:
            table = pickle.load(fh)  # our own cache file (written by _write_cache)
    except (OSError, pickle.UnpicklingError, EOFError, AttributeError, ImportError):
        return None
    return table if isinstance(table, cls) else None


def _write_cache(path: Path, table: Any) -> None:
    """Atomic write (temporary file + rename); a read-only cache directory is not an error."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".tmp")
    except OSError:
        return
    try:
        with os.fdopen(fd, "wb") as fh:
            pickle.dump(table, fh, protocol=pickle.HIGHEST_PROTOCOL)
        os.replace(tmp, path)
    except (OSError, pickle.PicklingError):
        Path(tmp).unlink(missing_ok=True)
