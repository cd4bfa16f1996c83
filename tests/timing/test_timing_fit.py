"""``ucbplan ephemeris fit``: eclipse-time tables, cycle counting, the WLS fit and its outputs.

Truth: ZTF J1539-like ephemeris, P = 414.7915404 s, Ṗ = −2.373e-11, T0 = BJD_TDB 2458305.6827886,
σ = 2 s, 60 epochs over 5 years. Independent checks: the truth is re-expressed at the fit's
reference cycle here in exact decimal arithmetic, and the analytic covariance (Jᵀ W J)⁻¹ is built
here from the derivatives of t(n; T0, P, Ṗ), not from the fit's own design.
"""

from __future__ import annotations

import io
import json
import math
from decimal import Decimal, localcontext
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import typer
import yaml
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from support.bad_eclipse_times import BAD_FIT_OPTIONS, GOOD, times_table

from ucbplan.cli import timing as timing_cli
from ucbplan.cli._flags import cli_message
from ucbplan.core.timing_epochs import format_bjd, parse_epoch_label, seconds_to_jd
from ucbplan.errors import InputError, InputFileError, OutputExistsError, UcbplanError
from ucbplan.inputs import load_yaml
from ucbplan.timing import (
    count_cycles,
    fit_times,
    period_from_times,
    period_guess,
    read_initial,
    read_times,
)
from ucbplan.timing.fit import EphemerisFit

P_TRUE = Decimal("414.7915404")
PDOT_TRUE = Decimal("-2.373e-11")
T0_TRUE = Decimal("2458305.6827886")
SIGMA = 2.0
DAY = Decimal(86400)
CYCLES_5YR = int(5 * 365.25 * 86400 / 414.7915404)


# ---------------------------------------------------------------------------------------------
# helpers: exact truth and tables


def true_time(
    n: float,
    t0: Decimal = T0_TRUE,
    p: Decimal = P_TRUE,
    pdot: Decimal = PDOT_TRUE,
    pddot: Decimal = Decimal(0),
) -> Decimal:
    """t(n) as an exact JD (decimal arithmetic)."""
    with localcontext() as ctx:
        ctx.prec = 60
        dn = Decimal(repr(float(n)))
        sec = p * dn + p * pdot * dn * dn / 2 + p * p * pddot * dn**3 / 6
        return t0 + sec / DAY


def truth_at(
    m: int, t0: Decimal = T0_TRUE, p: Decimal = P_TRUE, pdot: Decimal = PDOT_TRUE
) -> tuple[Decimal, float, float]:
    """(T0, P, Ṗ) of the same quadratic re-expressed about cycle m."""
    with localcontext() as ctx:
        ctx.prec = 60
        pm = p + p * pdot * m
        return true_time(m, t0, p, pdot), float(pm), float(p * pdot / pm)


def simulate(
    seed: int, n: int = 60, sigma: float = SIGMA, secondary_every: int = 0, span: int = CYCLES_5YR
) -> tuple[np.ndarray, list[str], np.ndarray]:
    """Cycles, BJD strings (14 decimals) and noise of a simulated timing campaign."""
    rng = np.random.default_rng(seed)
    cycles = np.sort(rng.choice(span, n, replace=False)).astype(float) - span // 3
    if secondary_every:
        cycles[::secondary_every] += 0.5
    noise = rng.normal(0.0, sigma, n)
    bjd = [
        f"{true_time(c) + Decimal(repr(float(e))) / DAY:.14f}"
        for c, e in zip(cycles, noise, strict=True)
    ]
    return cycles, bjd, noise


def write_table(
    path: Path,
    bjd: list[str],
    sigma: float | list[float] = SIGMA,
    cycles: np.ndarray | None = None,
    secondary: np.ndarray | None = None,
) -> Path:
    sig = sigma if isinstance(sigma, list) else [sigma] * len(bjd)
    header = ["bjd_tdb", "sigma_s"]
    if secondary is not None:
        header.append("kind")
    if cycles is not None:
        header.append("cycle")
    lines = [",".join(header)]
    for i, b in enumerate(bjd):
        cells = [b, repr(float(sig[i]))]
        if secondary is not None:
            cells.append("secondary" if secondary[i] else "primary")
        if cycles is not None:
            cells.append(repr(float(cycles[i])))
        lines.append(",".join(cells))
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def t0_error_s(fit: EphemerisFit, t0_true: Decimal) -> float:
    return float((fit.t0_jd - t0_true) * DAY)


def pulls(fit: EphemerisFit) -> np.ndarray:
    t0_m, p_m, pdot_m = truth_at(fit.t0_cycle)
    sig = fit.sigmas
    return np.array(
        [
            t0_error_s(fit, t0_m) / sig[0],
            (fit.values[1] - p_m) / sig[1],
            (fit.values[2] - pdot_m) / sig[2],
        ]
    )


def analytic_sigmas(cycles: np.ndarray, sigma: np.ndarray, m: int) -> np.ndarray:
    """σ's of (T0, P, Ṗ) at cycle m from (Jᵀ W J)⁻¹, J the derivatives of t(n; T0, P, Ṗ)."""
    _, p_m, pdot_m = truth_at(m)
    nu = cycles - m
    jac = np.stack([np.ones_like(nu), nu + 0.5 * pdot_m * nu**2, 0.5 * p_m * nu**2], axis=1)
    fisher = jac.T @ (jac / sigma[:, None] ** 2)
    d = np.sqrt(np.diag(fisher))
    cov = np.linalg.inv(fisher / np.outer(d, d)) / np.outer(d, d)
    return np.sqrt(np.diag(cov))


def one_line(exc: BaseException) -> str:
    msg = str(exc)
    assert "\n" not in msg and len(msg) < 400, msg
    return msg


# ---------------------------------------------------------------------------------------------
# recovery: Monte Carlo over seeds

N_MC = 200


@pytest.fixture(scope="module")
def monte_carlo(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    folder = tmp_path_factory.mktemp("mc")
    all_pulls, ratios, errors, analytic = [], [], [], []
    for seed in range(N_MC):
        cycles, bjd, _ = simulate(seed, secondary_every=4)
        times = read_times(
            write_table(folder / f"t{seed}.csv", bjd, cycles=cycles, secondary=cycles % 1 != 0)
        )
        fit = fit_times(times)
        all_pulls.append(pulls(fit))
        ratios.append(
            fit.sigmas / fit.sigma_scale / analytic_sigmas(cycles, times.sigma_s, fit.t0_cycle)
        )
        t0_m, p_m, pdot_m = truth_at(fit.t0_cycle)
        sig_a = analytic_sigmas(cycles, times.sigma_s, fit.t0_cycle)
        errors.append(
            np.array([t0_error_s(fit, t0_m), fit.values[1] - p_m, fit.values[2] - pdot_m]) / sig_a
        )
        analytic.append(sig_a)
    return {
        "pulls": np.array(all_pulls),
        "ratios": np.array(ratios),
        "scaled_errors": np.array(errors),
    }


def test_recovers_t0_p_pdot_within_3_sigma(monte_carlo: dict[str, Any]) -> None:
    """Pulls (fit − truth)/σ_fit over 200 seeds: ≤ 4 of 200 beyond 3σ per parameter (0.54
    expected), mean 0 ± 4/√N, sd 1 ± 4/√(2N) (σ's rescaled by √(χ²/dof) when > 1 make sd ≲ 1)."""
    z = monte_carlo["pulls"]
    n = z.shape[0]
    outside = np.sum(np.abs(z) > 3, axis=0)
    assert np.all(outside <= 4), outside
    assert np.all(np.abs(z.mean(axis=0)) < 4 / math.sqrt(n)), z.mean(axis=0)
    assert np.all(np.abs(z.std(axis=0, ddof=1) - 1) < 4 / math.sqrt(2 * n)), z.std(axis=0)


def test_sigmas_match_analytic_wls_covariance(monte_carlo: dict[str, Any]) -> None:
    """Before the χ² rescaling the fit's σ's are (Jᵀ W J)⁻¹'s to 10 % (in fact to ~1e-6), and the
    scatter of the estimates over seeds matches the analytic σ's."""
    ratios = monte_carlo["ratios"]
    assert np.all(np.abs(ratios - 1) < 0.10), (ratios.min(axis=0), ratios.max(axis=0))
    assert np.all(np.abs(ratios - 1) < 1e-5)
    sd = monte_carlo["scaled_errors"].std(axis=0, ddof=1)
    assert np.all(np.abs(sd - 1) < 4 / math.sqrt(2 * N_MC)), sd


def test_reported_sigmas_are_rescaled_by_sqrt_chi2_dof(tmp_path: Path) -> None:
    """Stated σ = 2 s, true scatter 4 s: χ²/dof ≈ 4, σ's scaled by ≈ 2 with a note."""
    cycles, bjd, _ = simulate(11, sigma=4.0)
    times = read_times(write_table(tmp_path / "t.csv", bjd, sigma=2.0, cycles=cycles))
    fit = fit_times(times)
    assert fit.rescaled and 1.6 < fit.sigma_scale < 2.4
    assert fit.sigma_scale == pytest.approx(math.sqrt(fit.chi2 / fit.dof))
    expected = analytic_sigmas(cycles, times.sigma_s, fit.t0_cycle) * fit.sigma_scale
    np.testing.assert_allclose(fit.sigmas, expected, rtol=1e-5)
    assert any("chi2/dof" in n and "scaled" in n for n in fit.notes)


def test_reference_cycle_is_the_integer_nearest_the_weighted_mean(tmp_path: Path) -> None:
    cycles, bjd, _ = simulate(5)
    sig = [1.0] * 30 + [3.0] * 30
    times = read_times(write_table(tmp_path / "t.csv", bjd, sigma=sig, cycles=cycles))
    w = 1 / np.asarray(sig) ** 2
    for terms in (2, 3):
        fit = fit_times(times, terms=terms)
        assert fit.t0_cycle == round(float(np.sum(w * cycles) / np.sum(w)))
    fit = fit_times(times, terms=2)
    corr = fit.cov[0, 1] / math.sqrt(fit.cov[0, 0] * fit.cov[1, 1])
    assert abs(corr) < 1e-3  # a linear ephemeris at the weighted mean: T0 decorrelated from P


def test_terms_2_and_4(tmp_path: Path) -> None:
    """--terms 2 on a linear ephemeris, --terms 4 recovers P̈ of a cubic one."""
    rng = np.random.default_rng(3)
    cycles = np.sort(rng.choice(CYCLES_5YR, 40, replace=False)).astype(float)
    lin = [f"{true_time(c, pdot=Decimal(0)):.14f}" for c in cycles]
    fit2 = fit_times(
        read_times(write_table(tmp_path / "a.csv", lin, sigma=0.5, cycles=cycles)), terms=2
    )
    assert fit2.names == ("t0", "period") and fit2.cov.shape == (2, 2)
    assert abs(fit2.values[1] - float(P_TRUE)) < 1e-6
    pddot = Decimal("3e-20")
    cub = [f"{true_time(c, pddot=pddot):.14f}" for c in cycles]
    fit4 = fit_times(
        read_times(write_table(tmp_path / "b.csv", cub, sigma=1e-3, cycles=cycles)), terms=4
    )
    assert fit4.names == ("t0", "period", "pdot", "pddot")
    # P̈ re-expressed at cycle m: 6 c3 / P_m² with c3 = P² P̈ / 6 unchanged by the shift
    _, p_m, _ = truth_at(fit4.t0_cycle)
    expect = float(P_TRUE) ** 2 * 3e-20 / p_m**2
    assert abs(fit4.values[3] - expect) < 3 * fit4.sigmas[3]


# ---------------------------------------------------------------------------------------------
# full precision


def test_thirteen_decimal_epoch_round_trips_below_a_microsecond(tmp_path: Path) -> None:
    text = "2458305.6827886123457"  # 13 decimals: ~9 ns resolution
    assert abs(float(text) - float(Decimal(text))) == 0  # what float64 keeps …
    lost = abs(Decimal(float(text)) - Decimal(text)) * DAY
    assert lost > Decimal("1e-6")  # … loses more than a microsecond
    path = tmp_path / "t.csv"
    path.write_text(f"bjd_tdb,sigma_s,cycle\n{text},1,0\n2458305.6875,1,1\n", encoding="utf-8")
    times = read_times(path)
    assert times.jd[0] == Decimal(text)
    back = seconds_to_jd(float(times.t_s[0]), times.ref_jd)
    assert abs(back - Decimal(text)) * DAY < Decimal("1e-6")
    assert abs(parse_epoch_label(format_bjd(Decimal(text)), "t0") - Decimal(text)) * DAY < Decimal(
        "1e-6"
    )


def test_bmjd_and_ecsv_keep_full_precision(tmp_path: Path) -> None:
    """bmjd_tdb = BJD − 2400000.5 exactly; an ECSV float64 column is re-read from its text, and
    an ECSV σ in days is converted to seconds."""
    path = tmp_path / "t.ecsv"
    path.write_text(
        "# %ECSV 1.0\n# ---\n# datatype:\n# - {name: bmjd_tdb, datatype: float64}\n"
        "# - {name: sigma_s, unit: d, datatype: float64}\n# - {name: kind, datatype: string}\n"
        "# schema: astropy-2.0\nbmjd_tdb sigma_s kind\n58305.1827886123457 2.5e-5 primary\n"
        "58305.1851891 2.5e-5 secondary\n",
        encoding="utf-8",
    )
    times = read_times(path)
    assert times.jd[0] == Decimal("2458305.6827886123457")
    np.testing.assert_allclose(times.sigma_s, 2.5e-5 * 86400)
    assert list(times.secondary) == [False, True]


def test_ecsv_time_column_is_read_exactly(tmp_path: Path) -> None:
    """An astropy Time column: its text as written (format jd), or its exact two parts
    (jd1_jd2 serialisation, ISO format); another scale is refused."""
    from astropy.table import Table
    from astropy.time import Time

    t = Time([2458305.0, 2458306.0], [0.6827886123457, 0.5], format="jd", scale="tdb")
    Table({"bjd_tdb": t, "sigma_s": [1.0, 2.0]}).write(tmp_path / "t.ecsv", format="ascii.ecsv")
    written = next(
        ln.split()[0] for ln in (tmp_path / "t.ecsv").read_text().splitlines() if ln[:1] == "2"
    )
    assert read_times(tmp_path / "t.ecsv").jd[0] == Decimal(written)
    exact = Decimal("2458305.6827886123457")
    Table({"bjd_tdb": t, "sigma_s": [1.0, 2.0]}).write(
        tmp_path / "j.ecsv", format="ascii.ecsv", serialize_method="jd1_jd2"
    )
    assert abs(read_times(tmp_path / "j.ecsv").jd[0] - exact) * DAY < Decimal("1e-6")
    iso = Time(t, format="isot", precision=9)
    Table({"bjd_tdb": iso, "sigma_s": [1.0, 2.0]}).write(tmp_path / "i.ecsv", format="ascii.ecsv")
    assert abs(read_times(tmp_path / "i.ecsv").jd[0] - exact) * DAY < Decimal("1e-6")
    Table({"bjd_tdb": Time(t, scale="utc"), "sigma_s": [1.0, 2.0]}).write(
        tmp_path / "u.ecsv", format="ascii.ecsv"
    )
    with pytest.raises(InputFileError, match="TDB"):
        read_times(tmp_path / "u.ecsv")


# ---------------------------------------------------------------------------------------------
# counting cycles


def test_counting_with_initial_ephemeris_recovers_the_true_cycles(tmp_path: Path) -> None:
    cycles, bjd, _ = simulate(21, secondary_every=3)
    times = read_times(write_table(tmp_path / "t.csv", bjd, secondary=cycles % 1 != 0))
    init = tmp_path / "init.yaml"
    init.write_text(
        'name: ZTF J1539+5027\nsky: {ra: "15h39m32.16s", dec: "+50d27m38.8s"}\ntiming:\n'
        '  t0: "BJD_TDB 2458305.6827886"\n  t0_marks: primary_eclipse\n  period: "414.79154 s"\n'
        "  pdot: -2.4e-11\n  covariance: {sigma: {t0: 8.4e-6 d}}\n  source: test\n",
        encoding="utf-8",
    )
    counted = count_cycles(times, read_initial(init))
    np.testing.assert_array_equal(counted, cycles)
    given = fit_times(
        read_times(write_table(tmp_path / "c.csv", bjd, cycles=cycles, secondary=cycles % 1 != 0))
    )
    fit = fit_times(times, read_initial(init))
    np.testing.assert_allclose(fit.values, given.values, rtol=0, atol=1e-12 * 1e3)
    assert "counted" in fit.cycles_origin


def test_counting_from_a_period_guess_bootstraps_from_the_densest_cluster(tmp_path: Path) -> None:
    """Nights of 5–15 consecutive eclipses every ~20 days for 5 years, --period "414.79 s": the
    count starts in the densest night and recovers every cycle up to one common offset."""
    rng = np.random.default_rng(8)
    cycles_l: list[float] = []
    start = 0
    while start < CYCLES_5YR:
        k = int(rng.integers(5, 16))
        cycles_l.extend(float(start + j) for j in range(k))
        start += 4000 + int(rng.integers(0, 500))
    cycles = np.array(cycles_l) - CYCLES_5YR // 2
    bjd = [f"{true_time(c) + Decimal(repr(rng.normal(0, 2.0))) / DAY:.14f}" for c in cycles]
    times = read_times(write_table(tmp_path / "t.csv", bjd))
    counted = count_cycles(times, period_guess("414.79 s"))
    offset = np.unique(counted - cycles)
    assert offset.size == 1
    fit = fit_times(times, period_guess("414.79 s"))
    assert np.all(np.abs(pulls_vs_truth(fit)) < 5)


def pulls_vs_truth(fit: EphemerisFit) -> np.ndarray:
    """Pulls when the counted cycles carry an unknown offset: compare T0 via the true ephemeris
    at the fit's epoch (the nearest true eclipse)."""
    t_s = float((fit.t0_jd - T0_TRUE) * DAY)
    n_true = round(t_s / float(P_TRUE))
    for _ in range(3):
        n_true = round(n_true + float((fit.t0_jd - true_time(n_true)) * DAY) / float(P_TRUE))
    t0_m, p_m, pdot_m = truth_at(n_true)
    sig = fit.sigmas
    return np.array(
        [
            t0_error_s(fit, t0_m) / sig[0],
            (fit.values[1] - p_m) / sig[1],
            (fit.values[2] - pdot_m) / sig[2],
        ]
    )


def test_ambiguous_gap_is_an_error_saying_what_to_supply(tmp_path: Path) -> None:
    """Two nights a year apart: "414.79 s" (±0.01 s) cannot bridge 76 000 cycles."""
    cycles = np.array([0.0, 1, 2, 3, 4, 76000, 76001, 76002])
    bjd = [f"{true_time(c):.14f}" for c in cycles]
    times = read_times(write_table(tmp_path / "t.csv", bjd))
    with pytest.raises(InputFileError, match="ambiguous") as info:
        fit_times(times, period_guess("414.79 s"))
    msg = one_line(info.value)
    assert "cycle column" in msg and "`initial`" in msg and "rows 5 and 6" in msg


def test_overconfident_period_guess_is_caught(tmp_path: Path) -> None:
    """A P with more digits than hold over the data (P at another epoch) is refused, not used."""
    _, bjd, _ = simulate(3)
    times = read_times(write_table(tmp_path / "t.csv", bjd))
    with pytest.raises(InputFileError) as info:
        count_cycles(times, period_guess("414.7915404 s"))
    msg = one_line(info.value)
    assert "--period" in msg and ("disagrees" in msg or "guess holds" in msg), msg


def test_no_cycles_and_no_guess(tmp_path: Path) -> None:
    times = read_times(write_table(tmp_path / "t.csv", ["2458305.5", "2458305.6", "2458306"]))
    with pytest.raises(InputFileError, match="`period`"):
        fit_times(times)


# ---------------------------------------------------------------------------------------------
# clipping and outliers


def test_outlier_reported_and_only_clip_drops_it(tmp_path: Path) -> None:
    cycles, bjd, _ = simulate(4)
    bad = true_time(cycles[17]) + Decimal(60) / DAY
    bjd[17] = f"{bad:.14f}"
    path = write_table(tmp_path / "t.csv", bjd, cycles=cycles)
    kept = fit_times(read_times(path))
    assert kept.outliers == (18,) and kept.clipped == () and kept.n_used == 60
    assert any("outlier" in n for n in kept.notes)
    clipped = fit_times(read_times(path), clip=5.0)
    assert clipped.clipped == (18,) and clipped.n_used == 59 and not clipped.used[17]
    assert any("dropped" in n and "18" in n for n in clipped.notes)
    assert np.all(np.abs(pulls(clipped)) < 4)


# ---------------------------------------------------------------------------------------------
# period guesses (the bad ones: tests/timing/test_eclipse_times_bad_input.py)


@pytest.mark.parametrize(
    ("text", "value", "sigma"),
    [
        ("414.79 s", 414.79, 0.01),
        ("414.7915404", 414.7915404, 1e-7),
        ("6.9 min", 414.0, 6.0),
        ("0.0048 d", 414.72, 8.64),
    ],
)
def test_period_guess_digits(text: str, value: float, sigma: float) -> None:
    g = period_guess(text)
    assert g.period_s == pytest.approx(value) and g.sigma_period_s == pytest.approx(sigma)


# ---------------------------------------------------------------------------------------------
# the command: JSON report, target YAML, plot, all-or-nothing


def run(args: list[str]) -> str:
    """Run ``ephemeris fit ARGS`` in-process (the command function alone); return stdout."""
    app = typer.Typer(pretty_exceptions_enable=False)

    @app.callback()
    def _root() -> None:
        pass

    app.command("ephemeris-fit")(timing_cli.ephemeris_fit)
    out = io.StringIO()
    from contextlib import redirect_stdout

    with redirect_stdout(out):
        app(["ephemeris-fit", *args], standalone_mode=False)
    return out.getvalue()


@pytest.fixture
def campaign(tmp_path: Path) -> tuple[Path, np.ndarray]:
    cycles, bjd, _ = simulate(2, secondary_every=5)
    return write_table(
        tmp_path / "times.csv", bjd, cycles=cycles, secondary=cycles % 1 != 0
    ), cycles


def test_json_report(campaign: tuple[Path, np.ndarray]) -> None:
    path, _ = campaign
    doc = json.loads(run([str(path), "--format", "json"]))
    params = doc["parameters"]
    assert set(params) == {"t0", "period", "pdot"}
    for p in params.values():
        assert set(p) == {"value", "sigma", "unit"}
    assert params["t0"]["value"].startswith("BJD_TDB 2458")
    assert len(params["t0"]["value"].split(".")[1]) >= 11  # 1 µs = 1.16e-11 d
    assert params["period"]["unit"] == "s" and params["pdot"]["unit"] == "s/s"
    assert np.array(doc["covariance"]["matrix"]).shape == (3, 3)
    assert doc["n_points"] == 60 and doc["dof"] == 57 and doc["chi2"] > 0
    assert doc["reference"]["t0_marks"] == "primary_eclipse"
    t0 = parse_epoch_label(params["t0"]["value"], "t0")
    t0_m, p_m, _ = truth_at(doc["reference"]["t0_cycle"])
    assert abs(float((t0 - t0_m) * DAY)) < 3 * params["t0"]["sigma"]
    assert abs(params["period"]["value"] - p_m) < 3 * params["period"]["sigma"]
    assert len(doc["points"]) == 60 and doc["outliers"] == []


def test_target_yaml_rereads_with_the_fitted_values(
    tmp_path: Path, campaign: tuple[Path, np.ndarray]
) -> None:
    path, _ = campaign
    like = tmp_path / "like.yaml"
    like.write_text(
        "name: ZTF J1539+5027\nsky: {ra: 15h39m32.16s, dec: +50d27m38.8s}\n"
        "masses: {m1: 0.61, m2: 0.21}\nlisa: {f_gw: 4.8e-3}\n",
        encoding="utf-8",
    )
    out = tmp_path / "target.yaml"
    report = json.loads(run([str(path), "--format", "json"]))
    run([str(path), "-o", str(out), "--like", str(like), "--plot", str(tmp_path / "oc.png")])
    doc = yaml.safe_load(out.read_text(encoding="utf-8"))
    assert load_yaml(out, "target") == doc
    assert doc["name"] == "ZTF J1539+5027" and doc["sky"]["ra"] == "15h39m32.16s"
    assert doc["masses"] == {"m1": 0.61, "m2": 0.21} and "lisa" not in doc
    timing = doc["timing"]
    assert timing["t0_marks"] == "primary_eclipse"
    t0_fit = parse_epoch_label(report["parameters"]["t0"]["value"], "t0")
    assert abs(parse_epoch_label(timing["t0"], "t0") - t0_fit) * DAY < Decimal("1e-6")
    p_text, unit = timing["period"].split()
    assert unit == "s"
    p = report["parameters"]["period"]
    assert abs(float(p_text) - p["value"]) < 0.01 * p["sigma"]
    assert timing["pdot"] == report["parameters"]["pdot"]["value"]
    assert timing["covariance"]["parameters"] == ["t0", "period", "pdot"]
    np.testing.assert_allclose(timing["covariance"]["matrix"], report["covariance"]["matrix"])
    assert timing["source"].startswith("ucbplan ephemeris fit of times.csv (60 times, chi2/dof=")
    assert (tmp_path / "oc.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # never overwrite without --overwrite; nothing written when one output exists
    before = out.read_bytes()
    with pytest.raises(OutputExistsError):
        run([str(path), "-o", str(out), "--name", "X", "--ra", "10", "--dec", "20"])
    assert out.read_bytes() == before
    fresh = tmp_path / "fresh.yaml"
    with pytest.raises(OutputExistsError):
        run([str(path), "-o", str(fresh), "--like", str(like), "--plot", str(tmp_path / "oc.png")])
    assert not fresh.exists()
    run([str(path), "-o", str(out), "--name", "X", "--ra", "10", "--dec", "20", "--overwrite"])
    assert yaml.safe_load(out.read_text())["sky"] == {"ra": "10", "dec": "20"}


def test_plot_alone_and_never_overwritten(
    tmp_path: Path, campaign: tuple[Path, np.ndarray]
) -> None:
    path, _ = campaign
    png = tmp_path / "oc.png"
    assert run([str(path), "--plot", str(png)]) == ""
    assert png.read_bytes()[:4] == b"\x89PNG"
    before = png.read_bytes()
    with pytest.raises(OutputExistsError):
        run([str(path), "--plot", str(png)])
    assert png.read_bytes() == before
    run([str(path), "--plot", str(tmp_path / "oc.pdf")])
    assert (tmp_path / "oc.pdf").read_bytes()[:5] == b"%PDF-"


@pytest.mark.parametrize(("args", "expect"), BAD_FIT_OPTIONS)
def test_bad_options(
    tmp_path: Path, campaign: tuple[Path, np.ndarray], args: list[str], expect: str
) -> None:
    path, _ = campaign
    args = [str(tmp_path / a) if a.endswith((".yaml", ".json", ".png")) else a for a in args]
    with pytest.raises(InputError) as info:
        run([str(path), *args])
    assert expect in cli_message(one_line(info.value))  # as the command line prints it
    assert sorted(p.name for p in tmp_path.iterdir()) == ["times.csv"]


# ---------------------------------------------------------------------------------------------
# property tests


@settings(
    max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    period=st.floats(60.0, 86400.0),
    pdot_e=st.floats(-1.0, 1.0),
    t0_frac=st.integers(0, 10**10),
    t0_day=st.integers(2_380_000, 2_600_000),
    epochs=st.lists(st.integers(-(10**6), 10**6), min_size=4, max_size=30, unique=True),
    secondary=st.lists(st.booleans(), min_size=30, max_size=30),
    sigma=st.floats(0.01, 100.0),
)
def test_noiseless_times_return_the_ephemeris(
    tmp_path: Path,
    period: float,
    pdot_e: float,
    t0_frac: int,
    t0_day: int,
    epochs: list[int],
    secondary: list[bool],
    sigma: float,
) -> None:
    """Random valid ephemerides and epochs (within ±20 years), exact times: the fit returns T0
    to < 1 µs, P and Ṗ to their round-off."""
    p = Decimal(repr(period))
    n_max = 20 * 365.25 * 86400 / period
    ints = sorted({round(e / 10**6 * n_max) for e in epochs})
    assume(len(ints) >= 4)
    pdot = Decimal(repr(pdot_e * 1e-3 / n_max))  # |Ṗ n| ≤ 1e-3 over the span
    t0 = Decimal(t0_day) + Decimal(t0_frac) / Decimal(10**10)
    cycles = np.array(ints, dtype=float) + np.where(secondary[: len(ints)], 0.5, 0.0)
    bjd = [f"{true_time(c, t0, p, pdot):.16f}" for c in cycles]
    times = read_times(
        write_table(tmp_path / "t.csv", bjd, sigma=sigma, cycles=cycles, secondary=cycles % 1 != 0)
    )
    fit = fit_times(times)
    t0_m, p_m, pdot_m = truth_at(fit.t0_cycle, t0, p, pdot)
    assert abs(t0_error_s(fit, t0_m)) < 1e-6
    assert abs(parse_epoch_label(format_bjd(fit.t0_jd), "t0") - t0_m) * DAY < Decimal("1e-6")
    span = float(np.ptp(cycles)) or 1.0
    assert abs(fit.values[1] - p_m) < 1e-6 / span * 10
    assert abs(fit.values[2] - pdot_m) * float(p) * span**2 < 1e-5


CELL = st.one_of(
    st.sampled_from(
        [
            "",
            " ",
            "nan",
            "-inf",
            "1e400",
            "-2",
            "0",
            "2458305.5",
            "58305",
            "primary",
            "secondary",
            "0.5",
            "1",
            "3",
            "1e-300",
            "1,2",
            '"',
            "é",
            "\x00",
            "x" * 3000,
        ]
    ),
    st.text(max_size=20),
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
)


@settings(
    max_examples=80, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(row=st.integers(0, 4), col=st.integers(0, 3), value=CELL, counted=st.booleans())
def test_mutated_tables_succeed_or_fail_in_one_line(
    tmp_path: Path, row: int, col: int, value: str, counted: bool
) -> None:
    """A valid table with one cell replaced: a fit, or a one-line UcbplanError, nothing else."""
    lines = times_table(GOOD).splitlines()
    lines = [lines[0], *lines[1:], "2458305.7019906,2,secondary,3.5"]
    cells = lines[row].split(",")
    cells[col] = value
    lines[row] = ",".join(cells)
    if counted:
        lines = [",".join(ln.split(",")[:3]) for ln in lines]
    path = tmp_path / "times.csv"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    try:
        times = read_times(path)
        fit_times(times, period_guess("414.79 s") if counted else None, terms=3)
    except UcbplanError as exc:
        one_line(exc)


OPTION_VALUES = st.one_of(
    st.sampled_from(
        [
            "",
            " ",
            "nan",
            "-inf",
            "1e400",
            "0",
            "-1",
            "414.79 s",
            "414.79",
            "6.9 min",
            "1h",
            "25h",
            "91d",
            "+50d27m38.8s",
            "15:39:32.16",
            "x" * 5000,
            "\x00",
            "é",
            "--help",
            "2",
            "4",
        ]
    ),
    st.text(max_size=30),
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
)


@settings(
    max_examples=50, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    option=st.sampled_from(["--period", "--clip", "--terms", "--ra", "--dec", "--name"]),
    value=OPTION_VALUES,
)
def test_any_option_value_gives_a_result_or_one_line(
    tmp_path: Path, option: str, value: str
) -> None:
    """Option values of every kind: success, or one line naming the option; no file on failure."""
    cycles, bjd, _ = simulate(6, n=12)
    folder = tmp_path / "case"
    folder.mkdir(exist_ok=True)
    for old in folder.iterdir():
        old.unlink()
    table = write_table(folder / "times.csv", bjd, cycles=cycles)
    out = folder / "target.yaml"
    args = [str(table), "-o", str(out), option, value]
    if option in ("--ra", "--dec"):
        args += ["--ra", "10"] if option == "--dec" else ["--dec", "20"]
    if option != "--name":
        args += ["--name", "X"]
    if option not in ("--ra", "--dec"):
        args += ["--ra", "10", "--dec", "20"]
    try:
        run(args)
    except UcbplanError as exc:
        one_line(exc)
        assert sorted(p.name for p in folder.iterdir()) == ["times.csv"]
    except Exception as exc:  # typer's vendored click: a usage error (e.g. --terms x), exit 2
        assert callable(getattr(exc, "show", None)) and getattr(exc, "exit_code", None) == 2, exc
        assert sorted(p.name for p in folder.iterdir()) == ["times.csv"]
    else:
        assert out.exists()


# ---------------------------------------------------------------------------------------------
# counting from the times alone (no cycle column, no --period, no --initial)


def _campaign(nights: list[int], per_night: int, seed: int, sigma: float = SIGMA) -> tuple:
    """Consecutive eclipses on each night (night k starts at cycle nights[k]), noisy BJDs."""
    rng = np.random.default_rng(seed)
    cycles = np.array([float(n + j) for n in nights for j in range(per_night)])
    bjd = [f"{true_time(c) + Decimal(repr(rng.normal(0, sigma))) / DAY:.14f}" for c in cycles]
    return cycles, bjd


#: Nights at days 0, 1, 3, 7, 15, 31 … 1023 (in cycles of 414.79 s): each gap about the
#: baseline so far, which the period of the nights before predicts to a few seconds.
DOUBLING = [round((2**k - 1) * 86400 / 414.7915404) for k in range(11)]


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_cycles_counted_from_the_times_alone_when_the_nights_allow_it(
    tmp_path: Path, seed: int
) -> None:
    """One night of 8 consecutive eclipses fixes P to ~0.1 s; it bridges the 1-day gap, and
    the count grows outward to 3 years: every cycle recovered up to one common offset, and the
    fit agrees with the exact truth (pulls < 5) as with a given period."""
    cycles, bjd = _campaign(DOUBLING, 8, seed)
    times = read_times(write_table(tmp_path / "t.csv", bjd))
    fit = fit_times(times)
    offset = np.unique(np.round(count_cycles(times, period_from_times(times)) - cycles, 9))
    assert offset.size == 1
    assert np.all(np.abs(pulls_vs_truth(fit)) < 5)
    assert fit.cycles_origin.startswith("counted from the times (the ")


def test_the_longest_period_that_fits_the_night_is_taken(tmp_path: Path) -> None:
    """Cycles 0, 2, 5 on one night: the closest pair (2 P apart) first suggests 2P, under which
    cycle 5 sits half a period from an eclipse; P itself fits all three. With only every other
    eclipse seen (0, 2, 4, 6), 2P fits: times alone cannot tell, and the longest is taken."""
    bjd = [f"{true_time(c):.14f}" for c in (0.0, 2.0, 5.0)]
    guess = period_from_times(read_times(write_table(tmp_path / "a.csv", bjd)))
    assert guess.period_s == pytest.approx(float(P_TRUE), abs=5 * guess.sigma_period_s)
    bjd = [f"{true_time(c):.14f}" for c in (0.0, 2.0, 4.0, 6.0)]
    guess = period_from_times(read_times(write_table(tmp_path / "b.csv", bjd)))
    assert guess.period_s == pytest.approx(2 * float(P_TRUE), abs=5 * guess.sigma_period_s)


def test_a_secondary_half_a_period_away_gives_the_period(tmp_path: Path) -> None:
    cycles = np.array([0.0, 0.5, 1.0, 2.5, 3.0])
    bjd = [f"{true_time(c):.14f}" for c in cycles]
    times = read_times(write_table(tmp_path / "t.csv", bjd, secondary=cycles % 1 != 0))
    guess = period_from_times(times)
    assert guess.period_s == pytest.approx(float(P_TRUE), abs=5 * guess.sigma_period_s)
    np.testing.assert_array_equal(count_cycles(times, guess) - cycles, 0.0)


def test_times_alone_that_cannot_bridge_a_gap_name_it(tmp_path: Path) -> None:
    """Nights 20 days apart: one night's period (σ ≈ 0.1 s) cannot bridge 4000 cycles."""
    _, bjd = _campaign([0, 4000, 8100], 8, 4)
    times = read_times(write_table(tmp_path / "t.csv", bjd))
    with pytest.raises(InputFileError, match="ambiguous") as info:
        fit_times(times)
    msg = one_line(info.value)
    assert "the 8 eclipses of BJD_TDB" in msg and "gap between rows 8 and 9" in msg
    assert "cycle column" in msg and "`initial`" in msg


def test_no_night_with_three_eclipses_is_an_error_naming_it(tmp_path: Path) -> None:
    bjd = [f"{true_time(c):.14f}" for c in (0.0, 1.0, 900.0, 901.0, 5000.0)]
    times = read_times(write_table(tmp_path / "t.csv", bjd))
    with pytest.raises(InputFileError) as info:
        fit_times(times)
    msg = one_line(info.value)
    assert "no night has 3 or more eclipses" in msg and "`period`" in msg


def test_times_of_a_night_that_fit_no_period_are_an_error(tmp_path: Path) -> None:
    """Times 0, 100 and 250 s (σ = 2 s): P = 100 s puts the third half-way between eclipses,
    and P = 50 s or shorter is within 40σ, where the noise could put a time on any eclipse."""
    base = true_time(0)
    bjd = [f"{base + Decimal(s) / DAY:.14f}" for s in (0, 100, 250)]
    times = read_times(write_table(tmp_path / "t.csv", bjd))
    with pytest.raises(InputFileError, match="fit no single period") as info:
        fit_times(times)
    assert "`period`" in one_line(info.value)


def test_ephemeris_fit_cli_without_period(tmp_path: Path) -> None:
    cycles, bjd = _campaign(DOUBLING[:6], 8, 5)
    path = write_table(tmp_path / "t.csv", bjd)
    doc = json.loads(run([str(path), "--format", "json"]))
    assert doc["n_points"] == len(cycles)
    assert abs(doc["parameters"]["period"]["value"] - float(P_TRUE)) < 1e-3


def test_eclipse_csv_comments_share_the_bounded_reader(tmp_path: Path) -> None:
    """Issue 33: the eclipse-time CSV reads # comments with the velocity tables' one reader."""
    from ucbplan.inputs import MAX_COMMENT_CHARS

    rows = "bjd_tdb,sigma_s\n2458305.6827886,2\n2458305.6875891,2\n2458305.6923896,2\n"
    p = tmp_path / "t.csv"
    p.write_text("# note\n" + rows + "  # trailing note\n", encoding="utf-8")
    assert len(read_times(p).jd) == 3
    p.write_text("#" * (MAX_COMMENT_CHARS + 1) + "\n" + rows, encoding="utf-8")
    with pytest.raises(InputFileError, match=r"^t.csv: line 1: a comment of 1000001 characters"):
        read_times(p)


def test_a_fit_without_pdot_writes_a_target_that_loads(tmp_path: Path) -> None:
    """Found while documenting TimingFit: a ``terms=2`` fit (T0, P; Ṗ held at 0) wrote a target
    without ``timing.pdot``, which the loader refuses (``timing.pdot: missing``). The fit held Ṗ
    at 0 exactly, so the file says so (a zero Ṗ claims no uncertainty)."""
    from astropy.table import Table

    import ucbplan

    period_d = 400.0 / 86400.0
    cycles = [0, 1000, 2000, 3000, 4000, 5000]
    bjd = [f"{2461000.5 + n * period_d:.7f}" for n in cycles]
    fit = ucbplan.fit_ephemeris(
        Table({"cycle": cycles, "bjd_tdb": bjd, "sigma_s": [1.0] * 6}), terms=2
    )
    target = fit.to_target(name="Demo", ra="15h39m32.16s", dec="+50d27m38.8s")
    assert target.timing is not None and target.timing.ephemeris.pdot == 0.0
    assert abs(target.timing.ephemeris.period_s - 400.0) < 1e-3
    path = tmp_path / "demo.yaml"
    path.write_text(fit.target_yaml(name="Demo", ra="15h39m32.16s", dec="+50d27m38.8s"))
    loaded = ucbplan.load_target(path)
    assert loaded.timing is not None and loaded.timing.ephemeris.pdot == 0.0
