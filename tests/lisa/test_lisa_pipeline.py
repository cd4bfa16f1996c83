"""The LISA simulation as library calls: no CLI, no printing, records that agree with each other."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from ucbplan.lisa.lines import LINE_COLUMNS, waveform_lines
from ucbplan.lisa.outputs import simulation_files, write_simulation
from ucbplan.lisa.pipeline import build_model, fisher_forecast, simulate
from ucbplan.lisa.simulation import SimulateOptions
from ucbplan.targets import load_target

INJECTION = Path(__file__).resolve().parents[2] / "catalogs" / "fiducial-injection.yaml"


@pytest.fixture(scope="module")
def model():  # type: ignore[no-untyped-def]
    return build_model(load_target(INJECTION), n_bins=64)


def test_build_model_checks_band_width() -> None:
    """An odd or too small N is refused before any work."""
    with pytest.raises(ValueError, match="n_bins"):
        build_model(load_target(INJECTION), n_bins=15)


def test_waveform_snr_agrees_with_likelihood_snr(model, capsys) -> None:  # type: ignore[no-untyped-def]
    """The lines table's optimal SNR (direct sum over |A~|², |E~|²) equals the likelihood's
    sqrt((h|h)) of the Fisher forecast (template path) to 1e-10; nothing is printed."""
    lines = waveform_lines(model)
    forecast = fisher_forecast(model)
    assert lines.snr == pytest.approx(forecast.snr, rel=1e-10)
    assert list(lines.table.colnames) == list(LINE_COLUMNS)
    assert len(lines.table) == 3 * 64
    assert set(lines.line_freqs_hz) == {"n=1+", "n=1-", "n=2", "n=3"}
    assert forecast.target.cov_names[:3] == ("phase", "f_gw", "fdot")
    assert all(s > 0 for s in forecast.sigmas.values())
    assert capsys.readouterr() == ("", "")


def test_simulate_records_and_files(model, tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    """A tiny zero-noise run: the posterior mean lies within 5 Fisher σ of the injection, the
    short chain is reported as a warning (not printed), and the written files load back."""
    opts = SimulateOptions(seed=3, walkers=18, steps=20, noise=False)
    res = simulate(model, opts)
    assert res.n_steps == 20 and res.samples.shape[1] == 9
    assert res.warnings and "shorter than 50 τ" in res.warnings[0]
    for name in ("phase", "f_gw", "eta"):
        pull = (res.posterior_mean[name] - res.injected[name]) / res.fisher_sigma[name]
        assert abs(pull) < 5, (name, pull)
    files = simulation_files(tmp_path / "post.yaml")
    write_simulation(res, files)
    back = load_target(files.target)
    assert back.samples == files.samples.resolve()
    with np.load(files.chain) as z:
        assert z["theta"].shape == (20, 18, 9)
    assert capsys.readouterr() == ("", "")
