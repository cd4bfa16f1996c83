"""Library parameter names → command-line flags: the one place the CLI translates them.

Library messages name the parameters a Python caller passed, never a flag (a test scans every
``raise`` outside ``ucbplan.cli``): at the start of a message bare (``max_visit: expected …``,
``n_exp/exptime/readout: …``), elsewhere between backticks (``lengthen `visit```, ``pass
`overwrite=True```, ``give `site` NAME``). The command line prints the flag its user typed
instead (``--max-visit: expected …``, ``lengthen --visit``, ``pass --overwrite``, ``give --site
NAME``): :func:`cli_message` renders both forms, and a few irregular phrases, from the tables
below. A name not in :data:`PARAMETERS` is left as it is written.
"""

from __future__ import annotations

import re

from ucbplan.api.ephemeris import COMPARE_FLAGS, EPHEMERIS_FLAGS
from ucbplan.api.exporting import EXPORT_FLAGS, NOW_FLAGS, P2_FLAGS
from ucbplan.api.flagspec import flag_names
from ucbplan.api.lisa_analysis import FISHER_FLAGS, LISA_FLAGS, SIMULATE_FLAGS, WAVEFORM_FLAGS
from ucbplan.api.plan_options import PLAN_FLAGS
from ucbplan.api.population_runs import POPULATION_SIMULATE_FLAGS, RANK_FLAGS, VISIBILITY_FLAGS
from ucbplan.api.populations import PARTS_FLAGS, POPULATION_FLAGS
from ucbplan.api.reduction import REDUCE_FLAGS
from ucbplan.api.replanning import REPLAN_FLAGS
from ucbplan.api.signal_sizes import FEASIBILITY_FLAGS
from ucbplan.api.timing import FIT_FLAGS
from ucbplan.api.validity import HORIZON_FLAGS

#: Parameters whose flag is not ``--`` + the name with ``-`` for ``_``.
_IRREGULAR = {
    "moon_sep_deg": "--moon-sep",
    "moon_illum_max": "--moon-illum",
    "zenith_hole_deg": "--zenith-hole",
    "sigma_v_kms": "--sigma-v",
    "sigma_floor_kms": "--sigma-floor",
    "extinction_k": "--extinction",
    "max_visit_s": "--max-visit",
    "k_eff_kms": "--k-eff",
    "overhead_s": "--overhead",
    "exptime_s": "--exptime",
    "readout_s": "--readout",
    "sessions_per_night": "--sessions",
    "n_epochs": "--epochs",
    "output": "-o",
}

#: Boolean parameters whose ``name=False`` is a flag of its own.
FALSE_FLAGS = {"dry_run": "--no-dry-run"}

#: Every parameter name a library message may mention.
PARAMETERS = frozenset(_IRREGULAR) | {
    # ucbplan.plan and friends
    *("airmass_max", "twilight", "alpha", "sigma_v", "sigma_floor", "max_visit", "k_eff"),
    *("mass_radius", "cos_i_sigma", "n_exp", "cadence", "min_lambda_k", "max_bin_fraction"),
    *("max_smear", "anchor", "start", "max_epochs", "end", "star", "seed", "epochs"),
    *("exptime", "readout", "overhead", "acquisition", "visit", "goal", "mode", "budget"),
    *("priority", "night", "nights", "instrument", "instruments_file", "site", "site_lonlat"),
    *("sites_file", "tz", "semester", "allow_smeared", "extinction", "plot", "sheet", "format"),
    *("overwrite", "force", "to", "create", "dry_run", "p2_environment", "p2_user", "rotmode"),
    *("eso_templates", "merge_overlaps", "tolerance_sigma", "tolerance_floor", "seeing"),
    # simulate / population
    *("n_bins", "t_start", "t_obs", "walkers", "steps", "max_steps", "until_converged"),
    *("resume", "circular", "chain", "noise", "columns", "hdf5_path", "skip_bad", "catalog"),
    *("workers", "scheduler", "cluster", "jobs", "chunk", "top", "sigma_ref", "min_hours"),
    # feasibility, ephemeris fit
    *("m1", "m2", "name", "like", "ra", "dec", "terms", "clip", "initial", "period"),
    *(f"optical_sigma_{s}" for s in ("phase", "f_rel", "fdot_rel", "p", "pdot", "t0")),
}

#: Every parameter the API's flag tables declare → the flag declared for it (issue 30: the
#: command line's options are declared once, beside the public functions).
_DECLARED = flag_names(
    PLAN_FLAGS,
    EXPORT_FLAGS,
    P2_FLAGS,
    NOW_FLAGS,
    HORIZON_FLAGS,
    EPHEMERIS_FLAGS,
    COMPARE_FLAGS,
    FIT_FLAGS,
    FEASIBILITY_FLAGS,
    REDUCE_FLAGS,
    LISA_FLAGS,
    SIMULATE_FLAGS,
    FISHER_FLAGS,
    WAVEFORM_FLAGS,
    POPULATION_FLAGS,
    PARTS_FLAGS,
    VISIBILITY_FLAGS,
    RANK_FLAGS,
    POPULATION_SIMULATE_FLAGS,
    REPLAN_FLAGS,
)
_IRREGULAR.update(
    {k: v for k, v in _DECLARED.items() if k not in _IRREGULAR and v != "--" + k.replace("_", "-")}
)
PARAMETERS = PARAMETERS | frozenset(_DECLARED)

#: Whole phrases whose command-line spelling no rule derives (Python text → CLI text).
PHRASES = {
    "optical_sigma_phase/optical_sigma_f_rel/optical_sigma_fdot_rel or "
    "optical_sigma_p/optical_sigma_pdot/optical_sigma_t0": (
        "--optical-sigma-phase/-f-rel/-fdot-rel or --optical-sigma-p/-pdot/-t0"
    ),
    "(`Plan.write` to a .json path)": "(`ucbplan plan --format json`)",
}

_NAME = r"[a-z_][a-z0-9_]*"
_LEADING = re.compile(rf"^({_NAME}(?:/{_NAME})*)(?=[: ])")
_QUOTED = re.compile(rf"`({_NAME})(?:=([^`]*))?`")


def flag_of(name: str) -> str:
    """The flag of the library parameter ``name`` (``max_visit`` → ``--max-visit``)."""
    return _IRREGULAR.get(name, "--" + name.replace("_", "-"))


#: Every parameter of :data:`PARAMETERS` → its command-line flag.
FLAGS = {name: flag_of(name) for name in sorted(PARAMETERS)}


def _quoted(m: re.Match[str]) -> str:
    name, value = m.group(1), m.group(2)
    if name not in PARAMETERS:
        return m.group(0)
    if value == "False" and name in FALSE_FLAGS:
        return FALSE_FLAGS[name]
    return flag_of(name) if value in (None, "True") else f"{flag_of(name)} {value}"


def _leading(message: str) -> str:
    m = _LEADING.match(message)
    if m is None:
        return message
    names = m.group(1).split("/")
    if not all(n in PARAMETERS for n in names):
        return message
    return "/".join(map(flag_of, names)) + message[m.end() :]


def cli_text(text: str) -> str:
    """A note or warning as the command line says it: the parameters it quotes (`name`)
    replaced by their flags. Its first word stays: a note may begin with a word that is also a
    parameter's name ("acquisition overhead 409 s …"), which only an error's leading
    ``name:`` means as one."""
    for python, cli in PHRASES.items():
        text = text.replace(python, cli)
    return _QUOTED.sub(_quoted, text)


def cli_message(message: str) -> str:
    """An error ``message`` as the command line says it: parameter names replaced by their
    flags, the leading one (``max_visit: …``) too."""
    return _leading(cli_text(message))
