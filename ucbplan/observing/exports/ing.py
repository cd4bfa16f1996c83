"""ING (WHT/ISIS) ``.cat`` catalogue: one line per target (docs/exports.md)."""

from __future__ import annotations

from astropy.table import Table

from ucbplan.observing.exports.columns import (
    coordinates,
    floats,
    required_times,
    strings,
    time_order,
)
from ucbplan.observing.exports.interface import ExportOptions, ExportResult
from ucbplan.observing.exports.text import ascii_names, fmt_sigma, iso_ms
from ucbplan.observing.tableformat import sexagesimal

__all__ = ["export_ing_cat", "ing_catalogue"]

#: Longest target name an ING catalogue accepts.
ING_NAME_MAX = 20


def ing_catalogue(table: Table, notes: list[str] | None = None) -> str:
    """ING (WHT/ISIS) catalogue: ``NAME hh mm ss.ss ±dd mm ss.s J2000 ! comment`` per target.

    Names are ≤ 20 ASCII characters without spaces, colons or tabs (transliterated with a note,
    see :func:`~ucbplan.observing.exports.text.ascii_names`); the comment gives the first block's
    UTC mid-time and σ. Save under a lower-case name ending ``.cat``.

    Raises
    ------
    InputFileError
        If two targets become the same catalogue name (both named), or a name has no ASCII
        spelling.
    """
    names = strings(table, "target")
    short_names = ascii_names(
        names, "ING catalogue", notes if notes is not None else [], ING_NAME_MAX, ":"
    )
    ra, dec = coordinates(table)
    sigma = floats(table, "sigma_t_s", unit="s")
    mids = required_times(table, "t_mid_utc")
    lines: list[str] = []
    seen: set[str] = set()
    for i in time_order(table):
        short = short_names[names[i]]
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
    notes: list[str] = []
    text = ing_catalogue(table, notes)
    return ExportResult(text.encode("ascii"), ".cat", tuple(dict.fromkeys(notes)))
