"""Figures of the core forecast (the paper's horizon figure)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from ucbplan.core.constants import DAY_S
from ucbplan.core.forecast import HorizonRow, anchor_sigma_u
from ucbplan.core.params import EphemerisSource
from ucbplan.plotting import pyplot, save_figure


class NamedSource(EphemerisSource, Protocol):
    """An :class:`~ucbplan.core.params.EphemerisSource` with a name for the title (a Target)."""

    @property
    def name(self) -> str:
        """Target name."""
        ...


def _envelope(
    days: np.ndarray, values: np.ndarray, omega_dot: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """Upper/lower envelope over one apsidal half-period (σ_u oscillates at 2ω̇ at an anchor)."""
    if omega_dot == 0.0:
        return days, values, None
    width = math.pi / abs(omega_dot) / DAY_S
    edges = np.arange(days[0], days[-1] + width, width)
    idx = np.digitize(days, edges)
    keep = np.unique(idx)
    centres = np.array([days[idx == i].mean() for i in keep])
    upper = np.array([values[idx == i].max() for i in keep])
    lower = np.array([values[idx == i].min() for i in keep])
    return centres, upper, lower


def horizon_plot(
    target: NamedSource, rows: Sequence[HorizonRow], path: Path, overwrite: bool = False
) -> None:
    """σ_u(t) after the LISA observation with the tolerance lines α·δu_tol (paper Fig. horizon).

    The curve is the quadrature-anchor σ_u (max over u★ = 0, π) and, dashed, the conjunction one.
    For a timing ephemeris (rows with a horizon before the reference) the time axis runs from
    before to after T0 and both horizons are marked. Written atomically to ``path`` (PNG, PDF or
    SVG by suffix).

    Raises
    ------
    OutputExistsError
        If ``path`` exists and ``overwrite`` is false.
    """
    plt = pyplot()
    two_sided = any(r.two_sided for r in rows)
    longest = max([r.t_valid_days for r in rows] + [365.0])
    if two_sided:
        earliest = max([r.t_valid_before_days or 0.0 for r in rows] + [365.0])
        days = np.linspace(-1.3 * earliest, 1.3 * longest, 20000)
    else:
        days = np.linspace(-target.t_obs_s / DAY_S, 1.3 * longest, 20000)
    quad, conj = _anchor_curves(target, days)
    fig, ax = plt.subplots(figsize=(8, 4.5), constrained_layout=True)
    for curve, color, ls, name in (
        (quad, "k", "-", "quadrature"),
        (conj, "0.5", "--", "conjunction"),
    ):
        days_c, upper, lower = _envelope(days, 1e3 * curve, target.params.omega_dot)
        if lower is not None:
            ax.fill_between(days_c, lower, upper, color=color, alpha=0.15, lw=0)
        label = f"σ_u, {name} anchor" + (
            " (upper envelope; band: apsidal oscillation)" if lower is not None else ""
        )
        ax.semilogy(
            days_c, upper, color=color, ls=ls, lw=1.5 if name == "quadrature" else 1.0, label=label
        )
    _tolerance_lines(ax, rows, days[0])
    ax.axvline(0.0, color="k", ls="--", lw=0.8)
    ax.set_xlabel(
        "time from the reference epoch T0 [days]"
        if two_sided
        else "time after the end of the LISA observation [days]"
    )
    ax.set_ylabel("σ_u [mrad]")
    ax.set_title(f"{target.name}: phase-coherence forecast")
    ax.legend(loc="lower right", fontsize=8)
    save_figure(fig, path, overwrite=overwrite, dpi=120)


def _anchor_curves(target: EphemerisSource, days: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Quadrature (max over u★ = 0, π) and conjunction (π/2, 3π/2) σ_u [rad] at ``days``
    after the end of the LISA observation."""
    p, cov = target.params, target.covariance
    tau = target.t_obs_s / 2 + days * DAY_S
    quad = np.maximum(anchor_sigma_u(p, cov, tau, 0.0), anchor_sigma_u(p, cov, tau, math.pi))
    conj = np.maximum(
        anchor_sigma_u(p, cov, tau, math.pi / 2), anchor_sigma_u(p, cov, tau, 3 * math.pi / 2)
    )
    return quad, conj


def _row_text(r: HorizonRow) -> str:
    """The T_valid part of a tolerance-line label."""
    if r.t_valid_before_days is not None:
        return f"T_valid = {r.t_valid_before_days:.0f} d before, {r.t_valid_days:.0f} d after"
    return f"T_valid = {r.t_valid_days:.0f} d"


def _merged_labels(rows: Sequence[HorizonRow]) -> list[tuple[HorizonRow, str]]:
    """One label per distinct (α, tolerance, T_valid): anchors that share a line share a label
    (conjunction and zero-crossing have the same tolerance and would overprint)."""
    groups: dict[tuple[float, float, str], list[HorizonRow]] = {}
    for r in rows:
        groups.setdefault((r.alpha, round(r.tolerance_rad, 12), _row_text(r)), []).append(r)
    return [
        (g[0], f" {', '.join(r.anchor for r in g)}, α={g[0].alpha:g}: {_row_text(g[0])}")
        for g in groups.values()
    ]


def _tolerance_lines(ax: Any, rows: Sequence[HorizonRow], x_text: float) -> None:
    """One horizontal line α·δu_tol per row, labelled, and a vertical line at its T_valid.

    Labels of lines closer than ~15 % in σ_u (one text height on the log axis) alternate above and
    below their line so that they do not overprint.
    """
    colors = {"conjunction": "tab:red", "quadrature": "tab:blue"}
    previous = -math.inf
    below = False
    for r, label in sorted(_merged_labels(rows), key=lambda item: item[0].tolerance_rad):
        c = colors.get(r.anchor, "tab:green")
        ls = "-" if r.alpha >= 1 else ":"
        y = 1e3 * r.tolerance_rad
        ax.axhline(y, color=c, ls=ls, lw=1)
        below = (not below) if y < 1.15 * previous else False
        previous = y
        ax.text(
            x_text, y, label, color=c, va="top" if below else "bottom", fontsize=8,
            bbox={"fc": "white", "ec": "none", "alpha": 0.75, "pad": 1.0},  # readable on curves
        )  # fmt: skip
        for other in rows:
            if other.alpha == r.alpha and other.tolerance_rad == r.tolerance_rad:
                _valid_lines(ax, other, colors.get(other.anchor, "tab:green"), ls)


def _valid_lines(ax: Any, r: HorizonRow, c: str, ls: str) -> None:
    """Vertical lines at the row's T_valid after (and before) the reference."""
    if r.t_valid_days > 0:
        ax.axvline(r.t_valid_days, color=c, ls=ls, lw=0.6, alpha=0.6)
    if r.t_valid_before_days:
        ax.axvline(-r.t_valid_before_days, color=c, ls=ls, lw=0.6, alpha=0.6)
