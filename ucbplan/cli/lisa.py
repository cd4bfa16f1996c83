"""``ucbplan simulate | fisher | waveform``: the reduced LISA simulation (paper Sec. 4.1).

A thin shell: parse options, build the model from the target file, call :mod:`ucbplan.lisa`,
write target YAML / ECSV / plots. Human-readable summaries go to stderr.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np
import typer
from astropy.time import TimeDelta

from ucbplan.cli._console import check_output_path, configure_offline, err_console, write_output
from ucbplan.errors import UcbplanError

__all__ = ["register"]

_CONVENTION = (
    "one-sided Fourier transform x~(f) = int_0^T x(t) exp(-2 pi i f t) dt, t = 0 at the start of "
    "the LISA observation (FastGB/GBGPU convention); TDI A = (Z - X)/sqrt2, E = (X - 2Y + Z)/sqrt6"
    " of first-generation Michelson X, Y, Z in fractional frequency"
)


def _t_obs(text: str | None, default_s: float) -> float:
    if text is None:
        return default_s
    import astropy.units as u

    try:
        val = float(u.Quantity(text.replace(" ", "")).to_value(u.s))
    except (TypeError, ValueError, u.UnitsError) as exc:
        raise UcbplanError(
            f"--t-obs: expected a duration like '4yr' (Julian) or '126232599.054s', got {text!r}"
        ) from exc
    if not val > 0:
        raise UcbplanError(f"--t-obs: must be positive, got {text!r}")
    return val


def _setup(target_path: Path, t_obs: str | None, n_bins: int, circular: bool) -> Any:
    from ucbplan.lisa.likelihood import model_for_target, source_from_target
    from ucbplan.target import load_target

    configure_offline()
    if n_bins < 16 or n_bins % 2:
        raise UcbplanError(f"--n-bins: expected an even number >= 16, got {n_bins}")
    target = load_target(target_path)
    truth = source_from_target(target)
    t_obs_s = _t_obs(t_obs, target.t_obs_s)
    eccentric = (not circular) and (truth.eta != 0.0 or truth.kappa != 0.0)
    if not eccentric:
        truth = dataclasses.replace(truth, eta=0.0, kappa=0.0, omega_dot=0.0)
    if eccentric and not 0.0 <= truth.omega_dot * t_obs_s / (2 * np.pi) <= 50.0:
        raise UcbplanError(
            f"{target_path}: omega_dot gives z_omega outside the prior [0, 50] bins for "
            f"T = {t_obs_s:.6g} s; use a shorter --t-obs or --circular"
        )
    base = dataclasses.replace(
        target,
        t_ref=target.t_start + TimeDelta(0.5 * t_obs_s, format="sec"),
        t_obs_s=t_obs_s,
    )
    model = model_for_target(target, t_obs_s, n_bins, eccentric, truth.f_gw)
    return base, truth, model, eccentric


_LABELS = {
    "log10_amplitude": r"$\log_{10}\mathcal{A}$",
    "f_gw": r"$f_0$ [Hz]",
    "log10_fdot": r"$\log_{10}\dot f$",
    "cos_inclination": r"$\cos\iota$",
    "psi": r"$\psi$",
    "phase": r"$\phi_0$",
    "eta": r"$\eta_0$",
    "kappa": r"$\kappa_0$",
    "z_omega": r"$z_\omega$",
}
_UNITS = {"phase": "rad", "f_gw": "Hz", "fdot": "Hz/s", "omega_dot": "rad/s", "psi": "rad"}


def _summary(
    title: str,
    names: tuple[str, ...],
    inj: dict,
    sig: dict,
    mean: dict | None = None,
    fis: dict | None = None,
) -> None:
    """Rich table on stderr: value (and posterior mean, Fisher σ when given) per parameter."""
    from rich.table import Table

    cols = ["parameter (midpoint)", "unit", "injected" if mean is not None else "value"]
    cols += ["estimate"] if mean is not None else []
    cols += ["σ"] + (["Fisher σ", "σ/Fisher"] if fis is not None else [])
    tab = Table(title=title, title_justify="left")
    for col in cols:
        tab.add_column(col, justify="left" if col == cols[0] else "right")
    for n in names:
        row = [n, _UNITS.get(n, "1"), f"{inj[n]:.10g}"]
        row += [f"{mean[n]:.10g}"] if mean is not None else []
        row += [f"{sig[n]:.4g}"]
        if fis is not None:
            row += [f"{fis[n]:.4g}", f"{sig[n] / fis[n]:.3f}"]
        tab.add_row(*row)
    err_console.print(tab)


def simulate(
    target: Path = typer.Argument(..., help="Target or injection YAML (needs amplitude, psi)."),
    output: Path = typer.Option(..., "-o", "--output", help="Posterior target YAML to write."),
    t_obs: str | None = typer.Option(None, "--t-obs", help="Observation length, e.g. '4yr'."),
    seed: int = typer.Option(0, "--seed", help="Seed for the noise and the sampler."),
    walkers: int = typer.Option(32, "--walkers", help="emcee walkers (>= 2 x parameters)."),
    steps: int = typer.Option(2000, "--steps", help="Steps (minimum with --until-converged)."),
    until_converged: bool = typer.Option(
        False, "--until-converged", help="Extend the chain until it is >= 50 τ long."
    ),
    max_steps: int = typer.Option(50000, "--max-steps", help="Cap for --until-converged."),
    noise: bool = typer.Option(True, "--noise/--no-noise", help="Add a Gaussian noise draw."),
    n_bins: int = typer.Option(
        512, "--n-bins", help="Band width N in bins (injection = templates)."
    ),
    circular: bool = typer.Option(False, "--circular", help="Fit the 6-parameter circular model."),
    chain: Path | None = typer.Option(None, "--chain", help="Chain .npz (default: next to -o)."),
    plots: Path | None = typer.Option(None, "--plots", help="Folder for corner plots."),
    resume: Path | None = typer.Option(
        None, "--resume", help="Continue a saved chain (.npz) of a run with the same options."
    ),
    overwrite: bool = typer.Option(False, "--overwrite", help="Replace existing output files."),
) -> None:
    """Simulate a LISA observation and sample the targeted-search posterior → target YAML."""
    from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

    from ucbplan.lisa import posterior as post
    from ucbplan.lisa.fisher import fisher_matrix
    from ucbplan.lisa.likelihood import Likelihood, Prior, simulate_data, theta_from_source
    from ucbplan.lisa.noise import SANGRIA
    from ucbplan.lisa.sampler import CONVERGENCE_FACTOR, run_sampler, save_chain
    from ucbplan.target import write_target

    base, truth, model, ecc = _setup(target, t_obs, n_bins, circular)
    samples_path = output.with_suffix(".samples.ecsv")
    chain_path = chain if chain is not None else output.with_suffix(".chain.npz")
    for p in (output, samples_path, chain_path):
        check_output_path(p, overwrite)
    if plots is not None and not plots.is_dir():
        raise UcbplanError(f"--plots: folder {plots} does not exist; create it first")
    t_obs_s = model.grid.t_obs_s
    theta0 = theta_from_source(truth, t_obs_s, ecc)
    if walkers < 2 * theta0.size:
        raise UcbplanError(f"--walkers: need >= {2 * theta0.size} for {theta0.size} parameters")
    rng = np.random.default_rng(seed)
    data = simulate_data(model, truth, SANGRIA, rng if noise else None)
    like = Likelihood(model, data, Prior.paper(truth, t_obs_s, ecc), SANGRIA)
    snr = float(like.snr(theta0[None])[0])
    cov = np.asarray(np.linalg.inv(fisher_matrix(like, theta0)), dtype=np.float64)
    previous = None
    if resume is not None:
        previous, cov = _load_resume(resume, theta0, seed, noise, n_bins, t_obs_s, walkers)
    err_console.print(
        f"{base.name}: optimal SNR {snr:.1f}, T_obs = {t_obs_s:.6f} s, N = {n_bins} bins, "
        f"{theta0.size} parameters, noise {'on' if noise else 'off'}, seed {seed}"
    )
    with Progress(
        TextColumn("emcee"),
        BarColumn(),
        TextColumn("{task.completed}/{task.total} steps τ_max≈{task.fields[tau]}"),
        TimeRemainingColumn(),
        console=err_console,
        transient=True,
    ) as prog:
        task = prog.add_task("emcee", total=steps, tau="?")

        def _progress(done: int, total: int, tau: float) -> None:
            prog.update(task, completed=done, total=total, tau=f"{tau:.0f}")

        res = run_sampler(
            like,
            theta0,
            cov,
            n_walkers=walkers,
            n_steps=steps,
            until_converged=until_converged,
            max_steps=max_steps,
            seed=seed,
            progress=_progress,
            previous=previous,
        )
    n_done, tau_max = res.theta.shape[0], float(np.max(res.tau))
    if not res.converged:
        err_console.print(
            f"[yellow]warning: chain of {n_done} steps is shorter than {CONVERGENCE_FACTOR:g} τ "
            f"(τ_max = {tau_max:.0f} steps): the posterior σ's are not reliable; rerun with "
            f"--steps {int(CONVERGENCE_FACTOR * tau_max) + 1} or --until-converged[/yellow]"
        )
    flat = res.flat_samples()
    cols = post.midpoint_samples(flat, t_obs_s)
    inj = {k: float(v[0]) for k, v in post.midpoint_samples(theta0[None], t_obs_s).items()}
    cols, n_fold = post.fold_phase_mode(cols, inj["phase"])
    meta = {
        "reference": "midpoint of the LISA observation (t_ref of the target YAML, TDB)",
        "t_ref_tdb": base.t_ref.tdb.isot,
        "seed": seed,
        "n_steps": n_done,
        "tau_max_steps": tau_max,
        "converged": res.converged,
        "folded_pi_mode_samples": n_fold,
        "snr": snr,
    }
    out_target = post.posterior_target(base, cols, samples_path, name=f"{base.name} (posterior)")
    post.write_samples(cols, samples_path, overwrite, meta)
    write_target(
        out_target,
        output,
        overwrite=overwrite,
        header=(
            f"ucbplan simulate {target.name} seed={seed} noise={noise} N={n_bins}: "
            f"{flat.shape[0]} samples, {n_done} steps (tau_max {tau_max:.0f}, "
            f"converged={res.converged}), SNR {snr:.1f}"
        ),
    )
    save_chain(
        res,
        chain_path,
        {"theta0": theta0, "fisher_cov": cov, "t_obs_s": t_obs_s, "noise": noise, "n_bins": n_bins},
    )
    fis = post.gaussian_target(base, theta0, cov, t_obs_s)
    names = out_target.cov_names
    sig = {n: float(np.std(cols[n])) for n in names}
    fsig = {n: float(np.sqrt(fis.cov_matrix[i, i])) for i, n in enumerate(fis.cov_names)}
    mean = {n: float(np.mean(cols[n])) for n in names}
    _summary(f"{out_target.name}: posterior vs injection", names, inj, sig, mean, fsig)
    if plots is not None:
        _corner_plots(plots, flat, theta0, cols, inj, res.names, t_obs_s, overwrite)
    err_console.print(f"wrote {output}, {samples_path.name}, {chain_path.name}")


def _load_resume(
    path: Path,
    theta0: np.ndarray,
    seed: int,
    noise: bool,
    n_bins: int,
    t_obs_s: float,
    walkers: int,
) -> tuple[tuple[np.ndarray, np.ndarray], np.ndarray]:
    """Chain and whitening covariance of a saved run, checked against the current options."""
    from ucbplan.errors import InputFileError

    try:
        with np.load(path) as z:
            saved = {k: z[k] for k in z.files}
    except (OSError, ValueError) as exc:
        raise InputFileError(
            f"{path}: cannot read the chain ({exc}); give a simulate .npz"
        ) from None
    want = {"seed": seed, "noise": noise, "n_bins": n_bins, "t_obs_s": t_obs_s}
    for key, val in want.items():
        if key not in saved or not np.isclose(float(saved[key]), float(val), rtol=1e-12):
            got = saved[key].item() if key in saved else "missing"
            raise InputFileError(
                f"{path}: {key} = {got}, this run has {val}; resume with the same "
                "--seed/--noise/--n-bins/--t-obs (the data must be identical)"
            )
    if saved["theta"].shape[1] != walkers or not np.allclose(saved["theta0"], theta0, rtol=0):
        raise InputFileError(
            f"{path}: chain has {saved['theta'].shape[1]} walkers for another target; resume "
            f"with --walkers {saved['theta'].shape[1]} and the same target file"
        )
    return (saved["theta"], saved["log_prob"]), saved["fisher_cov"]


def _corner_plots(
    folder: Path,
    flat: np.ndarray,
    theta0: np.ndarray,
    cols: dict,
    inj: dict,
    names: tuple[str, ...],
    t_obs_s: float,
    overwrite: bool,
) -> None:
    from ucbplan.lisa.plots import corner_plot

    paths = [folder / f for f in ("corner_start.png", "corner_midpoint.png", "corner_e_omega.png")]
    for p in paths:
        check_output_path(p, overwrite)
    corner_plot(flat, [_LABELS[n] for n in names], list(theta0), paths[0], "start epoch t_0")
    mid = ["fdot", "f_gw", "phase"] + (["eta", "kappa", "omega_dot"] if "eta" in cols else [])
    # as the paper's midpoint figure: the frequency offset in Fourier bins, Delta f_mid T_obs
    data = np.stack([(cols[n] - inj[n]) * t_obs_s if n == "f_gw" else cols[n] for n in mid], axis=1)
    labels = [
        r"$\dot f$ [Hz/s]",
        r"$\Delta f_{\rm mid} T_{\rm obs}$ [bins]",
        r"$\phi_{\rm mid}$ [rad]",
    ]
    labels += [r"$\eta_{\rm mid}$", r"$\kappa_{\rm mid}$", r"$\dot\omega$ [rad/s]"][: len(mid) - 3]
    truths = [inj[n] if n != "f_gw" else 0.0 for n in mid]
    corner_plot(data, labels, truths, paths[1], "midpoint t_mid")
    if "eta" in names:
        i_e, i_k, i_z = names.index("eta"), names.index("kappa"), names.index("z_omega")
        e = np.hypot(flat[:, i_e], flat[:, i_k])
        w0 = np.arctan2(flat[:, i_e], flat[:, i_k])
        tr = [
            float(np.hypot(theta0[i_e], theta0[i_k])),
            float(np.arctan2(theta0[i_e], theta0[i_k])),
        ]
        corner_plot(
            np.stack([e, w0, flat[:, i_z]], axis=1),
            [r"$e$", r"$\omega_0$ [rad]", r"$z_\omega$ [bins]"],
            [*tr, float(theta0[i_z])],
            paths[2],
            "eccentricity and apsidal advance",
        )


def fisher(
    target: Path = typer.Argument(..., help="Target or injection YAML (needs amplitude, psi)."),
    output: Path | None = typer.Option(None, "-o", "--output", help="Forecast target YAML."),
    t_obs: str | None = typer.Option(None, "--t-obs", help="Observation length, e.g. '4yr'."),
    n_bins: int = typer.Option(512, "--n-bins", help="Band width N in bins."),
    circular: bool = typer.Option(False, "--circular", help="6-parameter circular model."),
    overwrite: bool = typer.Option(False, "--overwrite", help="Replace an existing output."),
) -> None:
    """Fisher-matrix forecast of the targeted-search parameters → target YAML (midpoint)."""
    from ucbplan.lisa import posterior as post
    from ucbplan.lisa.fisher import fisher_matrix
    from ucbplan.lisa.likelihood import Likelihood, Prior, simulate_data, theta_from_source
    from ucbplan.lisa.noise import SANGRIA
    from ucbplan.target import write_target

    base, truth, model, ecc = _setup(target, t_obs, n_bins, circular)
    if output is not None:
        check_output_path(output, overwrite)
    t_obs_s = model.grid.t_obs_s
    theta0 = theta_from_source(truth, t_obs_s, ecc)
    like = Likelihood(
        model, simulate_data(model, truth, SANGRIA, None), Prior.paper(truth, t_obs_s, ecc), SANGRIA
    )
    snr = float(like.snr(theta0[None])[0])
    cov = np.asarray(np.linalg.inv(fisher_matrix(like, theta0)), dtype=np.float64)
    fis = post.gaussian_target(base, theta0, cov, t_obs_s)
    fis = dataclasses.replace(fis, name=f"{base.name} (Fisher forecast)")
    sig = {n: float(np.sqrt(fis.cov_matrix[i, i])) for i, n in enumerate(fis.cov_names)}
    mean = {n: float(getattr(fis.params, n, getattr(fis, n, np.nan))) for n in fis.cov_names}
    _summary(f"{fis.name}: SNR {snr:.1f}", fis.cov_names, mean, sig)
    if output is not None:
        write_target(
            fis, output, overwrite=overwrite, header=f"ucbplan fisher: SNR {snr:.1f}, N={n_bins}"
        )
        err_console.print(f"wrote {output}")


def waveform(
    target: Path = typer.Argument(..., help="Target or injection YAML (needs amplitude, psi)."),
    output: Path = typer.Option(..., "-o", "--output", help="Lines table (ECSV)."),
    plot: Path | None = typer.Option(None, "--plot", help="ASD figure of the three bands."),
    t_obs: str | None = typer.Option(None, "--t-obs", help="Observation length, e.g. '4yr'."),
    n_bins: int = typer.Option(512, "--n-bins", help="Band width N in bins."),
    overwrite: bool = typer.Option(False, "--overwrite", help="Replace existing outputs."),
) -> None:
    """Injected TDI A, E per band (ECSV: band, freq_hz, A_re, A_im, E_re, E_im, psd_a)."""
    from astropy.table import Table

    from ucbplan.lisa.noise import SANGRIA, NoiseModel, psd_a
    from ucbplan.lisa.waveform import LINES, line_frequencies

    base, truth, model, _ = _setup(target, t_obs, n_bins, False)
    check_output_path(output, overwrite)
    if plot is not None:
        check_output_path(plot, overwrite)
    t_obs_s = model.grid.t_obs_s
    bands = model.bands_for(truth)
    psd = psd_a(model.freqs_hz, t_obs_s, SANGRIA)
    snr = float(np.sqrt(np.sum(4.0 * np.abs(bands) ** 2 / (psd[:, None, :] * t_obs_s))))
    nb, n = model.freqs_hz.shape
    tab = Table(
        {
            "band": np.repeat(np.array(model.harmonics), n),
            "freq_hz": model.freqs_hz.ravel(),
            "A_re": bands[:, 0].real.ravel(),
            "A_im": bands[:, 0].imag.ravel(),
            "E_re": bands[:, 1].real.ravel(),
            "E_im": bands[:, 1].imag.ravel(),
            "psd_a": psd.ravel(),
        }
    )
    for c, unit in (("freq_hz", "Hz"), ("psd_a", "1/Hz")):
        tab[c].unit = unit
    for c in ("A_re", "A_im", "E_re", "E_im"):
        tab[c].unit = "1/Hz"
    f_lines = line_frequencies(truth.f_gw, truth.omega_dot)
    lines = {
        line.name: float(f_lines[i])
        for i, line in enumerate(LINES)
        if line.harmonic in model.harmonics
    }
    tab.meta.update(
        {
            "target": base.name,
            "convention": _CONVENTION,
            "t_start_tdb": base.t_start.tdb.isot,
            "t_obs_s": t_obs_s,
            "n_bins": n_bins,
            "band_harmonics": list(model.harmonics),
            "line_freqs_hz": lines,
            "optimal_snr": snr,
            "noise": "LDC Sangria instrument + Galactic foreground (one-sided, TDI A = E)",
        }
    )
    write_output(output, lambda h: tab.write(h, format="ascii.ecsv"), overwrite=overwrite)
    if plot is not None:
        from ucbplan.lisa.plots import asd_plot

        inst = psd_a(model.freqs_hz, t_obs_s, NoiseModel(foreground=False))
        unshifted = {k: v for k, v in zip(lines, line_frequencies(truth.f_gw, 0.0), strict=False)}
        asd_plot(model.freqs_hz, bands, psd, model.harmonics, lines, unshifted, t_obs_s, plot, inst)
    err_console.print(
        f"{base.name}: {nb} bands x {n} bins, optimal SNR {snr:.1f}; wrote {output}"
        + (f" and {plot}" if plot is not None else "")
    )


def register(app: typer.Typer) -> None:
    """Add ``simulate``, ``fisher`` and ``waveform`` to the ucbplan app."""
    app.command("simulate")(simulate)
    app.command("fisher")(fisher)
    app.command("waveform")(waveform)
