"""Files of a LISA simulation: posterior target YAML, samples ECSV, chain .npz.

:func:`write_simulation` writes a :class:`~ucbplan.lisa.pipeline.SimulationResult` (each file
atomically); :func:`load_resume` reads a chain back to continue it with the same data.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ucbplan.errors import InputFileError
from ucbplan.lisa import posterior as post
from ucbplan.lisa.sampler import save_chain

if TYPE_CHECKING:
    from ucbplan.lisa.pipeline import SimulationResult

__all__ = ["SimulationFiles", "load_resume", "simulation_files", "write_simulation"]

F64 = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class SimulationFiles:
    """Paths written by :func:`write_simulation`."""

    target: Path
    samples: Path
    chain: Path


def simulation_files(output: Path, chain: Path | None = None) -> SimulationFiles:
    """File names of a simulation: samples ECSV and chain .npz next to ``output`` by default."""
    chain_path = chain if chain is not None else output.with_suffix(".chain.npz")
    return SimulationFiles(output, output.with_suffix(".samples.ecsv"), chain_path)


def write_simulation(
    result: SimulationResult,
    files: SimulationFiles,
    *,
    overwrite: bool = False,
    source_name: str | None = None,
) -> None:
    """Write the posterior target YAML, its samples ECSV and the chain .npz (each atomically).

    Parameters
    ----------
    source_name : str, optional
        Target file name for the YAML header (default: that of the model's target).
    """
    from ucbplan.target import write_target

    problem, chain = result.problem, result.chain
    model, opts = problem.model, problem.options
    if source_name is None:
        src = model.base.source
        source_name = src.name if src is not None else model.base.name
    post.write_samples(result.columns, files.samples, overwrite, result.samples_meta())
    header = (
        f"ucbplan simulate {source_name} seed={opts.seed} noise={opts.noise} N={model.n_bins}: "
        f"{result.samples.shape[0]} samples, {result.n_steps} steps (tau_max "
        f"{result.tau_max:.0f}, converged={chain.converged}), SNR {problem.snr:.1f}"
    )
    write_target(result.posterior(files.samples), files.target, overwrite=overwrite, header=header)
    extra = {
        "theta0": problem.theta0,
        "fisher_cov": problem.fisher_cov,
        "t_obs_s": model.t_obs_s,
        "noise": opts.noise,
        "n_bins": model.n_bins,
    }
    save_chain(chain, files.chain, extra, overwrite=overwrite)


def _read_npz(path: Path) -> dict[str, F64]:
    """Arrays of a .npz file (no pickles), or a one-line InputFileError."""
    import zipfile

    bad = InputFileError(f"{path}: --resume: not a .npz chain; give the .npz of a simulate run")
    try:
        archive = np.load(path, allow_pickle=False)
        if not isinstance(archive, np.lib.npyio.NpzFile):
            raise bad
        with archive as z:
            return {k: z[k] for k in z.files}
    except FileNotFoundError:
        raise InputFileError(f"{path}: --resume: file not found; check the path") from None
    except IsADirectoryError:
        raise InputFileError(f"{path}: --resume: is a folder; give the chain .npz") from None
    except OSError as exc:
        raise InputFileError(f"{path}: --resume: cannot read ({exc.strerror})") from None
    except (ValueError, EOFError, zipfile.BadZipFile):
        raise bad from None


def load_resume(
    path: Path,
    theta0: F64,
    *,
    seed: int,
    noise: bool,
    n_bins: int,
    t_obs_s: float,
    walkers: int,
) -> tuple[tuple[F64, F64], F64]:
    """Chain and whitening covariance of a saved run, checked against the current options.

    Returns
    -------
    tuple
        ((theta chain (S, W, D), log_prob (S, W)), whitening covariance (D, D)).

    Raises
    ------
    InputFileError
        Unreadable chain, or one of another data set (seed, noise, N, T) or target/walkers.
    """
    saved = _read_npz(path)
    want = {"seed": seed, "noise": noise, "n_bins": n_bins, "t_obs_s": t_obs_s}
    for key, val in want.items():
        got = saved[key].item() if key in saved and saved[key].size == 1 else "missing"
        if not isinstance(got, (bool, int, float)) or not np.isclose(got, val, rtol=1e-12):
            raise InputFileError(
                f"{path}: {key} = {got}, this run has {val}; resume with the same "
                "--seed/--noise/--n-bins/--t-obs (the data must be identical)"
            )
    missing = [k for k in ("theta", "log_prob", "theta0", "fisher_cov") if k not in saved]
    if missing:
        raise InputFileError(
            f"{path}: not a simulate chain (no {missing[0]!r}); give a .npz of simulate"
        )
    chain, log_prob = saved["theta"], saved["log_prob"]
    d = theta0.size
    if chain.ndim != 3 or chain.shape[0] == 0 or log_prob.shape != chain.shape[:2]:
        raise InputFileError(f"{path}: chain of shape {chain.shape} is empty or malformed")
    if chain.shape[2] != d or saved["theta0"].shape != theta0.shape:
        model = "circular" if chain.shape[2] == 6 else "eccentric"
        raise InputFileError(
            f"{path}: chain has {chain.shape[2]} parameters, this run {d}; resume the "
            f"{model} model ({'--circular' if model == 'circular' else 'without --circular'})"
        )
    saved_walkers = chain.shape[1]
    if saved_walkers != walkers or not np.allclose(saved["theta0"], theta0, rtol=0):
        raise InputFileError(
            f"{path}: chain has {saved_walkers} walkers for another target; resume "
            f"with --walkers {saved_walkers} and the same target file"
        )
    return (chain, log_prob), saved["fisher_cov"]
