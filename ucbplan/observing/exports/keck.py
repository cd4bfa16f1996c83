"""Keck starlist: fixed columns, one line per target, block times as comments (docs/exports.md)."""

from __future__ import annotations

import math

import numpy as np
from astropy.table import Table

from ucbplan.errors import InputFileError
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
    site_name,
    strings,
    time_order,
    version,
    vmags,
)

__all__ = ["export_keck_starlist"]

#: Longest target name a Keck starlist accepts (the name field is columns 1–16).
KECK_NAME_MAX = 15


def _keck_name(name: str, notes: list[str]) -> str:
    text = safe_name(name)
    if len(text) > KECK_NAME_MAX:
        notes.append(f"Keck starlist: name {text!r} truncated to 15 characters")
        text = text[:KECK_NAME_MAX]
    return text


def _mid_decimals(sigma_s: float) -> int:
    """Decimals of the UTC mid-time second: 0.1 s unless σ is below 0.1 s."""
    return 1 if sigma_s >= 0.1 else 3


def _block_comments(table: Table, notes: list[str]) -> tuple[dict[str, list[str]], dict[str, int]]:
    """``#`` lines (UTC mid ± σ) per target in time order, and each target's first row.

    Raises
    ------
    InputFileError
        If two targets collide after truncation to 15 characters.
    """
    names = strings(table, "target")
    anchors = strings(table, "anchor")
    u_star = floats(table, "u_star_rad", unit="rad")
    sigma = floats(table, "sigma_t_s", unit="s")
    mids = required_times(table, "t_mid_utc")
    seen: dict[str, str] = {}
    comments: dict[str, list[str]] = {}
    first: dict[str, int] = {}
    for i in time_order(table):
        short = _keck_name(names[i], notes)
        if seen.setdefault(short, names[i]) != names[i]:
            raise InputFileError(
                f"Keck starlist: targets {seen[short]!r} and {names[i]!r} both become {short!r} "
                "(15-character limit); rename one in its target file"
            )
        first.setdefault(names[i], i)
        comments.setdefault(names[i], []).append(
            f"# {short} u*={u_star[i]:.6g} ({anchors[i]}) UTC-mid "
            f"{iso_ms(mids[i], _mid_decimals(float(sigma[i])))} +/-{fmt_sigma(float(sigma[i]))} s"
        )
    return comments, first


def _target_line(name: str, ra_deg: float, dec_deg: float, vmag: float, rotmode: str) -> str:
    """Name padded to 16 columns, ``HH MM SS.SS ±DD MM SS.S 2000``, then ``key=value`` pairs."""
    keys = []
    if math.isfinite(vmag):
        keys.append(f"vmag={vmag:.1f}")
    keys.append(f"rotmode={rotmode}")
    return (
        f"{_keck_name(name, []):<16}{sexagesimal(ra_deg / 15.0, 2, ' ', False)} "
        f"{sexagesimal(dec_deg, 1, ' ', True)} 2000 " + " ".join(keys)
    )


def export_keck_starlist(table: Table, options: ExportOptions) -> ExportResult:
    """Keck starlist: a ``#`` comment per block (UTC mid-time ± σ), then one line per target.

    Name in columns 1–16 (≤ 15 characters, spaces → underscores), RA ``HH MM SS.SS`` from
    column 17, Dec ``±DD MM SS.S``, equinox ``2000``, then ``key=value`` pairs (``vmag=`` when a
    ``vmag`` column exists, ``rotmode=``).

    Raises
    ------
    InputFileError
        If two targets collide after truncation to 15 characters.
    """
    notes: list[str] = []
    ra, dec = coordinates(table)
    vmag: np.ndarray = vmags(table)
    comments, first = _block_comments(table, notes)
    lines = [
        f"# ucbplan {version()} Keck starlist; site {site_name(table)}; times UTC at the site, "
        "+/- 1 sigma",
    ]
    for name, i in sorted(first.items(), key=lambda kv: kv[1]):
        lines.extend(comments[name])
        lines.append(_target_line(name, ra[i], dec[i], vmag[i], options.keck_rotmode))
    text = "\n".join(lines) + "\n"
    return ExportResult(text.encode("ascii"), ".txt", tuple(dict.fromkeys(notes)))
