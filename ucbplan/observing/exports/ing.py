"""ING (WHT/ISIS) ``.cat`` catalogue: one line per target (docs/exports.md)."""

from __future__ import annotations

from astropy.table import Table

from ucbplan.observing.blocks.cells import sexagesimal
from ucbplan.observing.exports.columns import (
    coordinates,
    floats,
    required_times,
    strings,
    time_order,
)
from ucbplan.observing.exports.interface import ExportOptions, ExportResult
from ucbplan.observing.exports.text import ascii_names, fmt_sigma, iso_ms
from ucbplan.observing.exports.visitgroups import (
    NO_EXPOSURE_FIELD,
    exposure_texts,
    target_totals,
)

#: Longest target name an ING catalogue accepts.
ING_NAME_MAX = 20


def ing_catalogue(table: Table, notes: list[str] | None = None) -> str:
    """ING (WHT/ISIS) catalogue: ``NAME hh mm ss.ss ±dd mm ss.s J2000 ! comment`` per target.

    Names are ≤ 20 ASCII characters without spaces, colons or tabs (transliterated with a note,
    see :func:`~ucbplan.observing.exports.text.ascii_names`); the comment gives the target's
    exposure totals. Below it, one ``!`` comment line per block gives its UTC mid-time, σ and
    exposures (``n x t s``): the catalogue has no exposure field. Save under a lower-case name
    ending ``.cat``.

    Raises
    ------
    InputFileError
        If two targets become the same catalogue name (both named), or a name has no ASCII
        spelling.
    """
    names = strings(table, "target")
    found = notes if notes is not None else []
    short_names = ascii_names(names, "ING catalogue", found, ING_NAME_MAX, ":")
    ra, dec = coordinates(table)
    sigma = floats(table, "sigma_t_s", unit="s")
    mids = required_times(table, "t_mid_utc")
    totals, exposures = target_totals(table), exposure_texts(table)
    order = time_order(table)
    lines: list[str] = []
    for name in dict.fromkeys(names[i] for i in order):
        i = next(j for j in order if names[j] == name)
        short = short_names[name]
        lines.append(
            f"{short:<20} {sexagesimal(ra[i] / 15.0, 2, ' ', False)} "
            f"{sexagesimal(dec[i], 1, ' ', True)} J2000 ! {totals[name]}"
        )
        lines.extend(
            f"! {short} UTC-mid {iso_ms(mids[j], 1)} +/-{fmt_sigma(float(sigma[j]))} s "
            f"{exposures[j]}"
            for j in order
            if names[j] == name
        )
    found.append(NO_EXPOSURE_FIELD.format(fmt="ING catalogue", mark="!"))
    return "\n".join(lines) + "\n"


def export_ing_cat(table: Table, options: ExportOptions) -> ExportResult:
    """ING (WHT/ISIS) ``.cat`` catalogue, one line per target (see :func:`ing_catalogue`)."""
    notes: list[str] = []
    text = ing_catalogue(table, notes)
    return ExportResult(text.encode("ascii"), ".cat", tuple(dict.fromkeys(notes)))
