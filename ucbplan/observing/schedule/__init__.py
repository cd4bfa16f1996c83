"""Night schedules: anchor epochs → candidate blocks → sessions placed by priority → blocks.

Modules, in data-flow order: :mod:`.settings` (planning modes, :class:`PlanSettings`),
:mod:`.nights` (night windows), :mod:`.candidates` (epochs → candidate blocks and sessions on one
time axis), :mod:`.placement` (priority placement into nights, reasons for what is not placed),
:mod:`.records` (placed sessions → :class:`~ucbplan.observing.blocks.block.Block` rows),
:mod:`.pairs` (fixed-u pairs), :mod:`.planner` (:func:`plan_nights`, the pipeline) and
:mod:`.run` (:func:`plan_files`, the ``plan`` command as one call).
"""

from ucbplan.observing.schedule.candidates import Candidates, candidate_blocks
from ucbplan.observing.schedule.nights import NightWindow, night_dates, night_windows
from ucbplan.observing.schedule.options import check_max_visit, plan_settings
from ucbplan.observing.schedule.pairs import delta_kappa
from ucbplan.observing.schedule.placement import Unplaced
from ucbplan.observing.schedule.planner import PlanSchedule, plan_nights
from ucbplan.observing.schedule.run import PlanRun, plan_files, with_priorities
from ucbplan.observing.schedule.settings import MODES, ModeSpec, PlanSettings, parse_mode

__all__ = [
    "MODES",
    "Candidates",
    "ModeSpec",
    "NightWindow",
    "PlanRun",
    "PlanSchedule",
    "PlanSettings",
    "Unplaced",
    "candidate_blocks",
    "check_max_visit",
    "delta_kappa",
    "night_dates",
    "night_windows",
    "parse_mode",
    "plan_files",
    "plan_nights",
    "plan_settings",
    "with_priorities",
]
