"""The public API: what a notebook needs, importable from ``ucbplan`` itself.

Every function here accepts astropy objects (``Time``, ``Quantity``, ``SkyCoord``,
``EarthLocation``) as readily as the strings the command line takes, runs in the offline
astropy scope (:func:`ucbplan.offline.offline`: the bundled IERS and leap-second tables, the
caller's astropy configuration untouched), raises :class:`ucbplan.UcbplanError` subclasses that
name the parameter at fault, and emits what the user must act on as :class:`ucbplan.
UcbplanWarning` (filterable) besides returning it. The command line is a shell over these.
"""

from ucbplan.api.ephemeris import compare_ephemerides, ephemeris
from ucbplan.api.exporting import Export, countdown, export, read_blocks
from ucbplan.api.lisa_analysis import fisher, simulate, waveform
from ucbplan.api.plan_result import GoalRecord, StrategyRecord
from ucbplan.api.planning import Plan, default_constraints, plan
from ucbplan.api.populations import PopulationForecast, population_forecast
from ucbplan.api.reduction import Report, reduce
from ucbplan.api.replanning import replan
from ucbplan.api.signal_sizes import feasibility
from ucbplan.api.targets import get_site, load_target, validate, write_target
from ucbplan.api.timing import TimingFit, fit_ephemeris
from ucbplan.api.validity import horizon

__all__ = [
    "Export",
    "GoalRecord",
    "Plan",
    "PopulationForecast",
    "Report",
    "StrategyRecord",
    "TimingFit",
    "compare_ephemerides",
    "countdown",
    "default_constraints",
    "ephemeris",
    "export",
    "feasibility",
    "fisher",
    "fit_ephemeris",
    "get_site",
    "horizon",
    "load_target",
    "plan",
    "population_forecast",
    "read_blocks",
    "reduce",
    "replan",
    "simulate",
    "validate",
    "waveform",
    "write_target",
]
