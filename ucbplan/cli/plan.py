"""``ucbplan plan``: phase-targeted blocks at an observatory (thin shell over ucbplan.observing)."""

from __future__ import annotations

import math
from datetime import date, timedelta
from pathlib import Path
from typing import IO, Any

import typer
from rich.markup import escape

from ucbplan.cli._console import check_output_path, err_console, rich_table, write_output
from ucbplan.errors import UcbplanError

__all__ = ["register"]

_MACHINE = ("ecsv", "csv", "json")


def _site(site: str | None, site_lonlat: str | None, sites_file: Path | None) -> Any:
    from ucbplan.observing.sites import get_site, site_from_lonlat

    if site_lonlat:
        return site_from_lonlat(site_lonlat)
    if not site:
        raise UcbplanError("no site: pass --site NAME (e.g. paranal) or --site-lonlat LON,LAT,H")
    return get_site(site, sites_file)


def _night(text: str, n: int) -> list[date]:
    try:
        first = date.fromisoformat(text)
    except ValueError:
        raise UcbplanError(
            f"--night: expected the local evening date YYYY-MM-DD, got {text!r}"
        ) from None
    if n < 1:
        raise UcbplanError(f"--nights must be >= 1, got {n}")
    return [first + timedelta(days=k) for k in range(n)]


def _with_priorities(targets: list[Any], items: list[str]) -> list[Any]:
    from dataclasses import replace

    values: dict[str, float] = {}
    for item in items:
        name, sep, value = item.rpartition("=")
        try:
            values[name.strip().lower()] = float(value)
        except ValueError:
            name = ""
        if not sep or not name:
            raise UcbplanError(f"--priority: expected NAME=NUMBER, got {item!r}")
    known = {t.name.lower() for t in targets}
    unknown = sorted(set(values) - known)
    if unknown:
        raise UcbplanError(
            f"--priority: no target named {unknown[0]!r}; targets: "
            + ", ".join(t.name for t in targets)
        )
    return [replace(t, priority=values.get(t.name.lower(), t.priority)) for t in targets]


def _format(fmt: str, output: Path | None) -> str:
    fmt = fmt.lower()
    if fmt not in ("table", *_MACHINE):
        raise UcbplanError(f"--format {fmt!r}: expected table, ecsv, csv or json")
    if fmt == "table" and output is not None:
        suffix = output.suffix.lower().lstrip(".")
        return suffix if suffix in _MACHINE else "ecsv"
    return fmt


def _print_night(blocks: list[Any], night: str, site: Any) -> None:
    table = rich_table(
        f"Night of {night} at {site.name} — times are UTC at the site (light time removed); "
        "±σ is the 1σ timing uncertainty",
        [
            "target",
            "block",
            "anchor",
            "u★ [rad]",
            "UTC mid ± σ",
            "local mid",
            "UTC start–end",
            "airmass s/m/e",
            "Moon [deg]",
            "Λ_K",
            "π-mode alt. UTC",
            *(["pair: Δκ_LISA"] if any(b.pair_id for b in blocks) else []),
        ],
    )
    paired = any(b.pair_id for b in blocks)
    for b in blocks:
        table.add_row(
            escape(b.target),
            escape(b.block_id.rsplit("-", 1)[-1]),
            escape(b.anchor),
            f"{b.u_star_rad:.4f}",
            f"{b.t_mid_utc.iso[11:23]} ± {b.sigma_t_s:.2f} s",
            _local(b),
            f"{b.t_start_utc.iso[11:19]}–{b.t_end_utc.iso[11:19]}",
            f"{b.airmass_start:.2f}/{b.airmass:.2f}/{b.airmass_end:.2f}",
            f"{b.moon_sep_deg:.0f}",
            f"{b.lambda_k:.4f}",
            b.t_alt_utc.iso[11:21] if b.t_alt_utc is not None else "",
            *([f"{escape(b.pair_id)}: {b.delta_kappa:+.2e}"] if paired else []),
        )
    err_console.print(table)


def _local(b: Any) -> str:
    from datetime import UTC
    from zoneinfo import ZoneInfo

    dt = b.t_mid_utc.to_datetime(timezone=UTC).astimezone(ZoneInfo(b.timezone))
    return dt.strftime("%H:%M:%S %Z")


def plan(
    targets: list[Path] = typer.Argument(..., help="Target YAML files."),
    site: str | None = typer.Option(None, "--site", help="Site name or alias (e.g. paranal)."),
    site_lonlat: str | None = typer.Option(
        None, "--site-lonlat", help="LON,LAT,HEIGHT (deg east, deg north, m) instead of --site."
    ),
    sites_file: Path | None = typer.Option(
        None, "--sites-file", help="YAML site table searched before the bundled one."
    ),
    night: str = typer.Option(..., "--night", help="Local date of the first evening, YYYY-MM-DD."),
    nights: int = typer.Option(1, "--nights", help="Number of consecutive nights."),
    mode: str = typer.Option(
        "quadrature",
        "--mode",
        help="quadrature | conjunction | zero-crossing | fixed-u-pairs | u=VALUE [rad].",
    ),
    twilight: str = typer.Option("nautical", "--twilight", help="civil | nautical | astronomical"),
    airmass_max: float = typer.Option(2.0, "--airmass-max", help="Largest airmass (sec z)."),
    moon_sep: float = typer.Option(30.0, "--moon-sep", help="Smallest Moon separation [deg]."),
    moon_illum: float | None = typer.Option(
        None, "--moon-illum", help="Largest Moon illuminated fraction (0-1) while the Moon is up."
    ),
    zenith_hole: float | None = typer.Option(
        None, "--zenith-hole", help="Zenith-hole radius [deg] (default: the site's; 0 = none)."
    ),
    exptime: float = typer.Option(60.0, "--exptime", help="Single-exposure time [s]."),
    n_exp: int = typer.Option(1, "--n-exp", help="Exposures per block (co-added)."),
    readout: float = typer.Option(0.0, "--readout", help="Dead time between exposures [s]."),
    alpha: float = typer.Option(1.0, "--alpha", help="Planning margin α of T_valid."),
    sigma_v: float | None = typer.Option(None, "--sigma-v", help="RV precision σ_v [km/s]."),
    k_eff: float | None = typer.Option(None, "--k-eff", help="Semi-amplitude K_eff [km/s]."),
    max_smear: str | None = typer.Option(
        None, "--max-smear", help="Smearing budget: '0.5*sigma_v' or km/s; exceeded = error."
    ),
    max_bin_fraction: float | None = typer.Option(
        None, "--max-bin-fraction", help="Largest block span as a fraction of P_b."
    ),
    overhead: float = typer.Option(
        300.0, "--overhead", help="Slew + acquisition before each session [s]."
    ),
    sessions: int = typer.Option(1, "--sessions", help="Sessions per target and night."),
    priority: list[str] = typer.Option(
        [], "--priority", help="NAME=P overrides a target file's priority (higher first)."
    ),
    output: Path | None = typer.Option(None, "-o", "--output", help="Write the blocks table."),
    fmt: str = typer.Option("table", "--format", help="table | ecsv | csv | json"),
    plot: Path | None = typer.Option(None, "--plot", help="Night chart PNG (first night)."),
    overwrite: bool = typer.Option(False, "--overwrite", help="Replace existing output files."),
) -> None:
    """Plan phase-targeted observing blocks (UTC at the site) for one or more nights."""
    args = dict(locals())
    from ucbplan.observing.timeconv import quiet_erfa

    with quiet_erfa():
        _plan(**args)


def _plan(
    targets: list[Path],
    site: str | None,
    site_lonlat: str | None,
    sites_file: Path | None,
    night: str,
    nights: int,
    mode: str,
    twilight: str,
    airmass_max: float,
    moon_sep: float,
    moon_illum: float | None,
    zenith_hole: float | None,
    exptime: float,
    n_exp: int,
    readout: float,
    alpha: float,
    sigma_v: float | None,
    k_eff: float | None,
    max_smear: str | None,
    max_bin_fraction: float | None,
    overhead: float,
    sessions: int,
    priority: list[str],
    output: Path | None,
    fmt: str,
    plot: Path | None,
    overwrite: bool,
) -> None:
    from ucbplan.observing.blocks import ExposurePlan
    from ucbplan.observing.blocktable import blocks_to_table, make_meta, write_table
    from ucbplan.observing.schedule.plan import PlanSettings, plan_nights
    from ucbplan.target import load_target

    fmt = _format(fmt, output)
    for path in (output, plot):
        if path is not None:
            check_output_path(path, overwrite)
    if not (alpha > 0 and math.isfinite(alpha)):
        raise UcbplanError(f"--alpha must be positive, got {alpha}")
    if sessions < 1:
        raise UcbplanError(f"--sessions must be >= 1, got {sessions}")
    the_site = _site(site, site_lonlat, sites_file)
    dates = _night(night, nights)
    loaded = _with_priorities([load_target(p) for p in targets], priority)
    settings = PlanSettings(
        mode=mode,
        twilight=twilight,
        airmass_max=airmass_max,
        moon_sep_deg=moon_sep,
        moon_illum_max=moon_illum,
        zenith_hole_deg=zenith_hole,
        exposure=ExposurePlan(exptime, n_exp, readout),
        alpha=alpha,
        sigma_v_kms=sigma_v,
        k_eff_kms=k_eff,
        max_smear=max_smear,
        max_bin_fraction=max_bin_fraction,
        overhead_s=overhead,
        sessions_per_night=sessions,
    )
    result = plan_nights(loaded, the_site, dates, settings)
    for w in result.warnings:
        err_console.print(f"[yellow]warning:[/] {escape(w)}", soft_wrap=True)
    grouped: dict[tuple[str, str], list[str]] = {}
    for miss in result.unplaced:
        grouped.setdefault((miss.target, miss.reason), []).append(miss.night)
    for (name, reason), when in grouped.items():
        span = when[0] if len(when) == 1 else f"{len(when)} nights {when[0]}..{when[-1]}"
        err_console.print(
            f"[yellow]not placed:[/] {escape(name)} ({span}): {escape(reason)}", soft_wrap=True
        )
    if not result.blocks:
        reasons = "; ".join(f"{m.target} {m.night}: {m.reason}" for m in result.unplaced)
        raise UcbplanError(f"no block could be planned at {the_site.name}: {reasons}")
    for label in dict.fromkeys(b.night for b in result.blocks):
        _print_night([b for b in result.blocks if b.night == label], label, the_site)
    meta = make_meta(
        site=the_site.as_dict(),
        targets=[{"name": t.name, "file": str(t.source), "sha256": t.sha256} for t in loaded],
        constraints=result.constraints,
        mode=settings.mode,
        extra={
            "nights": [d.isoformat() for d in dates],
            "alpha": alpha,
            "exposure": {"exptime_s": exptime, "n_exp": n_exp, "readout_s": readout},
            "overhead_s": overhead,
            "valid_until_tdb": {k: v.tdb.isot for k, v in result.valid_until.items()},
            "warnings": result.warnings,
            "unplaced": [f"{m.target} {m.night}: {m.reason}" for m in result.unplaced],
        },
    )
    table = blocks_to_table(result.blocks, meta)
    if fmt in _MACHINE:

        def _write(handle: IO[str]) -> None:
            write_table(table, handle, fmt)

        write_output(output, _write, overwrite=overwrite)
        if output is not None:
            err_console.print(f"wrote {len(table)} blocks to {escape(str(output))} ({fmt})")
    if plot is not None:
        from ucbplan.observing.nightplot import plot_night

        fig = plot_night(loaded, the_site, dates[0], result.blocks, airmass_max)
        write_output(
            plot, lambda h: fig.savefig(h, format="png", dpi=120), overwrite=overwrite, binary=True
        )
        err_console.print(f"wrote night chart to {escape(str(plot))}")


def register(app: typer.Typer) -> None:
    """Add ``plan`` to the app."""
    app.command("plan")(plan)
