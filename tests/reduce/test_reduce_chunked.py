"""The per-spectrum passes of ``reduce`` (orbit, window averages, light-time designs, Jacobians,
seconds since t_ref) run chunk by chunk (:data:`ucbplan.core.kepler.CHUNK_ROWS` spectra): every
operation is elementwise, so the chunks must give the same doubles as one piece, bit for bit
(issue 34). A chunk of one row is avoided: numpy's complex product of a one-element array
rounds differently from its vectorised loop."""

from __future__ import annotations

import numpy as np
import pytest
from support.reduce_synth import make_target

from ucbplan.core import kepler
from ucbplan.reduce import design
from ucbplan.reduce.pipeline import ReduceOptions, reduce
from ucbplan.reduce.velocities import VelocityTable


def _same_bits(a: object, b: object) -> bool:
    x, y = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    return x.shape == y.shape and bool(np.array_equal(x.view(np.int64), y.view(np.int64)))


def _passes(p, tau, window):  # type: ignore[no-untyped-def]
    """Every chunked pass of the design module, as a flat list of arrays."""
    at = design.track(p, tau)
    mid = design.mid_exposure(p, tau, window, at)
    jac = design.design_jacobian(p, tau, window, at, mid)
    lt = design.designs(p, tau, window, 2, (585.3, 712.6), at)
    plain = design.designs(p, tau, window, 2, None, at)
    wv = mid[0]
    return [at.phase, at.phase_mod, at.eta, at.kap, at.u, wv.h, wv.d_phase, wv.d_omega, wv.d_e,
            mid[1], jac, *lt, *plain]  # fmt: skip


@pytest.mark.parametrize("circular", [False, True])
@pytest.mark.parametrize("rows", [7, 64])
def test_chunks_give_the_same_doubles_as_one_piece(
    rows: int, circular: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    """101 spectra over 4 years (a partial last chunk, never of one row): chunks of 7 and 64
    rows against one chunk of all of them, eccentric and circular (the first-order Jacobian)."""
    p = make_target(circular=circular).params
    rng = np.random.default_rng(34)
    tau = np.sort(rng.uniform(-6e7, 6e8, 101))
    window = rng.uniform(0.0, 120.0, 101)
    whole = _passes(p, tau, window)
    monkeypatch.setattr(kepler, "CHUNK_ROWS", rows)
    chunked = _passes(p, tau, window)
    assert all(_same_bits(a, b) for a, b in zip(whole, chunked, strict=True))


def test_reduce_is_the_same_chunk_by_chunk(monkeypatch: pytest.MonkeyPatch) -> None:
    """The whole reduction (K, γ, phase errors, light time) with 5-row chunks and one chunk."""
    t = make_target()
    p = t.params
    rng = np.random.default_rng(3)
    tau = np.sort(rng.uniform(0.0, 3e8, 60))
    from astropy.time import TimeDelta

    from ucbplan.reduce.design import designs

    g = designs(p, tau, np.full(60, 30.0), 1, None)[0]
    table = VelocityTable(
        source=None,
        time=t.t_ref + TimeDelta(tau, format="sec"),
        window_s=np.full(60, 30.0),
        lambda_k=np.full(60, np.nan),
        v=(30.0 + 585.3 * g + rng.normal(0, 5, 60), 10.0 - 712.6 * g + rng.normal(0, 5, 60)),
        sigma=(np.full(60, 5.0), np.full(60, 5.0)),
        session=("A",) * 60,
        u_star=None,
    )

    def run() -> list[object]:
        r = reduce(t, table, ReduceOptions(n_samples=200, seed=1, light_time=True))
        lt = list(r.light_time.values())
        return [r.tau_s, r.u_rad, *r.design, r.dK, r.dgamma, r.sigma_u, [f.K for f in r.fits], lt]

    whole = run()
    monkeypatch.setattr(kepler, "CHUNK_ROWS", 5)
    assert all(_same_bits(a, b) for a, b in zip(whole, run(), strict=True))


def test_seconds_since_the_reference_are_astropys(monkeypatch: pytest.MonkeyPatch) -> None:
    """τ = (t − t_ref) in s chunk by chunk (7 rows) is astropy's whole-array subtraction, bit for
    bit, for TDB times over 20 years given as two-part JDs."""
    from astropy.time import Time

    from ucbplan.reduce.velocities import _seconds_since

    rng = np.random.default_rng(11)
    jd = 2464329.5 + np.sort(rng.uniform(-3650.0, 3650.0, 103))
    time = Time(np.floor(jd), jd - np.floor(jd), format="jd", scale="tdb")
    t_ref = Time("2037-01-01T00:00:00", scale="tdb")
    whole = np.asarray((time - t_ref).to_value("s"), dtype=np.float64)
    monkeypatch.setattr(kepler, "CHUNK_ROWS", 7)
    assert _same_bits(_seconds_since(time, t_ref), whole)


@pytest.mark.parametrize("derivatives", [False, True])
def test_a_shared_window_rotation_gives_the_same_averages(derivatives: bool) -> None:
    """The windows' cos and sin of ω̇Δt/2 computed once (``rotation``, shared by the five
    window-average passes of a reduction) give the averages computed without it, bit for bit;
    zero windows (floored) included."""
    rng = np.random.default_rng(5)
    phi, om = rng.uniform(0.0, 2.0 * np.pi, (2, 50))
    window = np.where(rng.uniform(size=50) < 0.2, 0.0, rng.uniform(1.0, 200.0, 50))
    nb, wdot, e = 0.0264, 1.5e-6, 0.0094
    rotation = kepler.window_rotation(wdot, window)
    own = kepler.window_average(phi, om, e, nb, wdot, window, derivatives)
    shared = kepler.window_average(phi, om, e, nb, wdot, window, derivatives, rotation)
    for a, b in zip(
        (own.h, own.d_phase, own.d_omega, own.d_e),
        (shared.h, shared.d_phase, shared.d_omega, shared.d_e),
        strict=True,
    ):
        assert _same_bits(a, b)


@pytest.mark.parametrize("derivatives", [False, True])
def test_series_terms_given_once_give_the_same_averages(derivatives: bool) -> None:
    """The series computed once for every chunk of a pass (``terms``) gives the averages that
    each call computing its own gives, bit for bit."""
    rng = np.random.default_rng(6)
    phi, om = rng.uniform(0.0, 2.0 * np.pi, (2, 40))
    window = rng.uniform(0.0, 200.0, 40)
    nb, wdot, e = 0.0264, 1.5e-6, 0.0094
    terms = kepler.series_terms(e, derivatives)
    own = kepler.window_average(phi, om, e, nb, wdot, window, derivatives)
    given = kepler.window_average(phi, om, e, nb, wdot, window, derivatives, None, terms)
    for a, b in zip(
        (own.h, own.d_phase, own.d_omega, own.d_e),
        (given.h, given.d_phase, given.d_omega, given.d_e),
        strict=True,
    ):
        assert _same_bits(a, b)


def test_window_factors_chunk_by_chunk_are_the_whole_arrays(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Λ_K, Λ_κ and Δt of windows given as widths (zero included) or as Λ_K (NaN width), in
    7-row chunks: the whole-array formulas' doubles, bit for bit."""
    from types import SimpleNamespace

    from ucbplan.core.smearing import lambda_k, lambda_kappa
    from ucbplan.reduce.regression import lambda_k_to_x

    rng = np.random.default_rng(8)
    w = rng.uniform(0.0, 120.0, 50)
    w[::9] = 0.0
    given = rng.uniform(size=50) < 0.3
    w[given] = np.nan
    lam = np.where(given, rng.uniform(0.5, 1.0, 50), np.nan)
    table = SimpleNamespace(window_s=w, lambda_k=lam, source=None, window_column="exptime_s")
    f, nbar = 8.4e-3, np.pi * 8.4e-3
    x = np.zeros(50)
    x[given] = lambda_k_to_x(lam[given])
    ref_lk = np.where(np.isfinite(w), lambda_k(np.nan_to_num(w), nbar), lam)
    ref_lkap = np.where(given, np.sinc(2.0 * x / np.pi), lambda_kappa(np.nan_to_num(w), nbar))
    ref_dt = np.where(given, 2.0 * x / nbar, np.nan_to_num(w))
    monkeypatch.setattr(kepler, "CHUNK_ROWS", 7)
    lk, lkap = design.window_factors(table, f)  # type: ignore[arg-type]
    dt = design.window_durations(table, f)  # type: ignore[arg-type]
    assert _same_bits(lk, ref_lk) and _same_bits(lkap, ref_lkap) and _same_bits(dt, ref_dt)


@pytest.mark.parametrize("circular", [False, True])
def test_sigma_u_from_the_track_is_u_jacobians(
    circular: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    """σ_u from the orbit track (its Φ_asc mod 2π and cos, sin of ω̇τ, which the design
    Jacobian shares) in 7-row chunks: √(J C Jᵀ) of core.phase.u_jacobian over the whole
    array, bit for bit; the track's turn is cos and sin of ω̇τ."""
    from ucbplan.core.phase import u_jacobian
    from ucbplan.reduce.pipeline import _sigma_u

    t = make_target(circular=circular)
    p, cov7 = t.params, t.covariance
    tau = np.sort(np.random.default_rng(12).uniform(-6e7, 6e8, 101))
    ju = u_jacobian(p, tau)
    ref = np.sqrt(np.clip(np.einsum("ni,ij,nj->n", ju, cov7, ju), 0.0, None))
    monkeypatch.setattr(kepler, "CHUNK_ROWS", 7)
    at = design.track(p, tau)
    w = p.omega_dot * tau
    assert _same_bits(at.cos_w, np.cos(w)) and _same_bits(at.sin_w, np.sin(w))
    assert _same_bits(_sigma_u(p, cov7, tau, at), ref)
