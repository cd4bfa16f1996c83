"""Population ranking: order sources by a stated figure of merit, write targets for the top N.

Two figures of merit, the one used named in the table meta:

- ``goal_hours`` (when an RV-precision reference is known and the catalog has magnitudes):
  telescope hours to reach a precision goal (``--goal``, e.g. ``K1=5%`` or ``M1=2%``) with
  quadrature spectra, from the goal model of :mod:`ucbplan.observing.precision.goals`: σ_v per
  exposure from the catalog magnitude (:func:`ucbplan.observing.precision.instruments.sigma_v_kms`,
  airmass 1), K1 and K2 from Mass1, Mass2, f and ι (else K_eff, single-lined), the smearing Λ_K of
  one exposure, and the wall time of :func:`~ucbplan.observing.precision.goals.time_budget`
  (exposures, readout, one acquisition per visit, waits for phase). Fewer hours rank first.
- ``t_valid`` (otherwise): T_valid after the end of LISA, quadrature anchor, α = 1 (from the
  forecast). Longer ranks first.

Sources without a merit (not ``ok``, no magnitude, a goal the model refuses) rank last, in
catalog order; ties keep catalog order. The top N are forecast again (the Fisher target with
its full covariance) and written as target files ready for ``ucbplan plan``; the ranked table
lists their absolute paths.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from astropy.table import Column

from ucbplan.errors import InputError, InputFileError, UcbplanError, shorten
from ucbplan.inputs import check_range
from ucbplan.observing.blocks.block import MAX_BLOCK_S, ExposurePlan, block_smearing
from ucbplan.observing.precision.goals import Goal, parse_goal, spectra_for_goal
from ucbplan.observing.precision.instruments import Instrument, sigma_v_kms
from ucbplan.observing.schedule.records import slug
from ucbplan.population.catalog import Catalog, Source
from ucbplan.population.catalog_forecast import (
    ForecastOptions,
    forecast_with_target,
    icrs_of,
    k_total_kms,
)
from ucbplan.population.tables import SOURCE_COLUMNS, columns_table, provenance

#: Forecast column of the T_valid figure of merit.
T_VALID_COLUMN = "t_valid_quadrature_a1"

#: The ranked table, declared once: (name, unit, dtype, description).
RANK_COLUMNS: tuple[tuple[str, str, str, str], ...] = (
    ("rank", "", "i8", "1 = best"),
    *SOURCE_COLUMNS,
    ("status", "", "str", "forecast status"),
    ("merit", "", "f8", "figure of merit (meta: figure_of_merit; NaN: none, ranked last)"),
    ("t_valid_quadrature", "d", "f8", "T_valid after LISA, quadrature, α=1"),
    ("vmag", "mag", "f8", "catalog magnitude"),
    ("sigma_v_exposure", "km / s", "f8", "σ_v of one exposure (goal_hours merit)"),
    ("n_spectra", "", "i8", "spectra to reach the goal (-1: not computed)"),
    ("hours_to_goal", "h", "f8", "wall time to reach the goal"),
    ("target_file", "", "str", "absolute path of the written target file (top N)"),
)


@dataclass(frozen=True)
class RankOptions:
    """How to rank (all of it goes into the table meta).

    Attributes
    ----------
    top : int
        Target files written for the best ``top`` sources.
    goal : str
        Precision goal of the ``goal_hours`` merit
        (:func:`ucbplan.observing.precision.goals.parse_goal`).
    instrument : Instrument or None
        RV-precision reference (σ_ref) and overheads; None: the ``t_valid`` merit.
    exptime_s, readout_s, acquisition_s, visit_s : float
        One exposure, readout after it, acquisition per visit, visit length [s].
    """

    top: int = 10
    goal: str = "K1=5%"
    instrument: Instrument | None = None
    exptime_s: float = 60.0
    readout_s: float = 0.0
    acquisition_s: float = 0.0
    visit_s: float = 3600.0

    def __post_init__(self) -> None:
        if not isinstance(self.top, int) or self.top < 0:
            raise InputError(f"top: expected an integer >= 0, got {shorten(self.top)}")
        parse_goal(self.goal)
        ExposurePlan(exptime_s=self.exptime_s, readout_s=self.readout_s)
        check_range("overhead", self.acquisition_s, 0.0, MAX_BLOCK_S, "s", "per visit")
        night = "a visit fits in one night"
        check_range("visit", self.visit_s, 0.0, MAX_BLOCK_S, "s", night, low_open=True)
        need = self.acquisition_s + self.exptime_s + self.readout_s
        if self.visit_s < need:
            raise InputError(
                f"visit: expected at least acquisition + one exposure + readout = {need:g} s, "
                f"got {self.visit_s:g} s; lengthen `visit` or shorten the exposure"
            )
        if self.instrument is not None and self.instrument.sigma_ref is None:
            raise InputError(
                f"instrument {self.instrument.name}: no RV-precision reference (sigma_ref) in "
                "the instrument table; add `sigma_ref` SIGMA_KMS,MAG,EXPTIME_S"
            )

    @property
    def merit(self) -> str:
        """``goal_hours`` with an RV-precision reference, else ``t_valid``."""
        return "goal_hours" if self.instrument is not None else "t_valid"


def forecast_options_of(meta: dict[str, Any], where: Path) -> ForecastOptions:
    """The forecast options recorded in a forecast table's meta.

    Raises
    ------
    InputFileError
        Not a ``ucbplan population forecast`` table.
    """
    if meta.get("command") != "ucbplan population forecast":
        raise InputFileError(
            f"{where}: expected a table written by 'ucbplan population forecast' (or a catalog), "
            f"got meta command {shorten(meta.get('command'))}"
        )
    k = meta.get("k_eff_kms")
    return ForecastOptions(
        sigma_v_kms=float(meta["sigma_v_kms"]),
        k_eff_kms=float(k) if isinstance(k, int | float) else None,
        t_obs_s=float(meta["t_obs_s"]),
        t_start_tdb=str(meta["t_start_tdb"]),
        n_bins=int(meta["n_bins"]),
        n_epochs=int(meta["n_epochs"]),
    )


def _k1_k2(src: Source, k_eff: float) -> tuple[float, float | None]:
    """(K1, K2) [km/s] from the masses (SB2), else (K_eff, None) single-lined."""
    if src.m1_msun is None or src.m2_msun is None:
        return k_eff, None
    k = k_total_kms(src.m1_msun, src.m2_msun, src.f_hz, math.cos(src.inclination_rad))
    m = src.m1_msun + src.m2_msun
    return k * src.m2_msun / m, k * src.m1_msun / m


def goal_hours(src: Source, f_gw: float, k_eff: float, goal: Goal, opts: RankOptions) -> dict:
    """σ_v per exposure, spectra and hours to reach ``goal`` for one source (NaN if refused)."""
    out: dict[str, Any] = {"sigma_v_exposure": math.nan, "n_spectra": -1, "hours_to_goal": math.nan}
    if opts.instrument is None or src.vmag is None or not k_eff > 0:
        return out
    try:
        sv = float(sigma_v_kms(opts.instrument, src.vmag, opts.exptime_s))
        k1, k2 = _k1_k2(src, k_eff)
        plan = ExposurePlan(exptime_s=opts.exptime_s)
        lam = block_smearing(plan, math.pi * f_gw, k1).lambda_k
        sin_i = math.sin(src.inclination_rad)
        gp = spectra_for_goal(
            goal,
            K1=k1,
            K2=k2,
            sigma_v_kms=sv,
            lambda_k=lam,
            period_s=2.0 / f_gw,
            sin_i=sin_i if sin_i > 0 else None,
            exptime_s=opts.exptime_s,
            readout_s=opts.readout_s,
            acquisition_s=opts.acquisition_s,
            visit_s=opts.visit_s,
        )
    except InputError:
        return out
    out.update(sigma_v_exposure=sv, n_spectra=gp.n_spectra)
    out["hours_to_goal"] = gp.time.total_h if gp.time is not None else math.nan
    return out


def rank_table(forecast: Any, catalog: Catalog, opts: RankOptions) -> Any:
    """The ranked table (best first) of a forecast table; ``target_file`` still empty."""
    by_id = {s.source_id: s for s in catalog.sources}
    goal = parse_goal(opts.goal)
    rows = []
    for r in forecast:
        sid = str(r["source_id"])
        if sid not in by_id:
            raise InputFileError(f"{catalog.path}: no source {shorten(sid)} of the forecast table")
        row: dict[str, Any] = {"source_id": sid, "row": int(r["row"]), "status": str(r["status"])}
        row.update(t_valid_quadrature=float(r[T_VALID_COLUMN]), vmag=float(r["vmag"]))
        row.update(goal_hours(by_id[sid], float(r["f_gw"]), float(r["k_eff"]), goal, opts))
        ok = row["status"] == "ok"
        merit = row["hours_to_goal"] if opts.merit == "goal_hours" else row["t_valid_quadrature"]
        row["merit"] = float(merit) if ok and math.isfinite(merit) else math.nan
        rows.append(row)
    merit = np.array([r["merit"] for r in rows])
    key = np.where(np.isnan(merit), np.inf, merit if opts.merit == "goal_hours" else -merit)
    order = np.lexsort((np.arange(len(rows)), key))
    ranked = []
    for k, i in enumerate(order):
        ranked.append({**rows[i], "rank": k + 1, "target_file": ""})
    tab = columns_table(ranked, RANK_COLUMNS)
    tab.meta.update(provenance("ucbplan population rank", catalog))
    tab.meta.update(_merit_meta(opts, goal, forecast.meta))
    return tab


def _merit_meta(opts: RankOptions, goal: Goal, fmeta: dict[str, Any]) -> dict[str, Any]:
    if opts.merit == "goal_hours":
        assert opts.instrument is not None
        text = (
            f"hours to reach {goal.describe()} with quadrature spectra (fewer first): σ_v per "
            f"exposure from the catalog Magnitude and {opts.instrument.name}'s σ_ref at airmass "
            "1, K1/K2 from Mass1, Mass2 (else K_eff, SB1), smearing of one exposure, time budget "
            "with readout, one acquisition per visit and waits for phase"
        )
    else:
        text = (
            "T_valid after the end of LISA, quadrature anchor, alpha = 1 (longer first); no "
            "RV-precision reference given (--instrument/--sigma-ref) for an hours-based merit"
        )
    return {
        "figure_of_merit": opts.merit,
        "figure_of_merit_text": text,
        "goal": opts.goal if opts.merit == "goal_hours" else None,
        "exptime_s": opts.exptime_s,
        "readout_s": opts.readout_s,
        "acquisition_s": opts.acquisition_s,
        "visit_s": opts.visit_s,
        "forecast_sigma_v_kms": fmeta.get("sigma_v_kms"),
        "forecast_t_obs_s": fmeta.get("t_obs_s"),
        "top": opts.top,
    }


def write_top_targets(
    ranked: Any, catalog: Catalog, fopts: ForecastOptions, out_dir: Path, top: int, overwrite: bool
) -> list[Path]:
    """Forecast the best ``top`` ranked sources again and write their target files.

    Files are ``out_dir/NNN-<source id>.yaml`` (NNN = rank); the ranked table's ``target_file``
    gets their absolute paths. Sources without a merit are not written.

    Raises
    ------
    OutputExistsError
        A file exists and ``overwrite`` is false (checked for all before any is written).
    """
    from ucbplan.io import check_output_path
    from ucbplan.targets.write import write_target

    by_id = {s.source_id: s for s in catalog.sources}
    picks = [i for i in range(len(ranked)) if np.isfinite(ranked["merit"][i])][:top]
    paths = {}
    for i in picks:
        name = f"{int(ranked['rank'][i]):03d}-{slug(str(ranked['source_id'][i]))}.yaml"
        paths[i] = (out_dir / name).resolve()
        check_output_path(paths[i], overwrite)
    for i, path in paths.items():
        src = by_id[str(ranked["source_id"][i])]
        ra, dec = icrs_of([src])
        _, target = forecast_with_target(src, float(ra[0]), float(dec[0]), fopts)
        if target is None:
            raise UcbplanError(f"{src.source_id}: the forecast no longer gives a target")
        k1, k2 = _k1_k2(src, target.spectroscopy.K_eff_kms)
        spec = dataclasses.replace(
            target.spectroscopy, lines="SB1" if k2 is None else "SB2", K1_kms=k1, K2_kms=k2
        )
        target = dataclasses.replace(target, name=src.source_id, spectroscopy=spec)
        header = (
            f"ucbplan population rank: rank {int(ranked['rank'][i])} of {len(ranked)} "
            f"({ranked.meta['figure_of_merit']}); Fisher forecast of catalog row {src.row}"
        )
        write_target(target, path, overwrite=overwrite, header=header)
    files = [str(paths[i]) if i in paths else "" for i in range(len(ranked))]
    desc = ranked["target_file"].description
    ranked.replace_column("target_file", Column(np.array(files, dtype=str), description=desc))
    return list(paths.values())


def rank_instrument(
    name: str | None, instruments_file: Path | None, sigma_ref: str | None
) -> Instrument | None:
    """The RV-precision reference: ``--instrument`` (its σ_ref and overheads), with σ_ref
    replaced by ``--sigma-ref SIGMA_KMS,MAG,EXPTIME_S`` (V band) when given; None if neither.

    Raises
    ------
    InputError
        Unknown instrument, or a ``--sigma-ref`` that is not three positive numbers.
    """
    from ucbplan.observing.precision.instruments import SigmaRef, instrument_or_none

    inst = instrument_or_none(name or None, instruments_file)
    if sigma_ref is None:
        return inst
    parts = sigma_ref.split(",") if len(sigma_ref) < 100 else []
    try:
        sv, mag, t = (float(p) for p in parts)
    except ValueError:
        sv = mag = t = math.nan
    if not (sv > 0 and t > 0 and math.isfinite(mag)):
        raise InputError(
            "sigma_ref: expected SIGMA_KMS,MAG,EXPTIME_S (σ_v of one exposure of that length "
            f"at that V magnitude), got {shorten(sigma_ref)}"
        )
    ref = SigmaRef(sigma_v_kms=sv, mag=mag, band="V", exptime_s=t)
    if inst is None:
        return Instrument("--sigma-ref", "", (), None, None, None, None, ref)
    return dataclasses.replace(inst, sigma_ref=ref)


def read_forecast_table(path: Path) -> Any | None:
    """The table if ``path`` is an ECSV written by ``ucbplan population forecast``, else None.

    Raises
    ------
    InputFileError
        Unreadable file, or a forecast table that astropy cannot read.
    """
    from astropy.table import Table

    from ucbplan.inputs import read_text

    text = read_text(path, "forecast table or catalog")
    head = text[:4000]
    if not head.lstrip("\ufeff").startswith("# %ECSV"):
        return None
    if "command: ucbplan population forecast" not in head:
        return None
    try:
        return Table.read(text, format="ascii.ecsv")
    except Exception as exc:  # astropy raises many types for malformed tables
        msg = " ".join(str(exc).split())
        raise InputFileError(f"{path}: not a readable forecast table ({shorten(msg)})") from None


def check_catalog_of(forecast: Any, catalog: Catalog, where: Path) -> None:
    """Refuse a catalog that is not the one the forecast table was computed from (SHA-256).

    Raises
    ------
    InputFileError
        The hashes differ.
    """
    want = forecast.meta.get("catalog_sha256")
    if want != catalog.sha256:
        raise InputFileError(
            f"{where}: forecast of catalog sha256 {shorten(want, 20)}, but {catalog.path.name} "
            f"has {catalog.sha256[:16]}…; pass the forecast's catalog with `catalog`"
        )


def rank_options(
    *,
    top: int,
    goal: str,
    instrument: str | None,
    instruments_file: Path | None,
    sigma_ref: str | None,
    exptime_s: float,
    readout_s: float | None,
    acquisition_s: float | None,
    visit_s: float,
) -> RankOptions:
    """Checked :class:`RankOptions` from the command line.

    Overheads: ``--readout``/``--overhead`` when given, else the instrument's (an error naming
    the option when the table has none), else 0 without an instrument.
    """
    from ucbplan.observing.precision.instruments import instrument_overheads

    inst = rank_instrument(instrument, instruments_file, sigma_ref)
    if instrument:
        over = instrument_overheads(inst, acquisition_s=acquisition_s, readout_s=readout_s)
        acq, ro = over.acquisition_s, over.readout_s
    else:
        acq, ro = acquisition_s or 0.0, readout_s or 0.0
    return RankOptions(
        top=top,
        goal=goal,
        instrument=inst,
        exptime_s=exptime_s,
        readout_s=ro,
        acquisition_s=acq,
        visit_s=visit_s,
    )
