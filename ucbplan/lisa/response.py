"""LISA response in the fast/slow decomposition of Cornish & Littenberg (2007).

A line h_ab(t) = Re[P_ab exp(i theta(chi))] with chi = t - k.x/c produces on the link from
spacecraft s to r (unit vector n from s to r) the fractional frequency (paper, Appendix
"Detector response")

    y_sr(t) = n^a n^b [h_ab(t - L - k.x_s/c) - h_ab(t - k.x_r/c)] / (2 (1 - k.n)).

Expanding theta(t - delta) = theta(t) - 2 pi f(t) delta (the neglected pi fdot delta^2 is
< 1e-8 rad for delta <= 500 s), each link is a slowly varying complex envelope times a carrier.
We heterodyne every envelope at a fixed band frequency f_b = q_b / T, sample it at N + 1 points
over the observation, combine the links into first-generation TDI X, Y, Z -> A, E and take the
discrete Fourier transform. This module holds the observation-fixed geometry (sky, orbits,
projections) and the band transforms; :mod:`ucbplan.lisa.waveform` supplies the source.

Fourier convention: one-sided x~(f) = integral_0^T x(t) exp(-2 pi i f t) dt with t = 0 at the
start of the observation (as FastGB / GBGPU), on the bins f = (q_b + k) / T, k = -N/2 .. N/2-1.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ucbplan.lisa.orbits import C_M_S, EqualArmOrbits

#: Links as (emitter, receiver) spacecraft indices.
LINKS: tuple[tuple[int, int], ...] = ((1, 0), (0, 1), (2, 0), (0, 2), (2, 1), (1, 2))


@dataclass(frozen=True, slots=True, eq=False)
class SkyFrame:
    """Propagation direction and polarization tensors of a plane wave (FastGB convention).

    Attributes
    ----------
    k : numpy.ndarray
        Unit propagation vector (3,), pointing away from the source.
    e_plus, e_cross : numpy.ndarray
        Polarization tensors (3, 3): e+ = u u - v v, ex = u v + v u with
        u = (cos th cos ph, cos th sin ph, -sin th), v = (sin ph, -cos ph, 0), th = pi/2 - beta.
    """

    k: NDArray[np.float64]
    e_plus: NDArray[np.float64]
    e_cross: NDArray[np.float64]


def sky_frame(ecl_lon_rad: float, ecl_lat_rad: float) -> SkyFrame:
    """Build the wave frame for a source at ecliptic (lambda, beta) [rad].

    Notes
    -----
    Same basis as FastGB/GBGPU, so psi has their meaning (paper, Appendix "Circular limit").
    """
    th = 0.5 * np.pi - ecl_lat_rad
    ph = ecl_lon_rad
    u = np.array([np.cos(th) * np.cos(ph), np.cos(th) * np.sin(ph), -np.sin(th)])
    v = np.array([np.sin(ph), -np.cos(ph), 0.0])
    k = np.array([-np.sin(th) * np.cos(ph), -np.sin(th) * np.sin(ph), -np.cos(th)])
    e_plus = np.outer(u, u) - np.outer(v, v)
    e_cross = np.outer(u, v) + np.outer(v, u)
    return SkyFrame(k=k, e_plus=e_plus, e_cross=e_cross)


def ecliptic_from_icrs(ra_deg: float, dec_deg: float) -> tuple[float, float]:
    """Convert ICRS (ra, dec) [deg] to barycentric mean ecliptic (J2000) (lambda, beta) [rad]."""
    lon, lat = ecliptic_from_icrs_batch(np.array([ra_deg]), np.array([dec_deg]))
    return float(lon[0]), float(lat[0])


def ecliptic_from_icrs_batch(
    ra_deg: NDArray[np.float64], dec_deg: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """:func:`ecliptic_from_icrs` for arrays of positions in one astropy call, (λ, β) [rad]."""
    import astropy.units as u
    from astropy.coordinates import BarycentricMeanEcliptic, SkyCoord

    c = SkyCoord(ra=np.asarray(ra_deg) * u.deg, dec=np.asarray(dec_deg) * u.deg, frame="icrs")
    e = c.transform_to(BarycentricMeanEcliptic())
    lon = np.asarray(e.lon.to_value(u.rad), dtype=np.float64)
    return lon, np.asarray(e.lat.to_value(u.rad), dtype=np.float64)


@dataclass(frozen=True, slots=True, eq=False)
class ResponseGrid:
    """Observation-fixed quantities on the slow-time grid t_m = m T / N, m = 0..N.

    Attributes
    ----------
    t_obs_s : float
        Observation length T [s].
    n : int
        Number of slow samples N (band width in bins).
    arm_s : float
        Arm light time L / c [s].
    t_s : numpy.ndarray
        Slow-time grid (N + 1,) [s], including the end point for the trapezoid rule.
    delay_s : numpy.ndarray
        k . x_j(t) / c for each spacecraft (3, N + 1) [s].
    proj_plus, proj_cross : numpy.ndarray
        n n : e+ and n n : ex divided by 2 (1 - k . n) for each link in LINKS (6, N + 1).
    """

    t_obs_s: float
    n: int
    arm_s: float
    t_s: NDArray[np.float64]
    delay_s: NDArray[np.float64]
    proj_plus: NDArray[np.float64]
    proj_cross: NDArray[np.float64]


def response_grid(orbits: EqualArmOrbits, sky: SkyFrame, t_obs_s: float, n: int) -> ResponseGrid:
    """Precompute orbit geometry for one observation and sky position.

    Parameters
    ----------
    orbits : EqualArmOrbits
        Spacecraft orbits.
    sky : SkyFrame
        Wave frame of the (fixed) sky position.
    t_obs_s : float
        Observation length T [s].
    n : int
        Slow-part samples N (even); the same N must be used for injection and templates.
    """
    if n < 8 or n % 2:
        raise ValueError(f"slow-part length N must be an even integer >= 8, got {n}")
    t, x, links = _link_geometry(orbits, float(t_obs_s), int(n))
    delay = np.einsum("a,jam->jm", sky.k, x) / C_M_S
    proj_p = np.empty((len(LINKS), t.size))
    proj_c = np.empty((len(LINKS), t.size))
    for li, nvec in enumerate(links):
        kn = np.einsum("a,am->m", sky.k, nvec)
        denom = 2.0 * (1.0 - kn)
        proj_p[li] = np.einsum("am,ab,bm->m", nvec, sky.e_plus, nvec) / denom
        proj_c[li] = np.einsum("am,ab,bm->m", nvec, sky.e_cross, nvec) / denom
    return ResponseGrid(
        t_obs_s=float(t_obs_s),
        n=int(n),
        arm_s=orbits.arm_light_time_s,
        t_s=t,
        delay_s=delay,
        proj_plus=proj_p,
        proj_cross=proj_c,
    )


@functools.lru_cache(maxsize=4)
def _link_geometry(
    orbits: EqualArmOrbits, t_obs_s: float, n: int
) -> tuple[NDArray[np.float64], NDArray[np.float64], tuple[NDArray[np.float64], ...]]:
    """Slow-time grid (M,), spacecraft positions (3, 3, M) and link unit vectors (3, M) each.

    They do not depend on the sky, so a population of sources on one grid shares them: cached
    (a few grids at most; read-only arrays).
    """
    t = np.linspace(0.0, t_obs_s, n + 1)
    x = orbits.positions(t)
    links = []
    for s, r in LINKS:
        d = x[r] - x[s]
        links.append(d / np.linalg.norm(d, axis=0))
    for a in (t, x, *links):
        a.flags.writeable = False
    return t, x, tuple(links)


def tdi_coefficients(f_hz: float, arm_s: float) -> NDArray[np.complex128]:
    """Link weights of the slow TDI A and E channels without the common (1 - D^2) factor.

    With D = exp(-2 pi i f L / c) the first-generation Michelson combination is
    X = (1 - D^2) [(y_10 + D y_01) - (y_20 + D y_02)] and Y, Z by cyclic permutation;
    A = (Z - X)/sqrt 2, E = (X - 2Y + Z)/sqrt 6.

    Returns
    -------
    numpy.ndarray
        Complex weights (2, 6): channel (A, E) x link (order of LINKS).
    """
    d = np.exp(-2j * np.pi * f_hz * arm_s)
    index = {link: i for i, link in enumerate(LINKS)}

    def michelson(j: int) -> NDArray[np.complex128]:
        a, b = (j + 1) % 3, (j + 2) % 3
        w = np.zeros(len(LINKS), dtype=complex)
        w[index[(a, j)]] += 1.0
        w[index[(j, a)]] += d
        w[index[(b, j)]] -= 1.0
        w[index[(j, b)]] -= d
        return w

    x, y, z = michelson(0), michelson(1), michelson(2)
    return np.stack([(z - x) / np.sqrt(2.0), (x - 2.0 * y + z) / np.sqrt(6.0)])


def _endpoint_weights(n: int, t_obs_s: float) -> NDArray[np.complex128]:
    """Per-bin weight of the end-point jump Y(T) - Y(0), in fftshift order (k = -N/2..N/2-1).

    Writing Y(t) = [Y(t) - dY t/T] + dY t/T, the bracket is continuous across the period and its
    rectangle-rule DFT converges fast; the ramp is transformed exactly:
    int_0^T (t/T) exp(-2 pi i k t/T) dt = i T / (2 pi k) (k != 0), T/2 (k = 0). The weight is
    that exact transform minus the ramp's own rectangle-rule DFT, (T/N) sum_m (m/N) w^m.
    """
    k = np.arange(-n // 2, n // 2)
    h = t_obs_s / n
    exact = np.zeros(n, dtype=complex)
    exact[k == 0] = 0.5 * t_obs_s
    nz = k != 0
    exact[nz] = 1j * t_obs_s / (2.0 * np.pi * k[nz])
    ramp_dft = np.empty(n, dtype=complex)
    ramp_dft[~nz] = 0.5 * (n - 1)
    ramp_dft[nz] = -1.0 / (1.0 - np.exp(-2j * np.pi * k[nz] / n))
    out: NDArray[np.complex128] = np.asarray(exact - h * ramp_dft, dtype=np.complex128)
    return out


def band_transform(
    slow: NDArray[np.complex128], t_obs_s: float, f_hz: NDArray[np.float64], arm_s: float
) -> NDArray[np.complex128]:
    """Fourier transform of a heterodyned slow envelope onto its band of N bins.

    Parameters
    ----------
    slow : numpy.ndarray
        Envelope samples (..., N + 1) on t_m = m T / N (end point included).
    t_obs_s : float
        Observation length T [s].
    f_hz : numpy.ndarray
        Bin frequencies (N,) [Hz] in order k = -N/2 .. N/2 - 1.
    arm_s : float
        Arm light time [s], for the exact per-bin (1 - D^2) TDI factor.

    Returns
    -------
    numpy.ndarray
        x~(f_k) (..., N) for x(t) = Re[slow(t) exp(2 pi i f_b t)], keeping the
        positive-frequency half (factor 1/2): (T/N) DFT plus the exact transform of the
        end-point jump (:func:`_endpoint_weights`), which carries the 1/k spectral-leakage tails
        of the finite observation that a plain DFT would alias back into the band.
    """
    n = slow.shape[-1] - 1
    dft_w, jump_w = band_weights(t_obs_s, f_hz, arm_s)
    spec = np.fft.fftshift(np.fft.fft(slow[..., :n], axis=-1), axes=-1)
    out: NDArray[np.complex128] = spec * dft_w + (slow[..., n] - slow[..., 0])[..., None] * jump_w
    return out


def band_weights(
    t_obs_s: float, f_hz: NDArray[np.float64], arm_s: float
) -> tuple[NDArray[np.complex128], NDArray[np.complex128]]:
    """Per-bin weights of :func:`band_transform`: x~ = DFT * w_dft + (Y(T) - Y(0)) * w_jump.

    Both include the factor 1/2 (positive-frequency half) and the exact (1 - D^2) TDI factor;
    w_dft holds T/N, w_jump the end-point weights (:func:`_endpoint_weights`). Bins in the order
    k = -N/2 .. N/2 - 1 of ``f_hz`` (N,).
    """
    n = f_hz.shape[-1]
    half_factor = 0.5 * (1.0 - np.exp(-4j * np.pi * f_hz * arm_s))
    return half_factor * (t_obs_s / n), half_factor * _endpoint_weights(n, t_obs_s)
