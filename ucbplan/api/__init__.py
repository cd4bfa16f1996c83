"""The public API: what a notebook needs, importable from ``ucbplan`` itself.

Every function here accepts astropy objects (``Time``, ``Quantity``, ``SkyCoord``,
``EarthLocation``) as readily as the strings the command line takes, runs in the offline
astropy scope (:func:`ucbplan.offline.offline`: the bundled IERS and leap-second tables, the
caller's astropy configuration untouched), raises :class:`ucbplan.UcbplanError` subclasses that
name the parameter at fault, and emits what the user must act on as :class:`ucbplan.
UcbplanWarning` (filterable) besides returning it. The command line is a shell over these.
"""

from ucbplan.api.ephemeris import ephemeris, fit_ephemeris, get_site, horizon, load_target
from ucbplan.api.lisa_analysis import fisher, simulate, waveform
from ucbplan.api.planning import Plan, default_constraints, plan
from ucbplan.api.populations import PopulationForecast, population_forecast
from ucbplan.api.reduction import Report, reduce

__all__ = [
    "Plan",
    "PopulationForecast",
    "Report",
    "default_constraints",
    "ephemeris",
    "fisher",
    "fit_ephemeris",
    "get_site",
    "horizon",
    "load_target",
    "plan",
    "population_forecast",
    "reduce",
    "simulate",
    "waveform",
]
