"""Weighted least-squares fit of a timing ephemeris to eclipse times.

The model is the polynomial in cycle number that such ephemerides are published in,

    t(n) = T0 + P·n + ½·P·Ṗ·n² (+ ⅙·P²·P̈·n³),

with n an integer at primary and a half-integer at secondary eclipses. It is linear in the
coefficients c = (T0, P, ½PṖ, ⅙P²P̈), which are fitted by weighted least squares (the whitened,
column-scaled design solved with ``lstsq`` and one step of iterative refinement; the covariance
from :func:`ucbplan.core.mvnormal.inverse_scaled` of the normal matrix, never an unscaled
inverse), then turned into (T0, P, Ṗ, P̈) with the Jacobian of that map.

The cycle count is re-centred on the integer cycle m nearest the weighted mean cycle (weights
1/σ²), which decorrelates T0 from P; T0 is the primary eclipse at cycle m. Times are float64
seconds since an exact reference epoch of the data, so nothing is lost to a JD's size.

χ²/dof > 1 rescales the covariance by χ²/dof (σ's by √(χ²/dof)) and says so; times more than
:data:`OUTLIER_SIGMA` rescaled σ from the fit are reported as outliers and only ``clip`` drops
points (iteratively, each one reported).
"""

from __future__ import annotations

import decimal
import math
from dataclasses import dataclass, field
from decimal import Decimal

import numpy as np
from numpy.typing import NDArray

from ucbplan.core.constants import DAY_S_INT
from ucbplan.core.mvnormal import inverse_scaled
from ucbplan.errors import InputError, NumericalError
from ucbplan.timing.eclipse_table import EclipseTimes

F64 = NDArray[np.float64]

#: Parameter names, in order, and the units of their values (T0 as seconds in the covariance).
PARAMETERS = ("t0", "period", "pdot", "pddot")
UNITS = ("s", "s", "s/s", "1/s")
COV_UNITS = ("s", "s", "1", "1/s")
#: |O − C| beyond this many (rescaled) σ is reported as an outlier.
OUTLIER_SIGMA = 4.0


def solve_wls(a: F64, y: F64, sigma: F64) -> tuple[F64, F64]:
    """Weighted least squares ``a @ c ≈ y`` with errors ``sigma``: (c, covariance of c).

    The whitened design is column-scaled before ``lstsq`` and the solution refined once on its
    own residuals; the covariance is the scaled inverse of the normal matrix.

    Raises
    ------
    numpy.linalg.LinAlgError
        If the design is singular (a coefficient the data do not constrain).
    """
    w = 1.0 / sigma
    aw = a * w[:, None]
    norms = np.sqrt(np.sum(aw * aw, axis=0))
    if np.any(norms == 0) or not np.all(np.isfinite(norms)):
        raise np.linalg.LinAlgError("a column of the design is zero")
    scaled = aw / norms
    coef = np.zeros(a.shape[1])
    for _ in range(2):  # solve, then refine on the (small) residuals
        resid = (y - a @ coef) * w
        step, *_ = np.linalg.lstsq(scaled, resid, rcond=None)
        coef = coef + step / norms
    cov = inverse_scaled(aw.T @ aw)
    return coef, cov


def design(nu: F64, k: int) -> F64:
    """The polynomial design [1, ν, ν², ν³][:k] (ν = cycles since the reference)."""
    return np.stack([nu**j for j in range(k)], axis=1)


def coefficients_to_parameters(c: F64) -> tuple[F64, F64]:
    """(T0, P, ½PṖ, ⅙P²P̈)[:k] → (T0, P, Ṗ, P̈)[:k] and the Jacobian d(params)/d(coefficients)."""
    k = c.size
    p = c.copy()
    jac = np.eye(k)
    period = c[1]
    if k > 2:
        p[2] = 2 * c[2] / period
        jac[2, 1], jac[2, 2] = -2 * c[2] / period**2, 2 / period
    if k > 3:
        p[3] = 6 * c[3] / period**2
        jac[3, 1], jac[3, 3] = -12 * c[3] / period**3, 6 / period**2
    return p, jac


def parameters_to_coefficients(p: F64) -> F64:
    """(T0, P, Ṗ, P̈)[:k] → (T0, P, ½PṖ, ⅙P²P̈)[:k]."""
    c = np.array(p, dtype=np.float64)
    if c.size > 2:
        c[2] = 0.5 * p[1] * p[2]
    if c.size > 3:
        c[3] = p[1] ** 2 * p[3] / 6
    return c


def shift_coefficients(c: F64, m: float) -> F64:
    """Coefficients of the same polynomial t(n) re-expressed about cycle ``m`` (t(m + ν))."""
    k = c.size
    out = np.zeros(k)
    for j in range(k):
        for i in range(j, k):
            out[j] += math.comb(i, j) * c[i] * m ** (i - j)
    return out


@dataclass(frozen=True)
class EphemerisFit:
    """The fitted ephemeris and everything needed to report it.

    ``t0_jd`` is T0 as an exact JD (TDB). ``values`` and ``cov`` are (T0, P, Ṗ[, P̈]) with T0
    in seconds since ``ref_jd`` (float64, for the covariance and plots); the covariance is
    already rescaled when ``rescaled``. ``nu`` are the cycles of all points counted from T0 (the
    primary eclipse at cycle ``t0_cycle`` of the input or counted numbering); ``o_minus_c_s``
    the residuals from the full fit.
    """

    source: str
    terms: int
    ref_jd: Decimal
    t0_jd: Decimal
    values: F64
    cov: F64
    t0_cycle: int
    weighted_mean_cycle: float
    nu: F64
    o_minus_c_s: F64
    z: F64
    used: NDArray[np.bool_]
    chi2: float
    dof: int
    sigma_scale: float
    outliers: tuple[int, ...]
    clipped: tuple[int, ...]
    cycles_origin: str
    notes: tuple[str, ...] = field(default=())

    @property
    def names(self) -> tuple[str, ...]:
        """Names of the fitted parameters."""
        return PARAMETERS[: self.terms]

    @property
    def sigmas(self) -> F64:
        """1σ of each parameter (rescaled when χ²/dof > 1)."""
        return np.sqrt(np.diag(self.cov))

    @property
    def period_s(self) -> float:
        """P at T0 [s]."""
        return float(self.values[1])

    @property
    def rescaled(self) -> bool:
        """Whether the σ's were scaled up by √(χ²/dof)."""
        return self.sigma_scale > 1.0

    @property
    def n_used(self) -> int:
        """Times in the fit (after ``clip``)."""
        return int(np.count_nonzero(self.used))

    def model_s(self, nu: F64) -> F64:
        """t(ν) in seconds since ``ref_jd`` for cycles ν counted from T0."""
        c = parameters_to_coefficients(self.values)
        return np.asarray(design(np.asarray(nu, dtype=np.float64), self.terms) @ c)


def _check_counts(
    times: EclipseTimes, cycles: F64, used: NDArray[np.bool_], terms: int, why: str
) -> None:
    n = int(np.count_nonzero(used))
    distinct = np.unique(cycles[used]).size
    if n < terms or distinct < terms:
        what = f"{n} times" if n < terms else f"{distinct} distinct cycles"
        # times in few cycles: the first ephemeris may have counted them wrong
        check = "" if n < terms else ", or check the first ephemeris (`period`, `initial`)"
        raise InputError(
            f"{times.label()}: {why}{what}, fewer than the {terms} parameters of `terms` {terms}; "
            f"add times or fit fewer terms (`terms` {max(2, min(terms - 1, distinct))}){check}"
        )


@dataclass(frozen=True)
class _Core:
    m: int
    wmean: float
    coef: F64
    cov_c: F64
    chi2: float
    dof: int


def _fit_core(y: F64, sigma: F64, cycles: F64, terms: int, label: str) -> _Core:
    w = 1.0 / sigma**2
    wmean = float(np.sum(w * cycles) / np.sum(w))
    m = math.floor(wmean + 0.5)
    a = design(cycles - m, terms)
    try:
        coef, cov_c = solve_wls(a, y, sigma)
    except np.linalg.LinAlgError:
        raise NumericalError(
            f"{label}: the times do not constrain all {terms} parameters (singular design); "
            "fit fewer terms (`terms`)"
        ) from None
    resid = (y - a @ coef) / sigma
    return _Core(m, wmean, coef, cov_c, float(resid @ resid), int(y.size - terms))


@dataclass(frozen=True)
class _Base:
    """A linear ephemeris T_b + P_b·(n − m_b), exact decimals, subtracted before the fit."""

    m: int
    t_s: Decimal
    period_s: Decimal

    def at(self, n: float) -> Decimal:
        """T_b + P_b·(n − m_b) in seconds since the reference epoch (exact)."""
        return _DEC.add(self.t_s, _DEC.multiply(self.period_s, Decimal(repr(float(n - self.m)))))


_DEC = decimal.Context(prec=60)


def _base(times: EclipseTimes, cycles: F64, terms: int) -> tuple[_Base, F64]:
    """A first fit on float64 seconds, then the times minus its linear part, computed exactly.

    The float64 seconds since the reference epoch carry a rounding of ~1e-16 of their size
    (~1e-8 s over years), which a lever arm of many cycles can amplify; the detrended times are
    O − C sized, so the second fit works with ~1e-13 s rounding.
    """
    first = _fit_core(times.t_s, times.sigma_s, cycles, terms, times.label())
    base = _Base(first.m, Decimal(float(first.coef[0])), Decimal(float(first.coef[1])))
    y = np.array(
        [
            float(_DEC.subtract(_DEC.multiply(_DEC.subtract(jd, times.ref_jd), _DAY), base.at(n)))
            for jd, n in zip(times.jd, cycles, strict=True)
        ]
    )
    return base, y


_DAY = Decimal(DAY_S_INT)


def fit_ephemeris(
    times: EclipseTimes,
    cycles: F64,
    terms: int = 3,
    clip: float | None = None,
    cycles_origin: str = "given in the table",
) -> EphemerisFit:
    """Fit (T0, P, Ṗ[, P̈]) to ``times`` at ``cycles`` (see the module notes).

    Parameters
    ----------
    times : EclipseTimes
        The measured times.
    cycles : array
        Cycle number of each time (integer primaries, half-integer secondaries).
    terms : int
        2 (T0, P), 3 (+ Ṗ) or 4 (+ P̈).
    clip : float or None
        Drop times more than ``clip`` rescaled σ from the fit (iteratively); None keeps all.
    cycles_origin : str
        How the cycles were obtained (reported).

    Raises
    ------
    InputError
        Fewer times or distinct cycles than parameters (also after clipping), bad ``terms``.
    NumericalError
        A singular design, or a fit with P ≤ 0.
    """
    if terms not in (2, 3, 4):
        raise InputError(f"terms: expected 2, 3 or 4, got {terms}")
    cycles = np.asarray(cycles, dtype=np.float64)
    label = times.label()
    _check_counts(times, cycles, np.ones(times.n, dtype=bool), terms, "")
    base, y = _base(times, cycles, terms)
    fit = _clipped_fit(times, cycles, y, terms, clip, label)
    t0_s, values, cov = _parameters(base, fit.core, fit.scale, label)
    t0_jd = _DEC.add(times.ref_jd, _DEC.divide(t0_s, _DAY))
    return _assemble(times, cycles, terms, fit, t0_jd, values, cov, clip, cycles_origin)


@dataclass(frozen=True)
class _Clipped:
    """A fit after clipping: the fit, its σ scale √(χ²/dof) (1 unless above 1), O − C [s],
    O − C in scaled σ's, the times used and the rows dropped."""

    core: _Core
    scale: float
    oc: F64
    z: F64
    used: NDArray[np.bool_]
    clipped: tuple[int, ...]


def _assemble(
    times: EclipseTimes,
    cycles: F64,
    terms: int,
    fit: _Clipped,
    t0_jd: Decimal,
    values: F64,
    cov: F64,
    clip: float | None,
    cycles_origin: str,
) -> EphemerisFit:
    """The :class:`EphemerisFit` record, with its outliers and notes."""
    core, used, z = fit.core, fit.used, fit.z
    outliers = tuple(int(r) for r in times.rows[used & (np.abs(z) > OUTLIER_SIGMA)])
    notes = _notes(core, fit.scale, outliers, fit.clipped, clip)
    return EphemerisFit(
        source=times.label(),
        terms=terms,
        ref_jd=times.ref_jd,
        t0_jd=t0_jd,
        values=values,
        cov=cov,
        t0_cycle=core.m,
        weighted_mean_cycle=core.wmean,
        nu=cycles - core.m,
        o_minus_c_s=fit.oc,
        z=z,
        used=used,
        chi2=core.chi2,
        dof=core.dof,
        sigma_scale=fit.scale,
        outliers=outliers,
        clipped=fit.clipped,
        cycles_origin=cycles_origin,
        notes=notes,
    )


def _clipped_fit(
    times: EclipseTimes, cycles: F64, y: F64, terms: int, clip: float | None, label: str
) -> _Clipped:
    """The fit of ``y`` after dropping, one round at a time, the times beyond ``clip`` σ."""
    used = np.ones(times.n, dtype=bool)
    clipped: list[int] = []
    for _ in range(times.n):
        core = _fit_core(y[used], times.sigma_s[used], cycles[used], terms, label)
        ratio = core.chi2 / core.dof if core.dof > 0 else 0.0
        scale = math.sqrt(ratio) if ratio > 1.0 else 1.0
        oc = y - design(cycles - core.m, terms) @ core.coef
        z = oc / (times.sigma_s * scale)
        if clip is None:
            break
        drop = used & (np.abs(z) > clip)
        if not drop.any():
            break
        clipped.extend(int(r) for r in times.rows[drop])
        used = used & ~drop
        _check_counts(times, cycles, used, terms, f"`clip` {clip:g} leaves ")
    return _Clipped(core, scale, oc, z, used, tuple(clipped))


def _parameters(base: _Base, core: _Core, scale: float, label: str) -> tuple[Decimal, F64, F64]:
    """T0 [s since the reference epoch, exact], the parameters and their (scaled) covariance.

    Raises
    ------
    NumericalError
        The fitted period is not positive.
    """
    t0_s = _DEC.add(base.at(core.m), Decimal(float(core.coef[0])))
    coef = core.coef.copy()
    coef[0] = float(t0_s)
    coef[1] = float(_DEC.add(base.period_s, Decimal(float(coef[1]))))
    values, jac = coefficients_to_parameters(coef)
    if values[1] <= 0:
        raise NumericalError(f"{label}: the fitted period is not positive; check the cycle numbers")
    cov = jac @ core.cov_c @ jac.T * scale**2
    return t0_s, values, 0.5 * (cov + cov.T)


def _notes(
    core: _Core,
    scale: float,
    outliers: tuple[int, ...],
    clipped: tuple[int, ...],
    clip: float | None,
) -> tuple[str, ...]:
    notes = []
    if core.dof == 0:
        notes.append(
            "no degrees of freedom (as many times as parameters): σ's from the input σ's only"
        )
    elif scale > 1.0:
        notes.append(
            f"chi2/dof = {core.chi2 / core.dof:.3g} > 1: parameter σ's scaled up by "
            f"√(chi2/dof) = {scale:.3g} (the timing errors look underestimated)"
        )
    if outliers:
        rows = ", ".join(map(str, outliers[:20])) + (" …" if len(outliers) > 20 else "")
        notes.append(
            f"{len(outliers)} outlier(s) beyond {OUTLIER_SIGMA:g}σ kept in the fit (rows {rows}); "
            "check them, or pass --clip K to drop times beyond Kσ"
        )
    if clipped:
        rows = ", ".join(map(str, clipped[:20])) + (" …" if len(clipped) > 20 else "")
        notes.append(f"--clip {clip:g} dropped {len(clipped)} time(s): rows {rows}")
    return tuple(notes)
