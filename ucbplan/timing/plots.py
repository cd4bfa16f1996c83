"""The O − C diagram of an ephemeris fit.

Top: observed minus the linear part of the fitted ephemeris (T0 + P·n) against cycle, with
error bars, and the fitted curve (the ½PṖn² (+ ⅙P²P̈n³) term): a period change shows as the
parabola. Bottom: residuals from the full fit. Secondary eclipses are open symbols, clipped times
crosses, outliers ringed.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ucbplan.plotting import pyplot, save_figure
from ucbplan.timing.eclipse_table import EclipseTimes
from ucbplan.timing.fit import EphemerisFit

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def oc_figure(fit: EphemerisFit, times: EclipseTimes, title: str | None = None) -> Figure:
    """The O − C figure (not yet written)."""
    plt = pyplot()
    fig, (top, bottom) = plt.subplots(
        2, 1, sharex=True, figsize=(7.5, 6.0), gridspec_kw={"height_ratios": [2, 1]}
    )
    nu = fit.nu
    linear = fit.values[0] + fit.values[1] * nu
    oc = times.t_s - linear
    err = times.sigma_s
    rows = set(fit.outliers)
    is_out = np.array([int(r) in rows for r in times.rows])
    for sel, style, label in (
        (fit.used & ~times.secondary, {"fmt": "o", "color": "C0"}, "primary"),
        (fit.used & times.secondary, {"fmt": "o", "mfc": "none", "color": "C0"}, "secondary"),
        (~fit.used, {"fmt": "x", "color": "C3"}, "clipped"),
    ):
        if sel.any():
            top.errorbar(nu[sel], oc[sel], yerr=err[sel], ms=4, lw=0.8, label=label, **style)
            bottom.errorbar(nu[sel], fit.o_minus_c_s[sel], yerr=err[sel], ms=4, lw=0.8, **style)
    if is_out.any():
        for ax, y in ((top, oc), (bottom, fit.o_minus_c_s)):
            ax.plot(nu[is_out], y[is_out], "o", ms=10, mfc="none", color="C1", label=None)
        top.plot([], [], "o", ms=10, mfc="none", color="C1", label="outlier (> 4σ)")
    grid = np.linspace(float(nu.min()), float(nu.max()), 400)
    curve = fit.model_s(grid) - (fit.values[0] + fit.values[1] * grid)
    top.plot(grid, curve, "-", color="k", lw=1.2, label="fitted ephemeris")
    bottom.axhline(0.0, color="k", lw=1.0)
    top.set_ylabel("O − C (linear ephemeris) [s]")
    bottom.set_ylabel("residual [s]")
    bottom.set_xlabel(f"cycle since T0 ({_t0_label(fit)}) [1]")
    scale = f", σ's ×{fit.sigma_scale:.2f}" if fit.rescaled else ""
    ratio = f"{fit.chi2 / fit.dof:.2f}" if fit.dof > 0 else "n/a"
    top.set_title(title or f"{fit.source}: {fit.n_used} times, χ²/dof = {ratio}{scale}")
    top.legend(fontsize="small")
    fig.tight_layout()
    return fig


def _t0_label(fit: EphemerisFit) -> str:
    from ucbplan.core.timing_epochs import format_bjd

    return format_bjd(fit.t0_jd, decimals=7)


def plot_oc(fit: EphemerisFit, times: EclipseTimes, path: Path, *, overwrite: bool = False) -> None:
    """Write the O − C figure to ``path`` (atomic; format from the suffix)."""
    save_figure(oc_figure(fit, times), path, overwrite=overwrite)
