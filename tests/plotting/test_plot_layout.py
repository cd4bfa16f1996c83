"""Every figure the project writes is readable: no overprinted text, nothing cut off, no legend on
the curves, units on every axis (:func:`ucbplan.plotting.layout.layout_problems`).

Each test runs the command that writes a figure with ``Figure.savefig`` wrapped, so the check sees
the figure exactly as it is saved; the checker itself is tested first on figures built to fail.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from matplotlib.figure import Figure
from typer.testing import CliRunner

from ucbplan.cli.app import app
from ucbplan.plotting import pyplot
from ucbplan.plotting.layout import layout_problems

pytestmark = [
    pytest.mark.filterwarnings("ignore::erfa.ErfaWarning"),
    pytest.mark.filterwarnings("ignore::astropy.utils.exceptions.AstropyWarning"),
]

ROOT = Path(__file__).resolve().parents[2]
CATALOGS = ROOT / "catalogs"
ECCENTRIC = CATALOGS / "fiducial-eccentric.yaml"


@pytest.fixture
def saved(monkeypatch: pytest.MonkeyPatch) -> Iterator[list[tuple[str, list[str]]]]:
    """(file name, layout problems) of every figure saved during the test."""
    seen: list[tuple[str, list[str]]] = []
    original = Figure.savefig

    def spy(self: Figure, fname: Any, *args: Any, **kwargs: Any) -> Any:
        seen.append((str(getattr(fname, "name", fname)), layout_problems(self)))
        return original(self, fname, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", spy)
    yield seen


def _run(*args: object) -> None:
    res = CliRunner().invoke(app, [str(a) for a in args])
    assert res.exit_code == 0, res.output


def _clean(saved: list[tuple[str, list[str]]], n: int) -> None:
    assert len(saved) == n, [s[0] for s in saved]
    for name, problems in saved:
        assert problems == [], f"{name}: {problems}"


# -- the checker fails where it should ------------------------------------------------------------


def test_checker_reports_overlap_outside_hidden_curve_and_missing_unit() -> None:
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(4, 3))
    x = np.linspace(0, 1, 200)
    ax.plot(x, 0.5 + 0 * x, label="flat curve under the legend")
    ax.legend(loc="center")
    ax.text(0.1, 0.1, "first label", transform=ax.transAxes)
    ax.text(0.12, 0.1, "second label", transform=ax.transAxes)
    ax.text(1.5, 0.5, "far off to the right", transform=ax.transAxes)
    ax.set_xlabel("time")
    ax.set_ylabel("altitude [deg]")
    problems = "\n".join(layout_problems(fig))
    plt.close(fig)
    assert "'first label' overlaps" in problems and "'second label'" in problems
    assert "'far off to the right' lies outside the figure" in problems
    assert "legend hides" in problems and "flat curve" in problems
    assert "x axis label 'time' has no [unit]" in problems
    assert "y axis" not in problems


def test_checker_sees_points_and_contours_under_a_legend() -> None:
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(4, 3))
    g = np.linspace(-1, 1, 50)
    ax.contour(g, g, np.hypot(*np.meshgrid(g, g)), levels=[0.3])
    ax.scatter(0.05 * np.cos(g * 3), 0.05 * np.sin(g * 3), label="points near the centre")
    ax.legend(loc="center", fontsize=14)
    problems = "\n".join(layout_problems(fig, check_units=False))
    plt.close(fig)
    assert "legend hides" in problems and "contour" in problems
    assert "points 'points near the centre'" in problems


def test_checker_passes_a_clean_figure_and_sees_tick_overlap() -> None:
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(5, 3), layout="constrained")
    ax.plot([0, 1], [0, 1])
    ax.set_xlabel("time [h]")
    ax.set_ylabel("altitude [deg]")
    assert layout_problems(fig) == []
    ax.set_xticks(np.linspace(0, 1, 40), [f"label {k}" for k in range(40)])
    assert any("x tick" in p and "overlaps" in p for p in layout_problems(fig))
    plt.close(fig)


# -- every figure the project writes --------------------------------------------------------------


@pytest.mark.parametrize(
    "target",
    ["fiducial-eccentric.yaml", "hm-cnc-simulated.yaml", "examples/synthetic-eclipsing.yaml"],
)
def test_horizon_plot_three_anchors(saved: list[Any], tmp_path: Path, target: str) -> None:
    """Three anchors × two α: conjunction and zero-crossing share a tolerance, and their labels
    overprinted (issue 15); the timing target has the long two-sided labels."""
    anchors = ["--anchor", "quadrature", "--anchor", "conjunction", "--anchor", "zero-crossing"]
    _run(
        "horizon",
        str(CATALOGS / target),
        "--alpha",
        "1",
        "--alpha",
        "0.5",
        *anchors,
        "--plot",
        str(tmp_path / "h.png"),
    )
    _clean(saved, 1)


def test_feasibility_aps_plot(saved: list[Any], tmp_path: Path) -> None:
    _run(*["feasibility", str(ECCENTRIC), "--plot", str(tmp_path / "aps.png"), "--format", "json"])
    _clean(saved, 1)


def test_waveform_asd_plot(saved: list[Any], tmp_path: Path) -> None:
    injection = CATALOGS / "fiducial-injection.yaml"
    _run(
        "waveform",
        str(injection),
        "-o",
        str(tmp_path / "l.ecsv"),
        "--n-bins",
        "64",
        "--plot",
        str(tmp_path / "asd.png"),
    )
    _clean(saved, 1)


def test_corner_plot_titles(saved: list[Any], tmp_path: Path) -> None:
    """Nine parameters with titles of long numbers: the start-epoch corner plot's worst case."""
    from ucbplan.lisa.plots import _LABELS, corner_plot

    rng = np.random.default_rng(1)
    scale = np.array([1e-3, 1e-9, 1e-2, 0.05, 0.1, 0.1, 1e-4, 1e-4, 0.2])
    centre = np.array([-22.1, 6.2208e-3, -16.3, 0.5, 1.1, 2.2, 1e-3, 2e-3, 0.3])
    samples = centre + scale * rng.standard_normal((4000, 9))
    corner_plot(samples, list(_LABELS.values()), list(centre), tmp_path / "c.png", "start epoch")
    _clean(saved, 1)


def test_reduce_plots(saved: list[Any], tmp_path: Path) -> None:
    vels = CATALOGS / "fiducial-eccentric-velocities.csv"
    _run(
        "reduce",
        str(ECCENTRIC),
        str(vels),
        "--seed",
        "2",
        "--samples",
        "500",
        "--format",
        "json",
        "--plots",
        str(tmp_path),
    )
    _clean(saved, 3)


def test_plan_night_chart(saved: list[Any], tmp_path: Path) -> None:
    hm = CATALOGS / "hm-cnc-simulated.yaml"
    _run(
        "plan",
        str(hm),
        "--site",
        "paranal",
        "--night",
        "2040-02-15",
        "--format",
        "ecsv",
        "-o",
        str(tmp_path / "b.ecsv"),
        "--plot",
        str(tmp_path / "n.png"),
    )
    _clean(saved, 1)


def test_population_plots(saved: list[Any], tmp_path: Path) -> None:
    from astropy.table import Table

    cat = tmp_path / "c.ecsv"
    Table.read(CATALOGS / "population" / "ldc-200.ecsv", format="ascii.ecsv")[:12].write(cat)
    _run(
        "population",
        "forecast",
        str(cat),
        "-o",
        str(tmp_path / "f.ecsv"),
        "--plots",
        str(tmp_path),
    )
    _clean(saved, 3)


def test_timing_oc_plot(saved: list[Any], tmp_path: Path) -> None:
    p_day, t0 = 0.004800, 2460000.0
    cycles = np.arange(0, 60000, 1000)
    rng = np.random.default_rng(3)
    bjd = t0 + p_day * cycles + 0.5e-12 * cycles**2 + 2.0 / 86400 * rng.standard_normal(60)
    rows = "\n".join(f"{c},{b:.10f},2.0" for c, b in zip(cycles, bjd, strict=True))
    times = tmp_path / "t.csv"
    times.write_text("cycle,bjd_tdb,sigma_s\n" + rows + "\n")
    _run(*["ephemeris", "fit", str(times), "--plot", str(tmp_path / "oc.png")])
    _clean(saved, 1)


def test_apsidal_signal_default_grid(saved: list[Any], tmp_path: Path) -> None:
    from ucbplan.feasibility.plots import plot_apsidal_signal

    plot_apsidal_signal(
        tmp_path / "a.png",
        k1_m_s=585.3e3,
        omega_dot_rad_s=1.498e-6,
        target_e=0.0096,
        target_omega1=math.pi / 3,
    )
    _clean(saved, 1)


@pytest.mark.slow
def test_simulation_corner_plots(saved: list[Any], tmp_path: Path) -> None:
    """The three corner plots of a tiny eccentric simulation (N = 64 bins, 20 steps)."""
    injection = CATALOGS / "fiducial-injection.yaml"
    out = tmp_path / "post.yaml"
    _run(
        "simulate", injection, "-o", out, "--n-bins", "64", "--steps", "20", "--seed", "3",
        "--walkers", "18", "--no-noise", "--plots", tmp_path,
    )  # fmt: skip
    names = sorted(Path(n).name for n, _ in saved)
    _clean(saved, 3)
    assert len(names) == 3
