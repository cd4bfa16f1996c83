"""The four-line source through the LISA response, batched over parameter sets.

:class:`FourLineModel` gives the TDI A, E of the lines of :mod:`ucbplan.lisa.source`
(docs/method.md, "Waveform and noise"; paper Eqs. app:final_form_h_plus, app:final_form_h_cross,
Appendix apsidal_mcmc) in fixed heterodyned bands, one per harmonic, for many parameter sets at
once; its numerical building blocks are in :mod:`ucbplan.lisa.numerics` and its optional compiled
loops in :mod:`ucbplan.lisa._fused`. All parameters are referenced to the start of the
observation (t = 0).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ucbplan.lisa import _fused
from ucbplan.lisa.numerics import (
    TABLE_Q,
    beta_powers,
    cis,
    gemm,
    n_monomials,
    quadratic_cis,
    quadratic_tables,
)
from ucbplan.lisa.response import LINKS, ResponseGrid, band_weights, tdi_coefficients
from ucbplan.lisa.source import LINES, SourceParams, line_amplitudes

#: Walkers per internal block of :meth:`FourLineModel.bands`: a sampler batch in one block (with
#: the link sums as column-blocked BLAS products, 64 beat 8, 16 and 32: the per-block Python
#: work outweighs the cache misses of the larger arrays).
_CHUNK = 64

#: Relative truncation error of the Taylor series of the link phases.
_TAYLOR_TOL = 1e-13

#: Most Taylor terms of the walker-dependent link phase (enough for |beta delay| <= 1.5 rad).
_K_MAX = 24

#: Fewest Taylor orders of the link moments computed at once (templates near the reference
#: track need two; computing all :data:`_K_MAX` up front would be most of a Fisher forecast's
#: cost).
_MIN_ORDERS = 2

#: Most rows (4 amplitude parts x monomials in beta) of the polynomial link sum; sources that
#: need more Taylor terms use Horner's rule (:meth:`FourLineModel._horner_sum`).
_POLY_ROWS = 48


def _taylor_terms(x: float) -> int:
    """Smallest K >= 2 with x^K / K! < _TAYLOR_TOL (relative truncation of the link phase)."""
    term, k = 1.0, 0
    while term >= _TAYLOR_TOL or k < 2:
        k += 1
        term *= x / k
        if k >= _K_MAX:
            raise ValueError(
                f"link phase correction {x:.3g} rad too large for the Taylor expansion; "
                "the source is outside the targeted prior (|f - f_c| or fdot too large)"
            )
    return k


class FourLineModel:
    """TDI A, E of the four-line source in fixed heterodyned bands (one per harmonic).

    Parameters
    ----------
    grid : ResponseGrid
        Observation geometry (slow-time grid of N + 1 samples, fixed sky).
    f_center_hz : float
        Search / injection n = 2 frequency that fixes the band centres:
        q_n = round(n f_center T / 2), band bins q_n - N/2 .. q_n + N/2 - 1.
    harmonics : tuple of int
        Harmonics to model: (1, 2, 3) eccentric, (2,) circular.
    fdot_ref : float
        Frequency derivative of the reference track [Hz/s] (the search / injection value).
    omega_dot_ref : float
        Apsidal rate of the reference track [rad/s].

    Notes
    -----
    Injection and templates must use the same N and band centres (docs/method.md, "Waveform and
    noise").
    Approximations (all verified against the brute-force time-domain TDI in the tests):
    theta(t - delay) = theta(t) - 2 pi f_p(t) delay (neglects pi fdot delay^2 < 1e-8 rad);
    the TDI link delays inside the slow envelopes use the band-centre frequency (phase error
    <= 2 pi (N/2T) 3L/c ~ 3e-4 rad at the band edge; the (1 - D^2) factor is exact per bin);
    the walker-dependent part of the link phases, exp(-i beta (d_j + L)), is summed as a Taylor
    series around the reference track (f_center_hz, fdot_ref, omega_dot_ref) with
    source-independent spacecraft moments (truncation < 1e-13 relative). The reference changes
    only how many Taylor terms are needed (templates near it need two), not the waveform.
    """

    def __init__(
        self,
        grid: ResponseGrid,
        f_center_hz: float,
        harmonics: tuple[int, ...] = (1, 2, 3),
        *,
        fdot_ref: float = 0.0,
        omega_dot_ref: float = 0.0,
    ) -> None:
        self.grid = grid
        self.harmonics = tuple(sorted(harmonics))
        t_obs, n = grid.t_obs_s, grid.n
        self.band_bins = np.array(
            [round(0.5 * h * f_center_hz * t_obs) for h in self.harmonics], dtype=np.int64
        )
        k = np.arange(-n // 2, n // 2)
        self.freqs_hz = (self.band_bins[:, None] + k[None, :]) / t_obs
        self.lines = tuple(
            (li, self.harmonics.index(line.harmonic))
            for li, line in enumerate(LINES)
            if line.harmonic in self.harmonics
        )
        self.f_center_hz = float(f_center_hz)
        self.fdot_ref = float(fdot_ref)
        self.omega_dot_ref = float(omega_dot_ref)
        self._f_het = round(f_center_hz * t_obs) / (2.0 * t_obs)  # c1 heterodyne [Hz]
        self._delay_max = float(np.max(np.abs(grid.delay_s)) + grid.arm_s)
        self._moments = np.empty((len(LINES), 4, 0, 2, 2 * grid.t_s.size))
        weights = [band_weights(t_obs, f, grid.arm_s) for f in self.freqs_hz]
        self._dft_w = np.stack([w[0] for w in weights])[:, None, :]  # (n_bands, 1, N)
        self._jump_w = np.stack([w[1] for w in weights])[:, None, :]
        self._t3 = grid.t_s**3 / 3.0
        self._tau = grid.t_s / t_obs
        # per modelled line: index in LINES, band, harmonic n, apsidal sign s (fused kernel)
        self._line_table = np.array(
            [(li, b, LINES[li].harmonic, LINES[li].shift) for li, b in self.lines], dtype=np.int64
        )
        self._bases: dict[tuple[int, int, int], NDArray[np.float64]] = {}

    def _link_weights(self) -> tuple[NDArray[np.complex128], NDArray[np.complex128]]:
        """Per band: TDI weights (channel, pol) x spacecraft of emitted and received light."""
        g = self.grid
        emit = np.zeros((self.n_bands, 4, 3, g.t_s.size), dtype=complex)
        recv = np.zeros_like(emit)
        for b, q in enumerate(self.band_bins):
            w = tdi_coefficients(q / g.t_obs_s, g.arm_s)
            for li, (s, r) in enumerate(LINKS):
                for ch in range(2):
                    for pol, proj in enumerate((g.proj_plus, g.proj_cross)):
                        emit[b, 2 * ch + pol, s] += w[ch, li] * proj[li]
                        recv[b, 2 * ch + pol, r] += w[ch, li] * proj[li]
        return emit, recv

    def _moments_upto(self, n_terms: int) -> NDArray[np.float64]:
        """The link moments with at least ``n_terms`` Taylor orders (computed on first need).

        Templates near the reference track need two orders (a Fisher forecast), a sampler's
        wide prior up to :data:`_K_MAX`: orders are computed when first asked for, at least
        :data:`_MIN_ORDERS` at a time (each order's values do not depend on how many are kept).
        """
        if self._moments.shape[2] < n_terms:
            have = self._moments.shape[2]
            self._moments = self._link_moments(min(_K_MAX, max(n_terms, 2 * have, _MIN_ORDERS)))
        return self._moments

    def _link_moments(self, n_orders: int) -> NDArray[np.float64]:
        """Source-independent Taylor moments of the link phases, (line, 4, K, channel, 2M) real,
        for the orders K < ``n_orders``.

        Every link factor exp(-2 pi i f_p(t) delay) of line p (2 pi f_p = n pi f(t) + s wdot)
        is split into a fixed part on the reference track (f_ref(t) = f_c + fdot_ref t,
        wdot_ref) and a walker-dependent part exp(-i beta_p(t) delay) with
        beta_p = n pi (f(t) - f_ref(t)) + s (wdot - wdot_ref), the same for all spacecraft. Its
        Taylor series in beta has moments that do not depend on the source, so the sum over
        spacecraft is done once here: MOM[p, k] = (-i)^k / k! sum_j [(d_j + L)^k emit_j -
        d_j^k recv_j] times the fixed part (emitters carry the arm delay L). The fixed band
        rotation and the (-1)^m that fftshifts the DFT (N even; (-1)^0 = (-1)^N leaves the
        end-point jump unchanged) are folded in too. Sources near the reference track need
        few Taylor terms.
        """
        g = self.grid
        t_obs, d, arm = g.t_obs_s, g.delay_s, g.arm_s
        emit, recv = self._link_weights()
        sign = np.where(np.arange(g.t_s.size) % 2 == 0, 1.0, -1.0)
        het = round(self.f_center_hz * t_obs) / 2.0
        moments = np.zeros((len(LINES), n_orders, 4, g.t_s.size), dtype=complex)
        used = sorted(li for li, _ in self.lines)
        for li, b in self.lines:
            h, s = LINES[li].harmonic, LINES[li].shift
            rot = np.exp(2j * np.pi * (h * het - self.band_bins[b]) * g.t_s / t_obs) * sign
            rate = np.pi * h * (self.f_center_hz + self.fdot_ref * g.t_s) + s * self.omega_dot_ref
            dop0 = np.exp(-1j * rate * d)  # (3, M)
            e_w = emit[b] * (dop0 * np.exp(-1j * rate * arm) * rot)[None]
            r_w = recv[b] * (dop0 * rot)[None]
            for order in range(n_orders):
                fac = (-1j) ** order / math.factorial(order)
                moments[li, order] = fac * (
                    np.einsum("cjm,jm->cm", e_w, (d + arm) ** order)
                    - np.einsum("cjm,jm->cm", r_w, d**order)
                )
        # (line, 4, K, channel, 2M) real: rows (MOM_+, MOM_x, i MOM_+, i MOM_x) as interleaved
        # re/im floats, so that [Re a_+, Re a_x, Im a_+, Im a_x] @ rows is the complex product
        # a . MOM; moments[p, :, :K] reshaped to (4, K * channel * 2M) is a strided matrix for
        # one real BLAS product (faster than the complex one at this inner size) with the walkers
        # (lines that are not modelled stay zero: only the modelled ones are filled)
        by_pol = moments[used].reshape(len(used), n_orders, 2, 2, -1).transpose(0, 3, 1, 2, 4)
        rows = np.zeros((len(LINES), 4, n_orders, 2, g.t_s.size), dtype=complex)
        rows[used, :2] = by_pol
        rows[used, 2:] = 1j * by_pol
        return rows.view(np.float64)

    @property
    def n_bands(self) -> int:
        """Number of frequency bands (one per modelled harmonic)."""
        return len(self.harmonics)

    def bands(
        self,
        amplitude: ArrayLike,
        f_gw: ArrayLike,
        fdot: ArrayLike,
        cos_inclination: ArrayLike,
        psi: ArrayLike,
        phase: ArrayLike,
        eta: ArrayLike = 0.0,
        kappa: ArrayLike = 0.0,
        omega_dot: ArrayLike = 0.0,
        fddot: ArrayLike = 0.0,
    ) -> NDArray[np.complex128]:
        """Compute A and E in every band for a batch of W parameter sets.

        Parameters are SI scalars or arrays broadcastable to shape (W,), referenced to the
        start of the observation (see :class:`SourceParams`).

        Returns
        -------
        numpy.ndarray
            Shape (W, n_bands, 2, N) complex: one-sided Fourier transform [1/Hz, fractional
            frequency] of TDI A (index 0) and E (index 1) on ``freqs_hz``.
        """
        arrs = np.broadcast_arrays(
            *(
                np.atleast_1d(np.asarray(x, dtype=float))
                for x in (
                    amplitude,
                    f_gw,
                    fdot,
                    cos_inclination,
                    psi,
                    phase,
                    eta,
                    kappa,
                    omega_dot,
                    fddot,
                )
            )
        )
        return self._batch(*(a.ravel() for a in arrs))

    def _batch(self, *flat: NDArray[np.float64]) -> NDArray[np.complex128]:
        """Per-walker coefficients for the whole batch, then the sampled arrays in blocks of
        _CHUNK walkers (cache blocking)."""
        amp, f0, fd, ci, ps, _ph, et, ka, wd, fdd = flat
        coef = self._amplitude_rows(amp, ci, ps, et, ka)  # (lines, W, 4)
        cubic = bool(np.any(fdd))
        # f(t) - f_ref(t) of the n = 2 line times pi, as a polynomial in tau = t / T
        t_obs = self.grid.t_obs_s
        df = [f0 - self.f_center_hz, (fd - self.fdot_ref) * t_obs]
        if cubic:
            df.append(0.5 * fdd * t_obs**2)
        df_tau = np.pi * np.stack(df, axis=-1)  # (W, d + 1)
        dwd = wd - self.omega_dot_ref
        n_terms = self._n_terms(df_tau, dwd)
        # beta_p(tau) = n pi (f(t) - f_ref(t)) + s (wdot - wdot_ref) of each modelled line
        beta = np.stack([LINES[li].harmonic * df_tau for li, _ in self.lines])
        beta[:, :, 0] += np.array([LINES[li].shift for li, _ in self.lines])[:, None] * dwd
        poly = 4 * n_monomials(n_terms, df_tau.shape[1] - 1) <= _POLY_ROWS
        if poly:  # walker rows of the polynomial link sums: amplitude part x monomial
            powers = beta_powers(beta.reshape(-1, beta.shape[-1]), n_terms)
            coef = (coef[..., None] * powers.reshape(*beta.shape[:2], 1, -1)).reshape(
                *beta.shape[:2], -1
            )
        fused = _fused.kernels()
        if fused is not None and not cubic:  # (the compiled loop takes quadratic phases)
            return self._blocks(
                lambda sl: self._block_fused(
                    fused,
                    coef[:, sl],
                    None if poly else beta[:, sl],
                    n_terms,
                    [x[sl] for x in flat],
                ),
                f0.size,
            )
        return self._blocks(
            lambda sl: self._block(
                coef[:, sl], None if poly else beta[:, sl], n_terms, [x[sl] for x in flat], cubic
            ),
            f0.size,
        )

    @staticmethod
    def _blocks(
        block: Callable[[slice], NDArray[np.complex128]], n_walk: int
    ) -> NDArray[np.complex128]:
        """``block`` over consecutive slices of at most _CHUNK walkers, concatenated."""
        out = [block(slice(i, i + _CHUNK)) for i in range(0, n_walk, _CHUNK)]
        return out[0] if len(out) == 1 else np.concatenate(out)

    def _amplitude_rows(
        self,
        amp: NDArray[np.float64],
        ci: NDArray[np.float64],
        ps: NDArray[np.float64],
        et: NDArray[np.float64],
        ka: NDArray[np.float64],
    ) -> NDArray[np.float64]:
        """[Re a+, Re ax, Im a+, Im ax] of each modelled line after the polarization rotation
        by 2 psi, (lines, W, 4): the row order of the moments."""
        h = line_amplitudes(amp, ci, et, ka)[[li for li, _ in self.lines]]  # (lines, 2, W)
        c2, s2 = np.cos(2.0 * ps), np.sin(2.0 * ps)
        hp, hx = h[:, 0] * c2 - h[:, 1] * s2, h[:, 0] * s2 + h[:, 1] * c2
        return np.stack([hp.real, hx.real, hp.imag, hx.imag], axis=-1)

    def _block(
        self,
        coef: NDArray[np.float64],
        beta: NDArray[np.float64] | None,
        n_terms: int,
        source: list[NDArray[np.float64]],
        cubic: bool,
    ) -> NDArray[np.complex128]:
        """A and E of one block of walkers, (W, n_bands, 2, N).

        ``coef``: walker rows of each line's link sum (polynomial rows, or the four amplitude
        parts with ``beta`` for Horner's rule); ``source``: the parameters (order of
        :meth:`bands`).
        """
        f0, fd, ph, fdd, wd = (source[i] for i in (1, 2, 5, 9, 8))
        n_walk, n = f0.size, self.grid.n
        carriers = self._carriers(self._orbital_carrier(f0, fd, ph, fdd, cubic), wd)
        slow = np.empty((n_walk, self.n_bands, 2, n + 1), dtype=complex)
        filled: set[int] = set()
        for i, (li, b) in enumerate(self.lines):
            out = slow[:, b] if b not in filled else np.empty((n_walk, 2, n + 1), dtype=complex)
            self._link_sum(coef[i], None if beta is None else beta[i], li, n_terms, 1 + cubic, out)
            out *= carriers[li][:, None, :]
            if b in filled:
                slow[:, b] += out
            filled.add(b)
        spec = np.fft.fft(slow[..., :n], axis=-1)  # fftshifted by the (-1)^m in the moments
        spec *= self._dft_w
        spec += (slow[..., n] - slow[..., 0])[..., None] * self._jump_w
        return spec

    def _block_fused(
        self,
        fused: tuple[Callable[..., None], Callable[..., None]],
        coef: NDArray[np.float64],
        beta: NDArray[np.float64] | None,
        n_terms: int,
        source: list[NDArray[np.float64]],
    ) -> NDArray[np.complex128]:
        """:meth:`_block` with the compiled loops of :mod:`ucbplan.lisa._fused` (no fddot):
        link sums by BLAS, one loop for carriers and bands, the FFT, one loop for the weights."""
        assemble, weigh = fused
        f0, fd, ph, wd = (source[i] for i in (1, 2, 5, 8))
        n_walk, n = f0.size, self.grid.n
        orbit = quadratic_tables(*self._orbit_phase(f0, fd, ph), n + 1)
        apsis = quadratic_tables(None, wd * (self.grid.t_obs_s / n), None, n + 1)
        tables = np.zeros((n_walk, 5, max(TABLE_Q, orbit[0].shape[1])), dtype=complex)
        for row, table in enumerate((*orbit, *apsis[:2])):
            assert table is not None
            tables[:, row, : table.shape[1]] = table
        sums = np.empty((len(self.lines), n_walk, 2, n + 1), dtype=complex)
        for i, (li, _) in enumerate(self.lines):
            beta_i = None if beta is None else beta[i]
            self._link_sum(coef[i], beta_i, li, n_terms, 1, sums[i])
        x = np.empty((n_walk, self.n_bands, 2, n), dtype=complex)
        jump = np.empty((n_walk, self.n_bands, 2), dtype=complex)
        assemble(sums, self._line_table[:, 1:], tables, TABLE_Q, x, jump)
        spec = np.fft.fft(x, axis=-1, out=x)  # fftshifted by the (-1)^m in the moments
        weigh(spec, jump, self._dft_w[:, 0], self._jump_w[:, 0])
        return spec

    def _n_terms(self, df_tau: NDArray[np.float64], dwd: NDArray[np.float64]) -> int:
        """Taylor order for exp(-i beta delay): (beta_max delay_max)^K / K! < _TAYLOR_TOL.

        beta_max bounds every line over the grid: 3 pi max |f(t) - f_ref(t)| + max |dwdot|
        (linear drift: the end points; with fddot: every grid sample).
        """
        if df_tau.shape[1] == 2:
            drift = np.abs(df_tau[:, :1] + df_tau[:, 1:] * np.array([0.0, 1.0]))
        else:
            drift = np.abs(np.polynomial.polynomial.polyval(self._tau, df_tau.T, tensor=True))
        beta_max = 3.0 * float(np.max(drift)) + float(np.max(np.abs(dwd)))
        return _taylor_terms(beta_max * self._delay_max)

    def _orbit_phase(
        self, f0: NDArray[np.float64], fd: NDArray[np.float64], ph: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """(a, b, c) of the heterodyned orbital phase a + b m + c m^2 at t_m = m T / N:
        phi0/2 + 2 pi (f0/2 - f_het) t + pi/2 fdot t^2 (theta_2 / 2 without fddot)."""
        step = self.grid.t_obs_s / self.grid.n
        lin = 2.0 * np.pi * (0.5 * f0 - self._f_het) * step
        return 0.5 * ph, lin, 0.5 * np.pi * fd * step * step

    def _orbital_carrier(
        self,
        f0: NDArray[np.float64],
        fd: NDArray[np.float64],
        ph: NDArray[np.float64],
        fdd: NDArray[np.float64],
        cubic: bool,
    ) -> NDArray[np.complex128]:
        """c1 = exp(i theta_2 / 2) heterodyned at f_het on the grid, (W, M).

        Without fddot its phase is quadratic in the sample index (:meth:`_orbit_phase`,
        :func:`quadratic_cis`); with it, phi0/2 + 2 pi (f0/2 - f_het) t + pi/2 (fdot t^2 +
        fddot t^3 / 3) is evaluated per sample.
        """
        if not cubic:
            return quadratic_cis(*self._orbit_phase(f0, fd, ph), self.grid.n + 1)
        t = self.grid.t_s[None, :]
        chirp = fd[:, None] * (t * t) + fdd[:, None] * self._t3
        chirp *= 0.5 * np.pi
        chirp += 0.5 * ph[:, None] + 2.0 * np.pi * (0.5 * f0 - self._f_het)[:, None] * t
        return cis(chirp)

    def _carriers(
        self, c1: NDArray[np.complex128], wd: NDArray[np.float64]
    ) -> dict[int, NDArray[np.complex128]]:
        """c1^n exp(i s wdot t) of each modelled line (index in LINES), (W, M) each.

        All lines share one orbital phase: line n is c1^n times exp(i s wdot t) (the fixed band
        rotations are in the moments).
        """
        need = {li for li, _ in self.lines}
        out: dict[int, NDArray[np.complex128]] = {}
        if 2 in need or 3 in need:
            c2 = c1 * c1
            out[2] = c2
        if need & {0, 1, 3}:
            # exp(i wdot t_m), t_m = m T / N: two short tables (:func:`quadratic_cis`)
            apsis = quadratic_cis(None, wd * (self.grid.t_obs_s / self.grid.n), None, c1.shape[1])
            out[0] = c1 * apsis
            np.conjugate(apsis, out=apsis)
            minus = c1 * apsis
            out[1] = minus
            if 3 in need:
                out[3] = c2 * minus
        return out

    def _link_sum(
        self,
        coef: NDArray[np.float64],
        beta: NDArray[np.float64] | None,
        line: int,
        n_terms: int,
        degree: int,
        out: NDArray[np.complex128],
    ) -> None:
        """Link sums of one line into ``out`` (W, 2, M): polynomial rows (``beta`` None, one
        product with :meth:`_poly_basis`; ``degree`` of beta in tau) or Horner's rule
        (:meth:`_horner_sum`)."""
        acc = out.view(np.float64).reshape(out.shape[0], -1)  # (W, ch * 2M) view
        if beta is None:
            gemm(coef, self._poly_basis(line, n_terms, degree), acc)
        else:
            self._horner_sum(coef, beta, line, n_terms, acc)

    def _horner_sum(
        self,
        coef: NDArray[np.float64],
        beta: NDArray[np.float64],
        line: int,
        n_terms: int,
        acc: NDArray[np.float64],
    ) -> None:
        """sum_k beta^k (amp . MOM[line, :, k]) by Horner's rule in beta(t), into ``acc``.

        ``coef`` (W, 4): [Re a+, Re ax, Im a+, Im ax]; ``beta`` (W, d + 1): beta(tau); ``acc``
        (W, ch * 2M): the real view of the (W, 2, M) link sums. One real product contracts the
        amplitudes with the moments of all orders, Horner's rule then runs on floats (for long
        series, where the polynomial rows of :meth:`_poly_basis` would be too many).
        """
        n_walk = coef.shape[0]
        mom = self._moments_upto(n_terms)[line, :, :n_terms].reshape(
            4, -1
        )  # (4, K * ch * 2M), a view
        flat = np.empty((n_walk, mom.shape[1]))
        gemm(coef, mom, flat)
        terms = flat.reshape(n_walk, n_terms, -1)
        beta_t = np.polynomial.polynomial.polyval(self._tau, beta.T)  # (W, M)
        beta2 = np.tile(np.repeat(beta_t, 2, axis=-1), (1, 2))  # re, im of both channels
        np.multiply(terms[:, n_terms - 1], beta2, out=acc)
        for k in range(n_terms - 2, 0, -1):
            acc += terms[:, k]
            acc *= beta2
        acc += terms[:, 0]

    def _poly_basis(self, line: int, n_terms: int, degree: int) -> NDArray[np.float64]:
        """Rows tau^e MOM[line, r, k] (r amplitude part, k < n_terms, e <= k degree), cached.

        Shape (4 x monomials, ch * 2M), r-major then k, e as in :func:`beta_powers`.
        """
        key = (line, n_terms, degree)
        if key not in self._bases:
            mom = self._moments_upto(n_terms)[line, :, :n_terms]  # (4, K, ch, 2M)
            tau2 = np.repeat(self._tau, 2)
            rows = [
                mom[:, k] * tau2**e for k in range(n_terms) for e in range(k * degree + 1)
            ]  # each (4, ch, 2M)
            basis = np.stack(rows, axis=1)
            self._bases[key] = np.ascontiguousarray(basis.reshape(-1, basis[0, 0].size))
        return self._bases[key]

    def bands_for(self, p: SourceParams) -> NDArray[np.complex128]:
        """:meth:`bands` for a single :class:`SourceParams`; shape (n_bands, 2, N)."""
        return self.bands(
            p.amplitude,
            p.f_gw,
            p.fdot,
            p.cos_inclination,
            p.psi,
            p.phase,
            p.eta,
            p.kappa,
            p.omega_dot,
            p.fddot,
        )[0]
