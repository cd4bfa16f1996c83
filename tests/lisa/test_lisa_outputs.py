"""simulate / fisher / waveform outputs (issue 11): a file set written as a unit, Ctrl-C keeps the
chain for --resume, one -o rule, and bad option values are one-line errors.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

from ucbplan.cli._flags import cli_message
from ucbplan.cli.app import app
from ucbplan.errors import InputError, OutputError
from ucbplan.lisa import sampler as sampler_mod
from ucbplan.lisa.likelihood import Likelihood
from ucbplan.lisa.outputs import (
    save_interrupted,
    simulation_files,
    write_simulation,
)
from ucbplan.lisa.pipeline import build_model, prepare_simulation, run_simulation
from ucbplan.lisa.sampler import SamplerInterrupted
from ucbplan.lisa.simulation import SimulateOptions, SimulationResult
from ucbplan.targets import load_target

ROOT = Path(__file__).resolve().parents[2]
INJECTION = ROOT / "catalogs" / "fiducial-injection.yaml"
OPTS = SimulateOptions(seed=3, walkers=18, steps=12, noise=False)


@pytest.fixture(scope="module")
def model() -> Any:
    return build_model(load_target(INJECTION), n_bins=64)


@pytest.fixture(scope="module")
def result(model: Any) -> SimulationResult:
    return run_simulation(prepare_simulation(model, OPTS))


def _one_line(text: str) -> str:
    lines = [ln for ln in text.strip().splitlines() if ln.strip()]
    assert len(lines) == 1, text
    assert len(lines[0]) < 400
    return lines[0]


def test_file_set_is_written_as_a_unit(result: SimulationResult, tmp_path: Path) -> None:
    """YAML, samples and chain appear together; the YAML loads and names its samples."""
    files = simulation_files(tmp_path / "post.yaml")
    write_simulation(result, files)
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "post.chain.npz",
        "post.samples.ecsv",
        "post.yaml",
    ]
    back = load_target(files.target)
    assert back.samples == files.samples.resolve()
    assert files.target.read_text(encoding="utf-8").startswith("# ucbplan simulate")
    with np.load(files.chain) as z:
        assert z["theta"].shape == (12, 18, 9)


@pytest.mark.parametrize("exc", [RuntimeError("boom"), OSError(28, "No space left on device")])
def test_failing_writer_leaves_nothing(
    result: SimulationResult, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, exc: Exception
) -> None:
    """The chain writer fails (a bug, a full disk): no file of the set and no temporary is left,
    so a rerun is not blocked; an existing set is not changed."""

    def fail(*args: object, **kwargs: object) -> None:
        raise exc

    files = simulation_files(tmp_path / "post.yaml")
    monkeypatch.setattr(sampler_mod.np, "savez_compressed", fail)
    with pytest.raises((RuntimeError, OutputError)):
        write_simulation(result, files)
    assert list(tmp_path.iterdir()) == []
    monkeypatch.undo()
    write_simulation(result, files)  # the rerun is not blocked
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    monkeypatch.setattr(sampler_mod.np, "savez_compressed", fail)
    with pytest.raises((RuntimeError, OutputError)):
        write_simulation(result, files, overwrite=True)
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before


@pytest.mark.parametrize(
    ("output", "chain"),
    [
        ("post.yaml", "post.yaml"),
        ("post.yaml", "post.samples.ecsv"),
        ("a/../post.yaml", "post.yaml"),
    ],
)
def test_outputs_naming_the_same_file_are_refused(tmp_path: Path, output: str, chain: str) -> None:
    (tmp_path / "a").mkdir()
    with pytest.raises(InputError, match="same file"):
        simulation_files(tmp_path / output, tmp_path / chain)


def test_interrupt_keeps_the_chain_for_resume(
    model: Any, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Ctrl-C after 10 steps: SamplerInterrupted (a KeyboardInterrupt) carries the 10 steps; saved
    with save_interrupted they resume to 10 + 12 steps."""
    problem = prepare_simulation(model, OPTS)

    def progress(done: int, total: int, tau: float) -> None:
        if done == 10:
            raise KeyboardInterrupt

    with pytest.raises(SamplerInterrupted) as stop:
        run_simulation(problem, progress)
    assert isinstance(stop.value, KeyboardInterrupt)
    partial = stop.value.partial
    assert partial is not None and partial.theta.shape == (10, 18, 9)
    assert np.all(np.isfinite(partial.log_prob))
    chain = tmp_path / "post.chain.npz"
    save_interrupted(problem, partial, chain)
    again = SimulateOptions(seed=3, walkers=18, steps=12, noise=False, resume=chain)
    resumed = run_simulation(prepare_simulation(model, again))
    assert resumed.chain.theta.shape == (22, 18, 9)
    np.testing.assert_array_equal(resumed.chain.theta[:10], partial.theta)


def test_interrupt_before_the_first_step_has_nothing_to_save(model: Any) -> None:
    problem = prepare_simulation(model, OPTS)
    calls = {"n": 0}
    original = Likelihood.log_prob

    def log_prob(self: Likelihood, theta: np.ndarray) -> np.ndarray:
        calls["n"] += 1
        if calls["n"] > 0:
            raise KeyboardInterrupt
        return original(self, theta)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(Likelihood, "log_prob", log_prob)
        with pytest.raises(SamplerInterrupted) as stop:
            run_simulation(problem)
    assert stop.value.partial is None


def test_cli_interrupt_saves_chain_only(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Through the CLI, a SIGINT in the middle of a step: the step finishes, then only the chain
    is written (no YAML or samples, which would describe an unfinished run), with the way to
    resume; emcee prints no traceback."""
    original = Likelihood.log_prob
    calls = {"n": 0}

    def log_prob(self: Likelihood, theta: np.ndarray) -> np.ndarray:
        calls["n"] += 1
        if calls["n"] == 40:  # 1 + 2 calls per step: inside step 20
            # To this thread, not the process: os.kill lets the kernel hand the signal to any
            # thread (pytest-xdist workers have several), and on a busy machine that thread ran
            # its C handler only steps later (a flaky test). pthread_kill to oneself is
            # delivered before it returns, and Python runs the handler at the next bytecode.
            signal.pthread_kill(threading.get_ident(), signal.SIGINT)
        return original(self, theta)

    monkeypatch.setattr(Likelihood, "log_prob", log_prob)
    out = tmp_path / "post.yaml"
    args = ["simulate", str(INJECTION), "-o", str(out), "--n-bins", "64", "--walkers", "18"]
    res = CliRunner().invoke(app, [*args, "--steps", "500", "--seed", "3", "--no-noise"])
    assert res.exit_code != 0
    assert [p.name for p in tmp_path.iterdir()] == ["post.chain.npz"]
    assert "--resume" in res.output and "Traceback" not in res.output
    with np.load(tmp_path / "post.chain.npz") as z:
        assert z["theta"].shape == (20, 18, 9)
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # handler restored


@pytest.mark.slow
def test_ctrl_c_exits_130_and_resume_continues(tmp_path: Path) -> None:
    """A real SIGINT to ``python -m ucbplan simulate``: exit 130, the chain is saved, and
    --resume continues it."""
    out = tmp_path / "post.yaml"
    args = [sys.executable, "-m", "ucbplan", "simulate", str(INJECTION), "-o", str(out)]
    args += ["--n-bins", "64", "--walkers", "18", "--seed", "3", "--no-noise"]
    env = dict(os.environ, COLUMNS="200")
    for wait in (3.0, 10.0):  # a loaded machine may not have started sampling after 3 s
        proc = subprocess.Popen(
            [*args, "--steps", "20000"], stderr=subprocess.PIPE, text=True, env=env, cwd=ROOT
        )
        try:
            assert proc.stderr is not None
            for line in proc.stderr:  # the SNR line is printed just before sampling starts
                if "optimal SNR" in line:
                    break
            time.sleep(wait)
            proc.send_signal(signal.SIGINT)
            _, err = proc.communicate(timeout=60)
        finally:
            proc.kill()
        assert proc.returncode == 130, err
        assert "Traceback" not in err
        if "chain saved" in err:
            break
    assert "chain saved" in err
    chain = tmp_path / "post.chain.npz"
    assert [p.name for p in tmp_path.iterdir()] == ["post.chain.npz"]
    with np.load(chain) as z:
        n_saved = z["theta"].shape[0]
    done = subprocess.run(
        [*args, "--steps", "5", "--resume", str(chain), "--overwrite"],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=ROOT,
    )
    assert done.returncode == 0, done.stderr
    with np.load(chain) as z:
        assert z["theta"].shape[0] == n_saved + 5
    assert out.exists() and out.with_suffix(".samples.ecsv").exists()


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["simulate", "-o", "{tmp}/p.json"], "give the file a .yaml name"),
        (["simulate", "-o", "{tmp}/p.yaml", "--chain", "{tmp}/p.yaml"], "same file"),
        (["simulate", "-o", "{tmp}/p.yaml", "--walkers", "10"], "at least 18"),
        (["simulate", "-o", "{tmp}/p.yaml", "--n-bins", "15"], "--n-bins"),
        (["simulate", "-o", "{tmp}/p.yaml", "--n-bins", "1000000000"], "--n-bins"),
        (["simulate", "-o", "{tmp}/p.yaml", "--t-obs", "nan yr"], "--t-obs"),
        (["simulate", "-o", "{tmp}/p.yaml", "--t-obs", "inf yr"], "--t-obs"),
        (["simulate", "-o", "{tmp}/p.yaml", "--t-obs", "1 s"], "--t-obs"),
        (["simulate", "-o", "{tmp}/p.yaml", "--t-obs", "x" * 5000], "characters"),
        (["simulate", "-o", "{tmp}/p.yaml", "--resume", "{tmp}"], "--resume"),
        (["fisher", "-o", "{tmp}/f.ecsv"], "give the file a .yaml name"),
        (["waveform", "-o", "{tmp}/l.json"], "give the file a .ecsv name"),
        (["waveform", "-o", "{tmp}/l.ecsv", "--plot", "{tmp}/l.ecsv"], "same file"),
    ],
)
def test_bad_options_are_one_line_errors(tmp_path: Path, argv: list[str], needle: str) -> None:
    """Each is a UcbplanError (exit 2 from the entry point) naming the option; nothing written."""
    cmd = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    res = CliRunner().invoke(app, [cmd[0], str(INJECTION), *cmd[1:]])
    assert res.exit_code != 0
    msg = _one_line(cli_message(str(res.exception)))  # as the entry point prints it
    assert needle in msg, msg
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    "argv", [["--steps", "0"], ["--walkers", "abc"], ["--seed", "-1"], ["--max-steps", "0"]]
)
def test_out_of_range_option_values_are_usage_errors(tmp_path: Path, argv: list[str]) -> None:
    """Values typer checks itself: exit 2 with the option named, no traceback, nothing written."""
    res = CliRunner().invoke(
        app, ["simulate", str(INJECTION), "-o", str(tmp_path / "p.yaml"), *argv]
    )
    assert res.exit_code == 2
    assert argv[0] in res.output and "Traceback" not in res.output
    assert list(tmp_path.iterdir()) == []
