"""ING (WHT/ISIS) ``.cat`` catalogue: one line per target (docs/exports.md)."""

from __future__ import annotations

from astropy.table import Table

from ucbplan.observing.exports.base import (
    ExportOptions,
    ExportResult,
    coordinates,
    floats,
    fmt_sigma,
    iso_ms,
    required_times,
    safe_name,
    sexagesimal,
    strings,
    time_order,
)

__all__ = ["export_ing_cat", "ing_catalogue"]

#: Longest target name an ING catalogue accepts.
ING_NAME_MAX = 20


def ing_catalogue(table: Table) -> str:
    """ING (WHT/ISIS) catalogue: ``NAME hh mm ss.ss ±dd mm ss.s J2000 ! comment`` per target.

    Names are ≤ 20 characters without spaces, colons or tabs; the comment gives the first
    block's UTC mid-time and σ. Save under a lower-case name ending ``.cat``.
    """
    names = strings(table, "target")
    ra, dec = coordinates(table)
    sigma = floats(table, "sigma_t_s", unit="s")
    mids = required_times(table, "t_mid_utc")
    lines: list[str] = []
    seen: set[str] = set()
    for i in time_order(table):
        short = safe_name(names[i], ING_NAME_MAX).replace(":", "_")
        if short in seen:
            continue
        seen.add(short)
        lines.append(
            f"{short:<20} {sexagesimal(ra[i] / 15.0, 2, ' ', False)} "
            f"{sexagesimal(dec[i], 1, ' ', True)} J2000 ! first UTC-mid {iso_ms(mids[i], 1)} "
            f"+/-{fmt_sigma(float(sigma[i]))} s"
        )
    return "\n".join(lines) + "\n"


def export_ing_cat(table: Table, options: ExportOptions) -> ExportResult:
    """ING (WHT/ISIS) ``.cat`` catalogue, one line per target (see :func:`ing_catalogue`)."""
    return ExportResult(ing_catalogue(table).encode("ascii"), ".cat")
