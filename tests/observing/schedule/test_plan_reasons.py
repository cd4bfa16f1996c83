"""Reasons why night-time anchor epochs were not planned: one case per reason (issue 9, item 7),
and per-target time budgets."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import pytest

from ucbplan.observing.schedule import plan_files, plan_settings
from ucbplan.observing.schedule.reasons import REASONS

ROOT = Path(__file__).resolve().parents[3]
HM = ROOT / "catalogs" / "hm-cnc-simulated.yaml"
NAME = "HM Cnc (simulated)"


def _variant(tmp_path: Path, name: str, dec: str | None = None) -> Path:
    """The HM Cnc file under another name (and declination)."""
    text = HM.read_text().replace(f"name: {NAME}", f"name: {name}")
    if dec is not None:
        text = text.replace('dec: "+15d27m30s"', f'dec: "{dec}"')
    path = tmp_path / f"{name.replace(' ', '_')}.yaml"
    path.write_text(text)
    return path


def _reasons(files: list[Path], nights: int = 1, night: str = "2040-02-15", **kw: Any) -> Any:
    priorities = kw.pop("priorities", {})
    settings = plan_settings(sigma_v_kms=5.0, k_eff_kms=400, **kw)
    run = plan_files(
        files,
        first_night=night,
        n_nights=nights,
        site="paranal",
        settings=settings,
        priorities=priorities,
    )
    total: dict[str, dict[str, int]] = {}
    for target, per_night in run.result.reasons.items():
        for counts in per_night.values():
            for why, k in counts.items():
                total.setdefault(target, {}).setdefault(why, 0)
                total[target][why] += k
    return run, total


def test_reasons_are_the_documented_ones() -> None:
    run, total = _reasons([HM], visit="1h")
    assert set(total[NAME]) <= set(REASONS)
    assert total[NAME]["altitude/airmass"] > 0  # HM Cnc sets in the second half of the night
    # only night-time candidates: at most one per anchor in the dark hours (P_b/2 = 161 s)
    assert sum(total[NAME].values()) + len(run.result.blocks) < 12 * 3600 / 160


def test_daylight_twilight() -> None:
    # 20-min exposures centred in the dark run into twilight at both ends of the night
    _, total = _reasons([HM], exptime_s=1200.0, allow_smeared=True, airmass_max=10.0)
    assert total[NAME].get("daylight/twilight", 0) > 0


def test_altitude_airmass() -> None:
    _, total = _reasons([HM], airmass_max=1.0001)
    assert total[NAME]["altitude/airmass"] > 0
    assert "daylight/twilight" not in total[NAME]


def test_zenith_hole(tmp_path: Path) -> None:
    at_zenith = _variant(tmp_path, "Zenith star", dec="-24d37m38s")  # Paranal's latitude
    _, total = _reasons([at_zenith], zenith_hole_deg=10.0, night="2040-01-15")
    assert total["Zenith star"].get("zenith hole", 0) > 0


def test_moon_separation() -> None:
    _, total = _reasons([HM], moon_sep_deg=179.0, nights=5)
    assert total[NAME].get("Moon separation", 0) > 0


def test_moon_illumination() -> None:
    _, total = _reasons([HM], moon_sep_deg=0.0, moon_illum_max=0.0, nights=5)
    assert total[NAME].get("Moon illumination", 0) > 0
    assert "Moon separation" not in total[NAME]


def test_outside_validity() -> None:
    # before the LISA observation starts (2035-01-01): the ephemeris is not valid yet
    run, total = _reasons([HM], night="2034-06-01", visit="1h")
    assert not run.result.blocks
    assert set(total[NAME]) == {"outside validity"}


def test_smearing_floor() -> None:
    # no exposure keeps Lambda_K >= 1: nothing is planned, and the reason says so
    run, total = _reasons([HM], visit="1h", min_lambda_k=1.0)
    assert not run.result.blocks
    assert total[NAME].get("smearing floor", 0) > 0
    assert any("smearing floor" in m.reason for m in run.result.unplaced)


def test_taken_by_a_higher_priority_target(tmp_path: Path) -> None:
    twin = _variant(tmp_path, "HM twin")
    _, total = _reasons([twin, HM], visit="1h", priorities={NAME: 2})
    assert total["HM twin"].get("taken by a higher-priority target", 0) > 0
    assert "taken by a higher-priority target" not in total[NAME]


def test_time_budget_spent_and_budget_kept() -> None:
    run, total = _reasons([HM], visit="30min", nights=3, budgets=[f"{NAME}=40min"])
    assert total[NAME].get("time budget spent", 0) > 0
    acc = run.accounting()["targets"][NAME]
    wall = acc["shutter_s"] + acc["overhead_s"] + acc["idle_s"]
    assert wall <= 40 * 60 + 1e-6
    assert acc["visits"] == 2  # a 30-min visit and a shorter one filling the 10 min left
    assert any(m.reason.startswith("time budget spent") for m in run.result.unplaced)


def test_budget_in_session_mode() -> None:
    run, _ = _reasons([HM], nights=3, sessions_per_night=5, budgets=[f"{NAME}=1h"])
    acc = run.accounting()["targets"][NAME]
    wall = acc["shutter_s"] + acc["overhead_s"] + acc["idle_s"]
    assert 0 < wall <= 3600 + 1e-6


@pytest.mark.parametrize("item", ["HM Cnc", "nobody=2h", f"{NAME}=2 weeks"])
def test_bad_budget_is_one_line(item: str) -> None:
    from ucbplan.errors import InputError

    with pytest.raises(InputError) as exc:
        _reasons([HM], budgets=[item])
    assert str(exc.value).startswith("budget") and "\n" not in str(exc.value)


def test_visit_refuses_fixed_u_pairs() -> None:
    from ucbplan.errors import InputError

    with pytest.raises(InputError, match=r"^visit: fixed-u pairs"):
        plan_settings(visit="1h", mode="fixed-u-pairs")


def test_why_nothing_fits_finds_the_sun_once_per_night(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Targets that never rise above the airmass limit at Paranal (dec +80): each night says
    why for each target, and the Sun's altitude behind those reasons is found once for all the
    nights and all of them (issue 34): three targets cost no more Sun than one."""
    from ucbplan.observing.observatory.sky import SkyModel
    from ucbplan.observing.schedule import placement

    calls: list[int] = []
    real = SkyModel.sun_alt_deg

    def counting(self: SkyModel, x: Any) -> Any:
        if sys._getframe(1).f_globals["__name__"] == placement.__name__:  # for the reasons
            calls.append(len(x))
        return real(self, x)

    files = [_variant(tmp_path, f"Polar {k}", dec="+80d00m00s") for k in range(3)]
    monkeypatch.setattr(SkyModel, "sun_alt_deg", counting)
    sun_calls = []
    for some in (files[:1], files):
        calls.clear()
        run, _ = _reasons(some, nights=2)
        sun_calls.append(list(calls))
        assert [(m.target, m.night) for m in run.result.unplaced] == [
            (f"Polar {k}", night)
            for k in range(len(some))
            for night in ("2040-02-15", "2040-02-16")
        ]
        assert {m.reason for m in run.result.unplaced} == {
            "never at airmass <= 2 during nautical night (highest altitude -14.5 deg)"
        }
    assert sun_calls[0] == sun_calls[1]  # one call for both nights, whatever the targets
    assert sun_calls[0] == [2 * 288]  # both noon-to-noon windows, every 300 s


@pytest.mark.parametrize("seed", range(8))
def test_counts_per_night_are_the_counts_one_by_one(seed: int) -> None:
    """(night, reason) counts, one count per cell for nights in order and apart (issue 34) or
    by running sums for nights that overlap, against counting candidate by candidate: nights
    that touch, lie apart, hold nothing or start before every candidate."""
    import numpy as np

    from ucbplan.observing.schedule.nights import NightSpan
    from ucbplan.observing.schedule.reasons import _counts_per_night

    rng = np.random.default_rng(seed)
    x = np.sort(rng.uniform(0.0, 100.0, 400).round(1))  # repeats: ties at night edges
    counted = rng.random(x.size) < 0.7
    codes = rng.integers(-1, len(REASONS), x.size)
    edges = np.sort(rng.choice(np.arange(-10.0, 111.0, 0.5), 12, replace=False))
    apart = [NightSpan(str(k), edges[k], edges[k + 1 + (k % 3 == 0)]) for k in range(0, 10, 2)]
    touching = [NightSpan(str(k), edges[k], edges[k + 1]) for k in range(11)]
    overlapping = [NightSpan("a", 10.0, 60.0), NightSpan("b", 40.0, 90.0), NightSpan("c", 0, 5)]
    for spans in (apart, touching, overlapping, [NightSpan("x", 200.0, 300.0)]):
        want = np.zeros((len(spans), len(REASONS) + 1), dtype=np.int64)
        for k, sp in enumerate(spans):
            for j in np.flatnonzero(counted & (x >= sp.x0) & (x < sp.x1)):
                want[k, codes[j] if codes[j] >= 0 else len(REASONS)] += 1
        got = _counts_per_night(x, counted, codes, spans)
        assert got.dtype == np.int64 and got.tolist() == want.tolist()
