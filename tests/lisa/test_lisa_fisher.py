"""Fisher matrix → covariance → whitening through ucbplan.core.mvnormal (issue 11).

The inversion is exact in scaled form for the fiducial injection, the forecast is the one the raw
``inv`` gave (its σ's agree to 1e-9: the fiducial matrix is well conditioned in sampled
coordinates, so the fix must not move it), and sources the data cannot constrain (face-on, too
faint) raise a one-line NumericalError naming the parameter instead of NaN σ's.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from ucbplan.core.mvnormal import inverse_scaled, sample_normal
from ucbplan.errors import NumericalError
from ucbplan.lisa.fisher import fisher_covariance, fisher_matrix, unwhiten, whitening
from ucbplan.lisa.likelihood import Prior, simulate_data, source_from_target
from ucbplan.lisa.noise import SANGRIA
from ucbplan.lisa.pipeline import build_model, fisher_forecast, prepare_simulation, simulate
from ucbplan.lisa.simulation import LisaModel, SimulateOptions
from ucbplan.targets import load_target, target_from_dict

INJECTION = Path(__file__).resolve().parents[2] / "catalogs" / "fiducial-injection.yaml"


def _variant(**lisa: Any) -> Any:
    """The fiducial injection with some ``lisa`` fields replaced."""
    doc = yaml.safe_load(INJECTION.read_text())
    doc["lisa"].update(lisa)
    return target_from_dict(doc, INJECTION)


def _zero_noise(model: LisaModel) -> tuple[Any, np.ndarray]:
    like = model.likelihood(simulate_data(model.model, model.truth, SANGRIA, None))
    return like, model.theta0()


@pytest.fixture(scope="module")
def fiducial() -> LisaModel:
    return build_model(load_target(INJECTION))


def test_fisher_inversion_is_exact_in_scaled_form(fiducial: LisaModel) -> None:
    """F · C = I for the fiducial injection with F and C scaled by √diag F (1e-8)."""
    like, theta0 = _zero_noise(fiducial)
    fis = fisher_matrix(like, theta0)
    cov = fisher_covariance(like, theta0)
    d = np.sqrt(np.diag(fis))
    prod = (fis / np.outer(d, d)) @ (cov * np.outer(d, d))
    assert np.abs(prod - np.eye(d.size)).max() < 1e-8
    np.testing.assert_array_equal(cov, cov.T)


def test_fisher_forecast_unchanged_by_the_scaled_inverse(fiducial: LisaModel) -> None:
    """The written forecast σ's equal those of the raw inverse used before (1e-9 relative)."""
    like, theta0 = _zero_noise(fiducial)
    old = np.linalg.inv(fisher_matrix(like, theta0))
    new = fisher_forecast(fiducial).cov_theta
    np.testing.assert_allclose(np.sqrt(np.diag(new)), np.sqrt(np.diag(old)), rtol=1e-9)
    corr = new / np.sqrt(np.outer(np.diag(new), np.diag(new)))
    corr_old = old / np.sqrt(np.outer(np.diag(old), np.diag(old)))
    np.testing.assert_allclose(corr, corr_old, atol=1e-9)


def test_whitening_round_trip_and_moments(fiducial: LisaModel) -> None:
    """θ = θ0 + A x with A Aᵀ = C: unwhiten inverts it (1e-10), and A x of x ~ N(0, I) has the
    Fisher covariance (σ to 2 %, correlations to 0.02 for 50 000 draws)."""
    like, theta0 = _zero_noise(fiducial)
    cov = fisher_covariance(like, theta0)
    root = whitening(cov)
    np.testing.assert_allclose(
        (root @ root.T) / np.sqrt(np.outer(np.diag(cov), np.diag(cov))),
        cov / np.sqrt(np.outer(np.diag(cov), np.diag(cov))),
        atol=1e-12,
    )
    x = np.random.default_rng(1).standard_normal((50_000, theta0.size))
    theta = x @ root.T
    np.testing.assert_allclose(unwhiten(cov, root, theta), x, atol=1e-10)
    sig = np.sqrt(np.diag(cov))
    np.testing.assert_allclose(theta.std(axis=0) / sig, 1.0, rtol=0.02)
    np.testing.assert_allclose(np.corrcoef(theta.T), cov / np.outer(sig, sig), atol=0.02)
    ref = sample_normal(np.zeros(theta0.size), cov, 50_000, np.random.default_rng(2))
    np.testing.assert_allclose(ref.std(axis=0) / sig, 1.0, rtol=0.02)
    np.testing.assert_allclose(inverse_scaled(inverse_scaled(cov)), cov, rtol=1e-9)


@pytest.mark.parametrize("cos_i", [1.0, -1.0, 0.9999])
def test_face_on_source_is_unconstrained_not_nan(cos_i: float) -> None:
    """Face-on, φ and ψ are degenerate: the forecast names them instead of printing NaN σ's."""
    model = build_model(_variant(cos_inclination=cos_i), n_bins=64)
    with pytest.raises(NumericalError, match="unconstrained") as err:
        fisher_forecast(model)
    msg = str(err.value)
    assert "phase" in msg and "psi" in msg and "face-on" in msg
    assert "\n" not in msg and len(msg) < 400
    assert "fiducial-injection.yaml" in msg


def test_faint_source_is_unconstrained() -> None:
    """A source far below the noise: simulate refuses (the Fisher σ exceeds the prior: the
    sampler cannot be whitened), one line naming a parameter and the SNR; the forecast is
    still given, with the same text as a warning."""
    model = build_model(_variant(amplitude=1e-40), n_bins=64)
    with pytest.raises(NumericalError, match=r"unconstrained.*prior width.*SNR") as err:
        prepare_simulation(model, SimulateOptions(walkers=18, steps=5))
    assert len(str(err.value)) < 400 and "\n" not in str(err.value)
    forecast = fisher_forecast(model)
    assert forecast.warnings and "unconstrained" in forecast.warnings[0]


def test_short_observation_leaves_fdot_unmeasured() -> None:
    """Ten days cannot measure ḟ: the forecast warns about it (and only it), σ's stay finite."""
    model = build_model(load_target(INJECTION), t_obs_s=10 * 86400.0, n_bins=64)
    forecast = fisher_forecast(model)
    assert len(forecast.warnings) == 1 and forecast.warnings[0].count("fdot") >= 1
    assert "phase" not in forecast.warnings[0].split("(also")[0]
    assert all(np.isfinite(s) for s in forecast.sigmas.values())
    assert fisher_forecast(build_model(load_target(INJECTION), n_bins=64)).warnings == ()


@pytest.mark.parametrize("fdot", ["2e-12 Hz / s"])
def test_prior_covers_fdot_above_the_paper_range(fdot: str) -> None:
    """ḟ above 1e-12 Hz/s: the log10 ḟ prior is widened to cover the source (it used to start
    the walkers outside the prior and crash)."""
    target = _variant(fdot=fdot)
    truth = source_from_target(target)
    prior = Prior.paper(truth, target.t_obs_s)
    model = build_model(target, n_bins=64)
    assert prior.names[2] == "log10_fdot" and prior.contains(model.theta0()[None])[0]
    lo, hi = prior.low[2], prior.high[2]
    assert lo == -18.0 and hi >= np.log10(truth.fdot) + 1
    res = simulate(model, SimulateOptions(seed=2, walkers=18, steps=15, noise=False))
    assert np.all(np.isfinite(res.chain.log_prob[-1]))


@pytest.mark.parametrize(
    "fdot", ["5e-19 Hz / s", "1e-20 Hz / s", "1e-23 Hz / s", "0 Hz / s", "-3e-19 Hz / s"]
)
def test_fdot_below_the_paper_range_is_sampled_linearly(fdot: str) -> None:
    """ḟ < 1e-18 Hz/s (issue 13: simulate's prior excluded it; ḟ ≲ 1e-20 still failed with
    "fdot unconstrained", ḟ ≤ 0 was refused): ḟ itself is sampled, uniform in ±1e-12 Hz/s.

    Independent check: ḟ enters the waveform only through the phase π ḟ t², so its Fisher 1σ
    hardly depends on ḟ; it must match the fiducial's σ(log10 ḟ) · ḟ ln 10 (the log-coordinate
    forecast of the same source, propagated) to 5 %."""
    model = build_model(_variant(fdot=fdot), n_bins=64)
    truth = model.truth
    prior = model.likelihood(np.zeros((3, 2, 64), complex)).prior
    assert prior.names[2] == "fdot" and (prior.low[2], prior.high[2]) == (-1e-12, 1e-12)
    assert prior.contains(model.theta0()[None])[0]
    assert model.theta0()[2] == truth.fdot
    forecast = fisher_forecast(model)
    assert forecast.warnings == ()
    fid = build_model(load_target(INJECTION), n_bins=64)
    fid_fc = fisher_forecast(fid)
    sigma_fid = np.sqrt(fid_fc.cov_theta[2, 2]) * np.log(10.0) * fid.truth.fdot
    assert np.sqrt(forecast.cov_theta[2, 2]) == pytest.approx(sigma_fid, rel=0.05)
    assert forecast.sigmas["fdot"] == pytest.approx(sigma_fid, rel=0.05)
    res = simulate(model, SimulateOptions(seed=2, walkers=18, steps=15, noise=True))
    assert np.all(np.isfinite(res.chain.log_prob[-1])) and res.chain.names[2] == "fdot"
    assert res.columns["fdot"].std() < 20 * sigma_fid
    assert abs(res.columns["fdot"].mean() - truth.fdot) < 20 * sigma_fid


def test_paper_fdot_prior_unchanged_for_the_fiducial(fiducial: LisaModel) -> None:
    """Inside [1e-18, 1e-12] Hz/s the prior is the paper's [-18, -12]."""
    prior = Prior.paper(fiducial.truth, fiducial.t_obs_s)
    assert (prior.low[2], prior.high[2]) == (-18.0, -12.0)


@pytest.mark.parametrize("psi", [-0.3, 0.339 + np.pi, 7.0])
def test_psi_outside_zero_pi_is_folded(psi: float) -> None:
    """ψ → ψ + π is an exact symmetry: ψ outside [0, π) is folded into the prior (a ψ of −0.3
    put every walker outside the prior: 'could not place walkers')."""
    target = _variant(psi=psi)
    truth = source_from_target(target)
    assert 0.0 <= truth.psi < np.pi
    assert truth.psi == pytest.approx(np.mod(psi, np.pi), abs=1e-12)
    model = build_model(target, n_bins=64)
    assert model.likelihood(np.zeros((3, 2, 64), complex)).prior.contains(model.theta0()[None])[0]
