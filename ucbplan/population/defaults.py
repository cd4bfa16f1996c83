"""The defaults of a population forecast, declared once for the library, its API and its CLI.

A light module (it imports only the light :mod:`ucbplan.lisa`): the command line reads it
when it builds its options.
"""

from __future__ import annotations

from ucbplan.lisa import DEFAULT_N_BINS as DEFAULT_N_BINS

#: RV precision per epoch assumed for every source [km/s].
DEFAULT_SIGMA_V_KMS = 15.0
#: LISA mission start assumed by default (as catalogs/fiducial-injection.yaml), TDB.
DEFAULT_T_START = "2035-01-01T00:00:00"
#: 4 sidereal years [s] (the paper's T_obs).
DEFAULT_T_OBS_S = 126232599.054
#: LISA detection threshold: a source below this SNR gets the status ``below-threshold`` (its
#: numbers are kept; the Fisher forecast of an undetected source is not a plan's ephemeris).
SNR_THRESHOLD = 7.0
