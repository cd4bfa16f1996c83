"""The one coordinate formatter (:func:`ucbplan.observing.blocks.cells.sexagesimal`): its
``astropy`` rounding writes the blocks table's ``ra_hms``/``dec_dms`` exactly as astropy's
``Angle.to_string`` did, its ``once`` rounding what the exports always wrote, and the two differ
only where these tests say (a one-off run over 1.4 million values found no other difference)."""

from __future__ import annotations

import numpy as np
import pytest
from astropy.coordinates import Angle
from hypothesis import given, settings
from hypothesis import strategies as st

from ucbplan.observing.blocks.cells import dec_dms_column, ra_hms_column, sexagesimal

#: Values per sample: enough to meet every kind of rounding case (a tie within a few ulps
#: differs in ~1 of 7), few enough to stay well under a second per test.
N = 20_000


def _astropy_ra(ra_deg: np.ndarray) -> np.ndarray:
    """``ra_hms`` as the table made it up to issue 25 (astropy's text)."""
    text = Angle(ra_deg, unit="deg").to_string(unit="hourangle", sep=":", precision=3, pad=True)
    return np.atleast_1d(text).astype(str)


def _astropy_dec(dec_deg: np.ndarray) -> np.ndarray:
    """``dec_dms`` as the table made it up to issue 25 (astropy's text)."""
    text = Angle(dec_deg, unit="deg").to_string(
        unit="deg", sep=":", precision=2, pad=True, alwayssign=True
    )
    return np.atleast_1d(text).astype(str)


def _near_ties(rng: np.random.Generator, units_per: float, top: float, scale: float) -> np.ndarray:
    """Values within 4 ulps of a rounding tie of the last decimal (``units_per`` per hour or
    degree), where floating-point steps decide the last digit."""
    k = rng.integers(0, int(top * units_per), N)
    value = (k + 0.5) / units_per * scale
    return value + rng.integers(-4, 5, N) * np.spacing(value)


def _ra_sample(rng: np.random.Generator) -> np.ndarray:
    edges = [0.0, -0.0, 360.0, np.nextafter(360.0, 0.0), 360 - 1e-9, 5e-324, 15.0, -1e-9]
    return np.concatenate(
        [
            rng.uniform(0.0, 360.0, N),
            _near_ties(rng, 3600 * 1000, 24, 15.0),
            np.nextafter(360.0, 0.0) - rng.uniform(0.0, 1e-5, N // 10),  # 23:59:59.9995+
            np.array([*edges, np.nan, np.inf]),
        ]
    )


def _dec_sample(rng: np.random.Generator) -> np.ndarray:
    edges = [0.0, -0.0, 90.0, -90.0, np.nextafter(90.0, 0.0), -5e-324, -1e-7, 1e-7]
    return np.concatenate(
        [
            rng.uniform(-90.0, 90.0, N),
            _near_ties(rng, 3600 * 100, 90, 1.0) * rng.choice([-1.0, 1.0], N),
            -rng.uniform(0.0, 1e-5, N // 10),  # tiny negatives
            np.array([*edges, np.nan, -np.inf]),
        ]
    )


def test_table_columns_are_astropys_text() -> None:
    rng = np.random.default_rng(25)
    ra, dec = _ra_sample(rng), _dec_sample(rng)
    assert ra_hms_column(ra).tolist() == _astropy_ra(ra).tolist()
    assert dec_dms_column(dec).tolist() == _astropy_dec(dec).tolist()


def test_sexagesimal_columns_match_per_element() -> None:
    # repeated (a target's blocks), signed zero, rounding carries, the poles and NaN
    ra = np.array([121.5967, 121.5967, 0.0, -0.0, 359.99999999, 15.0, 121.5967, np.nan])
    dec = np.array([15.4583, -0.0, 0.0, -0.0000001, 89.9999999999, -90.0, 15.4583, np.nan])
    got_ra, got_dec = ra_hms_column(ra), dec_dms_column(dec)
    ref_ra = [_astropy_ra(np.array([x]))[0] for x in ra]  # one by one
    ref_dec = [_astropy_dec(np.array([x]))[0] for x in dec]
    assert list(got_ra) == ref_ra and list(got_dec) == ref_dec
    assert (got_dec[1], got_dec[2]) == ("-00:00:00.00", "+00:00:00.00")  # -0.0 on its own
    assert got_ra.dtype == _astropy_ra(ra).dtype  # the table column's width unchanged
    assert len(ra_hms_column(np.array([]))) == 0


def _units(text: str) -> int:
    """Sexagesimal text as a whole number of its last decimal (the sign aside)."""
    head, minutes, seconds = text.lstrip("+-").split(":")
    whole, _, frac = seconds.partition(".")
    scale = 10 ** len(frac)
    return ((int(head) * 60 + int(minutes)) * 60 + int(whole)) * scale + int(frac or 0)


def _last_digit_apart(a: str, b: str) -> bool:
    """One unit of the last decimal apart (a carry may change more digits), same sign."""
    return a[0] == b[0] and abs(_units(a) - _units(b)) == 1


def test_the_two_roundings_differ_only_at_the_named_edges() -> None:
    rng = np.random.default_rng(2025)
    ra = _ra_sample(rng)
    ra = ra[np.isfinite(ra) & ~np.signbit(ra)]  # the exports drop an RA's sign
    hours = ra * (Angle(1.0, unit="deg").hourangle)  # astropy's scale, as the table converts
    kinds: dict[str, int] = {"wrap": 0, "tie": 0, "zero": 0}
    for value, h in zip(ra.tolist(), hours.tolist(), strict=True):
        table = sexagesimal(h, 3, ":", False, rounding="astropy")
        export = sexagesimal(value / 15.0, 3, ":", False)
        if table != export:
            kind = "wrap" if (table[:3], export[:3]) == ("24:", "00:") else "tie"
            assert kind == "wrap" or _last_digit_apart(table, export), (value, table, export)
            kinds[kind] += 1
    dec = _dec_sample(rng)
    for value in dec[np.isfinite(dec)].tolist():
        table = sexagesimal(value, 2, ":", True, rounding="astropy")
        export = sexagesimal(value, 2, ":", True)
        if table != export:
            zero = value <= 0 and (table, export) == ("-00:00:00.00", "+00:00:00.00")
            kind = "zero" if zero else "tie"
            assert zero or _last_digit_apart(table, export), (value, table, export)
            kinds[kind] += 1
    assert min(kinds.values()) > 0, kinds  # the samples meet every kind of difference


def test_the_two_roundings_agree_away_from_ties() -> None:
    # random values and catalogue grids (1 ms of RA, 0.01" of Dec) are never near a tie
    rng = np.random.default_rng(3)
    ra = np.concatenate([rng.uniform(0, 360, N), rng.integers(0, 86_400_000, N) / 3.6e6 * 15])
    hours = ra * Angle(1.0, unit="deg").hourangle
    table = [sexagesimal(h, 3, ":", False, rounding="astropy") for h in hours.tolist()]
    assert table == [sexagesimal(v / 15.0, 3, ":", False) for v in ra.tolist()]
    dec = np.concatenate(
        [rng.uniform(-90, 90, N), rng.integers(-32_400_000, 32_400_000, N) / 3.6e5]
    )
    table = [sexagesimal(d, 2, ":", True, rounding="astropy") for d in dec.tolist()]
    assert table == [sexagesimal(d, 2, ":", True) for d in dec.tolist()]


@pytest.mark.parametrize(
    ("value", "decimals", "signed", "astropy", "once"),
    [
        (23.99999999999, 3, False, "24:00:00.000", "00:00:00.000"),  # 24 h: wrap or not
        (-0.0, 2, True, "-00:00:00.00", "+00:00:00.00"),  # the sign of zero
        (-1e-9, 2, True, "-00:00:00.00", "+00:00:00.00"),  # a negative rounding to zero
        (-1.5, 1, False, "-01:30:00.0", "01:30:00.0"),  # unsigned: the sign dropped or kept
        (12.5, 2, True, "+12:30:00.00", "+12:30:00.00"),
        (59.99999999, 2, True, "+60:00:00.00", "+60:00:00.00"),  # the carry, both ways
    ],
)
def test_named_differences(
    value: float, decimals: int, signed: bool, astropy: str, once: str
) -> None:
    assert sexagesimal(value, decimals, ":", signed, rounding="astropy") == astropy
    assert sexagesimal(value, decimals, ":", signed) == once


def test_unknown_rounding_is_refused() -> None:
    with pytest.raises(ValueError, match="rounding"):
        sexagesimal(1.0, 2, ":", True, rounding="half-up")


@settings(max_examples=300, deadline=None)
@given(
    value=st.floats(allow_nan=True, allow_infinity=True, width=64),
    decimals=st.integers(0, 4),
    signed=st.booleans(),
)
def test_astropy_rounding_is_astropys_text(value: float, decimals: int, signed: bool) -> None:
    # any float, any precision: the text astropy's Angle.to_string writes (degrees as the unit)
    ref = Angle(value, unit="deg").to_string(
        unit="deg", sep=":", precision=decimals, pad=True, alwayssign=signed
    )
    assert sexagesimal(value, decimals, ":", signed, rounding="astropy") == str(ref)
