"""Figures of the LISA simulation: corner plots (``corner``) and the band ASD figure."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from numpy.typing import NDArray

__all__ = ["asd_plot", "corner_plot"]


def corner_plot(
    samples: NDArray[np.float64],
    labels: list[str],
    truths: list[float] | None,
    path: Path,
    title: str = "",
) -> None:
    """Corner plot of (S, D) samples with dashed truth lines, written to ``path`` (PNG/PDF)."""
    import matplotlib

    matplotlib.use("Agg")
    import corner
    import matplotlib.pyplot as plt

    fig = corner.corner(
        samples,
        labels=labels,
        truths=truths,
        truth_color="C3",
        show_titles=True,
        title_fmt=".3g",
        quantiles=[0.16, 0.5, 0.84],
        label_kwargs={"fontsize": 9},
    )
    if title:
        fig.suptitle(title)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def asd_plot(
    freqs_hz: NDArray[np.float64],
    bands: NDArray[np.complex128],
    psd: NDArray[np.float64],
    harmonics: tuple[int, ...],
    line_freqs_hz: dict[str, float],
    unshifted_hz: dict[str, float],
    t_obs_s: float,
    path: Path,
    psd_instrument: NDArray[np.float64] | None = None,
) -> None:
    """Paper Fig. wavforms: per band, the signal ASD 2|A~|/sqrt(T) vs the noise ASD.

    Parameters
    ----------
    freqs_hz : numpy.ndarray
        Bin frequencies (n_bands, N) [Hz].
    bands : numpy.ndarray
        Injected A, E (n_bands, 2, N).
    psd : numpy.ndarray
        Noise PSD (n_bands, N) [1/Hz] (instrument + foreground).
    line_freqs_hz, unshifted_hz : dict
        Line positions with and without the apsidal shift (dashed red / black).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(harmonics), 1, figsize=(7, 2.6 * len(harmonics)), squeeze=False)
    for b, ax in enumerate(axes[:, 0]):
        f = freqs_hz[b] * 1e3
        # one-sided ASD of the signal on the same scale as sqrt(S): 2 |x~| / sqrt(T)
        ax.semilogy(f, 2 * np.abs(bands[b, 0]) / np.sqrt(t_obs_s), color="C3", lw=1, label="A")
        ax.semilogy(f, 2 * np.abs(bands[b, 1]) / np.sqrt(t_obs_s), color="C1", lw=1, label="E")
        ax.semilogy(f, np.sqrt(psd[b]), color="k", lw=1, label="noise (incl. foreground)")
        if psd_instrument is not None:
            ax.semilogy(f, np.sqrt(psd_instrument[b]), "k--", lw=0.8, label="instrument")
        lo, hi = freqs_hz[b, 0], freqs_hz[b, -1]
        for fl in unshifted_hz.values():
            if lo <= fl <= hi:
                ax.axvline(fl * 1e3, color="k", ls="--", lw=0.7)
        for name, fl in line_freqs_hz.items():
            if lo <= fl <= hi:
                ax.axvline(fl * 1e3, color="r", ls="--", lw=0.7)
                ax.annotate(
                    name,
                    (fl * 1e3, 0.97),
                    xycoords=("data", "axes fraction"),
                    fontsize=7,
                    ha="left",
                    va="top",
                    color="r",
                )
        ax.set_ylabel("ASD [1/√Hz]")
        ax.set_title(f"n = {harmonics[b]} band ({freqs_hz.shape[1]} bins)", fontsize=9)
        ax.legend(fontsize=7, loc="lower right")
    axes[-1, 0].set_xlabel("frequency [mHz]")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
