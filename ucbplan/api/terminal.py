"""What the command line's shells need besides the public functions: writing outputs, the
offline scope, and the pieces of the plan view and of the countdown they print.

The command line imports only :mod:`ucbplan.api` (a test enforces it); this module is its door to
the few library helpers a shell prints or writes with, each named once here. The light ones are
imported at start-up; the others (astropy behind them) only when a command first uses them, so
``ucbplan --help`` stays fast.

Names
-----
check_output_path, output_format, write_output, dump_json
    Output files: refused when they exist (unless overwriting), the ``-o``/``--format`` rule,
    atomic writes (:mod:`ucbplan.io`).
check_figure_path
    A figure's suffix and path (:mod:`ucbplan.plotting`).
offline
    The offline astropy scope every command runs in (:mod:`ucbplan.offline`).
write_table
    A blocks table as ECSV, CSV or JSON to an open file.
block_columns, local_datetimes
    The columns of a plan's blocks, and local civil times (the ``plan`` view).
plan_exposures, what_next, countdown_lines, parse_utc
    The ``now`` countdown.
ObservingLog, LOG_KEYS, log_lines
    The observing log ``now --log`` writes, its keys and its line in the frame.
chart_format, sheet_format, night_charts, night_sheet
    The suffix checks of the night charts and the night sheet, and writing them for a plan.
sigma_v_note
    The measured σ_v of ``--observed`` spectra against the law (the ``plan`` view).
"""

from __future__ import annotations

import importlib
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ucbplan.io import check_output_path as check_output_path
from ucbplan.io import dump_json as dump_json
from ucbplan.io import output_format as output_format
from ucbplan.io import write_output as write_output

if TYPE_CHECKING:  # imported when first used (see _LAZY)
    from ucbplan.api._observed import sigma_v_note as sigma_v_note
    from ucbplan.observing.blocks.arrays import block_columns as block_columns
    from ucbplan.observing.blocks.cells import local_datetimes as local_datetimes
    from ucbplan.observing.blocks.write import csv_safe_table as csv_safe_table
    from ucbplan.observing.blocks.write import write_table as write_table
    from ucbplan.observing.night.chart import chart_format as chart_format
    from ucbplan.observing.night.countdown import (
        countdown_lines as countdown_lines,
    )
    from ucbplan.observing.night.countdown import (
        parse_utc as parse_utc,
    )
    from ucbplan.observing.night.countdown import (
        plan_exposures as plan_exposures,
    )
    from ucbplan.observing.night.countdown import (
        what_next as what_next,
    )
    from ucbplan.observing.night.observing_log import LOG_KEYS as LOG_KEYS
    from ucbplan.observing.night.observing_log import ObservingLog as ObservingLog
    from ucbplan.observing.night.observing_log import log_lines as log_lines
    from ucbplan.observing.night.sheet import sheet_format as sheet_format
    from ucbplan.offline import offline as offline
    from ucbplan.plotting import check_figure_path as check_figure_path

#: Names imported when first used: name → the library module that defines it.
_LAZY = {
    "offline": "ucbplan.offline",
    "check_figure_path": "ucbplan.plotting",
    "block_columns": "ucbplan.observing.blocks.arrays",
    "local_datetimes": "ucbplan.observing.blocks.cells",
    "plan_exposures": "ucbplan.observing.night.countdown",
    "what_next": "ucbplan.observing.night.countdown",
    "countdown_lines": "ucbplan.observing.night.countdown",
    "parse_utc": "ucbplan.observing.night.countdown",
    "chart_format": "ucbplan.observing.night.chart",
    "sheet_format": "ucbplan.observing.night.sheet",
    "write_table": "ucbplan.observing.blocks.write",
    "csv_safe_table": "ucbplan.observing.blocks.write",
    "sigma_v_note": "ucbplan.api._observed",
    "ObservingLog": "ucbplan.observing.night.observing_log",
    "LOG_KEYS": "ucbplan.observing.night.observing_log",
    "log_lines": "ucbplan.observing.night.observing_log",
}


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(module), name)


def night_charts(plan: Any, path: str | Path, overwrite: bool = False) -> int:
    """The night charts of ``plan`` (a :class:`ucbplan.Plan`): :meth:`ucbplan.Plan.charts`."""
    return int(plan.charts(path, overwrite=overwrite))


def night_sheet(plan: Any, path: str | Path, overwrite: bool = False) -> int:
    """The night sheet of ``plan`` (a :class:`ucbplan.Plan`): :meth:`ucbplan.Plan.sheet`."""
    return int(plan.sheet(path, overwrite=overwrite))
