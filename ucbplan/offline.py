"""Offline astropy, in a scope: the bundled IERS and leap-second tables, never the network.

Every public entry point (the functions of :mod:`ucbplan.api`, the command line, each
population task) runs inside :func:`offline`. On entry it sets astropy's IERS and data
configuration with ``conf.set_temp`` (no downloads, no age limit on the bundled predictions, no
internet) and, unless the caller has chosen an Earth-orientation table of their own
(``astropy.utils.iers.earth_orientation_table.set``), installs the bundled IERS-A/B table as an
explicit table for the scope. On exit everything is as it was: astropy's configuration, its
``IERS_Auto`` class and its default table are never replaced or filled by ucbplan.

The bundled table is read once per process, from a pickle of the parsed table (~10 ms) instead
of parsing the IERS-A and -B text files (~0.5 s). The cache lives in ``$UCBPLAN_CACHE_DIR``
(default ``$XDG_CACHE_HOME/ucbplan`` or ``~/.cache/ucbplan``; an empty value disables it) and is
keyed by the astropy version and the bundled files' size and modification time, so an update of
either package is picked up. A missing, stale or unreadable cache falls back to astropy's parser.
Times past the bundled tables are warned about by the planner (docs/method.md, time scales).

The scope also silences ERFA's "dubious year" warnings and astropy's IERS-range warnings, which
every conversion of a future date raises: ucbplan reports the tables' coverage itself, once per
run, in words a user can act on (:class:`ucbplan.EarthOrientationWarning`). The edges enter the
scope (the public API, the command line, each population task), so no inner function needs to.
"""

from __future__ import annotations

import hashlib
import os
import pickle
import tempfile
import warnings
from collections.abc import Iterator
from contextlib import ExitStack, contextmanager
from pathlib import Path
from typing import Any

#: The bundled IERS table once read in this process (an explicit cache: see :func:`offline`).
_TABLE: dict[str, Any] = {}


@contextmanager
def offline() -> Iterator[None]:
    """A scope in which astropy never touches the network, restored on exit.

    Nested scopes are cheap (the inner one finds the table in place). Use it around any time or
    coordinate work done outside ucbplan's own entry points, e.g. in a worker process::

        with offline():
            t.ut1

    Notes
    -----
    Sets, for the scope only: ``iers.conf.auto_download = False``, ``iers.conf.auto_max_age =
    None`` (the bundled IERS-A predictions are used however old, and nights past them are warned
    about, never refused) and ``data.conf.allow_internet = False``; and the bundled IERS table
    as ``iers.earth_orientation_table`` unless one was set by the caller; and a warnings filter
    for ERFA's "dubious year" and astropy's IERS-range warnings (``warnings.catch_warnings``,
    which is per process, not per thread: enter the scope once per task, not in threads that
    share one).
    """
    from astropy.utils import data, iers

    with ExitStack() as stack:
        stack.enter_context(iers.conf.set_temp("auto_download", False))
        stack.enter_context(iers.conf.set_temp("auto_max_age", None))
        stack.enter_context(data.conf.set_temp("allow_internet", False))
        # ScienceState keeps the caller's choice in ``_value`` (None: astropy's default table)
        if iers.earth_orientation_table._value is None:
            stack.enter_context(iers.earth_orientation_table.set(bundled_iers_table()))
        stack.enter_context(_quiet_future_dates())
        yield


@contextmanager
def _quiet_future_dates() -> Iterator[None]:
    """ERFA's "dubious year" and astropy's IERS-range warnings silenced (see the module notes)."""
    from astropy.utils.exceptions import AstropyWarning
    from erfa import ErfaWarning

    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", category=ErfaWarning)
        for text in (".*polar motion.*", ".*IERS.*", ".*leap.second.*"):
            warnings.filterwarnings("ignore", message=text, category=AstropyWarning)
        yield


def bundled_iers_table() -> Any:
    """The IERS-A/B table bundled with astropy, read once per process (from the cache if any).

    Must be called with downloads off (inside :func:`offline`): the table is an
    ``IERS_Auto`` instance, as astropy's own default would be offline.
    """
    table = _TABLE.get("iers")
    if table is None:
        from astropy.utils import iers

        try:
            path = iers_cache_path()
        except OSError:
            path = None
        table = _read_cache(path, iers.IERS_Auto) if path is not None else None
        if table is None:
            table = iers.IERS_Auto.read()
            if path is not None:
                _write_cache(path, table)
        _TABLE["iers"] = table
    return table


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
