"""``plan --visit``: one acquisition, then continuous exposures each centred on an anchor.

Independent checks: u(t_mid) recomputed through astropy's own light time; Sun, altitude and
airmass from astropy AltAz; the wall time of a visit against the closed form of
:func:`ucbplan.observing.precision.goals.time_budget`; the goal count against σ_v²/(σ_K² Λ_K²).
"""

from __future__ import annotations

import itertools
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from astropy import units as u
from astropy.coordinates import AltAz, SkyCoord, get_sun
from astropy.table import Table
from astropy.time import Time
from hypothesis import given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from ucbplan.cli._flags import cli_message
from ucbplan.cli.app import app
from ucbplan.core.ephemeris import arg_latitude
from ucbplan.observing.blocks.read import read_blocks
from ucbplan.observing.observatory.barycentric import site_utc_to_bary_tdb
from ucbplan.observing.observatory.sites import get_site
from ucbplan.observing.precision.goals import time_budget
from ucbplan.observing.schedule import plan_files, plan_settings
from ucbplan.offline import offline
from ucbplan.targets import Target, load_target

ROOT = Path(__file__).resolve().parents[3]
HM = ROOT / "catalogs" / "hm-cnc-simulated.yaml"
FID = ROOT / "catalogs" / "fiducial-eccentric.yaml"
DONE_WHEN = [
    "plan",
    str(HM),
    "--site",
    "paranal",
    "--night",
    "2040-02-15",
    "--instrument",
    "xshooter-vis",
    "--sigma-v",
    "5",
    "--visit",
    "1h",
]
#: X-shooter VIS acquisition and readout of the bundled instrument table [s].
ACQ_S, READOUT_S = 409.0, 45.0


def _iso(text: str) -> Time:
    return Time(str(text), scale="utc")


def _u_back(target: Target, t_utc: Time) -> float:
    """u at a UTC instant at Paranal, through astropy's own light time."""
    site = get_site("paranal")
    bary = site_utc_to_bary_tdb(t_utc, target.coord, site.location)
    with offline():
        whole = float(np.floor((bary - target.t_ref).to_value(u.s)))
        frac = float((bary - (target.t_ref + whole * u.s)).to_value(u.s))
    return float(arg_latitude(target.params, np.array([frac]), 1, origin_s=whole)[0])


@pytest.fixture(scope="module")
def done_when(tmp_path_factory: pytest.TempPathFactory) -> Table:
    out = tmp_path_factory.mktemp("visit") / "plan.ecsv"
    res = CliRunner().invoke(app, [*DONE_WHEN, "-o", str(out)])
    assert res.exit_code == 0, res.output
    return read_blocks(out)


def _wrap(x: float) -> float:
    return (x + math.pi) % (2 * math.pi) - math.pi


def test_done_when_exposures_centred_on_anchors(done_when: Table) -> None:
    hm = load_target(HM)
    assert len(done_when) >= 15
    for row in done_when:
        # the written barycentric epoch (us precision: 2e-8 rad) is the anchor ...
        with offline():
            tdb = Time(str(row["t_mid_tdb_bary"]), scale="tdb")
            whole = float(np.floor((tdb - hm.t_ref).to_value(u.s)))
            frac = float((tdb - (hm.t_ref + whole * u.s)).to_value(u.s))
        u_mid = float(arg_latitude(hm.params, np.array([frac]), 1, origin_s=whole)[0])
        assert abs(_wrap(u_mid - row["u_star_rad"])) < 1e-6, row["block_id"]
        # ... and the written UTC centre (ms precision: 2e-5 rad) is the same instant
        assert abs(_wrap(_u_back(hm, _iso(row["t_mid_utc"])) - row["u_star_rad"])) < 5e-5
        assert row["n_exp"] == 1
        assert row["lambda_k"] >= 0.9
        assert row["sigma_v_kms"] == 5.0


def test_done_when_one_acquisition_per_visit_no_overlap(done_when: Table) -> None:
    visits = done_when.meta["visits"]
    assert [v["visit_id"] for v in visits] == list(dict.fromkeys(done_when["visit_id"]))
    for v in visits:
        rows = done_when[done_when["visit_id"] == v["visit_id"]]
        n = len(rows)
        assert v["exposures"] == n
        # one acquisition, ending when the first exposure starts
        gap = (_iso(rows["t_start_utc"][0]) - _iso(v["acq_start_utc"])).to_value(u.s)
        assert gap == pytest.approx(ACQ_S, abs=1.0)
        assert v["overhead_s"] == pytest.approx(ACQ_S + n * READOUT_S)
        wall = v["shutter_s"] + v["overhead_s"] + v["idle_s"]
        assert wall <= 3600.0 + 1e-6
    starts = [_iso(t) for t in done_when["t_start_utc"]]
    ends = [_iso(t) for t in done_when["t_end_utc"]]
    for (_, e0), (s1, _) in itertools.pairwise(zip(starts, ends, strict=True)):
        # the next exposure starts after this one ends and is read out (0.1 s light-time slack)
        assert (s1 - e0).to_value(u.s) >= READOUT_S - 0.1


def test_done_when_inside_night_and_airmass(done_when: Table) -> None:
    site = get_site("paranal")
    coord = SkyCoord(done_when["ra_deg"][0] * u.deg, done_when["dec_deg"][0] * u.deg)
    with offline():
        for row in done_when:
            t = Time([row["t_start_utc"], row["t_mid_utc"], row["t_end_utc"]], scale="utc")
            frame = AltAz(obstime=t, location=site.location)
            alt = coord.transform_to(frame).alt.deg
            sun = get_sun(t).transform_to(frame).alt.deg
            assert np.all(sun <= -12.0 + 1e-3)
            assert np.all(1 / np.sin(np.radians(alt)) <= 2.0 + 1e-4)


def test_visit_exposures_centred_at_full_precision() -> None:
    # The same plan through the library: block times unrounded, through astropy's light time.
    settings = plan_settings(instrument="xshooter-vis", sigma_v_kms=5.0, visit="1h")
    run = plan_files([HM], first_night="2040-02-15", site="paranal", settings=settings)
    hm = load_target(HM)
    assert len(run.visits()) == 1
    for b in run.result.blocks:
        assert abs(_wrap(_u_back(hm, b.t_mid_utc) - b.u_star_rad)) < 1e-6, b.block_id


def test_visit_wall_time_matches_time_budget(done_when: Table) -> None:
    # Independent closed form: acquisition + N (t + r) + (N - 1)(step - cost).
    hm = load_target(HM)
    n = len(done_when)
    budget = time_budget(
        n,
        period_s=hm.period_s,
        exptime_s=60.0,
        readout_s=READOUT_S,
        acquisition_s=ACQ_S,
        anchors_per_orbit=2,
    )
    acc = done_when.meta["time_accounting"]
    total = acc["total"]
    assert set(total) == {"visits", "exposures", "shutter_s", "overhead_s", "idle_s", "efficiency"}
    assert acc["targets"][hm.name] == total
    wall = total["shutter_s"] + total["overhead_s"] + total["idle_s"]
    # anchors move by the light time (< 0.02 s per minute): 1 s over the hour
    assert wall == pytest.approx(budget.total_h * 3600, abs=1.0)
    assert total["shutter_s"] == pytest.approx(budget.shutter_h * 3600)
    assert total["efficiency"] == pytest.approx(total["shutter_s"] / wall, abs=1e-6)
    # 1 h visit of a 5.4-min binary: (3600 - 409 - 105) // 160.76 + 1 = 20 quadrature spectra
    assert n == 20


def test_visits_of_two_targets_never_overlap() -> None:
    settings = plan_settings(visit="45min", sigma_v_kms=5.0, sessions_per_night=3, k_eff_kms=400)
    run = plan_files([HM, FID], first_night="2040-02-15", site="paranal", settings=settings)
    visits = run.visits()
    assert {v.target for v in visits} == {t.name for t in run.targets}
    spans = sorted((_iso(v.acq_start_utc), _iso(v.end_utc) + READOUT_S * 0 * u.s) for v in visits)
    for (_, e0), (s1, _) in itertools.pairwise(spans):
        assert (s1 - e0).to_value(u.s) >= -1.0  # ISO second rounding of the summary
    blocks = sorted(run.result.blocks, key=lambda b: b.t_start_utc.jd)
    for a, b in itertools.pairwise(blocks):
        assert (b.t_start_utc - a.t_end_utc).to_value(u.s) > 0
        if a.visit_id != b.visit_id:  # the next visit's acquisition fits in between
            assert (b.t_start_utc - a.t_end_utc).to_value(u.s) >= 300.0 - 1e-3


def test_without_visit_each_session_is_a_visit() -> None:
    run = plan_files([HM], first_night="2040-02-15", site="paranal")
    acc = run.accounting()["total"]
    assert acc["visits"] == 1 and acc["exposures"] == 2
    blocks = run.result.blocks
    assert len({b.visit_id for b in blocks}) == 1
    gap = (blocks[1].t_start_utc - blocks[0].t_end_utc).to_value(u.s)
    assert acc["idle_s"] == pytest.approx(gap, abs=1e-3)
    assert acc["overhead_s"] == 300.0


def _main(
    args: list[str], monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> tuple[int, str]:
    """Run the console entry point (one-line errors, exit codes): (exit code, stderr)."""
    from ucbplan.cli import app as app_module

    monkeypatch.setattr(sys, "argv", ["ucbplan", *args])
    code = 0
    try:
        app_module.main()
    except SystemExit as exc:
        code = int(exc.code or 0)
    return code, capsys.readouterr().err


def _json(args: list[str]) -> Any:
    import json

    res = CliRunner().invoke(app, [*args, "--format", "json"])
    assert res.exit_code == 0, res.output
    return json.loads(res.stdout)


def test_json_carries_visits_and_time_accounting() -> None:
    doc = _json(DONE_WHEN)
    assert len(doc["rows"]) == doc["meta"]["time_accounting"]["total"]["exposures"]
    assert doc["meta"]["visits"][0]["exposures"] == len(doc["rows"])
    assert all(r["visit_id"] == doc["meta"]["visits"][0]["visit_id"] for r in doc["rows"])


def test_goal_sigma_k_plans_n_quadrature_spectra() -> None:
    # N = σ_v²/(σ_K² Λ_K²) with equal numbers at u = 0 and π, equal σ_v (issue 9, done-when).
    args = [*DONE_WHEN, "--nights", "3", "--goal", "sigma_K=1km/s"]
    doc = _json(args)
    rows = doc["rows"]
    lam = rows[0]["lambda_k"]
    expected = 5.0**2 / (1.0**2 * lam**2)
    assert len(rows) == pytest.approx(expected, rel=0.10)
    at_zero = sum(1 for r in rows if abs(r["u_star_rad"]) < 1e-9)
    assert at_zero == len(rows) - at_zero
    assert doc["meta"]["time_accounting"]["total"]["exposures"] == len(rows)


def test_goal_out_of_reach_is_one_line_and_writes_nothing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "p.ecsv"
    code, err = _main(
        [*DONE_WHEN, "--goal", "sigma_K=0.2km/s", "-o", str(out)], monkeypatch, capsys
    )
    assert code == 2
    msg = err.strip().splitlines()[-1]
    assert "needs 702 spectra" in msg and "add nights or relax the goal" in msg
    assert not out.exists()


@pytest.mark.parametrize(
    ("extra", "needle"),
    [
        (["--visit", "5min"], "--visit"),
        (["--visit", "an hour"], "--visit: expected a duration"),
        (["--instrument", "nosuch"], "unknown instrument"),
        (["--exptime", "150"], "--min-lambda-k"),
        (["--cadence", "sometimes"], "--cadence"),
        (["--instrument", "uves"], "pass --overhead SECONDS"),
        (["--goal", "q=1%"], "double-lined (SB2)"),
    ],
)
def test_bad_visit_input_is_one_line(
    extra: list[str],
    needle: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    out = tmp_path / "p.ecsv"
    code, err = _main([*DONE_WHEN, *extra, "-o", str(out)], monkeypatch, capsys)
    assert code == 2, err
    assert needle in err and len(err.strip().splitlines()) == 1
    assert len(err) < 400
    assert not out.exists()


def test_instrument_without_sigma_ref_names_sigma_v(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    args = [a for a in DONE_WHEN if a not in ("--sigma-v", "5")]
    code, err = _main(args, monkeypatch, capsys)
    assert code == 2
    assert "pass --sigma-v" in err and len(err.strip().splitlines()) == 1


def test_default_exposure_capped_at_floor_and_allow_smeared() -> None:
    settings = plan_settings(visit="1h", sigma_v_kms=5.0, min_lambda_k=0.99)
    run = plan_files([HM], first_night="2040-02-15", site="paranal", settings=settings)
    assert any("capped" in w for w in run.result.warnings)
    lam = {b.lambda_k for b in run.result.blocks}
    assert min(lam) >= 0.99 and min(lam) < 0.99 + 1e-4  # the longest exposure that keeps it
    smeared = plan_settings(visit="1h", sigma_v_kms=5.0, exptime_s=150.0, allow_smeared=True)
    run = plan_files([HM], first_night="2040-02-15", site="paranal", settings=smeared)
    assert run.result.blocks[0].lambda_k < 0.9


def test_phase_locked_cadence_hits_consecutive_anchors() -> None:
    settings = plan_settings(
        visit="1h", sigma_v_kms=5.0, cadence="phase-locked", readout_s=20.0, allow_smeared=True
    )
    run = plan_files([HM], first_night="2040-02-15", site="paranal", settings=settings)
    blocks = run.result.blocks
    hm = load_target(HM)
    assert len(blocks) >= 19  # (3600 - 409 - 160.8) // 160.8 + 1 = 19.9
    for a, b in itertools.pairwise(blocks):
        step = (b.t_mid_utc - a.t_mid_utc).to_value(u.s)
        assert step == pytest.approx(hm.period_s / 2, abs=0.1)  # the next anchor, no waiting
        assert abs(abs(a.u_star_rad - b.u_star_rad) - math.pi) < 1e-9
        assert (b.t_start_utc - a.t_end_utc).to_value(u.s) >= 20.0 - 0.1
    te = run.result.exposures[hm.name]
    assert te.duty_cycle == pytest.approx(te.plan.exptime_s / (hm.period_s / 2))
    assert te.duty_cycle > 0.85
    assert run.meta()["planning"]["targets"][hm.name]["duty_cycle"] == pytest.approx(
        te.duty_cycle, abs=1e-6
    )


def test_sigma_v_per_exposure_scales_with_instrument(tmp_path: Path) -> None:
    table = tmp_path / "inst.yaml"
    table.write_text(
        "instruments:\n"
        "  testspec:\n"
        "    telescope: test\n"
        "    sites: [paranal]\n"
        "    acquisition_s: 300\n"
        "    readout_s: 30\n"
        "    min_exptime_s: 1\n"
        "    extinction_k: 0.2\n"
        "    extinction_band: V\n"
        "    sigma_ref: {sigma_v_kms: 10, mag: 20, band: V, exptime_s: 600}\n"
    )
    # the law is checked at a given exposure time (without one, the time is chosen)
    settings = plan_settings(
        instrument="testspec", instruments_file=table, visit="1h", exptime_s=60.0
    )
    run = plan_files([HM], first_night="2040-02-15", site="paranal", settings=settings)
    for b in run.result.blocks:
        # V = 21.1, 60 s: 10 km/s x 10^(0.2 x 1.1) x sqrt(10) x 10^(0.2 x 0.2 (X - 1))
        want = 10 * 10 ** (0.2 * 1.1) * math.sqrt(10.0) * 10 ** (0.04 * (b.airmass - 1))
        assert b.sigma_v_kms == pytest.approx(want, rel=1e-9)
    assert run.visits()[0].overhead_s == pytest.approx(300 + 30 * len(run.result.blocks))


def _printed(run: Any, monkeypatch: pytest.MonkeyPatch, width: int = 100, **kw: bool) -> str:
    import io

    from ucbplan.cli import _plan_view as plan_cli
    from ucbplan.cli._console import _Console

    buf = io.StringIO()
    console = _Console(width=width, file=buf, no_color=True)
    console.fold = False  # messages one line each, as a log has them
    monkeypatch.setattr(plan_cli, "err_console", console)
    plan_cli.report(run, **kw)
    return buf.getvalue()


def test_plan_table_fits_100_columns(monkeypatch: pytest.MonkeyPatch) -> None:
    settings = plan_settings(visit="1h", sigma_v_kms=5.0, sessions_per_night=2, k_eff_kms=400)
    run = plan_files([HM, FID], first_night="2040-02-15", site="paranal", settings=settings)
    text = _printed(run, monkeypatch, verbose=True)
    lines = [ln for ln in text.splitlines() if ln.startswith(("│", "┃"))]
    assert len(lines) > len(run.result.blocks)  # every exposure printed ...
    table = [ln for ln in text.splitlines() if ln[:1] in "│┃┏┡└━┌"]
    assert all(len(ln) <= 100 for ln in table)  # the warnings above are soft-wrapped text
    assert "…" not in "\n".join(table)  # ... and no cell cut
    for b in run.result.blocks:
        assert f"{b.t_start_utc.iso[:19]}–{b.t_end_utc.iso[11:19]}" in text
    wide = _printed(run, monkeypatch, width=250, verbose=True, wide=True)
    assert "local mid" in wide and "local mid" not in text


def test_long_plan_prints_a_per_night_summary(monkeypatch: pytest.MonkeyPatch) -> None:
    settings = plan_settings(visit="1h", sigma_v_kms=5.0)
    run = plan_files([HM], first_night="2040-02-15", n_nights=4, site="paranal", settings=settings)
    text = _printed(run, monkeypatch)
    assert "per night" in text and "--verbose" in text
    assert run.result.blocks[0].t_start_utc.iso[:19] not in text  # no exposure rows
    for night in ("2040-02-15", "2040-02-18"):
        assert night in text
    full = _printed(run, monkeypatch, verbose=True)
    assert run.result.blocks[0].t_start_utc.iso[:19] in full


def test_phase_locked_quadrature_and_conjunction_every_quarter_orbit() -> None:
    settings = plan_settings(
        visit="30min",
        sigma_v_kms=5.0,
        cadence="phase-locked",
        readout_s=45.0,
        mode="quadrature+conjunction",
    )
    run = plan_files([HM], first_night="2040-02-15", site="paranal", settings=settings)
    hm = load_target(HM)
    blocks = run.result.blocks
    assert len(blocks) >= 15
    quarter = hm.period_s / 4
    for a, b in itertools.pairwise(blocks):
        step = (b.t_mid_utc - a.t_mid_utc).to_value(u.s)
        assert step == pytest.approx(quarter, abs=0.1)
        assert _wrap(b.u_star_rad - a.u_star_rad - math.pi / 2) == pytest.approx(0.0, abs=1e-9)
    for b in blocks:
        assert abs(_wrap(_u_back(hm, b.t_mid_utc) - b.u_star_rad)) < 1e-6
    te = run.result.exposures[hm.name]
    assert te.plan.exptime_s + 45.0 <= quarter
    assert te.duty_cycle == pytest.approx(te.plan.exptime_s / quarter)


def test_json_plan_reads_back(tmp_path: Path) -> None:
    out = tmp_path / "plan.json"
    res = CliRunner().invoke(app, [*DONE_WHEN, "-o", str(out)])
    assert res.exit_code == 0, res.output
    table = read_blocks(out)
    assert len(table) == 20 and "visit_id" in table.colnames


def test_goal_with_instrument_sigma_per_exposure(tmp_path: Path) -> None:
    """A goal counts each exposure's own σ_v (airmass, exposure time) in its Fisher sum
    (issue 20): the planned information reaches the goal, and one anchor pattern fewer would
    not."""
    table = tmp_path / "inst.yaml"
    table.write_text(
        "instruments:\n"
        "  testspec:\n"
        "    telescope: test\n"
        "    sites: [paranal]\n"
        "    acquisition_s: 300\n"
        "    readout_s: 30\n"
        "    min_exptime_s: 1\n"
        "    extinction_k: 0.2\n"
        "    extinction_band: V\n"
        "    sigma_ref: {sigma_v_kms: 3, mag: 20, band: V, exptime_s: 600}\n"
    )
    settings = plan_settings(
        instrument="testspec", instruments_file=table, visit="1h", goal="sigma_K=3km/s",
        exptime_s=60.0,
    )  # fmt: skip
    run = plan_files([HM], first_night="2040-02-15", n_nights=2, site="paranal", settings=settings)
    blocks = run.result.blocks
    for b in blocks:  # V = 21.1, 60 s, extinction 0.2 mag/airmass at the block's airmass
        want = 3 * 10 ** (0.2 * 1.1) * math.sqrt(10.0) * 10 ** (0.04 * (b.airmass - 1))
        assert b.sigma_v_kms == pytest.approx(want, rel=1e-9)
    info = sum((b.lambda_k * math.cos(b.u_star_rad) / b.sigma_v_kms) ** 2 for b in blocks)
    assert info >= 1 / 3.0**2 * (1 - 1e-9)
    by_time = sorted(blocks, key=lambda b: b.t_mid_utc.jd)
    short = sum((b.lambda_k / b.sigma_v_kms) ** 2 for b in by_time[:-2])
    assert short < 1 / 3.0**2


@pytest.mark.slow
@settings(max_examples=6, deadline=None)
@given(
    visit_min=st.integers(15, 120),
    exptime=st.floats(10.0, 80.0),
    readout=st.floats(0.0, 60.0),
    acq=st.floats(0.0, 600.0),
)
def test_visit_invariants_hold_for_any_visit(
    visit_min: int, exptime: float, readout: float, acq: float
) -> None:
    if acq + exptime + readout > visit_min * 60:
        return
    settings = plan_settings(
        visit=f"{visit_min}min",
        exptime_s=exptime,
        readout_s=readout,
        overhead_s=acq,
        sigma_v_kms=5.0,
        sessions_per_night=3,
    )
    run = plan_files([HM], first_night="2040-02-15", site="paranal", settings=settings)
    blocks = run.result.blocks
    assert blocks
    for a, b in itertools.pairwise(blocks):
        gap = (b.t_start_utc - a.t_end_utc).to_value(u.s)
        assert gap >= (readout if a.visit_id == b.visit_id else readout + acq) - 0.1
    for v in run.visits():
        assert v.wall_s <= visit_min * 60 + 1e-6
        assert v.idle_s >= 0 and v.overhead_s == pytest.approx(acq + v.exposures * readout)
        assert v.shutter_s == pytest.approx(v.exposures * exptime)
    total = run.accounting()["total"]
    assert total["exposures"] == len(blocks)


def test_cli_default_exposure_is_not_explicit() -> None:
    # without --exptime the CLI lets ucbplan choose: phase-locked works, the floor caps
    doc = _json([*DONE_WHEN, "--cadence", "phase-locked"])
    exptime = {r["exptime_s"] for r in doc["rows"]}
    assert len(exptime) == 1 and 80.0 < exptime.pop() < 81.0  # capped at Lambda_K = 0.9
    assert doc["meta"]["planning"]["cadence"] == "phase-locked"
    capped = _json([*DONE_WHEN, "--min-lambda-k", "0.99"])
    assert capped["rows"][0]["exptime_s"] < 60.0  # the default 60 s, capped
    res = CliRunner().invoke(app, [*DONE_WHEN, "--min-lambda-k", "0.99", "--exptime", "60"])
    assert res.exit_code != 0 and "--min-lambda-k" in cli_message(str(res.exception))  # given


def test_an_acquisition_never_starts_inside_the_zenith_hole(tmp_path: Path) -> None:
    """Issue 33: the acquisition was checked against night and airmass only, so a visit could
    start slewing to a target inside the zenith hole (87.2 deg with a 3-deg hole). A target that
    transits 0.1 deg from the zenith at Paranal: astropy's altitude over every acquisition
    (sampled every 10 s) stays out of the hole."""
    text = HM.read_text(encoding="utf-8").replace('dec: "+15d27m30s"', 'dec: "-24d31m00s"')
    target = tmp_path / "zenith.yaml"
    target.write_text(text, encoding="utf-8")
    settings = plan_settings(visit="30min", zenith_hole_deg=3.0, sigma_v_kms=5.0)
    run = plan_files([target], first_night="2040-02-15", n_nights=2, site="paranal",
                     settings=settings)  # fmt: skip
    starts: dict[str, Time] = {}
    for b in run.result.blocks:
        if b.session_id not in starts or b.t_start_utc < starts[b.session_id]:
            starts[b.session_id] = b.t_start_utc
    assert len(starts) >= 2
    site = get_site("paranal")
    coord = load_target(target).coord
    for first in starts.values():
        t = first - np.arange(0.0, settings.overhead_s + 1.0, 10.0) * u.s
        with offline():
            alt = coord.transform_to(AltAz(obstime=t, location=site.location)).alt.deg
        assert np.all(alt < 90.0 - 3.0 + 0.01), (first.iso, float(alt.max()))


@pytest.mark.parametrize(
    ("goal", "needle"),
    [
        (
            "sigma_K=3km/s",
            "visits as long as the nights allow (9.53 h) reach it: raise `max_visit`",
        ),
        ("sigma_K=2km/s", "882 in visits as long as the nights allow (9.53 h; σ(K) ≤ 2.169"),
    ],
)
def test_a_goal_shortfall_gives_the_capacity_at_the_longest_visit(goal: str, needle: str) -> None:
    """Issue 33: "the nights allow 294 spectra (3.76 km/s); add nights" was the capacity of
    2-h visits (the default max_visit); the same week holds 882 in visits as long as its nights
    (9.53 h of nautical night). The message gives both and names max_visit."""
    from ucbplan.errors import InputError

    kw: dict[str, Any] = dict(sigma_v_kms="30km/s@300s", readout_s=45.0, overhead_s=480.0)
    with pytest.raises(InputError) as exc:
        plan_files([HM], first_night="2040-02-15", n_nights=7, site="paranal",
                   settings=plan_settings(goal=goal, **kw))  # fmt: skip
    text = str(exc.value)
    assert "the nights given allow 294 in visits of at most 2 h (`max_visit`;" in text, text
    assert needle in text and "\n" not in text and len(text) < 390, text
    if goal == "sigma_K=3km/s":  # and planned with longer visits the goal holds
        plan_files([HM], first_night="2040-02-15", n_nights=7, site="paranal",
                   settings=plan_settings(goal=goal, max_visit="6h", **kw))  # fmt: skip
