"""Population forecast: per source the Fisher covariance, σ_u at the end, T_valid and SNR.

Each catalog row becomes a target at the LISA midpoint (its LDC start-epoch parameters moved by
T_obs/2), the library Fisher forecast (:func:`ucbplan.lisa.pipeline.fisher_forecast`, circular
6-parameter model, zero-noise data) gives its covariance, and :func:`ucbplan.core.forecast.
horizon_table` gives σ_u at the end of the observation and T_valid per anchor and α.

A source whose Fisher matrix does not constrain the phase (face-on: ψ and φ degenerate) gets
status ``unconstrained`` and NaN horizons, never a silent 300-year horizon; one below the LISA
detection threshold (SNR < ``SNR_THRESHOLD``) keeps its numbers with the status
``below-threshold``; any other per-source error is ``failed: <message>``; none stops the run.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from ucbplan.core.constants import DAY_S, G_SI, MSUN_KG, YEAR_S
from ucbplan.core.forecast import HORIZON_CAP_S, horizon_table
from ucbplan.core.params import PhaseParams, shift_reference
from ucbplan.errors import InputError, NumericalError, UcbplanError, shorten
from ucbplan.inputs import check_number
from ucbplan.lisa import MAX_N_BINS, MIN_T_OBS_S
from ucbplan.population.catalog import Source
from ucbplan.population.defaults import (
    DEFAULT_N_BINS,
    DEFAULT_SIGMA_V_KMS,
    DEFAULT_T_OBS_S,
    DEFAULT_T_START,
    SNR_THRESHOLD,
)
from ucbplan.population.execute import worker_setup
from ucbplan.population.tables import SOURCE_COLUMNS, blank_row
from ucbplan.targets.model import Spectroscopy

#: Anchors and planning margins of every forecast table (fixed: the table schema is stable).
ANCHORS: tuple[str, ...] = ("conjunction", "quadrature")
ALPHAS: tuple[float, ...] = (0.5, 1.0)


@dataclass(frozen=True, slots=True)
class ForecastOptions:
    """Options of a population forecast (all of them go into the table meta).

    Attributes
    ----------
    sigma_v_kms : float
        RV precision per epoch [km/s].
    k_eff_kms : float or None
        K for the tolerance [km/s]; None: per source from Mass1+Mass2 (K1+K2, SB2).
    t_obs_s : float
        LISA observation length [s].
    t_start_tdb : str
        Start of the LISA observation (ISO, TDB): catalog t = 0.
    n_bins : int
        Band width of the Fisher model [bins].
    n_epochs : int
        Tolerance form (2: two-epoch difference).
    """

    sigma_v_kms: float = DEFAULT_SIGMA_V_KMS
    k_eff_kms: float | None = None
    t_obs_s: float = DEFAULT_T_OBS_S
    t_start_tdb: str = DEFAULT_T_START
    n_bins: int = DEFAULT_N_BINS
    n_epochs: int = 2

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready mapping (fingerprints and meta)."""
        return asdict(self)

    def k_eff_meta(self) -> float | str:
        """``k_eff_kms`` as the tables' meta states it (the rule when it is per source)."""
        return self.k_eff_kms if self.k_eff_kms is not None else "per source: K1+K2"


def _t_cols() -> list[tuple[str, str, str, str]]:
    cols = []
    for a in ANCHORS:
        cols.append((f"sigma_u_end_{a}", "rad", "f8", f"σ_u at the end of LISA, {a} anchor"))
        cols.append((f"tol_{a}", "rad", "f8", f"δu_tol for the {a} anchor"))
        for al in ALPHAS:
            cols.append(
                (
                    f"t_valid_{a}_a{al:g}",
                    "d",
                    "f8",
                    f"T_valid after the end of LISA, {a}, α={al:g} (capped at 300 yr)",
                )
            )
    return cols


#: The forecast table, declared once: (name, unit, dtype, description).
FORECAST_COLUMNS: tuple[tuple[str, str, str, str], ...] = (
    *SOURCE_COLUMNS,
    ("status", "", "str", "ok | below-threshold (SNR < 7) | unconstrained | failed: <error>"),
    ("f_gw", "Hz", "f8", "GW frequency at the midpoint"),
    ("fdot", "Hz / s", "f8", "ḟ at the midpoint"),
    ("amplitude", "", "f8", "GW strain amplitude"),
    ("cos_inclination", "", "f8", "cos ι"),
    ("ra", "deg", "f8", "ICRS right ascension"),
    ("dec", "deg", "f8", "ICRS declination"),
    ("vmag", "mag", "f8", "catalog magnitude (NaN if none)"),
    ("distance", "kpc", "f8", "catalog distance (NaN if none)"),
    ("snr", "", "f8", "optimal LISA SNR"),
    ("k_eff", "km / s", "f8", "K of the tolerance"),
    ("sigma_phase", "rad", "f8", "Fisher σ of φ at the midpoint"),
    ("sigma_f_gw", "Hz", "f8", "Fisher σ of f at the midpoint"),
    ("sigma_fdot", "Hz / s", "f8", "Fisher σ of ḟ"),
    ("corr_phase_f_gw", "", "f8", "correlation φ–f (midpoint)"),
    ("corr_phase_fdot", "", "f8", "correlation φ–ḟ (midpoint)"),
    ("corr_f_gw_fdot", "", "f8", "correlation f–ḟ (midpoint)"),
    *_t_cols(),
)


def k_total_kms(m1_msun: float, m2_msun: float, f_gw_hz: float, cos_i: float) -> float:
    """K1 + K2 = (G M π f)^{1/3} sin ι [km/s] (circular orbit, P_orb = 2/f)."""
    v = (G_SI * (m1_msun + m2_msun) * MSUN_KG * math.pi * f_gw_hz) ** (1.0 / 3.0)
    return v * math.sqrt(max(0.0, 1.0 - cos_i * cos_i)) / 1e3


def source_target(
    src: Source, ra_deg: float, dec_deg: float, opts: ForecastOptions, t_ref: Any = None
) -> Any:
    """The catalog row as a :class:`ucbplan.targets.Target` at the midpoint (no covariance).

    ``t_ref``: the LISA midpoint (TDB :class:`~astropy.time.Time`) if the caller has it (a
    chunk shares one); default: ``opts.t_start_tdb`` + T_obs/2.
    """
    from astropy.time import Time, TimeDelta

    from ucbplan.targets import Target

    p0 = PhaseParams(phase=src.phase_rad % (2 * math.pi), f_gw=src.f_hz, fdot=src.fdot_hz_s)
    mid, _ = shift_reference(p0, np.zeros((7, 7)), 0.5 * opts.t_obs_s)
    if t_ref is None:
        t_ref = Time(opts.t_start_tdb, scale="tdb") + TimeDelta(0.5 * opts.t_obs_s, format="sec")
    return Target(
        name=f"population source {src.source_id}",
        source=None,
        ra_deg=ra_deg,
        dec_deg=dec_deg,
        t_ref=t_ref,
        t_obs_s=opts.t_obs_s,
        params=mid,
        cov_names=(),
        cov_matrix=np.zeros((0, 0)),
        cos_inclination=math.cos(src.inclination_rad),
        amplitude=src.amplitude,
        psi=src.psi_rad % math.pi,
        distance_kpc=src.distance_kpc,
        vmag=src.vmag,
        m1_msun=src.m1_msun,
        m2_msun=src.m2_msun,
    )


def icrs_of(sources: Sequence[Source]) -> tuple[np.ndarray, np.ndarray]:
    """ICRS (ra, dec) [deg] of the sources' barycentric mean ecliptic (J2000) positions."""
    import astropy.units as u
    from astropy.coordinates import BarycentricMeanEcliptic, SkyCoord

    lon = np.array([s.ecl_lon_rad for s in sources])
    lat = np.array([s.ecl_lat_rad for s in sources])
    c = SkyCoord(lon=lon * u.rad, lat=lat * u.rad, frame=BarycentricMeanEcliptic()).icrs
    return np.asarray(c.ra.deg, dtype=float), np.asarray(c.dec.deg, dtype=float)


def _nan_row(src: Source, status: str) -> dict[str, Any]:
    row = blank_row(FORECAST_COLUMNS, 0)
    row.update(source_id=src.source_id, row=src.row, status=status[:300])
    row["vmag"] = math.nan if src.vmag is None else src.vmag
    row["distance"] = math.nan if src.distance_kpc is None else src.distance_kpc
    row["amplitude"] = src.amplitude
    row["cos_inclination"] = math.cos(src.inclination_rad)
    return row


#: σ_φ at or above this leaves the GW phase unknown [rad].
SIGMA_PHASE_MAX = math.pi


def _constrained(cov: np.ndarray) -> bool:
    """Finite, positive variances, σ_φ < π and |correlations| ≤ 1 over (φ, f, ḟ)."""
    sub = cov[:3, :3]
    d = np.diag(sub)
    if not (np.all(np.isfinite(sub)) and np.all(d > 0)):
        return False
    if math.sqrt(d[0]) >= SIGMA_PHASE_MAX:
        return False
    corr = sub / np.sqrt(np.outer(d, d))
    return bool(np.all(np.abs(corr) <= 1.0 + 1e-9))


def forecast_source(
    src: Source, ra_deg: float, dec_deg: float, opts: ForecastOptions
) -> dict[str, Any]:
    """One row of the forecast table (status ok | below-threshold | unconstrained | failed)."""
    return forecast_with_target(src, ra_deg, dec_deg, opts)[0]


def forecast_with_target(
    src: Source, ra_deg: float, dec_deg: float, opts: ForecastOptions
) -> tuple[dict[str, Any], Any]:
    """The forecast row and, when its status is ``ok``, the Fisher target (midpoint, full
    covariance, ``spectroscopy`` carrying σ_v and the K of the tolerance); else None."""
    return forecast_rows([src], np.array([ra_deg]), np.array([dec_deg]), opts)[0]


def forecast_rows(
    sources: Sequence[Source], ra_deg: np.ndarray, dec_deg: np.ndarray, opts: ForecastOptions
) -> list[tuple[dict[str, Any], Any]]:
    """Forecast rows (and Fisher targets, None unless ``ok``) of a chunk of sources, in order.

    What the sources share is done once for the chunk: the sky conversion to the ecliptic
    frame of the LISA response (one astropy call), the LISA midpoint, and the horizons of
    every constrained source (one vectorised :func:`~ucbplan.core.validity_batch.
    horizon_columns` pass instead of a horizon table per source). The Fisher matrix of each
    source is its own (its band, sky and reference track differ).
    """
    from astropy.time import Time, TimeDelta

    from ucbplan.lisa.response import ecliptic_from_icrs_batch

    lon, lat = ecliptic_from_icrs_batch(np.asarray(ra_deg), np.asarray(dec_deg))
    t_ref = Time(opts.t_start_tdb, scale="tdb") + TimeDelta(0.5 * opts.t_obs_s, format="sec")
    staged = [
        _fisher_stage(s, float(r), float(d), (float(lo), float(la)), opts, t_ref)
        for s, r, d, lo, la in zip(sources, ra_deg, dec_deg, lon, lat, strict=True)
    ]
    _horizon_stage([(row, fc) for row, fc in staged if fc is not None], opts)
    out: list[tuple[dict[str, Any], Any]] = []
    for row, fc in staged:
        if fc is None or row["status"] != "ok":
            out.append((row, None))
            continue
        spec = Spectroscopy(K_eff_kms=row["k_eff"], sigma_v_kms=opts.sigma_v_kms)
        out.append((row, dataclasses.replace(fc, spectroscopy=spec)))
    return out


def _fisher_stage(
    src: Source,
    ra_deg: float,
    dec_deg: float,
    ecliptic_rad: tuple[float, float],
    opts: ForecastOptions,
    t_ref: Any,
) -> tuple[dict[str, Any], Any]:
    """The row up to its horizons and the Fisher target (None when the row is not ``ok``)."""
    row = _nan_row(src, "ok")
    row.update(ra=ra_deg, dec=dec_deg)
    try:
        from ucbplan.lisa.pipeline import build_model, fisher_forecast

        target = source_target(src, ra_deg, dec_deg, opts, t_ref)
        row["f_gw"], row["fdot"] = target.params.f_gw, target.params.fdot
        model = build_model(target, n_bins=opts.n_bins, circular=True, ecliptic_rad=ecliptic_rad)
        fc = fisher_forecast(model)
    except NumericalError as exc:
        msg = " ".join(str(exc).split())
        row["status"] = "unconstrained" if "unconstrained" in msg else f"failed: {msg}"
        return row, None
    except np.linalg.LinAlgError:
        row["status"] = "unconstrained"
        return row, None
    except (UcbplanError, ValueError) as exc:
        row["status"] = f"failed: {' '.join(str(exc).split())}"
        return row, None
    row["snr"] = fc.snr
    cov = fc.target.covariance
    if not _constrained(cov):
        row["status"] = "unconstrained"
        return row, None
    s = np.sqrt(np.diag(cov)[:3])
    row["sigma_phase"], row["sigma_f_gw"], row["sigma_fdot"] = (float(x) for x in s)
    row["corr_phase_f_gw"] = float(cov[0, 1] / (s[0] * s[1]))
    row["corr_phase_fdot"] = float(cov[0, 2] / (s[0] * s[2]))
    row["corr_f_gw_fdot"] = float(cov[1, 2] / (s[1] * s[2]))
    if opts.k_eff_kms is not None:
        k = opts.k_eff_kms
    elif src.m1_msun is not None and src.m2_msun is not None:
        k = k_total_kms(src.m1_msun, src.m2_msun, src.f_hz, math.cos(src.inclination_rad))
    else:
        row["status"] = "failed: no K: give --k-eff or Mass1 and Mass2 columns"
        return row, None
    row["k_eff"] = k
    if not k > 0:
        row["status"] = "failed: K = 0 (sin ι = 0): give --k-eff"
        return row, None
    if not fc.snr >= SNR_THRESHOLD:  # its horizons are computed, its status says it
        row["status"] = "below-threshold"
    return row, fc.target


def _horizon_stage(staged: list[tuple[dict[str, Any], Any]], opts: ForecastOptions) -> None:
    """σ_u at the end, δu_tol and T_valid of every staged row, in one vectorised pass.

    A pass that fails (a :class:`UcbplanError`) is redone source by source, so that only the
    sources that cause it get ``failed: <message>``.
    """
    from ucbplan.core.validity_batch import horizon_columns

    if not staged:
        return
    targets = [t for _, t in staged]
    try:
        cols = horizon_columns(
            np.array([t.params.as_array() for t in targets]),
            np.array([t.covariance for t in targets]),
            np.array([t.t_obs_s for t in targets]),
            opts.sigma_v_kms,
            np.array([row["k_eff"] for row, _ in staged]),
            ALPHAS,
            ANCHORS,
            n_epochs=opts.n_epochs,
        )
    except UcbplanError:
        if len(staged) == 1:
            _horizons_one(*staged[0], opts)
        else:
            for item in staged:
                _horizon_stage([item], opts)
        return
    for i, (row, _) in enumerate(staged):
        for a in ANCHORS:
            row[f"sigma_u_end_{a}"] = float(cols[f"sigma_u_end_rad:{a}"][i])
            row[f"tol_{a}"] = float(cols[f"delta_u_tol_rad:{a}"][i])
            for al in ALPHAS:
                row[f"t_valid_{a}_a{al:g}"] = float(cols[f"t_valid_days:{a}:{al:g}"][i])


def _horizons_one(row: dict[str, Any], target: Any, opts: ForecastOptions) -> None:
    """The horizons of one source with :func:`horizon_table` (its error becomes the status)."""
    try:
        rows = horizon_table(
            target, opts.sigma_v_kms, row["k_eff"], ALPHAS, ANCHORS, n_epochs=opts.n_epochs
        )
    except UcbplanError as exc:
        row["status"] = f"failed: {' '.join(str(exc).split())}"
        return
    for hr in rows:
        row[f"sigma_u_end_{hr.anchor}"] = hr.sigma_u_end_rad
        row[f"tol_{hr.anchor}"] = hr.delta_u_tol_rad
        row[f"t_valid_{hr.anchor}_a{hr.alpha:g}"] = hr.t_valid_days


def forecast_chunk(opts: ForecastOptions, sources: Sequence[Source]) -> list[dict[str, Any]]:
    """Rows of ``sources`` in order (a picklable task for any executor)."""
    worker_setup()
    ra, dec = icrs_of(sources)
    return [row for row, _ in forecast_rows(sources, ra, dec, opts)]


#: T_valid cap in days (horizons are searched up to 300 years).
HORIZON_CAP_DAYS = HORIZON_CAP_S / DAY_S


def forecast_options(
    *,
    sigma_v_kms: float,
    k_eff_kms: float | None,
    t_obs: str | None,
    t_start: str,
    n_bins: int,
) -> ForecastOptions:
    """Checked :class:`ForecastOptions` from the command-line values (``--t-obs`` as text).

    Raises
    ------
    InputError
        One line naming the parameter (the command line prints its flag): σ_v or K not
        positive, a duration that is not one, an odd or too small ``n_bins``, a start that is
        not an ISO time.
    """
    import astropy.units as u
    from astropy.time import Time

    # the ranges of the single-target commands (horizon, simulate): one rule per option
    check_number("sigma_v", sigma_v_kms, 0.0, 1e4, "km/s")
    check_number("k_eff", k_eff_kms, 0.1, 1e4, "km/s", "a binary's velocity semi-amplitude")
    if not (16 <= n_bins <= MAX_N_BINS and n_bins % 2 == 0):
        raise InputError(
            f"n_bins: expected an even number of bins in [16, {MAX_N_BINS}], got {n_bins}",
            parameter="n_bins",
        )
    try:
        t0 = Time(t_start, scale="tdb").isot
    except ValueError:
        raise InputError(
            f"t_start: expected an ISO time, got {shorten(t_start)}", parameter="t_start"
        ) from None
    t_obs_s = DEFAULT_T_OBS_S
    if t_obs is not None:
        try:
            t_obs_s = float(u.Quantity(t_obs.replace(" ", "")).to_value(u.s))
        except (TypeError, ValueError, u.UnitsError):
            raise InputError(
                f"t_obs: expected a duration like '4yr' or '1.2e8 s', got {shorten(t_obs)}",
                parameter="t_obs",
            ) from None
        if not MIN_T_OBS_S <= t_obs_s <= 100 * YEAR_S:
            raise InputError(
                f"t_obs: expected a duration from 1 day to 100 yr, got {shorten(t_obs)}",
                parameter="t_obs",
            )
    return ForecastOptions(
        sigma_v_kms=sigma_v_kms, k_eff_kms=k_eff_kms, t_obs_s=t_obs_s, t_start_tdb=t0, n_bins=n_bins
    )
