"""Files of a LISA simulation: posterior target YAML, samples ECSV, chain .npz.

:func:`write_simulation` writes a :class:`~ucbplan.lisa.simulation.SimulationResult` as one file
set (:func:`ucbplan.io.write_file_set`: all three files or none, temporaries that never block a
rerun); :func:`save_interrupted` keeps the chain of a run stopped by Ctrl-C; :func:`load_resume`
reads a chain back to continue it with the same data.
"""

from __future__ import annotations

import io
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from ucbplan.errors import InputError, InputFileError
from ucbplan.lisa import posterior as post
from ucbplan.lisa.sampler import SamplerResult, chain_writer, save_chain

if TYPE_CHECKING:
    from ucbplan.lisa.simulation import SimulationProblem, SimulationResult
    from ucbplan.targets import Target

F64 = NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class SimulationFiles:
    """Paths written by :func:`write_simulation`."""

    target: Path
    samples: Path
    chain: Path


def simulation_files(output: Path, chain: Path | None = None) -> SimulationFiles:
    """File names of a simulation: samples ECSV and chain .npz next to ``output`` by default.

    Raises
    ------
    InputError
        Two of the three outputs name the same file (``--chain`` equal to ``-o``, …).
    """
    chain_path = chain if chain is not None else output.with_suffix(".chain.npz")
    files = SimulationFiles(output, output.with_suffix(".samples.ecsv"), chain_path)
    named = {"-o": files.target, "the samples file": files.samples, "`chain`": files.chain}
    seen: dict[Path, str] = {}
    for what, path in named.items():
        key = path.resolve()
        if key in seen:
            raise InputError(
                f"{path}: {what} and {seen[key]} name the same file; give `chain` a name of its "
                "own (default: next to -o with .chain.npz)"
            )
        seen[key] = what
    return files


def _as_bytes(writer: Callable[[IO[str]], None]) -> Callable[[IO[bytes]], None]:
    """A text writer run on a binary handle (UTF-8), so one file set can mix text and .npz."""

    def _write(handle: IO[bytes]) -> None:
        text = io.TextIOWrapper(handle, encoding="utf-8", write_through=True)
        try:
            writer(text)
            text.flush()
        finally:
            text.detach()

    return _write


def _target_writer(t: Target, samples_name: str, header: str) -> Callable[[IO[str]], None]:
    """Writer of the posterior target YAML whose samples file lies beside it."""
    import yaml

    from ucbplan.targets import target_to_dict

    doc = target_to_dict(t)
    doc["lisa"]["samples"] = samples_name

    def _write(handle: IO[str]) -> None:
        for line in header.splitlines():
            handle.write(f"# {line}\n")
        yaml.safe_dump(doc, handle, sort_keys=False, allow_unicode=True, width=100)

    return _write


def _samples_name(files: SimulationFiles) -> str:
    """The samples path as the YAML records it: relative to the YAML's folder when below it."""
    try:
        return str(files.samples.resolve().relative_to(files.target.resolve().parent))
    except ValueError:
        return str(files.samples.resolve())


def _chain_extra(problem: SimulationProblem) -> dict[str, Any]:
    """What :func:`load_resume` checks a chain against (data set, target, whitening)."""
    model, opts = problem.model, problem.options
    return {
        "theta0": problem.theta0,
        "fisher_cov": problem.fisher_cov,
        "t_obs_s": model.t_obs_s,
        "noise": opts.noise,
        "n_bins": model.n_bins,
    }


def write_simulation(
    result: SimulationResult,
    files: SimulationFiles,
    *,
    overwrite: bool = False,
    source_name: str | None = None,
) -> None:
    """Write the posterior target YAML, its samples ECSV and the chain .npz as one file set.

    Either all three files are written or none is changed (:func:`ucbplan.io.write_file_set`);
    the YAML, which names the samples file, is moved into place last.

    Parameters
    ----------
    source_name : str, optional
        Target file name for the YAML header (default: that of the model's target).

    Raises
    ------
    OutputExistsError, OutputError
        An output exists without ``overwrite``, or cannot be written (nothing is left behind).
    """
    from ucbplan.io import write_file_set

    problem, chain = result.problem, result.chain
    model, opts = problem.model, problem.options
    if source_name is None:
        src = model.base.source
        source_name = src.name if src is not None else model.base.name
    header = (
        f"ucbplan simulate {source_name} seed={opts.seed} noise={opts.noise} N={model.n_bins}: "
        f"{result.samples.shape[0]} samples, {result.n_steps} steps (tau_max "
        f"{result.tau_max:.0f}, converged={chain.converged}), SNR {problem.snr:.1f}"
    )
    posterior = result.posterior(files.samples)
    write_file_set(
        {
            files.chain: chain_writer(chain, _chain_extra(problem)),
            files.samples: _as_bytes(post.samples_writer(result.columns, result.samples_meta())),
            files.target: _as_bytes(_target_writer(posterior, _samples_name(files), header)),
        },
        overwrite=overwrite,
        binary=True,
    )


def save_interrupted(
    problem: SimulationProblem, partial: SamplerResult, path: Path, *, overwrite: bool = False
) -> None:
    """Save the chain of an interrupted run to ``path`` for ``--resume`` (atomically).

    Raises
    ------
    OutputExistsError, OutputError
        As :func:`ucbplan.lisa.sampler.save_chain`.
    """
    save_chain(partial, path, _chain_extra(problem), overwrite=overwrite)


def _read_npz(path: Path) -> dict[str, F64]:
    """Arrays of a .npz file (no pickles), or a one-line InputFileError."""
    import zipfile

    bad = InputFileError(f"{path}: `resume`: not a .npz chain; give the .npz of a simulate run")
    try:
        archive = np.load(path, allow_pickle=False)
        if not isinstance(archive, np.lib.npyio.NpzFile):
            raise bad
        with archive as z:
            return {k: z[k] for k in z.files}
    except FileNotFoundError:
        raise InputFileError(f"{path}: `resume`: file not found; check the path") from None
    except IsADirectoryError:
        raise InputFileError(f"{path}: `resume`: is a folder; give the chain .npz") from None
    except OSError as exc:
        raise InputFileError(f"{path}: `resume`: cannot read ({exc.strerror})") from None
    except (ValueError, EOFError, zipfile.BadZipFile):
        raise bad from None


def _check_same_data(path: Path, saved: dict[str, F64], want: dict[str, Any]) -> None:
    """The saved chain's data set (seed, noise, N, T) is this run's.

    Raises
    ------
    InputFileError
        A value differs or is missing.
    """
    for key, val in want.items():
        got = saved[key].item() if key in saved and saved[key].size == 1 else "missing"
        if not isinstance(got, (bool, int, float)) or not np.isclose(got, val, rtol=1e-12):
            raise InputFileError(
                f"{path}: {key} = {got}, this run has {val}; resume with the same "
                "`seed`/`noise`/`n_bins`/`t_obs` (the data must be identical)"
            )


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
    _check_same_data(
        path, saved, {"seed": seed, "noise": noise, "n_bins": n_bins, "t_obs_s": t_obs_s}
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
            f"{model} model ({'`circular`' if model == 'circular' else 'without `circular`'})"
        )
    saved_walkers = chain.shape[1]
    if saved_walkers != walkers or not np.allclose(saved["theta0"], theta0, rtol=0):
        raise InputFileError(
            f"{path}: chain has {saved_walkers} walkers for another target; resume "
            f"with `walkers` {saved_walkers} and the same target file"
        )
    return (chain, log_prob), saved["fisher_cov"]
