"""Targeted-search likelihood over TDI A and E in the line bands, with the paper's priors.

Sampled parameters (paper Eq. ecc_waveform_params; Appendix apsidal_mcmc), referenced to the
start of the observation:

==================  ===========================================================================
log10_amplitude     uniform in [log10 A_s - 2, log10 A_s + 2] (A_s: search/injection value)
f_gw                uniform within +-10 Fourier bins of the search value (paper: +-10/T_obs)
log10_fdot          uniform in [-18, -12] (fdot > 0: inspiralling detached dWD; fdot [Hz/s]),
                    widened to one decade beyond a search value within a decade of its ends
fdot                replaces log10_fdot when the search value is below 1e-18 Hz/s (or <= 0:
                    a wide, low-mass or mass-transferring binary, whose fdot the data cannot
                    separate from 0 on a log scale): uniform in [-1e-12, 1e-12] Hz/s
cos_inclination     uniform in [-1, 1]
psi                 uniform in [0, pi] (psi -> psi + pi is an exact symmetry)
phase               uniform in [0, 2 pi]
eta, kappa          uniform in [-0.1, 0.1] with e = |eta + i kappa| < 0.1 (small-e model)
z_omega             uniform in [0, 50] bins (paper: omega_dot > 0 in GR); omega_dot = 2 pi z / T
==================  ===========================================================================

Circular sources sample the first six. The log-likelihood is Whittle's,
ln L = (d|h) - (h|h)/2 - (d|d)/2 with (a|b) = 4 Re sum a b* / (S T), summed over A and E and
all bands; it returns -inf outside the prior, never NaN.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ucbplan.core.constants import E_MAX
from ucbplan.lisa.noise import NoiseModel, psd_a
from ucbplan.lisa.source import SourceParams
from ucbplan.lisa.waveform import FourLineModel

if TYPE_CHECKING:
    from ucbplan.targets import Target

ECCENTRIC_NAMES: tuple[str, ...] = (
    "log10_amplitude",
    "f_gw",
    "log10_fdot",
    "cos_inclination",
    "psi",
    "phase",
    "eta",
    "kappa",
    "z_omega",
)
CIRCULAR_NAMES: tuple[str, ...] = ECCENTRIC_NAMES[:6]
#: The paper's log10 ḟ prior range [log10(Hz/s)]; below its floor ḟ is sampled linearly.
LOG10_FDOT_RANGE = (-18.0, -12.0)


def linear_fdot(fdot: float) -> bool:
    """Whether ḟ [Hz/s] is sampled linearly (below the paper's log10 ḟ floor, or ≤ 0)."""
    return not fdot >= 10.0 ** LOG10_FDOT_RANGE[0]


def sampled_names(eccentric: bool, fdot: float) -> tuple[str, ...]:
    """Names of the sampled coordinates for a search value ``fdot`` [Hz/s]."""
    names = ECCENTRIC_NAMES if eccentric else CIRCULAR_NAMES
    if linear_fdot(fdot):
        names = tuple("fdot" if n == "log10_fdot" else n for n in names)
    return names


@dataclass(frozen=True, slots=True)
class Prior:
    """Box priors (uniform) on the sampled parameters plus e < E_MAX.

    Attributes
    ----------
    names : tuple of str
        Sampled parameter names (ECCENTRIC_NAMES or CIRCULAR_NAMES).
    low, high : tuple of float
        Bounds in the order of ``names``.
    """

    names: tuple[str, ...]
    low: tuple[float, ...]
    high: tuple[float, ...]

    @classmethod
    def paper(cls, search: SourceParams, t_obs_s: float, eccentric: bool = True) -> Prior:
        """The targeted-search priors of Appendix apsidal_mcmc around a search value.

        The log10 ḟ range is the paper's [-18, -12], widened to one decade beyond a search value
        within a decade of its ends. Below 1e-18 Hz/s (or ḟ ≤ 0) ḟ itself is sampled, uniform
        in ±1e-12 Hz/s: a log prior has no floor there (its posterior piles up at the prior's
        lower edge and the Fisher σ of log10 ḟ exceeds any width), while ḟ's likelihood is a
        smooth Gaussian through 0.
        """
        la = float(np.log10(search.amplitude))
        lo, hi = LOG10_FDOT_RANGE
        lf = float(np.log10(search.fdot)) if search.fdot > 0 else lo
        df = 10.0 / t_obs_s
        bounds = {
            "log10_amplitude": (la - 2.0, la + 2.0),
            "f_gw": (search.f_gw - df, search.f_gw + df),
            # the paper's [-18, -12], widened so that it covers the source (ḟ < 1e-18 Hz/s: a
            # wide or low-mass binary; > 1e-12 Hz/s: nearly merging) with a decade to spare
            "log10_fdot": (min(lo, np.floor(lf) - 1.0), max(hi, np.ceil(lf) + 1.0)),
            "fdot": (-(10.0**hi), 10.0**hi),
            "cos_inclination": (-1.0, 1.0),
            "psi": (0.0, np.pi),
            "phase": (0.0, 2.0 * np.pi),
            "eta": (-E_MAX, E_MAX),
            "kappa": (-E_MAX, E_MAX),
            "z_omega": (0.0, 50.0),
        }
        names = sampled_names(eccentric, search.fdot)
        return cls(
            names=names,
            low=tuple(bounds[n][0] for n in names),
            high=tuple(bounds[n][1] for n in names),
        )

    def contains(self, theta: NDArray[np.float64]) -> NDArray[np.bool_]:
        """Boolean (W,) mask of parameter rows (W, D) inside the prior support."""
        th = np.atleast_2d(theta)
        ok = np.all(np.isfinite(th), axis=1)
        ok &= np.all((th >= np.asarray(self.low)) & (th <= np.asarray(self.high)), axis=1)
        if "eta" in self.names:
            e = np.hypot(th[:, self.names.index("eta")], th[:, self.names.index("kappa")])
            ok &= e < E_MAX
        return np.asarray(ok, dtype=bool)


def theta_from_source(p: SourceParams, t_obs_s: float, eccentric: bool = True) -> NDArray:
    """Sampled-coordinate vector (D,) of a physical parameter set (start epoch).

    The third coordinate is ḟ itself when :func:`linear_fdot`, else log10 ḟ.
    """
    th = [
        np.log10(p.amplitude),
        p.f_gw,
        p.fdot if linear_fdot(p.fdot) else np.log10(p.fdot),
        p.cos_inclination,
        p.psi,
        p.phase,
    ]
    if eccentric:
        th += [p.eta, p.kappa, p.omega_dot * t_obs_s / (2.0 * np.pi)]
    return np.asarray(th, dtype=float)


def physical_from_theta(
    theta: NDArray[np.float64], t_obs_s: float, names: tuple[str, ...] | None = None
) -> dict[str, NDArray]:
    """Physical (SI) parameter arrays (W,) from sampled rows (W, 6 or 9).

    ``names`` (the prior's) says whether column 2 is ḟ or log10 ḟ (default: log10 ḟ).
    """
    th = np.atleast_2d(theta)
    log_fdot = names is None or names[2] == "log10_fdot"
    out = {
        "amplitude": 10.0 ** th[:, 0],
        "f_gw": th[:, 1],
        "fdot": 10.0 ** th[:, 2] if log_fdot else th[:, 2],
        "cos_inclination": th[:, 3],
        "psi": th[:, 4],
        "phase": th[:, 5],
    }
    zeros = np.zeros(th.shape[0])
    if th.shape[1] > 6:
        out |= {
            "eta": th[:, 6],
            "kappa": th[:, 7],
            "omega_dot": 2.0 * np.pi * th[:, 8] / t_obs_s,
        }
    else:
        out |= {"eta": zeros, "kappa": zeros, "omega_dot": zeros}
    return out


class Likelihood:
    """Whittle likelihood of band data under the four-line model.

    Parameters
    ----------
    model : FourLineModel
        Template generator (same N and band centres as the data).
    data : numpy.ndarray
        Band data (n_bands, 2, N) on ``model.freqs_hz``.
    prior : Prior
        Prior support.
    noise : NoiseModel
        Noise PSD model for the weights.
    """

    def __init__(
        self,
        model: FourLineModel,
        data: NDArray[np.complex128],
        prior: Prior,
        noise: NoiseModel,
    ) -> None:
        self.model = model
        self.data = data
        self.prior = prior
        t_obs = model.grid.t_obs_s
        self.psd = psd_a(model.freqs_hz, t_obs, noise)  # (n_bands, N)
        self.weight = (4.0 / (self.psd * t_obs))[:, None, :]  # (n_bands, 1, N)
        self.d_d = float(np.sum(self.weight * np.abs(data) ** 2))
        # (d|h) = sum w (Re d Re h + Im d Im h) and (h|h) = sum w ((Re h)^2 + (Im h)^2) as real
        # dot products with h viewed as interleaved floats (one BLAS call per batch each)
        shape = np.broadcast_shapes(self.weight.shape, data.shape)
        w2 = np.repeat(np.broadcast_to(self.weight, shape), 2, axis=-1).ravel()
        self._w2 = np.ascontiguousarray(w2)
        self._wd2 = np.ascontiguousarray(
            w2 * np.asarray(data, dtype=complex).view(np.float64).ravel()
        )

    def inner(self, a: NDArray[np.complex128], b: NDArray[np.complex128]) -> NDArray:
        """Noise-weighted inner product (a|b) over bands and channels (broadcast over W)."""
        return np.asarray(np.sum(self.weight * (a * np.conj(b)), axis=(-3, -2, -1)).real)

    def templates(self, theta: NDArray[np.float64]) -> NDArray[np.complex128]:
        """Band templates (W, n_bands, 2, N) for sampled rows (W, D)."""
        p = physical_from_theta(theta, self.model.grid.t_obs_s, self.prior.names)
        return self.model.bands(**p)

    def log_likelihood(self, theta: NDArray[np.float64]) -> NDArray[np.float64]:
        """ln L (W,) for rows inside the prior support (no prior check)."""
        h = self.templates(theta)
        hf = h.view(np.float64).reshape(h.shape[0], -1)
        d_h = hf @ self._wd2
        h_h = (hf * hf) @ self._w2
        return np.asarray(d_h - 0.5 * h_h - 0.5 * self.d_d, dtype=float)

    def log_prob(self, theta: NDArray[np.float64]) -> NDArray[np.float64]:
        """ln posterior (W,) up to a constant: -inf outside the prior, never NaN."""
        th = np.atleast_2d(np.asarray(theta, dtype=float))
        out = np.full(th.shape[0], -np.inf)
        ok = self.prior.contains(th)
        if np.any(ok):
            ll = self.log_likelihood(th[ok])
            out[ok] = np.where(np.isfinite(ll), ll, -np.inf)
        return out

    def snr(self, theta: NDArray[np.float64]) -> NDArray[np.float64]:
        """Optimal SNR sqrt((h|h)) (W,) of the templates."""
        h = self.templates(theta)
        return np.sqrt(np.sum(self.weight * np.abs(h) ** 2, axis=(-3, -2, -1)))


def simulate_data(
    model: FourLineModel,
    truth: SourceParams,
    noise: NoiseModel,
    rng: np.random.Generator | None,
) -> NDArray[np.complex128]:
    """Injection plus (if ``rng`` is given) a Gaussian noise realisation, per band.

    Notes
    -----
    For one-sided PSD S and x~ = int x e^{-2 pi i f t} dt, E|n~|^2 = T S / 2, so each real and
    imaginary part has variance T S / 4. ``rng=None`` gives the zero-noise data set.
    """
    h = model.bands_for(truth)
    if rng is None:
        return h
    t_obs = model.grid.t_obs_s
    sig = np.sqrt(psd_a(model.freqs_hz, t_obs, noise) * t_obs / 4.0)[:, None, :]
    n = rng.standard_normal(h.shape) + 1j * rng.standard_normal(h.shape)
    return np.asarray(h + sig * n)


def source_from_target(target: Target) -> SourceParams:
    """Waveform parameters at the START of the observation from a (midpoint) target.

    Raises
    ------
    TargetFileError
        If the target lacks the GW-only fields the waveform needs (amplitude, cos_inclination,
        psi).
    """
    from ucbplan.core.params import shift_reference
    from ucbplan.errors import TargetFileError

    where = target.source.name if target.source is not None else target.name
    for key in ("amplitude", "cos_inclination", "psi"):
        if getattr(target, key) is None:
            raise TargetFileError(
                f"{where}: lisa.{key}: missing; the LISA simulation needs amplitude, "
                "cos_inclination and psi (see catalogs/fiducial-injection.yaml)"
            )
    start, _ = shift_reference(target.params, np.zeros((7, 7)), -0.5 * target.t_obs_s)
    return SourceParams(
        amplitude=float(target.amplitude),  # type: ignore[arg-type]
        f_gw=start.f_gw,
        fdot=start.fdot,
        cos_inclination=float(target.cos_inclination),  # type: ignore[arg-type]
        # ψ → ψ + π is an exact symmetry of the waveform: fold into the prior range [0, π)
        psi=float(np.mod(float(target.psi), np.pi)),  # type: ignore[arg-type]
        phase=float(np.mod(start.phase, 2.0 * np.pi)),
        eta=start.eta,
        kappa=start.kappa,
        omega_dot=start.omega_dot,
        fddot=start.fddot,
    )


def model_for_target(
    target: Target,
    t_obs_s: float,
    n: int,
    eccentric: bool,
    f_center_hz: float,
    *,
    fdot_ref: float = 0.0,
    omega_dot_ref: float = 0.0,
    ecliptic_rad: tuple[float, float] | None = None,
) -> FourLineModel:
    """Four-line model for the target's (fixed) sky and an observation of ``t_obs_s``.

    ``f_center_hz`` fixes the bands; with ``fdot_ref`` [Hz/s] and ``omega_dot_ref`` [rad/s]
    (the search values) it is the reference track that makes templates near it cheap
    (:class:`~ucbplan.lisa.waveform.FourLineModel`). ``ecliptic_rad``: the target's
    (λ, β) [rad] when the caller has already converted it (a population converts a whole
    chunk in one call); default: :func:`~ucbplan.lisa.response.ecliptic_from_icrs`.
    """
    from ucbplan.lisa.orbits import EqualArmOrbits
    from ucbplan.lisa.response import ecliptic_from_icrs, response_grid, sky_frame

    if ecliptic_rad is None:
        lon, lat = ecliptic_from_icrs(target.ra_deg, target.dec_deg)
    else:
        lon, lat = ecliptic_rad
    grid = response_grid(EqualArmOrbits(), sky_frame(lon, lat), t_obs_s, n)
    harmonics = (1, 2, 3) if eccentric else (2,)
    return FourLineModel(
        grid, f_center_hz, harmonics, fdot_ref=fdot_ref, omega_dot_ref=omega_dot_ref
    )
