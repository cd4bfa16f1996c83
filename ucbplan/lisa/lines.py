"""The injected signal per band as a table (the library behind ``ucbplan waveform``).

One row per Fourier bin of each band; the columns are declared once in :data:`LINE_COLUMNS`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ucbplan.lisa.noise import SANGRIA, psd_a
from ucbplan.lisa.source import LINES, line_frequencies

if TYPE_CHECKING:
    from astropy.table import Table

    from ucbplan.lisa.simulation import LisaModel

#: Fourier and TDI conventions of the table (written to its metadata).
CONVENTION = (
    "one-sided Fourier transform x~(f) = int_0^T x(t) exp(-2 pi i f t) dt, t = 0 at the start of "
    "the LISA observation (FastGB/GBGPU convention); TDI A = (Z - X)/sqrt2, E = (X - 2Y + Z)/sqrt6"
    " of first-generation Michelson X, Y, Z in fractional frequency"
)
#: Columns of the lines table and their units (None: dimensionless).
LINE_COLUMNS: dict[str, str | None] = {
    "band": None,
    "freq_hz": "Hz",
    "A_re": "1/Hz",
    "A_im": "1/Hz",
    "E_re": "1/Hz",
    "E_im": "1/Hz",
    "psd_a": "1/Hz",
}


@dataclass(frozen=True, slots=True, eq=False)
class WaveformLines:
    """The injected TDI A, E per band with the noise PSD.

    Attributes
    ----------
    model : LisaModel
        The injection model.
    bands : numpy.ndarray
        Injected A, E (n_bands, 2, N) [1/Hz].
    psd : numpy.ndarray
        Noise PSD (n_bands, N) [1/Hz] (instrument + Galactic foreground).
    snr : float
        Optimal SNR of the injection.
    line_freqs_hz : dict of float
        Frequency of each line inside the modelled bands (apsidally shifted) [Hz].
    table : astropy.table.Table
        :data:`LINE_COLUMNS`, one row per bin, with the conventions in ``meta``.
    """

    model: LisaModel
    bands: NDArray[np.complex128]
    psd: NDArray[np.float64]
    snr: float
    line_freqs_hz: dict[str, float]
    table: Table

    def __repr__(self) -> str:
        nb, n = self.model.model.freqs_hz.shape
        return f"<WaveformLines {self.model.base.name}: {nb} bands x {n} bins, SNR {self.snr:.1f}>"


def _table(model: LisaModel, bands: NDArray[np.complex128], psd: NDArray[np.float64]) -> Table:
    from astropy.table import Table

    fm = model.model
    n = fm.freqs_hz.shape[1]
    values = {
        "band": np.repeat(np.array(fm.harmonics), n),
        "freq_hz": fm.freqs_hz.ravel(),
        "A_re": bands[:, 0].real.ravel(),
        "A_im": bands[:, 0].imag.ravel(),
        "E_re": bands[:, 1].real.ravel(),
        "E_im": bands[:, 1].imag.ravel(),
        "psd_a": psd.ravel(),
    }
    tab = Table({name: values[name] for name in LINE_COLUMNS})
    for name, unit in LINE_COLUMNS.items():
        if unit is not None:
            tab[name].unit = unit
    return tab


def waveform_lines(model: LisaModel) -> WaveformLines:
    """Injected TDI A, E on the band grid, the noise PSD and the optimal SNR."""
    fm, truth, t_obs_s = model.model, model.truth, model.t_obs_s
    bands = fm.bands_for(truth)
    psd = psd_a(fm.freqs_hz, t_obs_s, SANGRIA)
    snr = float(np.sqrt(np.sum(4.0 * np.abs(bands) ** 2 / (psd[:, None, :] * t_obs_s))))
    f_lines = line_frequencies(truth.f_gw, truth.omega_dot)
    lines = {
        line.name: float(f_lines[i])
        for i, line in enumerate(LINES)
        if line.harmonic in fm.harmonics
    }
    tab = _table(model, bands, psd)
    base = model.base
    tab.meta.update(
        {
            "target": base.name,
            "convention": CONVENTION,
            "t_start_tdb": base.t_start.tdb.isot,
            "t_obs_s": t_obs_s,
            "n_bins": model.n_bins,
            "band_harmonics": list(fm.harmonics),
            "line_freqs_hz": lines,
            "optimal_snr": snr,
            "noise": "LDC Sangria instrument + Galactic foreground (one-sided, TDI A = E)",
        }
    )
    return WaveformLines(model, bands, psd, snr, lines, tab)
