"""Instrument records and the photon-limited σ_v scaling (issue 9 item 2)."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

from ucbplan.errors import InputError, InputFileError, UcbplanError
from ucbplan.observing.precision.instruments import (
    Instrument,
    Overheads,
    SigmaRef,
    check_exptime,
    get_instrument,
    instrument_magnitude,
    instrument_overheads,
    load_instruments,
    sigma_v_kms,
)

REF = SigmaRef(sigma_v_kms=10.0, mag=18.0, band="V", exptime_s=300.0)


def _with_ref(k: float | None = 0.11) -> Instrument:
    return replace(get_instrument("xshooter-vis"), sigma_ref=REF, extinction_k=k)


def _user_entry(**over: object) -> dict[str, object]:
    entry: dict[str, object] = {
        "telescope": "Test 4m",
        "sites": ["paranal"],
        "acquisition_s": 300,
        "readout_s": 20,
        "min_exptime_s": 1,
        "extinction_k": 0.12,
        "extinction_band": "V",
        "sigma_ref": {"sigma_v_kms": 5.0, "mag": 17.0, "band": "g", "exptime_s": 600},
        "sources": {"acquisition_s": "made up for a test"},
    }
    entry.update(over)
    return {k: v for k, v in entry.items() if v is not None}


def _write(tmp_path: Path, entries: dict[str, object]) -> Path:
    path = tmp_path / "inst.yaml"
    path.write_text(yaml.safe_dump({"instruments": entries}), encoding="utf-8")
    return path


def test_bundled_table_loads_into_frozen_records() -> None:
    table = load_instruments()
    assert {"xshooter-vis", "uves", "esi", "gmos-n"} <= set(table)
    xs = table["xshooter-vis"]
    assert xs.acquisition_s == 409 and xs.readout_s == 45 and xs.extinction_k == 0.11
    assert xs.sites == ("paranal",) and xs.sigma_ref is None and "sigma_ref" in xs.missing
    assert table["uves"].acquisition_s is None  # named under missing, not invented
    assert "acquisition_s" in xs.sources
    with pytest.raises(AttributeError):
        xs.readout_s = 1.0  # type: ignore[misc]


def test_name_lookup_is_case_insensitive() -> None:
    assert get_instrument(" XShooter-VIS ").name == "xshooter-vis"


def test_unknown_instrument_one_line_with_did_you_mean() -> None:
    with pytest.raises(InputError) as err:
        get_instrument("xshoter-vis")
    msg = str(err.value)
    assert "did you mean 'xshooter-vis'" in msg and "uves" in msg
    assert "\n" not in msg and len(msg) < 400


def test_user_file_searched_first_and_parsed(tmp_path: Path) -> None:
    path = _write(tmp_path, {"mytel": _user_entry(), "uves": _user_entry(readout_s=99)})
    inst = get_instrument("mytel", path)
    assert inst.sigma_ref == SigmaRef(5.0, 17.0, "g", 600.0)
    assert get_instrument("uves", path).readout_s == 99  # overrides the bundled one
    assert get_instrument("esi", path).name == "esi"  # bundled still reachable


@pytest.mark.parametrize(
    ("over", "field"),
    [
        ({"readout_s": -1}, "readout_s"),
        ({"extinction_k": "0.1"}, "extinction_k"),
        ({"sites": []}, "sites"),
        ({"telescope": None}, "telescope"),
        ({"colour": "red"}, "colour"),
        ({"sigma_ref": {"sigma_v_kms": 5.0, "mag": 17.0, "band": "g"}}, "exptime_s"),
        ({"sigma_ref": {"sigma_v_kms": 0, "mag": 17, "band": "g", "exptime_s": 1}}, "sigma_v_kms"),
        ({"sigma_ref": None}, "sigma_ref"),  # neither given nor missing
        ({"missing": ["readout_s"]}, "readout_s"),  # both given and missing
    ],
)
def test_user_file_errors_name_the_field(tmp_path: Path, over: dict, field: str) -> None:
    path = _write(tmp_path, {"mytel": _user_entry(**over)})
    with pytest.raises(InputFileError) as err:
        load_instruments(path)
    msg = str(err.value)
    assert field in msg and str(path) in msg and "\n" not in msg and len(msg) < 400


def test_scaling_four_times_the_time_halves_sigma() -> None:
    inst = _with_ref()
    s = sigma_v_kms(inst, 18.0, [300.0, 1200.0], 1.0)
    assert s[0] == pytest.approx(10.0) and s[1] / s[0] == pytest.approx(0.5, rel=1e-12)


def test_scaling_five_magnitudes_fainter_is_ten_times_worse() -> None:
    inst = _with_ref()
    assert sigma_v_kms(inst, 23.0, 300.0) / sigma_v_kms(inst, 18.0, 300.0) == pytest.approx(10.0)


def test_scaling_extinction_term() -> None:
    inst = _with_ref(k=0.2)
    x = np.array([1.0, 1.5, 2.0])
    s = sigma_v_kms(inst, 18.0, 300.0, x)
    np.testing.assert_allclose(s / s[0], 10.0 ** (0.2 * 0.2 * (x - 1.0)), rtol=1e-12)
    # Broadcast: exposure times x airmasses.
    grid = sigma_v_kms(inst, 18.0, np.array([[75.0], [300.0]]), x)
    assert grid.shape == (2, 3) and grid[0, 0] == pytest.approx(20.0)


def test_no_sigma_ref_says_pass_sigma_v() -> None:
    inst = get_instrument("uves")
    with pytest.raises(InputError, match="`sigma_v`") as err:
        sigma_v_kms(inst, 20.0, 300.0, 1.2)
    assert "\n" not in str(err.value)
    with pytest.raises(InputError, match="`sigma_v`"):
        instrument_magnitude(inst, {"V": 20.0})


def test_override_wins() -> None:
    s = sigma_v_kms(get_instrument("uves"), 20.0, [60.0, 120.0], 1.3, override_kms=7.5)
    np.testing.assert_array_equal(s, [7.5, 7.5])


def test_missing_extinction_refused_off_zenith() -> None:
    inst = _with_ref(k=None)
    assert sigma_v_kms(inst, 18.0, 300.0, 1.0) == pytest.approx(10.0)
    with pytest.raises(InputError, match="extinction_k"):
        sigma_v_kms(inst, 18.0, 300.0, 1.2)


def test_magnitude_in_reference_band() -> None:
    inst = _with_ref()
    assert instrument_magnitude(inst, {"g": 20.3, "v": 20.5}) == 20.5
    with pytest.raises(InputError, match="magnitudes"):
        instrument_magnitude(inst, {"g": 20.3})


@settings(max_examples=60, deadline=None)
@given(
    mag=st.floats(allow_nan=True, allow_infinity=True),
    t=st.floats(allow_nan=True, allow_infinity=True),
    x=st.floats(allow_nan=True, allow_infinity=True),
)
def test_sigma_v_fuzz(mag: float, t: float, x: float) -> None:
    inst = _with_ref()
    try:
        s = sigma_v_kms(inst, mag, t, x)
    except UcbplanError as exc:
        assert "\n" not in str(exc) and len(str(exc)) < 400
        return
    assert s.shape == () and (math.isnan(float(s)) or float(s) >= 0.0)


@pytest.mark.parametrize("t", [5e-324, 1e-300, 1e-6])
def test_an_exposure_shorter_than_a_millisecond_is_refused(t: float) -> None:
    """Found by hypothesis (test_sigma_v_fuzz): a subnormal exposure time overflowed the σ_v law
    (RuntimeWarning, then σ_v = inf) instead of being refused in one line."""
    with pytest.raises(InputError, match=r"^exptime: expected seconds ≥ 0.001") as err:
        sigma_v_kms(_with_ref(), 0.0, t, 1.0)
    assert "\n" not in str(err.value)
    assert math.isfinite(float(sigma_v_kms(_with_ref(), 0.0, 1e-3, 1.0)))


def test_overheads_option_wins_else_instrument_else_error() -> None:
    xs = get_instrument("xshooter-vis")
    assert instrument_overheads(xs) == Overheads(
        409.0, 45.0, "instrument xshooter-vis", "instrument xshooter-vis"
    )
    got = instrument_overheads(xs, readout_s=11.0)
    assert got.readout_s == 11.0 and got.readout_from == "readout" and got.acquisition_s == 409
    uves = get_instrument("uves")
    with pytest.raises(InputError, match="pass `overhead` SECONDS") as err:
        instrument_overheads(uves)
    assert "\n" not in str(err.value)
    assert instrument_overheads(uves, acquisition_s=600, readout_s=60).acquisition_s == 600
    with pytest.raises(InputError, match=r"^readout: "):
        instrument_overheads(None, acquisition_s=600)


def test_minimum_exposure() -> None:
    inst = replace(get_instrument("xshooter-vis"), min_exptime_s=1.0)
    check_exptime(inst, 1.0)
    with pytest.raises(InputError, match="at least 1 s"):
        check_exptime(inst, 0.5)
    check_exptime(get_instrument("uves"), 0.01)  # no confirmed minimum: nothing to refuse
