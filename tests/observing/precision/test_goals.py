"""Goal-driven plans (issue 9 item 3): goal parsing, Fisher-matrix N, time budget, shortfall."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ucbplan.errors import InputError, UcbplanError
from ucbplan.observing.precision.goals import (
    Goal,
    anchor_phases,
    parse_goal,
    shortfall,
    sigma_k_per_pattern,
    spectra_for_goal,
    time_budget,
)

K1, K2 = 585.3, 712.6  # HM Cnc-like [km/s]
PB = 321.5  # [s]


@pytest.mark.parametrize(
    ("text", "goal"),
    [
        ("sigma_K=2km/s", Goal("sigma_K", 2.0, False, "sigma_K=2km/s")),
        ("sigma_k=2", Goal("sigma_K", 2.0, False, "sigma_k=2")),
        ("K1=1%", Goal("K1", 0.01, True, "K1=1%")),
        ("q=1%", Goal("q", 0.01, True, "q=1%")),
        ("q=0.005", Goal("q", 0.005, False, "q=0.005")),
        ("M1=0.01Msun", Goal("M1", 0.01, False, "M1=0.01Msun")),
        (" M2 = 2 % ", Goal("M2", 0.02, True, "M2 = 2 %")),
    ],
)
def test_parse_goal(text: str, goal: Goal) -> None:
    assert parse_goal(text) == goal


@pytest.mark.parametrize(
    "text",
    [
        "",
        "sigma_K",
        "x=1%",
        "K1=-1%",
        "K1=0km/s",
        "M1=1km/s",
        "sigma_K=1%",
        "q=1Msun",
        "K1=150%",
        "K1=1e999km/s",
        "K1=nan",
    ],
)
def test_parse_goal_errors_one_line(text: str) -> None:
    with pytest.raises(InputError) as err:
        parse_goal(text)
    msg = str(err.value)
    assert msg.startswith("goal: ") and "\n" not in msg and len(msg) < 400


@settings(max_examples=150, deadline=None)
@given(st.text(max_size=60))
def test_parse_goal_fuzz(text: str) -> None:
    try:
        parse_goal(text)
    except UcbplanError as exc:
        assert "\n" not in str(exc) and len(str(exc)) < 400


def test_fisher_matrix_of_equal_quadratures_reduces_to_closed_form() -> None:
    lam, sv = 0.93, 7.0
    for n in (2, 6, 40):
        phases = [0.0, math.pi] * (n // 2)
        design = np.column_stack([np.ones(n), lam * np.cos(phases)])
        cov = np.linalg.inv(design.T @ design / sv**2)
        closed = sv / (math.sqrt(n) * lam)
        assert math.sqrt(cov[1, 1]) == pytest.approx(closed, rel=1e-12)
        assert sigma_k_per_pattern(phases, lam, sv) == pytest.approx(closed, rel=1e-12)


@pytest.mark.parametrize(
    ("sv", "sk", "lam"), [(20.0, 1.0, 0.95), (10.0, 0.3, 0.9), (5.0, 2.0, 1.0)]
)
def test_acceptance_goal_sigma_k_within_ten_percent_of_closed_form(
    sv: float, sk: float, lam: float
) -> None:
    # Issue 9 "Done when": --goal sigma_K=... plans N within 10 % of σ_v²/(σ_K² Λ_K²).
    plan = spectra_for_goal(
        parse_goal(f"sigma_K={sk}km/s"), K1=K1, K2=None, sigma_v_kms=sv, lambda_k=lam
    )
    target = sv**2 / (sk**2 * lam**2)
    assert plan.n_spectra % 2 == 0 and plan.n_spectra >= target
    assert plan.n_spectra == 2 * math.ceil(target / 2)
    assert plan.n_spectra <= 1.10 * target or plan.n_spectra - target < 2
    assert plan.per_anchor == (("quadrature", plan.n_spectra),)
    assert plan.expected <= sk


def _mc_sigma_k(phases: np.ndarray, lam: float, sv: float, reps: int, seed: int) -> float:
    rng = np.random.default_rng(seed)
    design = np.column_stack([np.ones(len(phases)), lam * np.cos(phases)])
    truth = design @ np.array([30.0, K1])
    vel = truth + sv * rng.standard_normal((reps, len(phases)))
    coef, *_ = np.linalg.lstsq(design, vel.T, rcond=None)
    return float(np.std(coef[1], ddof=1))


@pytest.mark.parametrize("anchors", [("quadrature",), ("quadrature", "conjunction")])
def test_fisher_n_against_monte_carlo_fits(anchors: tuple[str, ...]) -> None:
    sv, lam, goal = 10.0, 0.9, 2.0
    plan = spectra_for_goal(
        parse_goal(f"sigma_K={goal}km/s"),
        K1=K1,
        K2=None,
        sigma_v_kms=sv,
        lambda_k=lam,
        anchors=anchors,
    )
    pattern = np.array([u for _, u in anchor_phases(anchors)])
    phases = np.tile(pattern, plan.cycles)
    assert len(phases) == plan.n_spectra
    measured = _mc_sigma_k(phases, lam, sv, reps=4000, seed=9)
    assert measured == pytest.approx(plan.sigma_K1_kms, rel=0.05)
    assert measured == pytest.approx(goal, rel=0.05)


def test_quadrature_plus_conjunction_needs_twice_the_spectra() -> None:
    goal = parse_goal("sigma_K=1km/s")
    quad = spectra_for_goal(goal, K1=K1, K2=None, sigma_v_kms=10.0, lambda_k=1.0)
    both = spectra_for_goal(
        goal, K1=K1, K2=None, sigma_v_kms=10.0, lambda_k=1.0, anchors=("quadrature", "conjunction")
    )
    assert quad.n_spectra == 100 and both.n_spectra == 200
    assert dict(both.per_anchor) == {"quadrature": 100, "conjunction": 100}


def test_conjunctions_alone_cannot_measure_k() -> None:
    with pytest.raises(InputError, match="quadrature"):
        spectra_for_goal(
            parse_goal("K1=1%"),
            K1=K1,
            K2=None,
            sigma_v_kms=10.0,
            lambda_k=0.9,
            anchors=("conjunction",),
        )


def test_relative_and_derived_goals_propagate() -> None:
    sv, lam = 10.0, 0.9
    kw = {"K1": K1, "K2": K2, "sigma_v_kms": sv, "lambda_k": lam}
    k1 = spectra_for_goal(parse_goal("K1=0.1%"), **kw)
    assert k1.expected == pytest.approx(k1.sigma_K1_kms / K1) and k1.expected <= 1e-3
    assert k1.n_spectra == 2 * math.ceil((sv / (lam * 1e-3 * K1)) ** 2 / 2)
    q = spectra_for_goal(parse_goal("q=0.1%"), **kw)
    r = math.hypot(q.sigma_K1_kms / K1, q.sigma_K2_kms / K2)
    assert q.expected == pytest.approx(r) and r <= 1e-3
    m1 = spectra_for_goal(parse_goal("M1=0.1%"), **kw)
    s = K1 + K2
    rel = math.hypot(2 * m1.sigma_K1_kms / s, (1 / K2 + 2 / s) * m1.sigma_K2_kms)
    assert m1.expected == pytest.approx(rel) and rel <= 1e-3

    # M1 ∝ K2 (K1+K2)²: a finite-difference check of the propagation.
    def m1_of(a: float, b: float) -> float:
        return b * (a + b) ** 2

    d1 = (m1_of(K1 + 1e-3, K2) - m1_of(K1 - 1e-3, K2)) / 2e-3 / m1_of(K1, K2)
    d2 = (m1_of(K1, K2 + 1e-3) - m1_of(K1, K2 - 1e-3)) / 2e-3 / m1_of(K1, K2)
    assert d1 == pytest.approx(2 / s, rel=1e-6) and d2 == pytest.approx(1 / K2 + 2 / s, rel=1e-6)


def test_absolute_mass_goal_uses_kepler_masses() -> None:
    # HM Cnc-like: M1 ≈ 0.55 Msun for these K's and P_b at sin i = 1 (see docs/method.md).
    kw = {"K1": K1, "K2": K2, "sigma_v_kms": 10.0, "lambda_k": 0.9, "period_s": PB, "sin_i": 1.0}
    rel = spectra_for_goal(parse_goal("M1=1%"), **kw)
    ab = spectra_for_goal(parse_goal("M1=0.005Msun"), **kw)
    m1 = ab.expected / rel.expected * rel.cycles**0.5 / ab.cycles**0.5  # = M1 [Msun]
    assert 0.3 < m1 < 0.8
    with pytest.raises(InputError, match="P_b and sin i"):
        spectra_for_goal(parse_goal("M1=0.005Msun"), K1=K1, K2=K2, sigma_v_kms=10.0, lambda_k=0.9)


def test_sb1_target_refuses_sb2_goals() -> None:
    for text in ("q=1%", "M1=1%", "K2=1%"):
        with pytest.raises(InputError, match="SB2"):
            spectra_for_goal(parse_goal(text), K1=K1, K2=None, sigma_v_kms=10.0, lambda_k=0.9)


def test_time_budget_visits_overheads_idle() -> None:
    # 40 s + 45 s readout per exposure, quadratures P_b/2 = 160.75 s apart: step 160.75 s.
    tb = time_budget(
        32, period_s=PB, exptime_s=40.0, readout_s=45.0, acquisition_s=409.0, visit_s=3600.0
    )
    assert tb.step_s == pytest.approx(PB / 2)
    assert tb.spectra_per_visit == int((3600 - 409 - 85) // (PB / 2)) + 1 == 20
    assert tb.n_visits == 2
    assert tb.shutter_h == pytest.approx(32 * 40 / 3600)
    assert tb.overhead_h == pytest.approx((2 * 409 + 32 * 45) / 3600)
    assert tb.idle_h == pytest.approx((19 + 11) * (PB / 2 - 85) / 3600)
    assert tb.total_h == pytest.approx(tb.shutter_h + tb.overhead_h + tb.idle_h)
    assert 0 < tb.efficiency < 1
    # An exposure longer than P_b/2 waits for the next reachable quadrature: step = P_b.
    long = time_budget(4, period_s=PB, exptime_s=150.0, readout_s=20.0)
    assert long.step_s == pytest.approx(PB) and long.n_visits == 1
    assert long.idle_h == pytest.approx(3 * (PB - 170) / 3600)


def test_goal_plan_carries_time_budget() -> None:
    plan = spectra_for_goal(
        parse_goal("sigma_K=2km/s"),
        K1=K1,
        K2=K2,
        sigma_v_kms=10.0,
        lambda_k=0.9,
        period_s=PB,
        exptime_s=40.0,
        readout_s=45.0,
        acquisition_s=409.0,
        visit_s=3600.0,
    )
    assert plan.n_spectra == 32 and plan.time is not None and plan.time.n_visits == 2


def test_visit_too_short_is_one_line() -> None:
    with pytest.raises(InputError, match=r"^visit: ") as err:
        time_budget(
            4, period_s=PB, exptime_s=60.0, readout_s=45.0, acquisition_s=409.0, visit_s=300.0
        )
    assert "\n" not in str(err.value)


def test_shortfall_reports_unreachable_goal() -> None:
    plan = spectra_for_goal(
        parse_goal("sigma_K=2km/s"), K1=K1, K2=None, sigma_v_kms=10.0, lambda_k=0.9
    )
    assert shortfall(plan, available_spectra=plan.n_spectra) is None
    short = shortfall(plan, available_spectra=8)
    assert short is not None and short.needed_spectra == 32 and short.available_spectra == 8
    assert short.reachable == pytest.approx(10.0 / (0.9 * math.sqrt(8)))
    msg = short.message()
    assert "32" in msg and "8" in msg and "\n" not in msg and len(msg) < 400
    timed = dict(period_s=PB, exptime_s=40.0, readout_s=45.0, acquisition_s=409.0, visit_s=3600.0)
    assert shortfall(plan, available_hours=10.0, **timed) is None
    short_h = shortfall(plan, available_hours=1.0, **timed)
    assert short_h is not None and 0 < short_h.available_spectra < 32
    n = short_h.available_spectra
    assert time_budget(n, **timed).total_h <= 1.0 < time_budget(n + 2, **timed).total_h


def test_absurd_goal_refused() -> None:
    with pytest.raises(InputError, match="relax"):
        spectra_for_goal(
            parse_goal("sigma_K=1e-6km/s"), K1=K1, K2=None, sigma_v_kms=10.0, lambda_k=0.9
        )


@settings(max_examples=80, deadline=None)
@given(
    sv=st.floats(-1, 100) | st.just(math.nan),
    lam=st.floats(-0.5, 1.5) | st.just(math.nan),
    goal=st.floats(1e-3, 50),
)
def test_spectra_for_goal_fuzz(sv: float, lam: float, goal: float) -> None:
    try:
        plan = spectra_for_goal(
            Goal("sigma_K", goal, False, "g"), K1=K1, K2=K2, sigma_v_kms=sv, lambda_k=lam
        )
    except UcbplanError as exc:
        assert "\n" not in str(exc) and len(str(exc)) < 400
        return
    assert plan.n_spectra % 2 == 0 and plan.expected <= goal * (1 + 1e-9)


def test_repeated_anchor_names_count_once() -> None:
    assert anchor_phases(["quadrature", "Quadrature"]) == anchor_phases(["quadrature"])
    with pytest.raises(InputError, match=r"^anchor: "):
        anchor_phases(["opposition"])
    with pytest.raises(InputError, match="u=RADIANS"):
        anchor_phases(["u=abc"])


@pytest.mark.parametrize("goal", ["sigma_K=1e-300km/s", "K1=1e-300%", "sigma_K=1e-6km/s"])
def test_goal_magnitude_is_one_check_everywhere(goal: str) -> None:
    """Issue 33: a tiny goal overflowed (OverflowError) in plan and feasibility, and
    feasibility ran for minutes building 10¹² visits; one check (check_goal_spectra) refuses
    a goal needing more than MAX_SPECTRA spectra in the library (the API's path) and both
    commands, fast and in one line."""
    import time

    from support.cli import run_main

    from ucbplan.observing.precision.goals import goal_info_needed
    from ucbplan.targets import load_target

    hm = "catalogs/hm-cnc-simulated.yaml"
    assert goal_info_needed(parse_goal(goal), load_target(hm)) > 1e7  # inf, not an overflow
    with pytest.raises(InputError, match="would need more than 10000000 spectra"):
        spectra_for_goal(parse_goal(goal), K1=K1, K2=None, sigma_v_kms=30.0, lambda_k=0.9)
    night = ["--site", "paranal", "--night", "2040-02-15", "--visit", "1h"]
    for args in (
        ["plan", hm, *night, "--sigma-v", "30", "--goal", goal],
        ["plan", hm, *night, "--sigma-v", "30km/s@600s", "--readout", "30", "--goal", goal],
        ["feasibility", hm, "--sigma-v", "30km/s@600s", "--goal", goal],
    ):
        t0 = time.process_time()
        code, _, err = run_main(args)
        assert time.process_time() - t0 < 10.0, args
        assert code == 2 and err.count("\n") == 1, err
        assert "would need more than 10000000 spectra; relax the goal" in err, err
