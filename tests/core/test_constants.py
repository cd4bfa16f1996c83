"""The constants declared once in ucbplan.core.constants equal astropy's (CODATA 2018, IAU 2015)."""

from __future__ import annotations

import astropy.constants as const
import astropy.units as u
import pytest

from ucbplan.core import constants as k


@pytest.mark.parametrize(
    ("ours", "theirs"),
    [
        (k.C_M_S, const.c.si.value),
        (k.C_KM_S, const.c.to_value(u.km / u.s)),
        (k.G_SI, const.G.si.value),
        (k.MSUN_KG, const.M_sun.si.value),
        (k.RSUN_M, const.R_sun.si.value),
        (k.AU_M, const.au.si.value),
        (k.KPC_M, (1 * u.kpc).to_value(u.m)),
        (k.YEAR_S, (1 * u.yr).to_value(u.s)),
        (k.DAY_S, (1 * u.day).to_value(u.s)),
    ],
)
def test_constants_match_astropy(ours: float, theirs: float) -> None:
    # exact to the last bit (1e-15 relative): they are the same published numbers
    assert ours == pytest.approx(theirs, rel=1e-15)


def test_sidereal_year_reproduces_paper_t_obs() -> None:
    # the paper's T_obs = 4 sidereal years = 126232599.054 s (docs/method.md, Time)
    assert 4 * k.SIDEREAL_YEAR_S == pytest.approx(126232599.054, abs=1e-3)
