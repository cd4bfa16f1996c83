"""ICS calendar (RFC 5545): one VEVENT per block, times in UTC (docs/exports.md)."""

from __future__ import annotations

import unicodedata
from dataclasses import dataclass
from datetime import datetime, timedelta

import numpy as np
from astropy.table import Table

from ucbplan.errors import InputFileError, shorten
from ucbplan.observing.exports.columns import (
    floats,
    parse_utc,
    required_times,
    strings,
    time_order,
    times_utc,
)
from ucbplan.observing.exports.interface import ExportOptions, ExportResult
from ucbplan.observing.exports.provenance import created_utc, site_name, version
from ucbplan.observing.exports.text import fmt_sigma, iso_ms, safe_name

#: Longest content line in octets (RFC 5545 §3.1); longer lines are folded.
ICS_LINE_OCTETS = 75


def ics_escape(text: str) -> str:
    """Escape a TEXT value (RFC 5545 §3.3.11): backslash, semicolon, comma, newline.

    Line breaks of any kind (CR LF, a bare CR, U+2028/2029) become the escaped ``\\n``; other
    control characters, which no TEXT value may hold (§3.3.11, ``TSAFE-CHAR``), are dropped.
    """
    text = text.replace("\r\n", "\n").replace("\r", "\n")
    text = "".join(
        "\n" if unicodedata.category(ch) in ("Zl", "Zp") else ch
        for ch in text
        if ch in "\n\t" or unicodedata.category(ch) not in ("Cc", "Cs")
    )
    return text.replace("\\", "\\\\").replace(";", "\\;").replace(",", "\\,").replace("\n", "\\n")


def ics_fold(line: str) -> str:
    """Fold a content line at 75 octets (RFC 5545 §3.1), never inside a UTF-8 character."""
    data = line.encode("utf-8")
    if len(data) <= ICS_LINE_OCTETS:
        return line
    parts: list[str] = []
    limit = ICS_LINE_OCTETS
    while data:
        cut = min(limit, len(data))
        while cut < len(data) and (data[cut] & 0xC0) == 0x80:
            cut -= 1
        parts.append(data[:cut].decode("utf-8"))
        data = data[cut:]
        limit = ICS_LINE_OCTETS - 1  # continuation lines start with one space
    return "\r\n ".join(parts)


def _ics_stamp(t: datetime) -> str:
    return t.strftime("%Y%m%dT%H%M%SZ")


def _ceil_second(t: datetime) -> datetime:
    base = t.replace(microsecond=0)
    return base if base == t else base + timedelta(seconds=1)


def _dtstamp(table: Table, first_start: datetime | None) -> str:
    """``meta.created_utc`` (else the first block start): the same table gives the same file."""
    created = created_utc(table)
    if created:
        try:
            return _ics_stamp(parse_utc(created, "meta.created_utc", 0))
        except InputFileError:
            pass
    return _ics_stamp(first_start) if first_start else "19700101T000000Z"


@dataclass(frozen=True, slots=True)
class _Columns:
    """The blocks-table columns the calendar reads."""

    names: list[str]
    blocks: list[str]
    anchors: list[str]
    u_star: np.ndarray
    sigma: np.ndarray
    airmass: np.ndarray
    alt: np.ndarray
    moon: np.ndarray
    exptime: np.ndarray
    n_exp: np.ndarray
    mids: list[datetime]
    starts: list[datetime]
    ends: list[datetime]
    alts: list[datetime | None]
    tdb: list[str]


def _columns(table: Table) -> _Columns:
    return _Columns(
        names=strings(table, "target"),
        blocks=strings(table, "block_id"),
        anchors=strings(table, "anchor"),
        u_star=floats(table, "u_star_rad", unit="rad"),
        sigma=floats(table, "sigma_t_s", unit="s"),
        airmass=floats(table, "airmass"),
        alt=floats(table, "altitude_deg", unit="deg"),
        moon=floats(table, "moon_sep_deg", unit="deg"),
        exptime=floats(table, "exptime_s", unit="s"),
        n_exp=floats(table, "n_exp"),
        mids=required_times(table, "t_mid_utc"),
        starts=required_times(table, "t_start_utc"),
        ends=required_times(table, "t_end_utc"),
        alts=times_utc(table, "t_alt_utc", required=False),
        tdb=strings(table, "t_mid_tdb_bary"),
    )


def _description(c: _Columns, i: int, site: str) -> str:
    alt = c.alts[i]
    # The pi-mode line only where there is one: a timing ephemeris has no phase ambiguity.
    pi_mode = [] if alt is None else [f"pi-mode alternative UTC {iso_ms(alt)}"]
    return "\n".join(
        [
            f"{c.names[i]} block {c.blocks[i]}: {c.anchors[i]}, u*={c.u_star[i]:.6g} rad (star 1)",
            f"mid-exposure UTC {iso_ms(c.mids[i])} +/- {fmt_sigma(float(c.sigma[i]))} s "
            f"(1 sigma), at {site}",
            f"barycentric TDB {c.tdb[i]}",
            *pi_mode,
            f"{int(c.n_exp[i])} x {c.exptime[i]:g} s; airmass {c.airmass[i]:.2f}, altitude "
            f"{c.alt[i]:.1f} deg, Moon separation {c.moon[i]:.1f} deg",
        ]
    )


def _event(c: _Columns, i: int, site: str, stamp: str) -> list[str]:
    """VEVENT lines of block ``i``: DTSTART/DTEND rounded outward to whole seconds."""
    summary = (
        f"{c.names[i]} {c.anchors[i]} u*={c.u_star[i]:.3g} +/-{fmt_sigma(float(c.sigma[i]))} s"
    )
    return [
        "BEGIN:VEVENT",
        f"UID:{ics_escape(safe_name(c.blocks[i]))}@ucbplan",
        f"DTSTAMP:{stamp}",
        f"DTSTART:{_ics_stamp(c.starts[i].replace(microsecond=0))}",
        f"DTEND:{_ics_stamp(_ceil_second(c.ends[i]))}",
        "SUMMARY:" + ics_escape(summary),
        "DESCRIPTION:" + ics_escape(_description(c, i, site)),
        "LOCATION:" + ics_escape(site),
        "TRANSP:OPAQUE",
        "END:VEVENT",
    ]


def _check_uids(blocks: list[str]) -> None:
    """Refuse two blocks whose ids give the same calendar UID (a calendar keeps only one)."""
    owner: dict[str, str] = {}
    for block in blocks:
        uid = ics_escape(safe_name(block))
        if owner.setdefault(uid, block) != block:
            raise InputFileError(
                f"ICS: blocks {shorten(owner[uid], 60)} and {shorten(block, 60)} both become "
                f"calendar UID {shorten(uid, 60)}@ucbplan; rename one"
            )


def export_ics(table: Table, options: ExportOptions) -> ExportResult:
    """ICS calendar: one VEVENT per block, DTSTART/DTEND in UTC rounded outward to seconds.

    DTSTAMP is the table's ``meta.created_utc`` (else the first block start) so that the same
    table always gives the same file. UIDs are ``<block_id>@ucbplan``. Lines end in CRLF and are
    folded at 75 octets.
    """
    c = _columns(table)
    _check_uids(c.blocks)
    site = site_name(table)
    stamp = _dtstamp(table, min(c.starts, default=None))
    lines = [
        "BEGIN:VCALENDAR",
        "VERSION:2.0",
        f"PRODID:-//ucbplan//ucbplan {version()}//EN",
        "CALSCALE:GREGORIAN",
        "METHOD:PUBLISH",
    ]
    for i in time_order(table):
        lines.extend(_event(c, i, site, stamp))
    lines.append("END:VCALENDAR")
    text = "".join(ics_fold(line) + "\r\n" for line in lines)
    return ExportResult(text.encode("utf-8"), ".ics", ())
