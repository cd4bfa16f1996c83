"""Figures of the LISA simulation: corner plots (``corner``) and the band ASD figure.

Every figure is written atomically through :func:`ucbplan.plotting.save_figure` (110 dpi).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from ucbplan.io import check_output_path
from ucbplan.plotting import pyplot, save_figure

if TYPE_CHECKING:
    from ucbplan.lisa.lines import WaveformLines
    from ucbplan.lisa.simulation import SimulationResult

#: File names written by :func:`simulation_corner_plots`.
CORNER_NAMES = ("corner_start.png", "corner_midpoint.png", "corner_e_omega.png")
_DPI = 110
#: Axis labels of the sampled parameters.
_LABELS = {
    "log10_amplitude": r"$\log_{10}\mathcal{A}$ [1]",
    "f_gw": r"$f_0$ [Hz]",
    "log10_fdot": r"$\log_{10}\dot f$ [dex(Hz/s)]",
    "fdot": r"$\dot f$ [Hz/s]",  # sources with fdot < 1e-18 Hz/s are sampled in fdot itself
    "cos_inclination": r"$\cos\iota$ [1]",
    "psi": r"$\psi$ [rad]",
    "phase": r"$\phi_0$ [rad]",
    "eta": r"$\eta_0$ [1]",
    "kappa": r"$\kappa_0$ [1]",
    "z_omega": r"$z_\omega$ [bins]",
}


def corner_plot(
    samples: NDArray[np.float64],
    labels: list[str],
    truths: list[float] | None,
    path: Path,
    title: str = "",
    *,
    overwrite: bool = False,
) -> None:
    """Corner plot of (S, D) samples with dashed truth lines, written to ``path`` (PNG/PDF)."""
    pyplot()
    import corner

    fig = corner.corner(
        samples,
        labels=labels,
        truths=truths,
        truth_color="C3",
        show_titles=True,
        title_fmt=".3g",
        quantiles=[0.16, 0.5, 0.84],
        label_kwargs={"fontsize": 9},
        title_kwargs={"fontsize": 8},
        max_n_ticks=3,
        labelpad=0.15,
    )
    # room between panels for the 45° tick labels, below them for the offset text, and at the
    # left and bottom for the labels moved clear of it
    par = fig.subplotpars
    width, height = fig.get_size_inches()
    fig.subplots_adjust(
        left=par.left + 0.4 / width, bottom=par.bottom + 0.4 / height, wspace=0.12, hspace=0.12
    )
    for ax in fig.axes:
        ax.tick_params(labelsize=7)
    if title:
        # in the empty upper triangle, clear of the first panel's title
        fig.suptitle(title, x=0.97, y=0.97, ha="right", va="top")
    save_figure(fig, path, overwrite=overwrite, dpi=_DPI)


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
    *,
    overwrite: bool = False,
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
    fig, axes = pyplot().subplots(
        len(harmonics), 1, figsize=(7, 2.9 * len(harmonics)), squeeze=False, layout="constrained"
    )
    for b, ax in enumerate(axes[:, 0]):
        f = freqs_hz[b] * 1e3
        # one-sided ASD of the signal on the same scale as sqrt(S): 2 |x~| / sqrt(T)
        ax.semilogy(f, 2 * np.abs(bands[b, 0]) / np.sqrt(t_obs_s), color="C3", lw=1, label="A")
        ax.semilogy(f, 2 * np.abs(bands[b, 1]) / np.sqrt(t_obs_s), color="C1", lw=1, label="E")
        ax.semilogy(f, np.sqrt(psd[b]), color="k", lw=1, label="noise (incl. foreground)")
        if psd_instrument is not None:
            ax.semilogy(f, np.sqrt(psd_instrument[b]), "k--", lw=0.8, label="instrument")
        _mark_lines(ax, freqs_hz[b, 0], freqs_hz[b, -1], line_freqs_hz, unshifted_hz)
        _label_band(ax, harmonics[b], freqs_hz.shape[1])
    # one legend above the panels, clear of the lines
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside upper center", ncol=len(labels), fontsize=8)
    save_figure(fig, path, overwrite=overwrite, dpi=_DPI)


def _label_band(ax: Any, harmonic: int, n_bins: int) -> None:
    """Axis labels, title and plain frequency ticks of the band of harmonic ``harmonic``."""
    from matplotlib.ticker import MaxNLocator

    ax.set_ylabel("ASD [1/√Hz]")
    ax.set_title(f"n = {harmonic} band ({n_bins} bins)", fontsize=9)
    ax.set_xlabel("frequency [mHz]", fontsize=8)
    # plain frequencies: an offset ("+1.2609e1") is easy to misread
    ax.ticklabel_format(axis="x", useOffset=False)
    ax.xaxis.set_major_locator(MaxNLocator(5))


def _mark_lines(
    ax: Any, lo: float, hi: float, line_freqs_hz: dict[str, float], unshifted_hz: dict[str, float]
) -> None:
    """Dashed lines at the line positions in [lo, hi] Hz: unshifted black, shifted red, named."""
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


def waveform_plot(lines: WaveformLines, path: Path, *, overwrite: bool = False) -> None:
    """:func:`asd_plot` of ``ucbplan waveform``: the bands with instrument-only noise and the
    line positions with and without the apsidal shift."""
    from ucbplan.lisa.noise import NoiseModel, psd_a
    from ucbplan.lisa.source import line_frequencies

    fm, t_obs_s = lines.model.model, lines.model.t_obs_s
    inst = psd_a(fm.freqs_hz, t_obs_s, NoiseModel(foreground=False))
    zero_shift = line_frequencies(lines.model.truth.f_gw, 0.0)
    unshifted = {k: v for k, v in zip(lines.line_freqs_hz, zero_shift, strict=False)}
    asd_plot(
        fm.freqs_hz,
        lines.bands,
        lines.psd,
        fm.harmonics,
        lines.line_freqs_hz,
        unshifted,
        t_obs_s,
        path,
        inst,
        overwrite=overwrite,
    )


def _midpoint_corner(result: SimulationResult, path: Path, overwrite: bool) -> None:
    """Midpoint parameters, the frequency as an offset in Fourier bins (Δf_mid T_obs)."""
    cols, inj, t_obs_s = result.columns, result.injected, result.model.t_obs_s
    mid = ["fdot", "f_gw", "phase"] + (["eta", "kappa", "omega_dot"] if "eta" in cols else [])
    # as the paper's midpoint figure: the frequency offset in Fourier bins, Delta f_mid T_obs
    data = np.stack([(cols[n] - inj[n]) * t_obs_s if n == "f_gw" else cols[n] for n in mid], axis=1)
    labels = [
        r"$\dot f$ [Hz/s]",
        r"$\Delta f_{\rm mid} T_{\rm obs}$ [bins]",
        r"$\phi_{\rm mid}$ [rad]",
    ]
    labels += [r"$\eta_{\rm mid}$ [1]", r"$\kappa_{\rm mid}$ [1]", r"$\dot\omega$ [rad/s]"][
        : len(mid) - 3
    ]
    truths = [inj[n] if n != "f_gw" else 0.0 for n in mid]
    corner_plot(data, labels, truths, path, "midpoint t_mid", overwrite=overwrite)


def _eccentricity_corner(result: SimulationResult, path: Path, overwrite: bool) -> None:
    """e, ω_0 and z_ω at the start epoch."""
    flat, theta0, names = result.samples, result.problem.theta0, result.chain.names
    i_e, i_k, i_z = names.index("eta"), names.index("kappa"), names.index("z_omega")
    e = np.hypot(flat[:, i_e], flat[:, i_k])
    w0 = np.arctan2(flat[:, i_e], flat[:, i_k])
    tr = [
        float(np.hypot(theta0[i_e], theta0[i_k])),
        float(np.arctan2(theta0[i_e], theta0[i_k])),
    ]
    corner_plot(
        np.stack([e, w0, flat[:, i_z]], axis=1),
        [r"$e$ [1]", r"$\omega_0$ [rad]", r"$z_\omega$ [bins]"],
        [*tr, float(theta0[i_z])],
        path,
        "eccentricity and apsidal advance",
        overwrite=overwrite,
    )


def simulation_corner_plots(
    result: SimulationResult, folder: Path, *, overwrite: bool = False
) -> list[Path]:
    """Corner plots of a simulation into ``folder`` (names :data:`CORNER_NAMES`).

    Start-epoch sampled parameters, midpoint parameters, and (eccentric model) e, ω_0, z_ω.

    Raises
    ------
    OutputExistsError
        A figure exists and ``overwrite`` is false (checked for all before writing any).
    """
    paths = [folder / name for name in CORNER_NAMES]
    for p in paths:
        check_output_path(p, overwrite)
    names, theta0 = result.chain.names, result.problem.theta0
    labels = [_LABELS[n] for n in names]
    corner_plot(
        result.samples, labels, list(theta0), paths[0], "start epoch t_0", overwrite=overwrite
    )
    _midpoint_corner(result, paths[1], overwrite)
    if "eta" not in names:
        return paths[:2]
    _eccentricity_corner(result, paths[2], overwrite)
    return paths
