"""Post-processing: start -> midpoint transform, pi-mode folding, target YAML + samples ECSV.

The paper's chain is referenced to the start t_0; planning needs the midpoint (Sec. 4.1 and its
footnote). Per sample (docs/method.md, "Phase model"):
phi_mid = phi_0 + 2 pi (f_0 T/2 + fdot (T/2)^2 / 2), f_mid = f_0 + fdot T/2,
(eta, kappa) rotated by omega_dot T/2; fdot and omega_dot are epoch-independent.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from pathlib import Path
from typing import IO

import numpy as np
from numpy.typing import NDArray

from ucbplan.core.params import PhaseParams, shift_columns, shift_jacobian
from ucbplan.lisa.likelihood import physical_from_theta
from ucbplan.targets import Target

EXTRA_NAMES = ("cos_inclination", "amplitude", "psi")
_ECC_NAMES = ("phase", "f_gw", "fdot", "eta", "kappa", "omega_dot")
_CIRC_NAMES = ("phase", "f_gw", "fdot")


def midpoint_samples(
    theta: NDArray[np.float64], t_obs_s: float, names: tuple[str, ...] | None = None
) -> dict[str, NDArray]:
    """Physical samples referenced to the midpoint, keyed like PARAM_NAMES + EXTRA_NAMES.

    Parameters
    ----------
    theta : numpy.ndarray
        Sampled-coordinate rows (S, D), start epoch.
    t_obs_s : float
        Observation length T [s].
    names : tuple of str, optional
        Sampled coordinates (the prior's names; default: log10 ḟ).
    """
    p = physical_from_theta(theta, t_obs_s, names)
    names = _ECC_NAMES if theta.shape[1] > 6 else _CIRC_NAMES
    return shift_columns({k: p[k] for k in (*names, *EXTRA_NAMES)}, 0.5 * t_obs_s)


def fold_phase_mode(cols: dict[str, NDArray], phase_ref: float) -> tuple[dict[str, NDArray], int]:
    """Fold the phi pi-mode onto the branch of ``phase_ref`` (paper Sec. 4.1).

    Samples with phi within pi/2 of phase_ref + pi are the psi -> psi + pi/2, phi -> phi + pi
    mode, reached from the injected branch by (kappa, eta) -> (-eta, kappa) (the map under
    which the n=3 and n=1(+) lines are invariant; the b1 line breaks it at O(e), see
    docs/method.md "Errata of the paper", so the fold is approximate for eta, kappa). They are
    mapped back with phi -= pi, psi -= pi/2 (mod pi) and the inverse rotation.

    Returns
    -------
    dict, int
        Folded columns and the number of folded samples.
    """
    out = dict(cols)
    d = np.mod(cols["phase"] - phase_ref + np.pi, 2.0 * np.pi) - np.pi  # in [-pi, pi)
    alt = np.abs(d) > 0.5 * np.pi
    d = np.where(d > 0.5 * np.pi, d - np.pi, np.where(d < -0.5 * np.pi, d + np.pi, d))
    out["phase"] = np.mod(phase_ref + d, 2.0 * np.pi)
    out["psi"] = np.where(alt, np.mod(cols["psi"] - 0.5 * np.pi, np.pi), cols["psi"])
    if "eta" in cols:
        # inverse of (kappa, eta) -> (-eta, kappa): kappa = eta', eta = -kappa'
        out["kappa"] = np.where(alt, cols["eta"], cols["kappa"])
        out["eta"] = np.where(alt, -cols["kappa"], cols["eta"])
    return out, int(np.count_nonzero(alt))


def samples_writer(cols: dict[str, NDArray], meta: dict) -> Callable[[IO[str]], None]:
    """Writer of posterior samples as ECSV (columns named like PARAM_NAMES, SI units)."""
    from astropy.table import Table

    tab = Table({k: np.asarray(v, dtype=float) for k, v in cols.items()})
    tab.meta.update(meta)

    def _write(handle: IO[str]) -> None:
        tab.write(handle, format="ascii.ecsv")

    return _write


def write_samples(cols: dict[str, NDArray], path: Path, overwrite: bool, meta: dict) -> None:
    """Write posterior samples as ECSV atomically (:func:`samples_writer`)."""
    from ucbplan.io import write_output

    write_output(path, samples_writer(cols, meta), overwrite=overwrite)


def _with_moments(
    base: Target, names: tuple[str, ...], mean: dict[str, float], cov: NDArray, **kw: object
) -> Target:
    p = base.params
    vals = {f.name: getattr(p, f.name) for f in dataclasses.fields(PhaseParams)}
    vals |= {k: float(v) for k, v in mean.items() if k in vals}
    if "eta" not in names:
        vals |= {"eta": 0.0, "kappa": 0.0, "omega_dot": 0.0}
    return dataclasses.replace(
        base,
        params=PhaseParams(**vals),
        cov_names=names,
        cov_matrix=np.asarray(cov, dtype=float),
        cos_inclination=float(mean["cos_inclination"]),
        amplitude=float(mean["amplitude"]),
        psi=float(mean["psi"]),
        ref_shift_s=0.0,
        **kw,  # type: ignore[arg-type]
    )


def posterior_target(
    base: Target, cols: dict[str, NDArray], samples_path: Path | None, name: str | None = None
) -> Target:
    """Target (midpoint) with posterior means and the full sample covariance.

    Parameters
    ----------
    base : Target
        The injection/search target (sky, t_ref = midpoint, spectroscopy are kept).
    cols : dict
        Midpoint samples (after folding).
    samples_path : pathlib.Path or None
        Where the samples ECSV is written (recorded in the YAML); None: not recorded.
    """
    names = (_ECC_NAMES if "eta" in cols else _CIRC_NAMES) + EXTRA_NAMES
    mat = np.stack([cols[n] for n in names])
    mean = {n: float(np.mean(cols[n])) for n in names}
    cov = np.atleast_2d(np.cov(mat))
    samples = samples_path.resolve() if samples_path is not None else None
    return _with_moments(base, names, mean, cov, samples=samples, name=name or base.name)


def sampled_to_physical_jacobian(
    theta0: NDArray[np.float64], t_obs_s: float, sampled: tuple[str, ...] | None = None
) -> tuple[tuple[str, ...], NDArray[np.float64]]:
    """Jacobian d(physical, start epoch)/d(sampled) at ``theta0``; names of the physical rows.

    ``sampled`` (the prior's names) says whether column 2 is ḟ or log10 ḟ (default: log10 ḟ).
    """
    log_fdot = sampled is None or sampled[2] == "log10_fdot"
    ecc = theta0.size > 6
    names = (_ECC_NAMES if ecc else _CIRC_NAMES) + EXTRA_NAMES
    j = np.zeros((len(names), theta0.size))
    ln10 = np.log(10.0)
    col = {"log10_amplitude": 0, "f_gw": 1, "log10_fdot": 2, "cos_inclination": 3, "psi": 4}
    col |= {"phase": 5, "eta": 6, "kappa": 7, "z_omega": 8}
    for i, n in enumerate(names):
        if n == "amplitude":
            j[i, col["log10_amplitude"]] = ln10 * 10.0 ** theta0[0]
        elif n == "fdot":
            j[i, col["log10_fdot"]] = ln10 * 10.0 ** theta0[2] if log_fdot else 1.0
        elif n == "omega_dot":
            j[i, col["z_omega"]] = 2.0 * np.pi / t_obs_s
        else:
            j[i, col[n]] = 1.0
    return names, j


def gaussian_target(
    base: Target,
    theta0: NDArray[np.float64],
    cov_theta: NDArray[np.float64],
    t_obs_s: float,
    sampled: tuple[str, ...] | None = None,
) -> Target:
    """Target (midpoint) from a Gaussian in sampled coordinates at the start (Fisher forecast).

    Means are ``theta0`` moved to the midpoint; the covariance is propagated through the
    sampled -> physical Jacobian and :func:`ucbplan.core.params.shift_jacobian` (T/2);
    ``sampled`` are the prior's names (default: log10 ḟ).
    """
    names, j = sampled_to_physical_jacobian(theta0, t_obs_s, sampled)
    cov_start = j @ cov_theta @ j.T
    cols = midpoint_samples(theta0[None, :], t_obs_s, sampled)
    mean = {k: float(v[0]) for k, v in cols.items()}
    p = physical_from_theta(theta0[None, :], t_obs_s, sampled)
    p_start = PhaseParams(
        phase=float(p["phase"][0]),
        f_gw=float(p["f_gw"][0]),
        fdot=float(p["fdot"][0]),
        eta=float(p["eta"][0]),
        kappa=float(p["kappa"][0]),
        omega_dot=float(p["omega_dot"][0]),
    )
    from ucbplan.core.params import PARAM_NAMES

    j7 = shift_jacobian(p_start, 0.5 * t_obs_s)
    shift = np.eye(len(names))
    for a, na in enumerate(names):
        for b, nb in enumerate(names):
            if na in PARAM_NAMES and nb in PARAM_NAMES:
                shift[a, b] = j7[PARAM_NAMES.index(na), PARAM_NAMES.index(nb)]
    cov_mid = shift @ cov_start @ shift.T
    return _with_moments(base, names, mean, 0.5 * (cov_mid + cov_mid.T), samples=None)
