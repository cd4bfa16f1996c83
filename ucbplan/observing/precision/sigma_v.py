"""The RV precision of one spectrum as a function of its exposure time, magnitude and airmass.

``--sigma-v`` takes three forms (:func:`parse_sigma_v`):

- ``30`` (or ``30km/s``): σ_v of every exposure, whatever its length. The exposure time is then
  not optimised (a longer exposure would not be more precise).
- ``30km/s@600s``: σ_v of one 600-s spectrum of this target; other exposure times scale as
  photons do.
- ``30km/s@600s,V=20.0``: σ_v of one 600-s spectrum of a V = 20.0 star; the target's own V
  magnitude sets its σ_v.

The photon-limited law (the one ``configs/instruments.yaml`` states for the instruments' σ_ref)::

    σ_v,i = σ_ref · (T_ref/T_i)^½ · 10^{0.2 (m − m_ref)} · 10^{0.2 k (X_i − 1)}

(the flux falls as 10^{−0.4(m + kX)}, the velocity noise as flux^{−½}), with k the extinction
[mag/airmass] and X_i the airmass at the exposure's centre, and an optional systematic floor
σ_sys added in quadrature: σ_v,i ← (σ_v,i² + σ_sys²)^½.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ucbplan.core.constants import HOUR_S
from ucbplan.errors import InputError, shorten
from ucbplan.inputs import check_range

#: Photometric bands a σ_v reference may be quoted in (Johnson-Cousins, SDSS, Gaia, 2MASS).
KNOWN_BANDS = (
    "U",
    "B",
    "V",
    "R",
    "I",
    "u",
    "g",
    "r",
    "i",
    "z",
    "G",
    "BP",
    "RP",
    "J",
    "H",
    "K",
    "Ks",
)
#: Largest σ_v of a reference spectrum, or systematic floor [km/s].
MAX_SIGMA_KMS = 1.0e4
#: Longest reference exposure [s] (12 h: one night).
MAX_REF_EXPTIME_S = 43200.0
#: Open range of reference magnitudes [mag].
MAG_LIMITS = (-30.0, 40.0)
#: Largest extinction coefficient [mag/airmass].
MAX_EXTINCTION = 5.0

_NUMBER = r"([+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)"
_FORM = re.compile(
    rf"^\s*{_NUMBER}\s*(km/s|kms|m/s)?\s*(?:@\s*{_NUMBER}\s*(s|sec|min|h)?\s*)?"
    rf"(?:,\s*([A-Za-z]+)\s*=\s*{_NUMBER}\s*)?$"
)
_TIME_UNITS = {None: 1.0, "s": 1.0, "sec": 1.0, "min": 60.0, "h": HOUR_S}
_FORMS = "a number in km/s (30), or 30km/s@600s, or 30km/s@600s,V=20.0"

F64 = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class SigmaVModel:
    """σ_v of one spectrum [km/s] (module notes).

    Attributes
    ----------
    sigma_kms : float
        σ_v of the reference spectrum [km/s].
    exptime_s : float or None
        Reference exposure time T_ref [s]; None: ``sigma_kms`` holds for every exposure.
    band, mag : str or None, float or None
        Band and magnitude of the reference star; None: the reference is the target itself.
    floor_kms : float
        Systematic floor σ_sys added in quadrature [km/s].
    extinction_k : float
        Extinction coefficient k [mag/airmass] in the reference band.
    option : str
        The parameter (or flag) it was given as, named in error messages.
    """

    sigma_kms: float
    exptime_s: float | None = None
    band: str | None = None
    mag: float | None = None
    floor_kms: float = 0.0
    extinction_k: float = 0.0
    option: str = "sigma_v_kms"

    def __post_init__(self) -> None:
        why = "sigma_v of one spectrum"
        check_range(self.option, self.sigma_kms, 0.0, MAX_SIGMA_KMS, "km/s", why, low_open=True)
        if self.exptime_s is not None:
            why = "reference exposure time"
            check_range(
                self.option, self.exptime_s, 0.0, MAX_REF_EXPTIME_S, "s", why, low_open=True
            )
        if (self.band is None) != (self.mag is None):
            raise InputError(f"{self.option}: give both a band and a magnitude (V=20.0), or none")
        if self.band is not None:
            _check_band(self.option, self.band)
            check_range(self.option, self.mag, *MAG_LIMITS, "mag", "reference magnitude")
        why = "systematic floor added in quadrature"
        check_range("sigma_floor_kms", self.floor_kms, 0.0, MAX_SIGMA_KMS, "km/s", why)
        why = "atmospheric extinction"
        check_range("extinction_k", self.extinction_k, 0.0, MAX_EXTINCTION, "mag/airmass", why)

    @property
    def follows_exposure(self) -> bool:
        """Whether σ_v depends on the exposure time (a reference exposure was given)."""
        return self.exptime_s is not None

    def target_mag(self, magnitudes: Mapping[str, float], name: str = "target") -> float | None:
        """The target's magnitude in the reference band (None when the reference is the
        target itself).

        Raises
        ------
        InputError
            The target file has no magnitude in that band.
        """
        if self.band is None:
            return None
        exact = {b.strip(): m for b, m in magnitudes.items()}
        if self.band in exact:  # SDSS g and Gaia G are different bands
            return float(exact[self.band])
        loose = [m for b, m in exact.items() if b.lower() == self.band.lower()]
        if len(loose) == 1 and self.band not in ("g", "G"):
            return float(loose[0])
        have = ", ".join(magnitudes) or "none"
        raise InputError(
            f"{name}: magnitudes: expected a {self.band} magnitude (the band of {self.option}), "
            f"got {have}; add magnitudes: {{{self.band}: ...}} to the target file"
        )

    def sigma(
        self, exptime_s: ArrayLike, airmass: ArrayLike = 1.0, mag: float | None = None
    ) -> F64:
        """σ_v [km/s] of exposures of ``exptime_s`` [s] at ``airmass``, for a star of ``mag``
        (in the reference band; ignored without a reference magnitude). Vectorised.

        A fixed σ_v (no reference exposure) is returned as it is, broadcast.
        """
        t = np.asarray(exptime_s, dtype=np.float64)
        x = np.asarray(airmass, dtype=np.float64)
        if not self.follows_exposure:
            shape = np.broadcast(t, x).shape
            return np.full(shape, math.hypot(self.sigma_kms, self.floor_kms))
        assert self.exptime_s is not None  # follows_exposure
        photon = self.sigma_kms * np.sqrt(self.exptime_s / t)
        if self.mag is not None and mag is not None:
            photon = photon * 10.0 ** (0.2 * (mag - self.mag))
        photon = photon * 10.0 ** (0.2 * self.extinction_k * (x - 1.0))
        return np.asarray(np.hypot(photon, self.floor_kms), dtype=np.float64)

    def describe(self) -> str:
        """The model as a short text, e.g. ``30 km/s @ 600 s (V = 20), floor 2 km/s``."""
        if not self.follows_exposure:
            text = f"{self.sigma_kms:g} km/s per exposure"
        else:
            text = f"{self.sigma_kms:g} km/s @ {self.exptime_s:g} s"
            if self.band is not None:
                text += f" ({self.band} = {self.mag:g})"
            if self.extinction_k:
                text += f", k = {self.extinction_k:g} mag/airmass"
        if self.floor_kms:
            text += f", floor {self.floor_kms:g} km/s"
        return text


def _check_band(option: str, band: str) -> None:
    if band not in KNOWN_BANDS:
        near = [b for b in KNOWN_BANDS if b.lower() == band.lower()]
        hint = f" (did you mean {near[0]}?)" if near else ""
        raise InputError(
            f"{option}: unknown band {shorten(band, 20)}{hint}; expected one of "
            f"{', '.join(KNOWN_BANDS)}"
        )


def parse_sigma_v(
    text: str | float,
    *,
    floor_kms: float = 0.0,
    extinction_k: float = 0.0,
    option: str = "sigma_v_kms",
) -> SigmaVModel:
    """``--sigma-v`` text → :class:`SigmaVModel` (module notes for the forms).

    Raises
    ------
    InputError
        Any other form, a non-positive σ_v or time, an unknown band: one line with the forms.
    """
    if isinstance(text, int | float) and not isinstance(text, bool):
        return SigmaVModel(float(text), floor_kms=floor_kms, option=option)
    m = _FORM.match(str(text)[:80])
    if not m:
        raise InputError(f"{option}: expected {_FORMS}, got {shorten(text, 60)}")
    value, unit, t_ref, t_unit, band, mag = m.groups()
    sigma = float(value) / (1000.0 if unit == "m/s" else 1.0)
    exptime = float(t_ref) * _TIME_UNITS[t_unit] if t_ref is not None else None
    if band is not None and exptime is None:
        raise InputError(
            f"{option}: a reference magnitude needs a reference exposure "
            f"(30km/s@600s,{band}={mag}), got {shorten(text, 60)}"
        )
    return SigmaVModel(
        sigma_kms=sigma,
        exptime_s=exptime,
        band=band,
        mag=float(mag) if mag is not None else None,
        floor_kms=floor_kms,
        extinction_k=extinction_k if exptime is not None else 0.0,
        option=option,
    )
