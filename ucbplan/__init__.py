"""ucbplan: phase-targeted spectroscopy of ultracompact binaries from LISA ephemerides.

The method is that of the paper bundled with the project (see README, "How to cite"). The
public API (docs/api.md) is importable from here::

    import ucbplan
    run = ucbplan.plan("hm-cnc.yaml", site="paranal", night="2040-02-15")

Names are loaded on first use (PEP 562), so ``import ucbplan`` and ``ucbplan --help`` stay
cheap: nothing below is imported until a name is asked for. The names and the modules that
define them are listed once, in :data:`_PUBLIC`.

``ucbplan.reduce`` is the function, also once the subpackage of the same name has been
imported (Python binds a subpackage to its parent's attribute on import; the package's module
class keeps the public name instead, so the answer does not depend on import order). Reach the
subpackage's modules with ``from ucbplan.reduce import pipeline``.
"""

from __future__ import annotations

import importlib
import sys
import types

from ucbplan._version import __version__

# typing is not imported at run time (``import ucbplan`` stays a few modules); annotations are
# strings (PEP 563) and the TYPE_CHECKING block below is read by type checkers only
TYPE_CHECKING = False

#: Public name → the module that defines it.
_PUBLIC = {
    "load_target": "ucbplan.api",
    "get_site": "ucbplan.api",
    "ephemeris": "ucbplan.api",
    "horizon": "ucbplan.api",
    "plan": "ucbplan.api",
    "replan": "ucbplan.api",
    "Plan": "ucbplan.api",
    "StrategyRecord": "ucbplan.api",  # a2: Plan.strategies
    "GoalRecord": "ucbplan.api",  # a2: Plan.goals
    "default_constraints": "ucbplan.api",
    "reduce": "ucbplan.api",
    "Report": "ucbplan.api",
    "fit_ephemeris": "ucbplan.api",
    "simulate": "ucbplan.api",
    "population_forecast": "ucbplan.api",
    # b1
    "write_target": "ucbplan.api",
    "validate": "ucbplan.api",
    "compare_ephemerides": "ucbplan.api",
    "feasibility": "ucbplan.api",
    "TimingFit": "ucbplan.api",
    "Constraint": "ucbplan.observing.constraints",
    "AirmassConstraint": "ucbplan.observing.constraints",
    "AltitudeConstraint": "ucbplan.observing.constraints",
    "AtNightConstraint": "ucbplan.observing.constraints",
    "MoonIlluminationConstraint": "ucbplan.observing.constraints",
    "MoonSeparationConstraint": "ucbplan.observing.constraints",
    "ZenithHoleConstraint": "ucbplan.observing.constraints",
    "UcbplanError": "ucbplan.errors",
    "InputError": "ucbplan.errors",
    "UcbplanWarning": "ucbplan.errors",
    "PlanWarning": "ucbplan.errors",
    "ReduceWarning": "ucbplan.errors",
    "EarthOrientationWarning": "ucbplan.errors",
    # a1 (issue 30): a saved plan read back and exported
    "read_blocks": "ucbplan.api",
    "export": "ucbplan.api",
    "Export": "ucbplan.api",
    # b2 (issue 30): the measuring half
    "fisher": "ucbplan.api",
    "waveform": "ucbplan.api",
    "PopulationForecast": "ucbplan.api",
    # helper c (issue 30): warnings by cause
    "SmearingWarning": "ucbplan.errors",
    "ExposureWarning": "ucbplan.errors",
    "EphemerisRangeWarning": "ucbplan.errors",
    "SamplerConvergenceWarning": "ucbplan.errors",
}

__all__ = ["__version__", *_PUBLIC]


def __getattr__(name: str) -> Any:
    """Load a public name from its module on first use (module docstring)."""
    module = _PUBLIC.get(name)
    if module is None:
        raise AttributeError(f"module 'ucbplan' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # later look-ups skip this function
    return value


def __dir__() -> list[str]:
    return sorted(__all__)


class _Package(types.ModuleType):
    """The ``ucbplan`` module: a public name is never replaced by a subpackage of that name."""

    def __setattr__(self, name: str, value: Any) -> None:
        if name in _PUBLIC and isinstance(value, types.ModuleType):
            return  # the import system binding ucbplan.reduce (the subpackage): keep reduce()
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package


if TYPE_CHECKING:  # the same names for type checkers and IDEs ("as": re-exported)
    from typing import Any

    from ucbplan.api import (
        Export as Export,
    )
    from ucbplan.api import (
        GoalRecord as GoalRecord,
    )
    from ucbplan.api import (
        Plan as Plan,
    )
    from ucbplan.api import (
        PopulationForecast as PopulationForecast,
    )
    from ucbplan.api import (
        Report as Report,
    )
    from ucbplan.api import (
        StrategyRecord as StrategyRecord,
    )
    from ucbplan.api import (  # b1
        TimingFit as TimingFit,
    )
    from ucbplan.api import (
        compare_ephemerides as compare_ephemerides,
    )
    from ucbplan.api import (
        default_constraints as default_constraints,
    )
    from ucbplan.api import (
        ephemeris as ephemeris,
    )
    from ucbplan.api import (
        export as export,
    )
    from ucbplan.api import (
        feasibility as feasibility,
    )
    from ucbplan.api import (
        fisher as fisher,
    )
    from ucbplan.api import (
        fit_ephemeris as fit_ephemeris,
    )
    from ucbplan.api import (
        get_site as get_site,
    )
    from ucbplan.api import (
        horizon as horizon,
    )
    from ucbplan.api import (
        load_target as load_target,
    )
    from ucbplan.api import (
        plan as plan,
    )
    from ucbplan.api import (
        population_forecast as population_forecast,
    )
    from ucbplan.api import (
        read_blocks as read_blocks,
    )
    from ucbplan.api import (
        reduce as reduce,
    )
    from ucbplan.api import (
        simulate as simulate,
    )
    from ucbplan.api import (
        validate as validate,
    )
    from ucbplan.api import (
        waveform as waveform,
    )
    from ucbplan.api import (
        write_target as write_target,
    )
    from ucbplan.errors import (
        EarthOrientationWarning as EarthOrientationWarning,
    )
    from ucbplan.errors import (  # helper c (issue 30): warnings by cause
        EphemerisRangeWarning as EphemerisRangeWarning,
    )
    from ucbplan.errors import (
        ExposureWarning as ExposureWarning,
    )
    from ucbplan.errors import (
        InputError as InputError,
    )
    from ucbplan.errors import (
        PlanWarning as PlanWarning,
    )
    from ucbplan.errors import (
        ReduceWarning as ReduceWarning,
    )
    from ucbplan.errors import (
        SamplerConvergenceWarning as SamplerConvergenceWarning,
    )
    from ucbplan.errors import (
        SmearingWarning as SmearingWarning,
    )
    from ucbplan.errors import (
        UcbplanError as UcbplanError,
    )
    from ucbplan.errors import (
        UcbplanWarning as UcbplanWarning,
    )
    from ucbplan.observing.constraints import AirmassConstraint as AirmassConstraint
    from ucbplan.observing.constraints import AltitudeConstraint as AltitudeConstraint
    from ucbplan.observing.constraints import AtNightConstraint as AtNightConstraint
    from ucbplan.observing.constraints import Constraint as Constraint
    from ucbplan.observing.constraints import (
        MoonIlluminationConstraint as MoonIlluminationConstraint,
    )
    from ucbplan.observing.constraints import MoonSeparationConstraint as MoonSeparationConstraint
    from ucbplan.observing.constraints import ZenithHoleConstraint as ZenithHoleConstraint
