"""The apsidal-signal figure (paper Fig. apsidal_signal_omega1_dependence)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from ucbplan.core.constants import DAY_S
from ucbplan.errors import InputError, UcbplanError
from ucbplan.feasibility.report import FeasibilityReport
from ucbplan.feasibility.signals import apsidal_period_s, delta_v_aps
from ucbplan.plotting import pyplot, save_figure

_LINESTYLES = ("-", "--", ":", "-.")


def plot_apsidal_signal(
    path: str | Path,
    *,
    k1_m_s: float,
    omega_dot_rad_s: float,
    e_values: tuple[float, ...] = (0.005, 0.01, 0.03),
    omega1_values: tuple[float, ...] = (0.0, math.pi / 4, math.pi / 2, 3 * math.pi / 4),
    target_e: float | None = None,
    target_omega1: float | None = None,
    title: str = "",
    overwrite: bool = False,
) -> None:
    """Plot Δv_aps against the baseline, like Fig. apsidal_signal_omega1_dependence.

    Colours are ω_1, line styles the eccentricities; the dashed vertical line marks the apsidal
    period 2π/ω̇; the target's own (e, ω_1) is drawn in black when given. Writes the figure to
    ``path`` atomically (PNG, PDF or SVG by suffix).

    Raises
    ------
    InputError
        If ω̇ = 0 (no apsidal signal to plot).
    OutputExistsError
        If ``path`` exists and ``overwrite`` is false.
    """
    if omega_dot_rad_s == 0:
        raise InputError(
            "omega_dot is 0: no apsidal signal; give masses or a target with omega_dot"
        )
    plt = pyplot()
    t_aps = apsidal_period_s(omega_dot_rad_s)
    baseline = np.linspace(0.0, 2.5 * t_aps, 600)
    days = baseline / DAY_S
    fig, ax = plt.subplots(figsize=(9, 4.5), layout="constrained")
    colours = plt.get_cmap("viridis")(np.linspace(0, 0.9, len(omega1_values)))
    _plot_grid(ax, baseline, k1_m_s, omega_dot_rad_s, e_values, omega1_values, colours)
    if target_e is not None and target_omega1 is not None:
        dv = delta_v_aps(k1_m_s, target_e, target_omega1, omega_dot_rad_s, baseline) / 1e3
        label = f"target e={target_e:.3g}, ω₁={target_omega1:.2f} rad"
        ax.plot(days, dv, color="k", lw=2.2, label=label)
    _decorate(ax, t_aps, k1_m_s, title)
    save_figure(fig, Path(path), overwrite=overwrite, dpi=120)


def _plot_grid(
    ax: Any,
    baseline: Any,
    k1_m_s: float,
    omega_dot_rad_s: float,
    e_values: tuple[float, ...],
    omega1_values: tuple[float, ...],
    colours: Any,
) -> None:
    """Δv_aps [km/s] against the baseline [d] for each (ω_1, e): a colour per ω_1, a line style
    per e (with grey legend entries for the styles)."""
    days = baseline / DAY_S
    for j, w1 in enumerate(omega1_values):
        for i, e in enumerate(e_values):
            dv = delta_v_aps(k1_m_s, e, w1, omega_dot_rad_s, baseline) / 1e3
            label = f"ω₁={w1:.2f} rad" if i == 0 else None
            ax.plot(
                days,
                dv,
                color=colours[j],
                ls=_LINESTYLES[i % len(_LINESTYLES)],
                lw=1.2,
                label=label,
            )
    for i, e in enumerate(e_values):
        ax.plot([], [], color="grey", ls=_LINESTYLES[i % len(_LINESTYLES)], label=f"e={e:g}")


def _decorate(ax: Any, t_aps: float, k1_m_s: float, title: str) -> None:
    """Apsidal-period marker, axis labels, title and legend."""
    ax.axvline(t_aps / DAY_S, color="k", ls="--", lw=0.8, label="apsidal period 2π/ω̇")
    ax.set_xlabel("baseline ΔT = t_β − t_α [days]")
    ax.set_ylabel("Δv_aps [km/s]")
    ax.set_title(title or f"apsidal signal, K₁ = {k1_m_s / 1e3:.0f} km/s")
    # beside the axes, not on them: the curves fill the whole panel
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)


def plot_report(report: FeasibilityReport, path: Path, *, overwrite: bool = False) -> None:
    """The apsidal-signal figure of a :class:`FeasibilityReport`, the target's (e, ω_0) in black.

    Raises
    ------
    UcbplanError
        If the report has no K_1 or no apsidal rate (nothing to plot).
    OutputExistsError
        If ``path`` exists and ``overwrite`` is false.
    """
    if report.k1_m_s is None or report.omega_dot_used == 0.0:
        raise UcbplanError(
            f"plot: {report.name} has no K1 or no apsidal rate; give `m1`/`m2` (and "
            "lisa.cos_inclination or timing.inclination in the target file) or K1 under "
            "spectroscopy"
        )
    plot_apsidal_signal(
        path,
        k1_m_s=report.k1_m_s,
        omega_dot_rad_s=report.omega_dot_used,
        target_e=report.e if report.e > 0 else None,
        target_omega1=report.omega0_rad,
        title=f"{report.name}: apsidal signal (Eq. apsidal_drift_est0)",
        overwrite=overwrite,
    )
