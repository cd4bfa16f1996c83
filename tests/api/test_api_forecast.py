"""The forecast half of the public API: targets, sites, epochs, horizons, timing fits, feasibility.

Regression tests of issue 33 ("Python API: exceptions outside ucbplan's error tree") and issue 30
(first-class results, inputs as typed) for these functions, and a property test over their
arguments: whatever they are given, they return or raise a one-line :class:`UcbplanError`
naming the parameter.
"""

from __future__ import annotations

import math
import re
import sys
from decimal import Decimal
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from astropy import units as u
from astropy.coordinates import EarthLocation, SkyCoord
from astropy.table import Table
from hypothesis import given, settings
from hypothesis import strategies as st
from support.strategies import any_value

import ucbplan
from ucbplan.errors import InputError, OutputExistsError, UcbplanError

pytestmark = [
    pytest.mark.filterwarnings("ignore::erfa.ErfaWarning"),
    pytest.mark.filterwarnings("ignore::ucbplan.errors.UcbplanWarning"),
]

HM = "catalogs/hm-cnc-simulated.yaml"
TIMING = "catalogs/examples/synthetic-eclipsing.yaml"
P_S = Decimal("400.0")
T0 = Decimal("2461000.5")


def one_line(exc: BaseException, parameter: str) -> str:
    text = str(exc)
    assert isinstance(exc, UcbplanError), type(exc)
    assert "\n" not in text and len(text) < 400, text
    assert text.startswith(parameter), text
    return text


def _bjd(n: float, pdot: float = -2e-11) -> str:
    sec = float(P_S) * n + 0.5 * float(P_S) * pdot * n * n
    return f"{T0 + Decimal(repr(sec)) / Decimal(86400):.12f}"


def _times(cycles: list[float]) -> Table:
    return Table({"bjd_tdb": [_bjd(n) for n in cycles], "sigma_s": [1.0] * len(cycles)})


#: Ten eclipses in a night, then nights ever further apart: countable with a Ṗ prior of 1e-9.
CYCLES = [*range(10), 216, 217, 5000, 5001, 12000, 20000, 30000, 45000, 62000, 80000, 80001]


@pytest.fixture
def times_csv(tmp_path: Path) -> Path:
    path = tmp_path / "times.csv"
    _times(CYCLES).write(path, format="ascii.csv")
    return path


# ------------------------------------------------------------------ issue 33: the door's checks


def test_get_site_refuses_an_array_location_in_one_line() -> None:
    loc = EarthLocation.from_geodetic([10, 20] * u.deg, [30, 40] * u.deg, [0, 0] * u.m)
    with pytest.raises(InputError) as info:
        ucbplan.get_site(loc)
    assert "2" in one_line(info.value, "site: ")


@pytest.mark.parametrize("bad", [None, math.nan, math.inf, "x", 0, -5, 2.5, True])
def test_ephemeris_refuses_a_bad_max_epochs(bad: Any) -> None:
    with pytest.raises(InputError) as info:
        ucbplan.ephemeris(HM, "2040-02-15", "2040-02-16", max_epochs=bad)
    one_line(info.value, "max_epochs: ")


def test_horizon_refuses_alpha_none() -> None:
    with pytest.raises(InputError) as info:
        ucbplan.horizon(HM, alpha=None)
    one_line(info.value, "alpha: ")


def test_fit_ephemeris_refuses_a_text_clip(times_csv: Path) -> None:
    with pytest.raises(InputError) as info:
        ucbplan.fit_ephemeris(times_csv, clip="3")
    one_line(info.value, "clip: ")


@pytest.mark.parametrize(
    ("call", "parameter"),
    [
        (lambda c: ucbplan.get_site(c), "site: "),
        (lambda c: ucbplan.load_target(c), "target: "),
        (lambda c: ucbplan.horizon(HM, anchors=[c]), "anchor"),
        (lambda c: ucbplan.ephemeris(HM, c, "2040-02-16"), "start"),
        (lambda c: ucbplan.ephemeris(HM, "2040-02-15", "2040-02-16", anchor=c), "anchor"),
    ],
)
def test_a_skycoord_where_a_name_is_expected_is_one_line(call: Any, parameter: str) -> None:
    with pytest.raises(UcbplanError) as info:
        call(SkyCoord(1, 2, unit="deg"))
    one_line(info.value, parameter)


# ------------------------------------------------------------------ issue 33: the Ṗ hint


def test_an_unknown_pdot_hint_says_what_helps() -> None:
    """Nights 0, 1 and 23 d, then a year: P is known to ~1e-4 s (±8 s over the gap) but Ṗ = 0 ±
    1e-9 leaves ±1100 s; "more digits in the period" cannot help, a Ṗ prior or times between
    can."""
    times = _times([*range(10), 216, 217, 218, 5000, 5001, 5002, 80000, 80001, 80003])
    with pytest.raises(InputError) as info:
        ucbplan.fit_ephemeris(times, period="400.0000000 s")
    text = str(info.value)
    assert "\n" not in text and "ambiguous" in text
    assert "unknown Ṗ" in text and "pdot" in text and "bridge the gap" in text
    assert "more digits in the period will not help" in text


def test_a_period_limited_count_keeps_the_period_hint() -> None:
    """Ten eclipses then one 216 cycles later with P written to 0.1 s: ±22 s from P (> P/8 =
    50 s? no: the night's own P is ±0.04 s) -- a guess of "400 s" (±1 s) over 80000 cycles is
    limited by P, and the hint says so."""
    times = _times([0.0, 1, 2, 80000, 80001, 80002])
    with pytest.raises(InputError) as info:
        ucbplan.fit_ephemeris(times, period="400 s")
    text = str(info.value)
    assert "with more digits" in text and "unknown Ṗ" not in text


# ------------------------------------------------------------------ issue 30: typed inputs/results


def test_fit_ephemeris_takes_a_table_and_a_path_alike(times_csv: Path) -> None:
    from_table = ucbplan.fit_ephemeris(_times(CYCLES))
    from_file = ucbplan.fit_ephemeris(times_csv)
    from_text = ucbplan.fit_ephemeris(str(times_csv))
    np.testing.assert_array_equal(from_table.fit.values, from_file.fit.values)
    np.testing.assert_array_equal(from_text.fit.cov, from_file.fit.cov)
    # the truth (P = 400 s, Ṗ = −2e-11, T0 = BJD 2461000.5 at cycle 0; σ = 1 s, no noise)
    fit = from_table
    assert fit.period.to_value(u.s) == pytest.approx(
        400.0 * (1 - 2e-11 * fit.fit.t0_cycle), abs=1e-9
    )
    assert fit.pdot == pytest.approx(-2e-11, abs=1e-14)
    assert fit.to_dict()["n_points"] == len(CYCLES)


def test_fit_ephemeris_takes_a_target_as_its_first_ephemeris() -> None:
    """The shipped synthetic target is the truth of these times: counting from it works (its
    period "400.0 s" is trusted to ±0.1 s: 300 cycles from T0 to ±30 s < P/8)."""
    times = _times([0.0, 300, 301, 302])
    fit = ucbplan.fit_ephemeris(times, initial=ucbplan.load_target(TIMING), terms=2)
    assert fit.fit.cycles_origin.startswith("counted")
    same = ucbplan.fit_ephemeris(times, initial=TIMING, terms=2)
    np.testing.assert_array_equal(fit.fit.values, same.fit.values)


def test_fit_result_is_short_and_becomes_a_target(tmp_path: Path) -> None:
    fit = ucbplan.fit_ephemeris(_times(CYCLES))
    text = repr(fit)
    assert text.startswith("<TimingFit") and "\n" not in text and len(text) < 200, text
    target = fit.to_target(like=TIMING, name="Refit")
    assert target.kind == "timing" and target.name == "Refit"
    # the file writes P to ~1 % of its σ (timing.document._period_text)
    assert target.period_s == pytest.approx(fit.fit.period_s, abs=0.01 * fit.sigmas["period"])
    assert abs((target.t_ref - fit.t0).to_value(u.s)) < 1e-6
    assert len(repr(target)) < 200 and "\n" not in repr(target)
    path = ucbplan.write_target(target, tmp_path / "refit.yaml")
    back = ucbplan.load_target(path)
    assert back.name == "Refit" and back.period_s == target.period_s
    before = path.read_bytes()
    with pytest.raises(OutputExistsError):
        ucbplan.write_target(back, path)
    assert path.read_bytes() == before
    ucbplan.write_target(back, path, overwrite=True)


@pytest.mark.parametrize(
    ("given", "parameter"),
    [
        ({"name": 5}, "name: "),
        ({"name": ["x"]}, "name: "),
        ({"ra": 5, "dec": "+50d"}, "ra: "),
        ({"ra": "15h39m", "dec": 50.4}, "dec: "),
    ],
)
def test_to_target_refuses_a_name_or_position_not_text_in_one_line(
    given: dict[str, Any], parameter: str
) -> None:
    """A number where the target's name or sky position is text was an AttributeError from
    ``str.strip`` (a traceback outside ucbplan's errors), found by the tutorial notebook."""
    fit = ucbplan.fit_ephemeris(_times(CYCLES))
    for call in (fit.to_target, fit.target_yaml, fit.target_document):
        with pytest.raises(InputError) as info:
            call(**{"like": TIMING, **given})
        one_line(info.value, parameter)


def test_horizon_is_the_batched_table_with_the_per_target_numbers() -> None:
    from ucbplan.core.forecast import horizon_table

    tab = ucbplan.horizon([HM, TIMING], alpha=(0.5, 1.0))
    assert {"target", "kind", "t_valid_days", "t_valid_before_days"} <= set(tab.colnames)
    assert list(tab["target"][:4]) == ["HM Cnc (simulated LISA posterior)"] * 4 or len(tab) == 8
    t = ucbplan.load_target(HM)
    spec = t.spectroscopy
    rows = horizon_table(t, spec.sigma_v_kms, spec.k_for_tolerance, alphas=(0.5, 1.0))
    np.testing.assert_allclose(tab["t_valid_days"][:4], [r.t_valid_days for r in rows], rtol=1e-6)


def test_feasibility_returns_a_typed_report() -> None:
    got = ucbplan.feasibility(HM, baseline=30 * u.day)
    assert got.report.baseline_s == pytest.approx(30 * 86400.0)
    text = repr(got)
    assert text.startswith("<Feasibility") and "\n" not in text
    doc = got.to_dict()
    assert doc["units"].startswith("SI") and doc["name"] == got.report.name
    assert "strategies" not in doc
    assert ucbplan.feasibility(HM, baseline="30 d").to_dict() == doc


# ------------------------------------------------------------------ any value, one line

#: test_api's values (numbers, text, None, booleans, quantities) and what a notebook holds.
_ANY = st.one_of(
    any_value(units=[u.deg, u.rad, u.m, u.s, u.one]),
    st.just(SkyCoord(1, 2, unit="deg")),
    st.just(EarthLocation.from_geodetic([1, 2] * u.deg, [3, 4] * u.deg)),
    st.lists(st.floats(allow_nan=True), max_size=3),
    st.dictionaries(st.text(max_size=3), st.integers(), max_size=2),
)

#: (call, the parameter it varies): each call sets one argument and keeps the others valid.
_CALLS: dict[str, Any] = {
    "site": lambda v: ucbplan.get_site(v),
    "timezone": lambda v: ucbplan.get_site("paranal", timezone=v),
    "target": lambda v: ucbplan.load_target(v),
    "start": lambda v: ucbplan.ephemeris(HM, v, "2040-02-16"),
    "anchor": lambda v: ucbplan.ephemeris(HM, "2040-02-15", "2040-02-16", anchor=v),
    "star": lambda v: ucbplan.ephemeris(HM, "2040-02-15", "2040-02-16", star=v),
    "max_epochs": lambda v: ucbplan.ephemeris(HM, "2040-02-15", "2040-02-16", max_epochs=v),
    "sigma_v": lambda v: ucbplan.horizon(HM, sigma_v=v),
    "k_eff": lambda v: ucbplan.horizon(HM, k_eff=v),
    "alpha": lambda v: ucbplan.horizon(HM, alpha=v),
    "n_epochs": lambda v: ucbplan.horizon(HM, n_epochs=v),
    "anchors": lambda v: ucbplan.horizon(HM, anchors=v),
    "times": lambda v: ucbplan.fit_ephemeris(v),
    "period": lambda v: ucbplan.fit_ephemeris(_times(CYCLES), period=v),
    "initial": lambda v: ucbplan.fit_ephemeris(_times(CYCLES), initial=v),
    "terms": lambda v: ucbplan.fit_ephemeris(_times(CYCLES), terms=v),
    "clip": lambda v: ucbplan.fit_ephemeris(_times(CYCLES), clip=v),
    "m1": lambda v: ucbplan.feasibility(HM, m1=v),
    "n_spectra": lambda v: ucbplan.feasibility(HM, n_spectra=v),
    "baseline": lambda v: ucbplan.feasibility(HM, baseline=v),
    "a_out": lambda v: ucbplan.feasibility(HM, a_out=v),
    "optical_epoch": lambda v: ucbplan.feasibility(HM, optical_epoch=v),
}


def _names_it(text: str, parameter: str, value: Any) -> bool:
    """The message names the parameter (as the library or the command line spells it), or the
    value given (a file or site that is not there)."""
    words = text.replace("-", "_").lower()
    stem = parameter.removesuffix("s")
    return stem in words or (isinstance(value, str) and value.strip() != "" and value in text)


@settings(max_examples=300, deadline=None)
@given(parameter=st.sampled_from(sorted(_CALLS)), value=_ANY)
def test_forecast_functions_take_any_value(parameter: str, value: Any) -> None:
    # returned, or refused in one line of ucbplan's error tree naming the parameter
    try:
        _CALLS[parameter](value)
    except UcbplanError as exc:
        text = str(exc)
        assert "\n" not in text and len(text) < 600, text
        assert _names_it(text, parameter, value), (parameter, value, text)


def test_the_timing_page_the_fit_points_to_exists_and_is_in_the_site() -> None:
    root = Path(__file__).resolve().parents[2]
    pages = set(re.findall(r"docs/[\w/.-]+\.md", ucbplan.fit_ephemeris.__doc__ or ""))
    pages |= set(re.findall(r"docs/[\w/.-]+\.md", sys.modules["ucbplan.api.timing"].__doc__ or ""))
    assert pages == {"docs/timing.md"}
    assert (root / "docs" / "timing.md").is_file()
    assert "timing.md" in (root / "mkdocs.yml").read_text(encoding="utf-8")


@pytest.mark.slow  # a fresh interpreter (~3 s): the command line's own error path
def test_feasibility_refuses_a_visit_no_strategy_fits_before_printing() -> None:
    """Issue 33: `--visit 5min --overhead 480` printed the 36-line report, then its error."""
    import subprocess

    args = [HM, "--sigma-v", "30km/s@600s", "--visit", "5min", "--overhead", "480"]
    proc = subprocess.run(
        [sys.executable, "-m", "ucbplan", "feasibility", *args],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 2 and proc.stdout == ""
    lines = [ln for ln in proc.stderr.splitlines() if ln.strip()]
    # one line naming the visit (the shared visit check: acquisition + one exposure + readout)
    assert len(lines) == 1 and lines[0].startswith("error: --visit: "), proc.stderr


def test_to_target_copies_from_a_target_or_a_document_alike() -> None:
    fit = ucbplan.fit_ephemeris(_times(CYCLES))
    source = ucbplan.load_target(TIMING)
    from_target = fit.to_target(like=source)
    from_file = fit.to_target(like=TIMING)
    assert from_target.name == from_file.name == source.name
    assert (from_target.ra_deg, from_target.dec_deg) == (from_file.ra_deg, from_file.dec_deg)
    assert from_target.spectroscopy == from_file.spectroscopy
    given = fit.to_target(name="Given", ra="08h00m00s", dec="-20d00m00s")
    assert given.name == "Given" and given.spectroscopy is None
    with pytest.raises(InputError) as info:
        fit.to_target(like=SkyCoord(1, 2, unit="deg"))
    one_line(info.value, "like: ")
