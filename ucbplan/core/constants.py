"""Physical constants and time units, declared once for the whole package (SI).

The values are astropy's (CODATA 2018, IAU 2015 nominal solar values), written out so the numerical
core does not import ``astropy.constants``; ``tests/core/test_constants.py`` checks them against
astropy.
"""

from __future__ import annotations

import math

#: Speed of light [m/s] (exact).
C_M_S = 299792458.0
#: Speed of light [km/s].
C_KM_S = 299792.458
#: Newtonian constant of gravitation [m^3 kg^-1 s^-2] (CODATA 2018).
G_SI = 6.67430e-11
#: Solar mass [kg] (IAU 2015 nominal GM_sun / CODATA 2018 G, as astropy.constants.M_sun).
MSUN_KG = 1.988409870698051e30
#: Nominal solar radius [m] (IAU 2015).
RSUN_M = 6.957e8
#: Astronomical unit [m] (IAU 2012, exact).
AU_M = 1.495978707e11
#: Kiloparsec [m] (IAU 2015 parsec).
KPC_M = 3.0856775814913673e19
#: IAU 2006 Resolution B3: d(TDB)/d(TCB) = 1 − L_B.
L_B = 1.550519768e-8

#: One day [s], as an int (exact integer arithmetic: POSIX seconds, Decimal epochs).
DAY_S_INT = 86400
#: One day [s].
DAY_S = float(DAY_S_INT)
#: One hour [s], as an int (whole-second clock arithmetic).
HOUR_S_INT = 3600
#: One hour [s].
HOUR_S = float(HOUR_S_INT)
#: Julian year [s] (what astropy's bare "yr" means).
YEAR_S = 365.25 * DAY_S
#: One twelfth of a Julian year [s].
MONTH_S = YEAR_S / 12.0
#: Sidereal year [s]; the paper's T_obs = 4 sidereal years.
SIDEREAL_YEAR_S = 31558149.7635
#: 2π.
TWO_PI = 2.0 * math.pi

#: Largest eccentricity the first-order (small-e) phase model accepts.
E_MAX = 0.1
