"""Gemini timing windows and the phase-constraint table, read back and checked independently.

Gemini: the JSON windows against numpy datetime64 arithmetic on the blocks table. Phase table:
read back by astropy (ECSV) and checked on a table whose barycentric mid-times follow a known
linear ephemeris (recovered exactly) or a known quadratic drift (the stated linear error is the
drift's largest difference from the middle block).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from astropy.table import Table
from astropy.time import Time, TimeDelta
from support.exports import HM_P_S, fixture_table, golden, golden_export, ms, written_table

from ucbplan.errors import SiteError
from ucbplan.observing.exports import EXPORT_FORMATS, ExportOptions, export_blocks
from ucbplan.observing.observatory.sites import get_site

OPTS = ExportOptions(acquisition_s=600.0)


def _at(site: str) -> Table:
    table = fixture_table()
    table.meta["site"] = get_site(site).as_dict()
    return table


def test_new_formats_are_registered() -> None:
    assert {"gemini", "phase-table"} <= set(EXPORT_FORMATS)


@pytest.mark.parametrize("name", ["exports_gemini.json", "exports_phase_table.ecsv"])
def test_golden(tmp_path: Path, name: str) -> None:
    # Byte for byte (change detector); the rules are checked by the tests below.
    table = written_table(tmp_path)
    assert golden_export(table, name) == golden(name), (
        f"{name} differs; see tests/support/exports.py"
    )


def test_golden_gemini_windows_match_the_blocks(tmp_path: Path) -> None:
    table = written_table(tmp_path)
    doc = json.loads(golden("exports_gemini.json"))
    _check_windows(doc, table)


def test_golden_phase_table_reads_back() -> None:
    out = Table.read(golden("exports_phase_table.ecsv").decode(), format="ascii.ecsv")
    assert list(out["target"]) == ["HM Cnc", "SDSS J0000-0030"]
    assert out["period_s"][0] == pytest.approx(HM_P_S) and str(out["period_s"].unit) == "s"


# ------------------------------------------------------------------------------------ Gemini


@pytest.mark.parametrize("site", ["mauna kea", "gemini-south"])
def test_gemini_windows_hold_the_observation_start(site: str) -> None:
    table = _at(site)
    _check_windows(json.loads(export_blocks(table, "gemini", OPTS).content), table)


def _check_windows(doc: dict[str, Any], table: Table) -> None:
    rows = {str(r["block_id"]): r for r in table}
    # the fixture's blocks are lone visits: one observation each, in time order
    assert [o["block_ids"] for o in doc["observations"]] == [
        [b] for b in sorted(rows, key=lambda b: ms(rows[b]["t_mid_utc"]))
    ]
    minute = np.timedelta64(60, "s")
    for obs in doc["observations"]:
        row = rows[obs["block_ids"][0]]
        assert obs["exposure_count"] == row["n_exp"] and obs["exposure_time_s"] == row["exptime_s"]
        half = np.timedelta64(round(max(3 * row["sigma_t_s"], 10.0) * 1000), "ms")
        start = ms(row["t_start_utc"]) - np.timedelta64(600, "s")
        window = obs["timing_window"]
        lo = np.datetime64(window["start_utc"].replace(" ", "T"), "ms")
        hi = lo + np.timedelta64(window["duration_minutes"], "m")
        assert lo <= start - half and start + half <= hi  # the start window fits inside
        assert start - half - lo < minute and hi - (start + half) < minute  # whole minutes, tight
        hours, minutes = map(int, window["duration"].split(":"))
        assert hours * 60 + minutes == window["duration_minutes"] and window["repeat"] is None


def test_gemini_refuses_a_paranal_plan() -> None:
    with pytest.raises(SiteError, match="Mauna Kea, Cerro Pachon"):
        export_blocks(_at("paranal"), "gemini", OPTS)


# ------------------------------------------------------------------------------- phase table


def _linear_tdb(table: Table, t0: Time, period: float, drift_per_s2: float = 0.0) -> Table:
    """HM Cnc's barycentric mid-times put on t0 + (n + u/2π)·P (+ drift·(t − t_mid)²)."""
    t = Table(table[table["target"] == "HM Cnc"], copy=True)
    now = Time(list(t["t_mid_tdb_bary"]), scale="tdb")
    n = np.round((now - t0).sec / period)
    exact = t0 + TimeDelta((n + np.asarray(t["u_star_rad"]) / (2 * math.pi)) * period, format="sec")
    middle = exact[np.argsort(exact.jd)][len(exact) // 2]
    drift = drift_per_s2 * (exact - middle).sec ** 2
    t["t_mid_tdb_bary"] = [x.isot for x in exact + TimeDelta(drift, format="sec")]
    t["period_s"] = period
    return t


def _read(table: Table) -> tuple[Table, tuple[str, ...]]:
    res = export_blocks(table, "phase-table", OPTS)
    return Table.read(res.content.decode(), format="ascii.ecsv"), res.notes


def test_phase_table_recovers_a_linear_ephemeris() -> None:
    t0 = Time("2037-01-10T00:00:00", scale="tdb")
    out, notes = _read(_linear_tdb(fixture_table(), t0, HM_P_S))
    (row,) = out
    assert row["period_s"] == pytest.approx(HM_P_S, rel=1e-12)
    assert str(out["period_s"].unit) == "s" and str(out["t0_bjd_tdb"].unit) == "d"
    cycles = (Time(row["t0_tdb"], scale="tdb") - t0).sec / HM_P_S
    assert abs(cycles - round(cycles)) * HM_P_S < 2e-3  # the same zero phase, to ms precision
    assert row["t0_bjd_tdb"] == pytest.approx(Time(row["t0_tdb"], scale="tdb").jd, abs=1e-8)
    assert row["linear_max_error_s"] < 2e-3 and row["linear_valid_over_window"]
    # u = 0 and pi: phases 0 and 0.5, half-width 10 s / P wrapping through 0.
    h = 10.0 / HM_P_S
    assert row["phase_ranges"] == f"{1 - h:.4f}-{h:.4f}; {0.5 - h:.4f}-{0.5 + h:.4f}"
    assert not any("misses" in n for n in notes)


def test_phase_table_states_a_quadratic_drift() -> None:
    t0 = Time("2037-01-10T00:00:00", scale="tdb")
    drift = 1e-11  # s per s^2: ~44 s after 26 days from the middle block
    table = _linear_tdb(fixture_table(), t0, HM_P_S, drift)
    out, notes = _read(table)
    mids = Time(list(table["t_mid_tdb_bary"]), scale="tdb")
    middle = mids[np.argsort(mids.jd)][1]
    # Expected by hand: the drift relative to the middle block (where the ephemeris is anchored).
    expected = max(abs(drift * (m - middle).sec ** 2) for m in mids)
    assert out[0]["linear_max_error_s"] == pytest.approx(expected, rel=1e-3, abs=2e-3)
    assert not out[0]["linear_valid_over_window"] and any("misses" in n for n in notes)


def test_phase_table_takes_any_site_and_states_validity() -> None:
    table = _at("kitt peak")
    table.meta["valid_until_tdb"] = {"HM Cnc": "2040-01-01T00:00:00.000"}
    out, _ = _read(table)
    hm = out[out["target"] == "HM Cnc"][0]
    assert hm["plan_ephemeris_valid_until_tdb"] == "2040-01-01T00:00:00.000"
    assert "BJD_TDB" in out.meta["time_scale"] and "ascending node" in out.meta["phase_convention"]
