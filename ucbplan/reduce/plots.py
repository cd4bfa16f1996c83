"""Figures of a reduction: RV vs F̄ with residuals, Δv1 vs Δv2, and the mass–mass diagram (Sec. 5).

Uses :func:`ucbplan.plotting.pyplot` (Agg, no display). Each ``fig_*`` function returns a matplotlib
Figure (or None when not applicable); :func:`plot_all` writes them with
:func:`ucbplan.plotting.save_figure` (atomic: no partial files, no silent overwrite).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from ucbplan.io import check_output_path
from ucbplan.plotting import pyplot, save_figure

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ucbplan.reduce.pipeline import Reduction

#: File names written by :func:`plot_all`.
PLOT_NAMES = ("rv_vs_F.png", "dv1_vs_dv2.png", "mass_mass.png")


def fig_rv(red: Reduction) -> Figure:
    """Velocities vs the window-averaged orbital factor F̄ with the fitted lines and residuals.

    Notes
    -----
    Eqs. v1v2_ecc_rv / vbar_master: v1 = γ1 + K1 F̄, v2 = γ2 − K2 F̄.
    """
    plt = pyplot()
    fig, (ax, axr) = plt.subplots(
        2, 1, figsize=(7, 6), sharex=True, gridspec_kw={"height_ratios": [3, 1]}
    )
    draw_rv(red, ax, axr)
    fig.tight_layout()
    return fig


def draw_rv(red: Reduction, ax: Any, axr: Any = None) -> None:
    """Draw the velocities vs F̄ with the fitted lines on ``ax`` and, given ``axr``, the
    residuals there (:func:`fig_rv`'s panels)."""
    colors = ("tab:blue", "tab:red")
    for j, f in enumerate(red.fits):
        x = red.design[j]
        v, s = red.table.v[j], red.table.sigma[j]
        sign = 1.0 if j == 0 else -1.0
        xx = np.linspace(x.min(), x.max(), 50)
        ax.errorbar(
            x,
            v,
            s,
            fmt=".",
            ms=3,
            alpha=0.5,
            color=colors[j],
            label=f"star {j + 1}: K = {f.K:.2f} ± {f.sigma_K:.2f} km/s",
        )
        ax.plot(xx, f.gamma + sign * f.K * xx, color="k", lw=1)
        if axr is None:
            continue
        axr.errorbar(x, f.line.residuals, s, fmt=".", ms=3, alpha=0.5, color=colors[j])
        out = f.line.outliers
        if np.any(out):
            axr.plot(x[out], f.line.residuals[out], "kx", label="> 4σ")
    ax.set_ylabel("radial velocity [km/s]")
    ax.legend(loc="best", fontsize=8)
    ax.set_title(f"{red.target.name}: v–F regressions")
    xlabel = "F̄ = window-averaged cos u + κ_LISA [dimensionless]"
    if axr is None:
        ax.set_xlabel(xlabel)
        return
    axr.axhline(0.0, color="k", lw=0.8)
    axr.set_ylabel("residual [km/s]")
    axr.set_xlabel(xlabel)


def fig_dv1_dv2(red: Reduction) -> Figure | None:
    """Fixed-u pairs Δv1 vs Δv2 with the WIL41-on-differences line (Eq. SB2_fixedu_diff_WIL41).

    Returns None when there are no SB2 pairs.
    """
    pairs = [p for p in red.drift.pairs if len(p.dv) == 2]
    if not pairs:
        return None
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6, 5))
    x = np.array([p.dv[1] for p in pairs])
    y = np.array([p.dv[0] for p in pairs])
    ax.errorbar(
        x,
        y,
        xerr=[p.sigma_dv[1] for p in pairs],
        yerr=[p.sigma_dv[0] for p in pairs],
        fmt="o",
        label="fixed-u pairs",
    )
    xx = np.linspace(x.min() - 5, x.max() + 5, 10)
    if red.drift.wil41_line is not None:
        ln = red.drift.wil41_line
        ax.plot(
            xx,
            ln.intercept + ln.slope * xx,
            "k-",
            label=f"fit: q = {red.drift.q_line:.3f} ± {red.drift.sigma_q_line:.3f}",
        )
    if len(red.fits) == 2:
        q = red.fits[0].K / red.fits[1].K
        ax.plot(xx, -q * xx, "k:", label=f"expected: slope −q (q = {q:.4f} from K1/K2), Δv_CM = 0")
    ax.set_xlabel("Δv2 [km/s]")
    ax.set_ylabel("Δv1 [km/s]")
    ax.legend(fontsize=8)
    ax.set_title("Inter-session differences at fixed u")
    fig.tight_layout()
    return fig


def _band(
    ax: Any,
    M1: NDArray[np.float64],
    M2: NDArray[np.float64],
    g: NDArray[np.float64],
    value: float,
    sigma: float,
    color: str,
    label: str,
) -> None:
    if not (np.isfinite(value) and np.isfinite(sigma)):
        return
    ax.contourf(
        M1,
        M2,
        (np.abs(g - value) <= sigma).astype(float),
        levels=[0.5, 1.5],
        colors=[color],
        alpha=0.35,
    )
    ax.contour(M1, M2, g, levels=[value], colors=[color], linewidths=1.2)
    ax.plot([], [], color=color, lw=6, alpha=0.5, label=label)


def fig_mass_mass(red: Reduction) -> Figure | None:
    """Mass–mass diagram: q_SB2, M_tot^K, M_c (ḟ, GR only), M_tot^ω̇ loci with 1σ bands (Sec. 5).

    Returns None when no component masses were measured.
    """
    s = red.summaries
    if "M1" not in s:
        return None
    plt = pyplot()
    m1c, m2c = s["M1"].value, s["M2"].value
    span = max(0.08, 12 * max(s["M1"].sigma, s["M2"].sigma))
    g1 = np.linspace(m1c - span, m1c + span, 400)
    g2 = np.linspace(m2c - span, m2c + span, 400)
    M1, M2 = np.meshgrid(g1, g2)
    fig, ax = plt.subplots(figsize=(9.5, 6), layout="constrained")
    loci: list[
        tuple[
            Callable[[NDArray[np.float64], NDArray[np.float64]], NDArray[np.float64]], str, str, str
        ]
    ] = [
        (lambda a, b: b / a, "q", "tab:blue", "q_SB2 = K1/K2"),
        (lambda a, b: a + b, "M_tot", "tab:orange", "M_tot^K (Kepler)"),
        (lambda a, b: (a * b) ** 0.6 / (a + b) ** 0.2, "M_c_fdot", "tab:green", "M_c (ḟ, GR only)"),
        (lambda a, b: a + b, "M_tot_omega_dot", "tab:purple", "M_tot^ω̇ (ω̇ = ω̇_GR)"),
    ]
    for fn, key, color, label in loci:
        if key in s:
            _band(ax, M1, M2, fn(M1, M2), s[key].value, s[key].sigma, color, label)
    ax.errorbar(
        [m1c],
        [m2c],
        xerr=[[m1c - s["M1"].lo], [s["M1"].hi - m1c]],
        yerr=[[m2c - s["M2"].lo], [s["M2"].hi - m2c]],
        fmt="k*",
        ms=10,
        label=f"M1 = {m1c:.4f}, M2 = {m2c:.4f} M☉",
    )
    ax.set_xlabel("M1 [M☉]")
    ax.set_ylabel("M2 [M☉]")
    ax.set_xlim(g1[0], g1[-1])
    ax.set_ylim(g2[0], g2[-1])
    # beside the axes: inside, it covered the loci
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)
    ax.set_title(f"{red.target.name}: mass–mass diagram (1σ bands)")
    return fig


def plot_all(red: Reduction, folder: Path, *, overwrite: bool = False) -> list[Path]:
    """Write every applicable figure into ``folder`` (names :data:`PLOT_NAMES`).

    Raises
    ------
    OutputExistsError
        A figure exists and ``overwrite`` is false (checked for all before writing any).
    """
    for name in PLOT_NAMES:
        check_output_path(folder / name, overwrite)
    out = []
    for fn, name in (
        (fig_rv, PLOT_NAMES[0]),
        (fig_dv1_dv2, PLOT_NAMES[1]),
        (fig_mass_mass, PLOT_NAMES[2]),
    ):
        fig = fn(red)
        if fig is None:
            continue
        path = folder / name
        save_figure(fig, path, overwrite=overwrite, dpi=120)
        out.append(path)
    return out
