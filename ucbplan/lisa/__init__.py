"""Reduced small-eccentricity LISA simulation: waveform, response, noise, inference.

Stands apart from the planning pipeline and only *produces* target files (paper Sec. 4.1,
Appendices D and E). Import the submodules directly; nothing is loaded on package import.

Modules: :mod:`~ucbplan.lisa.pipeline` (the library behind ``ucbplan simulate | fisher``:
:func:`~ucbplan.lisa.pipeline.build_model`, :func:`~ucbplan.lisa.pipeline.fisher_forecast`,
:func:`~ucbplan.lisa.pipeline.simulate`), :mod:`~ucbplan.lisa.simulation` (the records it passes
along: model, options, problem, result), :mod:`~ucbplan.lisa.lines` (``ucbplan waveform``),
:mod:`~ucbplan.lisa.outputs` (the simulation's files); the source model :mod:`~ucbplan.lisa.source`;
kernels :mod:`~ucbplan.lisa.waveform` (with :mod:`~ucbplan.lisa.numerics`),
:mod:`~ucbplan.lisa.response`, :mod:`~ucbplan.lisa.orbits`, :mod:`~ucbplan.lisa.noise`,
:mod:`~ucbplan.lisa.likelihood`, :mod:`~ucbplan.lisa.fisher`, :mod:`~ucbplan.lisa.sampler`,
:mod:`~ucbplan.lisa.posterior` (start → midpoint, π-mode fold); figures :mod:`~ucbplan.lisa.plots`.
"""

from ucbplan.core.constants import DAY_S

__all__ = [
    "DEFAULT_MAX_STEPS",
    "DEFAULT_N_BINS",
    "DEFAULT_STEPS",
    "DEFAULT_WALKERS",
    "MAX_N_BINS",
    "MIN_T_OBS_S",
]

#: Largest band width N of the model (memory: templates are walkers × 3 bands × 2 channels × N
#: complex numbers); every command that takes ``--n-bins`` checks it.
MAX_N_BINS = 65536
#: Shortest accepted observation [s] (a day: the response needs a resolved orbit).
MIN_T_OBS_S = DAY_S

# The defaults of the model and the sampler, declared once for the library, the API
# (:mod:`ucbplan.api.lisa_analysis`, whose signatures the command line derives from) and the
# population runs.
#: Band width N (frequency bins) of the model: injection and templates.
DEFAULT_N_BINS = 512
#: emcee walkers (at least 2 per sampled parameter).
DEFAULT_WALKERS = 32
#: Chain steps (the minimum with ``until_converged``).
DEFAULT_STEPS = 2000
#: Cap of the chain with ``until_converged``.
DEFAULT_MAX_STEPS = 50_000
