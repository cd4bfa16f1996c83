"""Summary figures of a population forecast: T_valid vs f and vs SNR, cumulative counts."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ucbplan.plotting import pyplot, save_figure


def forecast_plots(
    tab: Any, folder: Path, *, column: str = "t_valid_quadrature_a1", overwrite: bool = False
) -> list[Path]:
    """Write three PNGs into ``folder`` from the ``ok`` rows of a forecast table; their paths."""
    plt = pyplot()
    ok = np.asarray(tab["status"]) == "ok"
    tv = np.asarray(tab[column], dtype=float)[ok]
    f_mhz = np.asarray(tab["f_gw"], dtype=float)[ok] * 1e3
    snr = np.asarray(tab["snr"], dtype=float)[ok]
    label = f"T_valid ({column.removeprefix('t_valid_').replace('_a', ', α=')}) [d]"
    tv_plot = np.where(tv > 0, tv, np.nan)
    out: list[Path] = []
    for name, x, xlabel in (
        ("tvalid_vs_f.png", f_mhz, "GW frequency f [mHz]"),
        ("tvalid_vs_snr.png", snr, "LISA optimal SNR [1]"),
    ):
        fig, ax = plt.subplots(figsize=(6, 4))
        ax.scatter(x, tv_plot, s=8)
        ax.set_xscale("log")
        ax.set_yscale("log")
        _plain_log_ticks(ax.xaxis)
        ax.set_xlabel(xlabel)
        ax.set_ylabel(label)
        ax.set_title(f"{int(ok.sum())} constrained sources (T_valid = 0 not shown)")
        path = folder / name
        fig.tight_layout()
        save_figure(fig, path, overwrite=overwrite)
        out.append(path)
    fig, ax = plt.subplots(figsize=(6, 4))
    xs = np.sort(tv[tv > 0])
    ax.step(xs, np.arange(xs.size, 0, -1), where="post")
    ax.set_xscale("log")
    ax.set_xlabel(label)
    ax.set_ylabel("number of sources with T_valid > x [1]")
    fig.tight_layout()
    path = folder / "tvalid_cumulative.png"
    save_figure(fig, path, overwrite=overwrite)
    out.append(path)
    return out


def _plain_log_ticks(axis: Any) -> None:
    """Plain numbers (2, 3, 10, 20) on a log axis that spans little more than a decade.

    Matplotlib's default labels the minor ticks as 2×10⁰, 3×10⁰ …, which overprint each other.
    """
    from matplotlib.ticker import LogLocator, NullFormatter, ScalarFormatter

    axis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
    axis.set_major_formatter(ScalarFormatter())
    axis.set_minor_formatter(NullFormatter())
