"""Offline astropy: the bundled IERS and leap-second tables, never the network.

Call :func:`configure_offline` before any time or coordinate work, in the CLI and in every worker
process. It changes astropy's configuration only, and only once per process.
"""

from __future__ import annotations

__all__ = ["configure_offline"]

_OFFLINE_DONE = False


def configure_offline() -> None:
    """Configure astropy so that nothing ever touches the network (docs/method.md, time scales).

    Called once at CLI start, never on import. Uses the IERS-A/B tables and leap seconds bundled
    with ``astropy-iers-data``; nights past their coverage are warned about by the planner.
    """
    global _OFFLINE_DONE
    if _OFFLINE_DONE:
        return
    from astropy.utils import data, iers

    iers.conf.auto_download = False
    iers.conf.auto_max_age = None
    data.conf.allow_internet = False
    _OFFLINE_DONE = True
