"""Library parameter names → command-line flags: the one place the CLI translates them.

Library errors name the parameter a caller passed (``airmass_max: expected …``); the command
line prints the flag its user typed instead (``--airmass-max: expected …``). :func:`cli_message`
rewrites the name an error starts with; messages that already name a flag pass unchanged.
"""

from __future__ import annotations

import re

from ucbplan.api.flagspec import flag_names
from ucbplan.api.plan_options import PLAN_FLAGS

__all__ = ["FLAGS", "cli_message"]

#: Parameter of the library (PlanSettings fields, ucbplan.plan / ucbplan.horizon keywords)
#: → the flag of the command line that sets it.
FLAGS = {
    "airmass_max": "--airmass-max",
    "moon_sep_deg": "--moon-sep",
    "moon_illum_max": "--moon-illum",
    "zenith_hole_deg": "--zenith-hole",
    "twilight": "--twilight",
    "alpha": "--alpha",
    "sigma_v_kms": "--sigma-v",
    "sigma_v": "--sigma-v",
    "sigma_floor_kms": "--sigma-floor",
    "extinction_k": "--extinction",
    "max_visit_s": "--max-visit",
    "max_visit": "--max-visit",
    "k_eff_kms": "--k-eff",
    "k_eff": "--k-eff",
    "mass_radius": "--mass-radius",
    "cos_i_sigma": "--cos-i-sigma",
    "overhead_s": "--overhead",
    "exptime_s": "--exptime",
    "n_exp": "--n-exp",
    "readout_s": "--readout",
    "sessions_per_night": "--sessions",
    "cadence": "--cadence",
    "min_lambda_k": "--min-lambda-k",
    "max_bin_fraction": "--max-bin-fraction",
    "max_smear": "--max-smear",
    "n_epochs": "--epochs",
    "anchor": "--anchor",
    "start": "--start",
    "max_epochs": "--max-epochs",
    "end": "--end",
    "star": "--star",
    "seed": "--seed",
    # b1: validate, horizon, ephemeris predict/compare/fit, feasibility
    "at": "--at",
    "terms": "--terms",
    "clip": "--clip",
    "period": "--period",
    "initial": "--initial",
    "plot": "--plot",
    "anchors": "--anchor",
    "m1": "--m1",
    "m2": "--m2",
    "m3": "--m3",
    "a_out": "--a-out",
    "n_spectra": "--n-spectra",
    "baseline": "--baseline",
    "optical_epoch": "--optical-epoch",
    "readout": "--readout",
    "overhead": "--overhead",
    "sigma_floor": "--sigma-floor",
    "extinction": "--extinction",
    # b2 (issue 30): reduce, simulate, fisher, waveform, population
    "samples": "--samples",
    "n_bins": "--n-bins",
    "t_obs": "--t-obs",
    "t_start": "--t-start",
    "walkers": "--walkers",
    "steps": "--steps",
    "max_steps": "--max-steps",
    "workers": "--workers",
    "jobs": "--jobs",
    "chunk": "--chunk",
}

# a1 (issue 30): ``ucbplan.plan``'s keywords, from the flag table declared beside it
FLAGS.update({k: v for k, v in flag_names(PLAN_FLAGS).items() if k not in FLAGS})

_LEADING_NAME = re.compile(r"^([a-z_][a-z0-9_]*)(?=[: ])")


def cli_message(message: str) -> str:
    """``message`` with a leading library parameter name replaced by its flag."""
    m = _LEADING_NAME.match(message)
    if m is None or m.group(1) not in FLAGS:
        return message
    return FLAGS[m.group(1)] + message[m.end() :]
