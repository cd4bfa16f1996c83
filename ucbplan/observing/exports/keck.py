"""Keck starlist: fixed columns, one line per target, block times as comments (docs/exports.md)."""

from __future__ import annotations

import math

import numpy as np
from astropy.table import Table

from ucbplan.observing.blocks.cells import sexagesimal
from ucbplan.observing.exports.columns import (
    coordinates,
    floats,
    required_times,
    strings,
    time_order,
    vmags,
)
from ucbplan.observing.exports.interface import ExportOptions, ExportResult
from ucbplan.observing.exports.provenance import site_name, version
from ucbplan.observing.exports.text import ascii_names, ascii_text, fmt_sigma, iso_ms
from ucbplan.observing.exports.visitgroups import (
    NO_EXPOSURE_FIELD,
    exposure_texts,
    target_totals,
)

#: Longest target name a Keck starlist accepts (the name field is columns 1–16).
KECK_NAME_MAX = 15


def _mid_decimals(sigma_s: float) -> int:
    """Decimals of the UTC mid-time second: 0.1 s unless σ is below 0.1 s."""
    return 1 if sigma_s >= 0.1 else 3


def _block_comments(
    table: Table, short_names: dict[str, str]
) -> tuple[dict[str, list[str]], dict[str, int]]:
    """``#`` lines (UTC mid ± σ) per target in time order, and each target's first row."""
    names = strings(table, "target")
    anchors = strings(table, "anchor")
    u_star = floats(table, "u_star_rad", unit="rad")
    sigma = floats(table, "sigma_t_s", unit="s")
    mids = required_times(table, "t_mid_utc")
    exposures = exposure_texts(table)
    comments: dict[str, list[str]] = {}
    first: dict[str, int] = {}
    for i in time_order(table):
        short = short_names[names[i]]
        first.setdefault(names[i], i)
        comments.setdefault(names[i], []).append(
            f"# {short} u*={u_star[i]:.6g} ({ascii_text(anchors[i])}) UTC-mid "
            f"{iso_ms(mids[i], _mid_decimals(float(sigma[i])))} +/-{fmt_sigma(float(sigma[i]))} s "
            f"{exposures[i]}"
        )
    return comments, first


def _target_line(short: str, ra_deg: float, dec_deg: float, vmag: float, rotmode: str) -> str:
    """Name padded to 16 columns, ``HH MM SS.SS ±DD MM SS.S 2000``, then ``key=value`` pairs."""
    keys = []
    if math.isfinite(vmag):
        keys.append(f"vmag={vmag:.1f}")
    keys.append(f"rotmode={rotmode}")
    return (
        f"{short:<16}{sexagesimal(ra_deg / 15.0, 2, ' ', False)} "
        f"{sexagesimal(dec_deg, 1, ' ', True)} 2000 " + " ".join(keys)
    )


def export_keck_starlist(table: Table, options: ExportOptions) -> ExportResult:
    """Keck starlist: per target a ``#`` line with its exposure totals and a ``#`` comment per
    block (UTC mid-time ± σ, exposures ``n x t s``), then the target line.

    A starlist line has no exposure field: the counts and times are in the comments (a note
    says so) and are set in the instrument's own software.

    Name in columns 1–16 (≤ 15 characters, spaces → underscores), RA ``HH MM SS.SS`` from
    column 17, Dec ``±DD MM SS.S``, equinox ``2000``, then ``key=value`` pairs (``vmag=`` when a
    ``vmag`` column exists, ``rotmode=``).

    Names are ASCII (transliterated with a note, see
    :func:`~ucbplan.observing.exports.text.ascii_names`).

    Raises
    ------
    InputFileError
        If two targets collide after transliteration or truncation to 15 characters, or a name
        has no ASCII spelling.
    """
    notes: list[str] = []
    short = ascii_names(strings(table, "target"), "Keck starlist", notes, KECK_NAME_MAX)
    ra, dec = coordinates(table)
    vmag: np.ndarray = vmags(table, notes)
    comments, first = _block_comments(table, short)
    lines = [
        f"# ucbplan {version()} Keck starlist; site {ascii_text(site_name(table))}; times UTC "
        "at the site, "
        "+/- 1 sigma",
    ]
    totals = target_totals(table)
    for name, i in sorted(first.items(), key=lambda kv: kv[1]):
        lines.append(f"# {short[name]} {totals[name]}")
        lines.extend(comments[name])
        lines.append(_target_line(short[name], ra[i], dec[i], vmag[i], options.keck_rotmode))
    notes.append(NO_EXPOSURE_FIELD.format(fmt="Keck starlist", mark="#"))
    text = "\n".join(lines) + "\n"
    return ExportResult(text.encode("ascii"), ".txt", tuple(dict.fromkeys(notes)))
