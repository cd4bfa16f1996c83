"""LCO/SOAR request group: the golden file, its OCS structure checked against the blocks table."""

from __future__ import annotations

import json
from typing import Any

import numpy as np
import pytest
from astropy.table import Table
from support.exports import GOLDEN_ACQUISITION_S, golden, golden_export, ms, written_table

from ucbplan.observing.exports import ExportOptions
from ucbplan.observing.exports.lco import lco_requests

NAME = "exports_lco.json"


@pytest.fixture(scope="module")
def table(tmp_path_factory: pytest.TempPathFactory) -> Table:
    return written_table(tmp_path_factory.mktemp("exports"))


@pytest.fixture(scope="module")
def doc() -> dict[str, Any]:
    return dict(json.loads(golden(NAME)))


def _rows_by_start(table: Table) -> Table:
    return table[np.argsort([ms(t) for t in table["t_start_utc"]], kind="stable")]


def _second(value: np.datetime64) -> str:
    """ISO text rounded to the nearest whole second (halves up)."""
    return str((value + np.timedelta64(500, "ms")).astype("datetime64[s]"))


def test_golden(table: Table) -> None:
    assert golden_export(table, NAME) == golden(NAME), (
        f"{NAME} differs; see tests/support/exports.py"
    )


def test_golden_is_an_ocs_request_group_of_the_blocks(doc: dict[str, Any], table: Table) -> None:
    assert doc["observation_type"] == "TIME_CRITICAL" and doc["operator"] == "MANY"
    assert isinstance(doc["proposal"], str) and isinstance(doc["ipp_value"], float)
    assert len(doc["requests"]) == len(table)
    for request, row in zip(doc["requests"], _rows_by_start(table), strict=True):
        assert set(request) == {"location", "windows", "configurations"}
        assert set(request["location"]) == {"telescope_class"}
        (window,) = request["windows"]
        assert set(window) == {"start", "end"} and window["start"] < window["end"]
        (config,) = request["configurations"]
        assert config["type"] == "SPECTRUM" and config["instrument_type"]
        target = config["target"]
        assert target["name"] == row["target"] and target["type"] == "ICRS"
        assert target["ra"] == pytest.approx(row["ra_deg"], abs=1e-12)
        assert target["dec"] == pytest.approx(row["dec_deg"], abs=1e-12)
        assert target["epoch"] == 2000
        assert set(config["constraints"]) == {"max_airmass", "min_lunar_distance"}
        (instrument,) = config["instrument_configs"]
        assert instrument == {"exposure_time": row["exptime_s"], "exposure_count": row["n_exp"]}


def _floor_s(value: np.datetime64) -> str:
    return str(value.astype("datetime64[s]"))


def _ceil_s(value: np.datetime64) -> str:
    return str((value + np.timedelta64(999, "ms")).astype("datetime64[s]"))


def test_golden_windows_hold_the_whole_request(doc: dict[str, Any], table: Table) -> None:
    # Decision (was a strict xfail): the OCS places a request anywhere its whole duration fits in
    # the window, so the window is [t_start - acquisition - half, t_end + half], half =
    # max(3 sigma, 10 s), rounded outward to the second; the request start then slides by +/- half.
    for request, row in zip(doc["requests"], _rows_by_start(table), strict=True):
        half = np.timedelta64(round(max(3 * row["sigma_t_s"], 10.0) * 1000), "ms")
        request_start = ms(row["t_start_utc"]) - np.timedelta64(round(GOLDEN_ACQUISITION_S), "s")
        request_end = ms(row["t_end_utc"])
        (window,) = request["windows"]
        assert window == {
            "start": _floor_s(request_start - half),
            "end": _ceil_s(request_end + half),
        }
        lo, hi = np.datetime64(window["start"], "ms"), np.datetime64(window["end"], "ms")
        assert lo <= request_start and request_end <= hi  # the window contains the request
        slack = (hi - lo) - (request_end - request_start)  # how far the start can slide
        assert 2 * half <= slack <= 2 * half + np.timedelta64(2, "s")


def test_block_times_ride_along(doc: dict[str, Any], table: Table) -> None:
    blocks = doc["ucbplan"]["blocks"]
    rows = _rows_by_start(table)
    assert [b["t_mid_utc"] for b in blocks] == list(rows["t_mid_utc"])
    assert [b["sigma_t_s"] for b in blocks] == list(rows["sigma_t_s"])


def test_request_settings_are_passed_through(table: Table) -> None:
    group = lco_requests(
        table, ExportOptions(acquisition_s=0.0), proposal="LCO2037A-001", max_airmass=1.6
    )
    assert group["proposal"] == "LCO2037A-001"
    assert {r["configurations"][0]["constraints"]["max_airmass"] for r in group["requests"]} == {
        1.6
    }
