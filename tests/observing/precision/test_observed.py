"""``plan --observed``: spectra already taken count toward the goal (issue 32, items 1 and 3).

Base case: HM Cnc (simulated) at Paranal, ``--sigma-v 30km/s@300s --visit 1h --instrument
xshooter-vis``; the observed files are the plan of 2040-02-15 written with ``-o`` and given a
``status`` column (or turned into a velocities file), replanned from 2040-02-16.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from astropy.table import Table
from astropy.time import Time
from support.observed import (
    CLI_BASE,
    NAME,
    TARGET,
    brute_force_info,
    plan_base,
    with_status,
)
from typer.testing import CliRunner

from ucbplan.cli.app import app
from ucbplan.core.phase import arg_latitude
from ucbplan.observing.precision.observed import (
    ObservedSpectra,
    observed_fisher,
    observed_information,
    sigma_v_ratio,
)
from ucbplan.observing.schedule.exposure import exposure_sigma_v
from ucbplan.targets import load_target


def test_information_of_random_spectra_equals_brute_force_fisher() -> None:
    rng = np.random.default_rng(32)
    target = load_target(TARGET)
    tau = rng.uniform(0.0, 3.0e7, 23)
    exptime = rng.uniform(20.0, 200.0, 23)
    sigma = rng.uniform(10.0, 50.0, 23)
    x = target.params.n_bar * exptime / 2.0
    spectra = ObservedSpectra(NAME, tau, np.sin(x) / x, sigma, sigma * np.nan)
    got = observed_information(spectra, target.params)
    assert got == pytest.approx(brute_force_info(tau, exptime, sigma), rel=1e-12)


@pytest.mark.parametrize("one_anchor", [False, True])
def test_joint_information_with_planned_spectra_equals_brute_force_fisher(one_anchor: bool) -> None:
    """Taken spectra (random, or all at one epoch: nothing alone) and balanced planned ones
    (pairs at u = 0, π, one σ_v per pair) share one γ: ObservedFisher.joint equals 1/σ_K² of
    the stacked design matrix inverted with numpy (1e-9: float rounding only), and needed()
    inverts joint()."""
    rng = np.random.default_rng(7)
    target = load_target(TARGET)
    tau = np.full(6, 2.0e6) if one_anchor else rng.uniform(0.0, 3.0e7, 6)
    sigma = rng.uniform(10.0, 40.0, 6)
    taken = ObservedSpectra(NAME, tau, np.full(6, 0.9), sigma, sigma * np.nan)
    lam, pair_sigma = 0.8, rng.uniform(15.0, 30.0, 5)
    g_plan = np.tile([lam, -lam], 5)
    s_plan = np.repeat(pair_sigma, 2)
    fisher = observed_fisher(taken, target.params, ratio=1.0 / lam**2)
    g_taken = 0.9 * np.cos(arg_latitude(target.params, tau))
    a = np.column_stack([np.ones(16), np.concatenate([g_taken, g_plan])])
    w = np.diag(1.0 / np.concatenate([sigma, s_plan]) ** 2)
    brute = 1.0 / float(np.linalg.inv(a.T @ w @ a)[1, 1])
    planned = float(np.sum((g_plan / s_plan) ** 2))
    assert fisher.joint(planned) == pytest.approx(brute, rel=1e-9)
    assert (fisher.alone == 0.0) is one_anchor
    goal = 3.0 * brute
    assert fisher.joint(fisher.needed(goal)) == pytest.approx(goal, rel=1e-9)


def test_a_degenerate_or_empty_set_collects_nothing() -> None:
    target = load_target(TARGET)
    empty = np.zeros(0)
    assert (
        observed_information(ObservedSpectra(NAME, empty, empty, empty, empty), target.params) == 0
    )
    # all spectra at one phase: γ and K cannot be told apart
    tau = np.full(3, 1.0e6)
    one = ObservedSpectra(NAME, tau, np.full(3, 0.9), np.full(3, 5.0), tau * np.nan)
    assert observed_information(one, target.params) == 0.0


def test_sigma_v_ratio_is_the_median_of_measured_over_predicted() -> None:
    assert sigma_v_ratio([1.0, 2.6, 3.9, 9.0], [1.0, 2.0, 3.0, np.nan]) == pytest.approx(1.3)
    assert math.isnan(sigma_v_ratio([1.0], [np.nan]))


def test_collected_information_of_a_blocks_table_equals_brute_force(
    first_night: Path, tmp_path: Path
) -> None:
    obs = with_status(first_night, tmp_path / "obs.ecsv")
    p = plan_base("2040-02-16", 2, goal="sigma_K=13km/s", observed=obs)
    goal = p.run.result.goals[NAME]
    table = Table.read(obs, format="ascii.ecsv")
    target = load_target(TARGET)
    tau = (Time(list(table["t_mid_tdb_bary"]), scale="tdb") - target.t_ref).to_value("s")
    want = brute_force_info(tau, np.asarray(table["exptime_s"]), np.asarray(table["sigma_v_kms"]))
    assert goal.collected_spectra == len(table) == 14
    assert goal.collected_info == pytest.approx(want, rel=1e-12)
    # each spectrum's own u from the ephemeris falls on the anchor it was planned at (±1e-4 rad)
    u = arg_latitude(target.params, tau)
    assert np.allclose(np.cos(u), np.cos(np.asarray(table["u_star_rad"])), atol=1e-8)


def test_velocities_file_gives_the_information_of_the_blocks_table(
    first_night: Path, tmp_path: Path
) -> None:
    table = Table.read(first_night, format="ascii.ecsv")
    jd = Time(list(table["t_mid_tdb_bary"]), scale="tdb").jd
    vel = tmp_path / "rv.csv"
    lines = ["bjd_tdb,exptime_s,v,sigma_v"] + [
        f"{float(t)!r},{float(e)!r},0.0,{float(s)!r}"
        for t, e, s in zip(jd, table["exptime_s"], table["sigma_v_kms"], strict=True)
    ]
    vel.write_text("\n".join(lines) + "\n", encoding="utf-8")
    from_rv = plan_base("2040-02-16", 2, goal="sigma_K=13km/s", observed=vel)
    from_blocks = plan_base(
        "2040-02-16", 2, goal="sigma_K=13km/s", observed=with_status(first_night, tmp_path / "b")
    )
    a, b = (x.run.result.goals[NAME].collected_info for x in (from_rv, from_blocks))
    assert a == pytest.approx(b, rel=1e-6)  # bjd as a float JD: ~20 µs, far below an orbit


def test_csv_blocks_table_counts_like_the_ecsv(first_night: Path, tmp_path: Path) -> None:
    status = ["taken", "taken", "missed"] * 4 + ["taken", "skipped"]
    ecsv = with_status(first_night, tmp_path / "obs.ecsv", status=status)
    csv = tmp_path / "obs.csv"
    Table.read(ecsv, format="ascii.ecsv").write(csv, format="ascii.csv")
    a, b = (
        plan_base("2040-02-16", 2, goal="sigma_K=13km/s", observed=f).run.result.goals[NAME]
        for f in (ecsv, csv)
    )
    assert a.collected_spectra == b.collected_spectra == 9  # only the taken rows
    assert a.collected_info > 0 and a.collected_info == pytest.approx(b.collected_info, rel=1e-12)


def test_goal_already_reached_plans_nothing_and_says_so(first_night: Path, tmp_path: Path) -> None:
    obs = with_status(first_night, tmp_path / "obs.ecsv")
    out = tmp_path / "rest.ecsv"
    args = [*CLI_BASE, "--night", "2040-02-16", "--goal", "sigma_K=20km/s", "--observed", str(obs)]
    result = CliRunner().invoke(app, [*args, "-o", str(out)])
    assert result.exit_code == 0, result.output
    lines = [ln for ln in result.output.splitlines() if "already reached" in ln]
    assert len(lines) == 1 and "14 spectra taken" in lines[0] and "no visits planned" in lines[0]
    assert len(Table.read(out, format="ascii.ecsv")) == 0


def test_half_the_information_observed_plans_about_half_the_spectra(
    first_night: Path, tmp_path: Path
) -> None:
    obs = with_status(first_night, tmp_path / "obs.ecsv")
    taken = plan_base("2040-02-16", 2, goal="sigma_K=13km/s", observed=obs)
    collected = taken.run.result.goals[NAME].collected_info
    goal_kms = (2.0 * collected) ** -0.5  # the spectra taken hold half of what it needs
    text = f"sigma_K={goal_kms:.6f}km/s"
    fresh = plan_base("2040-02-16", 2, goal=text).run.result.goals[NAME]
    rest = plan_base("2040-02-16", 2, goal=text, observed=obs)
    plan = rest.run.result.goals[NAME]
    assert plan.info_needed == pytest.approx(collected, rel=1e-6)
    assert abs(plan.n_spectra - fresh.n_spectra / 2) <= 0.15 * fresh.n_spectra
    # the σ_K it promises: the spectra taken and the planned rows together, Fisher-summed
    t = rest.table
    lam_cos = np.asarray(t["lambda_k"]) * np.cos(np.asarray(t["u_star_rad"]))
    planned = float(np.sum((lam_cos / np.asarray(t["sigma_v_kms"])) ** 2))
    combined = (collected + planned) ** -0.5
    assert plan.expected == pytest.approx(combined, rel=0.02)
    assert combined <= goal_kms * 1.0000001


def test_sigma_v_worse_than_the_law_is_detected_and_rescales_it(
    first_night: Path, tmp_path: Path
) -> None:
    obs = with_status(first_night, tmp_path / "obs.ecsv", sigma_v_kms=lambda c: 1.3 * c)
    p = plan_base("2040-02-16", 2, goal="sigma_K=13km/s", observed=obs)
    assert p.run.settings.sigma_v_scale == pytest.approx(1.3, rel=1e-6)
    kept = plan_base("2040-02-16", 2, goal="sigma_K=13km/s", observed=obs, sigma_v_scale=1)
    assert kept.run.settings.sigma_v_scale == 1.0
    # the remainder's σ_v: the law × 1.3, row by row (its exposure time and airmass)
    law = dataclasses.replace(p.run.settings, sigma_v_scale=1.0)
    t, target = p.table, p.run.targets[0]
    assert len(t) > 0
    for te, x, sv in zip(t["exptime_s"].value, t["airmass"], t["sigma_v_kms"].value, strict=True):
        assert sv == pytest.approx(1.3 * float(exposure_sigma_v(target, law, te, x)), rel=1e-6)
    args = [*CLI_BASE, "--night", "2040-02-16", "--nights", "2", "--goal", "sigma_K=13km/s"]
    result = CliRunner().invoke(app, [*args, "--observed", str(obs)])
    assert result.exit_code == 0, result.output
    note = [ln for ln in result.output.splitlines() if ln.startswith("observed:")]
    assert len(note) == 1 and "= 1.3 over 14 spectra" in note[0] and "× 1.3" in note[0]
    # per target: collected so far, still needed, then the plan for the rest
    lines = [ln for ln in result.output.splitlines() if ln.startswith("goal σ(K) ≤ 13 km/s")]
    assert len(lines) == 2 and "collected so far σ_K = " in lines[0]
    assert "from the 14 spectra taken; still needed" in lines[0] and "spectra in" in lines[1]


def test_planned_sigma_v_read_back_is_not_called_measured(
    first_night: Path, tmp_path: Path
) -> None:
    """A blocks table (or log) whose σ_v are the plan's own says so, instead of reporting a
    "measured/predicted" ratio of 1 that no measurement made."""
    obs = with_status(first_night, tmp_path / "obs.ecsv")
    args = [*CLI_BASE, "--night", "2040-02-16", "--nights", "2", "--goal", "sigma_K=13km/s"]
    result = CliRunner().invoke(app, [*args, "--observed", str(obs)])
    assert result.exit_code == 0, result.output
    note = [ln for ln in result.output.splitlines() if ln.startswith("observed:")]
    assert len(note) == 1 and "14 spectra carry the plan's σ_v, not measured ones" in note[0]
    assert "measured/predicted" not in note[0] and len(note[0]) <= 100
    # one measured value among them: a ratio again
    edited = with_status(first_night, tmp_path / "one.ecsv", sigma_v_kms=lambda c: c * 1.02)
    result = CliRunner().invoke(app, [*args, "--observed", str(edited)])
    assert "median measured/predicted σ_v = 1.02" in result.output
