"""Observatory exports of the master blocks table: ESO p2, Keck starlist, ICS calendar, proposal.

Each format is a small function ``(table, options) -> ExportResult`` registered by name in
:data:`EXPORTERS`; :func:`export_blocks` looks the name up and fails with the list of known names.
Formats follow ``EXPORTS.md``. Every time written is UTC at the site (from the ``t_*_utc``
columns) and carries its 1σ uncertainty ``sigma_t_s``.

Missing optional columns get documented defaults, each reported once in ``ExportResult.notes``:
no ``acq_s`` column → the plan's ``meta['overhead_s']``, else :data:`DEFAULT_ACQUISITION_S` (or
``--acquisition``); no ``vmag`` → the target file named in ``meta['targets']``; no ``period_s`` →
P_b ≈ 4 |t_alt − t_mid| (the φ_ref π-mode alternative epoch lies a quarter orbit away); no
``readout_s`` → the dead time inside the block, (t_end − t_start) − n_exp·exptime.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from datetime import UTC, datetime, timedelta
from typing import Any

import numpy as np
from astropy.table import Table

from ucbplan.errors import InputFileError, UcbplanError

__all__ = [
    "DEFAULT_ACQUISITION_S",
    "EXPORTERS",
    "ExportOptions",
    "ExportResult",
    "export_blocks",
    "export_eso_p2",
    "export_ics",
    "export_ing_cat",
    "export_keck_starlist",
    "export_lco",
    "export_proposal",
]

#: Acquisition overhead assumed when neither ``--acquisition`` nor an ``acq_s`` column is given [s]
#: (a typical VLT/Keck slit acquisition of a faint target: pointing, acquisition image, centring).
DEFAULT_ACQUISITION_S = 600.0


@dataclass(frozen=True, slots=True)
class ExportOptions:
    """Knobs shared by the export formats.

    Attributes
    ----------
    acquisition_s : float or None
        Acquisition overhead before the first exposure [s]; None → ``acq_s`` column, else the
        plan's ``meta['overhead_s']``, else :data:`DEFAULT_ACQUISITION_S`.
    tolerance_sigma : float
        ESO window half-width in units of σ_t (k in k·σ_t).
    tolerance_floor_s : float
        Smallest ESO window half-width [s] (an operator cannot start an OB to better than this).
    rounding_warn_fraction : float
        Warn when minute rounding widens an ESO window by more than this fraction of P_b.
    merge_overlaps : bool
        Merge overlapping ESO windows of one target into one OB instead of raising.
    proposal_format : str
        ``ecsv``, ``csv`` or ``latex`` for the proposal table.
    keck_rotmode : str
        Keck ``rotmode=`` value (``vertical`` = parallactic slit, right for spectroscopy).
    """

    acquisition_s: float | None = None
    tolerance_sigma: float = 3.0
    tolerance_floor_s: float = 10.0
    rounding_warn_fraction: float = 0.1
    merge_overlaps: bool = False
    proposal_format: str = "ecsv"
    keck_rotmode: str = "vertical"


@dataclass(frozen=True, slots=True)
class ExportResult:
    """Bytes to write plus notes for the user (defaults taken, rounding warnings)."""

    content: bytes
    suffix: str
    notes: tuple[str, ...] = field(default_factory=tuple)


# --------------------------------------------------------------------------------------------
# Column access, robust to missing optional extras
# --------------------------------------------------------------------------------------------


def _parse_utc(text: str, column: str, row: int) -> datetime:
    try:
        value = datetime.fromisoformat(text.strip())
    except ValueError as exc:
        raise InputFileError(
            f"blocks table: column {column} row {row}: got {text!r}, expected ISO UTC "
            "like 2037-01-15T01:02:03.400; regenerate the table with `ucbplan plan`"
        ) from exc
    return value.replace(tzinfo=UTC) if value.tzinfo is None else value.astimezone(UTC)


def times_utc(table: Table, column: str, required: bool = True) -> list[datetime | None]:
    """UTC datetimes (µs resolution) of an ISO string or astropy Time column; None for blanks."""
    if column not in table.colnames:
        if required:
            raise InputFileError(f"blocks table lacks column {column}; regenerate it")
        return [None] * len(table)
    col = table[column]
    from astropy.time import Time

    if isinstance(col, Time):
        from ucbplan.observing.timeconv import quiet_erfa

        with quiet_erfa():  # future dates: ERFA's "dubious year" is about leap seconds only
            texts = list(np.atleast_1d(col.utc.isot))
    else:
        texts = [str(v) if v is not np.ma.masked else "" for v in col]
    out: list[datetime | None] = []
    for i, text in enumerate(texts):
        if not text or text in ("--", "nan", "None"):
            if required:
                raise InputFileError(f"blocks table: column {column} row {i}: empty time")
            out.append(None)
        else:
            out.append(_parse_utc(text, column, i))
    return out


def required_times(table: Table, column: str) -> list[datetime]:
    """Like :func:`times_utc` for a required column: every row must hold a time."""
    return [t for t in times_utc(table, column) if t is not None]


def floats(table: Table, column: str, default: float | None = None, unit: str = "") -> np.ndarray:
    """Column as float64 (in ``unit`` if the column has one); ``default`` when it is missing."""
    if column not in table.colnames:
        if default is None:
            raise InputFileError(f"blocks table lacks column {column}; regenerate it")
        return np.full(len(table), float(default))
    col = table[column]
    if unit and getattr(col, "unit", None) is not None:
        values = col.quantity.to_value(unit)
    else:
        values = np.ma.filled(np.ma.asarray(col, dtype=float), np.nan)
    return np.asarray(values, dtype=float)


def strings(table: Table, column: str, default: str = "") -> list[str]:
    """Column as str (masked → ``default``); all ``default`` when missing."""
    if column not in table.colnames:
        return [default] * len(table)
    return [default if v is np.ma.masked else str(v) for v in table[column]]


def iso_minute(t: datetime) -> str:
    """``YYYY-MM-DDTHH:MM`` (UTC)."""
    return t.strftime("%Y-%m-%dT%H:%M")


def iso_ms(t: datetime, decimals: int = 3) -> str:
    """``YYYY-MM-DDTHH:MM:SS.sss`` (UTC) rounded to ``decimals`` ≤ 6 digits of the second."""
    step = 10 ** (6 - decimals)
    micro = t.microsecond + t.second * 1_000_000
    rounded = (micro + step // 2) // step * step  # half up
    t = t.replace(second=0, microsecond=0) + timedelta(microseconds=rounded)
    text = t.strftime("%Y-%m-%dT%H:%M:%S")
    if decimals > 0:
        text += f".{t.microsecond:06d}"[: decimals + 1]
    return text


def sexagesimal(value: float, decimals: int, sep: str, signed: bool, width: int = 2) -> str:
    """Sexagesimal string with correct carry (never ``60.00``) and ``-00`` for small negatives.

    ``value`` is in hours (RA) or degrees (Dec).
    """
    scale = 10**decimals
    total = round(abs(value) * 3600.0 * scale)
    if not signed:
        total %= 24 * 3600 * scale  # RA: 23 59 59.999 rounds to 00 00 00.00, not 24
    sign = "-" if (value < 0 and total > 0) else "+"
    whole, frac = divmod(total, scale)
    minutes_total, seconds = divmod(whole, 60)
    units, minutes = divmod(minutes_total, 60)
    sec = f"{seconds:02d}" + (f".{frac:0{decimals}d}" if decimals else "")
    head = f"{units:0{width}d}"
    return (sign if signed else "") + sep.join([head, f"{minutes:02d}", sec])


def coordinates(table: Table) -> tuple[np.ndarray, np.ndarray]:
    """ICRS RA, Dec [deg] from ``ra_deg``/``dec_deg`` or the sexagesimal ``ra_hms``/``dec_dms``."""
    if "ra_deg" in table.colnames and "dec_deg" in table.colnames:
        return floats(table, "ra_deg", unit="deg"), floats(table, "dec_deg", unit="deg")
    if "ra_hms" in table.colnames and "dec_dms" in table.colnames:
        from astropy.coordinates import Angle

        ra = Angle(strings(table, "ra_hms"), unit="hourangle").deg
        dec = Angle(strings(table, "dec_dms"), unit="deg").deg
        return np.asarray(ra, dtype=float), np.asarray(dec, dtype=float)
    raise InputFileError(
        "blocks table has neither ra_deg/dec_deg nor ra_hms/dec_dms columns; regenerate it with "
        "`ucbplan plan`"
    )


def period_s(table: Table, notes: list[str]) -> np.ndarray:
    """Orbital period per row [s]: ``period_s`` column, else 4 |t_alt − t_mid|, else NaN."""
    if "period_s" in table.colnames:
        values = floats(table, "period_s", unit="s")
        if np.all(np.isfinite(values)):
            return values
    mids = required_times(table, "t_mid_utc")
    alts = times_utc(table, "t_alt_utc", required=False)
    out = np.array(
        [
            4.0 * abs((a - m).total_seconds()) if a is not None else math.nan
            for a, m in zip(alts, mids, strict=True)
        ]
    )
    notes.append("no period_s column: P_b estimated as 4|t_alt_utc - t_mid_utc|")
    return out


def acquisition_s(table: Table, options: ExportOptions, notes: list[str]) -> np.ndarray:
    """Acquisition overhead per row [s]: option, else ``acq_s`` column, else the default."""
    if options.acquisition_s is not None:
        return np.full(len(table), float(options.acquisition_s))
    if "acq_s" in table.colnames:
        return floats(table, "acq_s", unit="s")
    planned = (table.meta or {}).get("overhead_s")
    if isinstance(planned, int | float) and math.isfinite(planned) and planned >= 0:
        notes.append(
            f"acquisition overhead {float(planned):.0f} s from the plan's overhead_s (the time "
            "`ucbplan plan` reserved before each session); pass --acquisition S to change it"
        )
        return np.full(len(table), float(planned))
    notes.append(
        f"no acq_s column: assuming {DEFAULT_ACQUISITION_S:.0f} s acquisition overhead; "
        "pass --acquisition S with your instrument's value"
    )
    return np.full(len(table), DEFAULT_ACQUISITION_S)


def readout_total_s(table: Table, notes: list[str]) -> np.ndarray:
    """Dead time inside each block [s]: n_exp·readout_s, else (t_end − t_start) − n_exp·exptime."""
    n_exp = floats(table, "n_exp")
    if "readout_s" in table.colnames:
        return n_exp * floats(table, "readout_s", unit="s")
    starts = required_times(table, "t_start_utc")
    ends = required_times(table, "t_end_utc")
    width = np.array([(e - s).total_seconds() for s, e in zip(starts, ends, strict=True)])
    notes.append("no readout_s column: readout taken as block width minus exposure time")
    return np.maximum(width - n_exp * floats(table, "exptime_s", unit="s"), 0.0)


def _file_vmag(entry: dict[str, Any]) -> float | None:
    """``vmag`` of the target file named in the table's provenance, if it is still readable."""
    path = entry.get("file")
    if not path:
        return None
    import hashlib
    from pathlib import Path

    from ucbplan.target import load_target

    try:
        digest = hashlib.sha256(Path(str(path)).read_bytes()).hexdigest()
        if entry.get("sha256") and digest != entry["sha256"]:
            return None  # the file changed since planning: do not trust it
        return load_target(str(path)).vmag
    except (UcbplanError, OSError):
        return None


def vmags(table: Table) -> np.ndarray:
    """V magnitude per row: ``vmag`` column, else ``meta['targets'][*]`` (its ``vmag`` or the
    ``vmag`` of the target file it names), else NaN."""
    out = floats(table, "vmag", default=math.nan)
    if np.all(np.isfinite(out)):
        return out
    items = table.meta.get("targets", []) if table.meta else []
    by_name = {
        str(t.get("name")): t.get("vmag") if t.get("vmag") is not None else _file_vmag(t)
        for t in items
        if isinstance(t, dict)
    }
    for i, name in enumerate(strings(table, "target")):
        value = by_name.get(name)
        if not math.isfinite(out[i]) and value is not None:
            out[i] = float(value)
    return out


def safe_name(name: str, max_len: int | None = None) -> str:
    """Spaces → underscores (optionally truncated), for catalogue and OB names."""
    text = "_".join(name.split())
    return text[:max_len] if max_len else text


def fmt_sigma(sigma_s: float) -> str:
    """σ with two significant figures (``0.6``, ``0.63``, ``12``) [s]."""
    if not math.isfinite(sigma_s):
        return "nan"
    return f"{sigma_s:.0f}" if sigma_s >= 10 else f"{sigma_s:.2g}"


def _mid_decimals(sigma_s: float) -> int:
    return 1 if sigma_s >= 0.1 else 3


def _created(table: Table) -> str:
    return str(table.meta.get("created_utc", "")) if table.meta else ""


def _site_name(table: Table) -> str:
    site = table.meta.get("site") if table.meta else None
    if isinstance(site, dict):
        return str(site.get("name", "unknown site"))
    return str(site) if site else "unknown site"


def _version() -> str:
    from ucbplan import __version__

    return __version__


def _order(table: Table) -> list[int]:
    mids = required_times(table, "t_mid_utc")
    return sorted(range(len(table)), key=lambda i: (mids[i], i))


# --------------------------------------------------------------------------------------------
# ESO p2: absolute time windows on the OB start
# --------------------------------------------------------------------------------------------


def _floor_minute(t: datetime) -> datetime:
    return t.replace(second=0, microsecond=0)


def _ceil_minute(t: datetime) -> datetime:
    base = _floor_minute(t)
    return base if base == t else base + timedelta(minutes=1)


def _eso_obs(table: Table, options: ExportOptions, notes: list[str]) -> list[dict[str, Any]]:
    mids = required_times(table, "t_mid_utc")
    starts = required_times(table, "t_start_utc")
    sigma = floats(table, "sigma_t_s", unit="s")
    acq = acquisition_s(table, options, notes)
    per = period_s(table, notes)
    names, blocks = strings(table, "target"), strings(table, "block_id")
    anchors = strings(table, "anchor")
    u_star = floats(table, "u_star_rad", unit="rad")
    exptime, n_exp = floats(table, "exptime_s", unit="s"), floats(table, "n_exp")
    sessions = strings(table, "session_id")
    obs: list[dict[str, Any]] = []
    for i in _order(table):
        mid, start = mids[i], starts[i]
        half = max(options.tolerance_sigma * float(sigma[i]), options.tolerance_floor_s)
        ob_start = start - timedelta(seconds=float(acq[i]))
        lo = ob_start - timedelta(seconds=half)
        hi = ob_start + timedelta(seconds=half)
        lo_min, hi_min = _floor_minute(lo), _ceil_minute(hi)
        widening = (lo - lo_min).total_seconds() + (hi_min - hi).total_seconds()
        obs.append(
            {
                "name": safe_name(blocks[i], 32),
                "target": names[i],
                "block_ids": [blocks[i]],
                "anchor": anchors[i],
                "u_star_rad": float(u_star[i]),
                "t_mid_utc": iso_ms(mid),
                "sigma_t_s": float(sigma[i]),
                "ob_start_utc": iso_ms(ob_start),
                "acquisition_s": float(acq[i]),
                "exptime_s": float(exptime[i]),
                "n_exp": int(n_exp[i]),
                "window_half_width_s": half,
                "window_exact_utc": {"from": iso_ms(lo), "to": iso_ms(hi)},
                "rounding_widening_s": widening,
                "_lo": lo_min,
                "_hi": hi_min,
                "_ob_start": ob_start,
                "_mid": mid,
                "_period_s": float(per[i]),
                "_members": [
                    {
                        "block_id": blocks[i],
                        "t_mid_utc": iso_ms(mid),
                        "sigma_t_s": float(sigma[i]),
                        "_mid": mid,
                    }
                ],
                "_session": sessions[i],
            }
        )
    obs = _group_sessions(obs)
    for ob in obs:
        per_s, widening = ob.pop("_period_s"), ob["rounding_widening_s"]
        if math.isfinite(per_s) and widening > options.rounding_warn_fraction * per_s:
            notes.append(
                f"ESO p2 {ob['name']}: minute rounding widens the OB start window by "
                f"{widening:.0f} s = {widening / per_s:.2f} P_b; the OB start no longer fixes "
                "the orbital phase: plan exposures covering the window and select in `reduce`"
            )
    return _resolve_overlaps(obs, options)


def _group_sessions(obs: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """One OB per planner session (one acquisition, e.g. a u = 0 / π pair); blank = own OB."""
    out: list[dict[str, Any]] = []
    first: dict[tuple[str, str], dict[str, Any]] = {}
    for ob in obs:  # time-ordered
        key = (ob["target"], ob.pop("_session"))
        lead = first.get(key) if key[1] else None
        if lead is None:
            first[key] = ob
            out.append(ob)
        else:
            _merge(lead, ob)
    return out


def _merge(lead: dict[str, Any], ob: dict[str, Any]) -> None:
    lead["block_ids"] = [*lead["block_ids"], *ob["block_ids"]]
    lead["_members"] = [*lead["_members"], *ob["_members"]]


def _resolve_overlaps(obs: list[dict[str, Any]], options: ExportOptions) -> list[dict[str, Any]]:
    obs = sorted(obs, key=lambda o: (o["_lo"], o["_ob_start"]))
    out: list[dict[str, Any]] = []
    for ob in obs:
        prev = out[-1] if out else None
        if prev is None or ob["_lo"] >= prev["_hi"]:
            out.append(ob)
            continue
        pair = f"{prev['block_ids'][-1]} and {ob['block_ids'][0]}"
        if not options.merge_overlaps or prev["target"] != ob["target"]:
            how = (
                "pass --merge-overlaps to execute them as one OB"
                if prev["target"] == ob["target"]
                else "drop one of them from the blocks table (different targets)"
            )
            raise UcbplanError(
                f"ESO p2: OB start windows of blocks {pair} overlap "
                f"({iso_minute(prev['_lo'])}-{iso_minute(prev['_hi'])} and "
                f"{iso_minute(ob['_lo'])}-{iso_minute(ob['_hi'])} UTC); {how}, "
                "or lower --tolerance-sigma"
            )
        _merge(prev, ob)
    return out


def _visits(ob: dict[str, Any]) -> list[dict[str, Any]]:
    """Every block of a merged OB with its mid-exposure offset from the nominal OB start."""
    return [
        {
            "block_id": m["block_id"],
            "t_mid_utc": m["t_mid_utc"],
            "sigma_t_s": m["sigma_t_s"],
            "mid_offset_from_ob_start_s": round((m["_mid"] - ob["_ob_start"]).total_seconds(), 3),
        }
        for m in ob["_members"]
    ]


def export_eso_p2(table: Table, options: ExportOptions) -> ExportResult:
    """ESO p2 absolute-time-window JSON: one OB per visit, windows on the OB start.

    A visit is a planner session (blocks sharing ``session_id``, e.g. a u = 0 / π pair observed
    after one acquisition) or a single block; a merged OB lists each block's mid-exposure offset
    from the nominal OB start in ``merged_visits``.

    The window is t_mid − (acquisition + exposure/2) ± max(k·σ_t, floor), i.e. the block start
    minus the acquisition overhead, rounded outward to whole minutes (p2 drops seconds). Each OB
    carries the p2api ``absoluteTimeConstraints`` list, the OBX ``absolute_times_list`` line, and
    the document carries the p2 target-list CSV lines.

    Raises
    ------
    UcbplanError
        When windows overlap (different targets, or the same target without ``merge_overlaps``).
    """
    notes: list[str] = []
    obs = _eso_obs(table, options, notes)
    ra, dec = coordinates(table)
    targets: dict[str, str] = {}
    for name, r, d in zip(strings(table, "target"), ra, dec, strict=True):
        targets.setdefault(
            name,
            f"{safe_name(name)},{sexagesimal(r / 15.0, 3, ':', False)},"
            f"{sexagesimal(d, 3, ':', True)},J2000",
        )
    for ob in obs:
        lo, hi = ob.pop("_lo"), ob.pop("_hi")
        if len(ob["_members"]) > 1:
            ob["merged_visits"] = _visits(ob)
        for key in ("_ob_start", "_mid", "_members"):
            ob.pop(key)
        ob["absoluteTimeConstraints"] = [{"from": iso_minute(lo), "to": iso_minute(hi)}]
        ob["obx_absolute_times_list"] = (
            f'absolute_times_list "{{{lo:%Y-%m-%dT%H:%M:%S} {hi:%Y-%m-%dT%H:%M:%S} 0}} "'
        )
    doc = {
        "format": "ucbplan eso-p2 absolute time windows, version 1",
        "ucbplan_version": _version(),
        "source_created_utc": _created(table),
        "site": _site_name(table),
        "time_scale": "UTC at the site; windows constrain the OB start (acquisition included)",
        "window_rule": (
            "OB start = t_start_utc - acquisition_s; window = OB start +/- "
            f"max({options.tolerance_sigma:g} sigma_t, {options.tolerance_floor_s:g} s), "
            "rounded outward to whole minutes"
        ),
        "p2api_usage": "api.saveAbsoluteTimeConstraints(obId, ob['absoluteTimeConstraints'], v)",
        "target_list_csv": list(targets.values()),
        "obs": obs,
    }
    text = json.dumps(doc, indent=2, allow_nan=False) + "\n"
    return ExportResult(text.encode(), ".json", tuple(dict.fromkeys(notes)))


# --------------------------------------------------------------------------------------------
# Keck starlist
# --------------------------------------------------------------------------------------------


def _keck_name(name: str, notes: list[str]) -> str:
    text = safe_name(name)
    if len(text) > 15:
        notes.append(f"Keck starlist: name {text!r} truncated to 15 characters")
        text = text[:15]
    return text


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
    names = strings(table, "target")
    anchors = strings(table, "anchor")
    u_star = floats(table, "u_star_rad", unit="rad")
    sigma = floats(table, "sigma_t_s", unit="s")
    mids = required_times(table, "t_mid_utc")
    vmag = vmags(table)
    seen: dict[str, str] = {}
    comments: dict[str, list[str]] = {}
    first: dict[str, int] = {}
    for i in _order(table):
        short = _keck_name(names[i], notes)
        if seen.setdefault(short, names[i]) != names[i]:
            raise InputFileError(
                f"Keck starlist: targets {seen[short]!r} and {names[i]!r} both become {short!r} "
                "(15-character limit); rename one in its target file"
            )
        first.setdefault(names[i], i)
        mid = mids[i]
        comments.setdefault(names[i], []).append(
            f"# {short} u*={u_star[i]:.6g} ({anchors[i]}) UTC-mid "
            f"{iso_ms(mid, _mid_decimals(float(sigma[i])))} +/-{fmt_sigma(float(sigma[i]))} s"
        )
    lines = [
        f"# ucbplan {_version()} Keck starlist; site {_site_name(table)}; times UTC at the site, "
        "+/- 1 sigma",
    ]
    for name, i in sorted(first.items(), key=lambda kv: kv[1]):
        lines.extend(comments[name])
        short = _keck_name(name, [])
        keys = []
        if math.isfinite(vmag[i]):
            keys.append(f"vmag={vmag[i]:.1f}")
        keys.append(f"rotmode={options.keck_rotmode}")
        lines.append(
            f"{short:<16}{sexagesimal(ra[i] / 15.0, 2, ' ', False)} "
            f"{sexagesimal(dec[i], 1, ' ', True)} 2000 " + " ".join(keys)
        )
    text = "\n".join(lines) + "\n"
    return ExportResult(text.encode("ascii"), ".txt", tuple(dict.fromkeys(notes)))


# --------------------------------------------------------------------------------------------
# ICS calendar (RFC 5545)
# --------------------------------------------------------------------------------------------


def ics_escape(text: str) -> str:
    """Escape a TEXT value (RFC 5545 §3.3.11): backslash, semicolon, comma, newline."""
    return text.replace("\\", "\\\\").replace(";", "\\;").replace(",", "\\,").replace("\n", "\\n")


def ics_fold(line: str) -> str:
    """Fold a content line at 75 octets (RFC 5545 §3.1), never inside a UTF-8 character."""
    data = line.encode("utf-8")
    if len(data) <= 75:
        return line
    parts: list[str] = []
    limit = 75
    while data:
        cut = min(limit, len(data))
        while cut < len(data) and (data[cut] & 0xC0) == 0x80:
            cut -= 1
        parts.append(data[:cut].decode("utf-8"))
        data = data[cut:]
        limit = 74  # continuation lines start with one space
    return "\r\n ".join(parts)


def _ics_stamp(t: datetime) -> str:
    return t.strftime("%Y%m%dT%H%M%SZ")


def _dtstamp(table: Table, first_start: datetime | None) -> str:
    created = _created(table)
    if created:
        try:
            return _ics_stamp(_parse_utc(created, "meta.created_utc", 0))
        except InputFileError:
            pass
    return _ics_stamp(first_start) if first_start else "19700101T000000Z"


def export_ics(table: Table, options: ExportOptions) -> ExportResult:
    """ICS calendar: one VEVENT per block, DTSTART/DTEND in UTC rounded outward to seconds.

    DTSTAMP is the table's ``meta.created_utc`` (else the first block start) so that the same
    table always gives the same file. UIDs are ``<block_id>@ucbplan``.
    """
    notes: list[str] = []
    names, blocks, anchors = (
        strings(table, "target"),
        strings(table, "block_id"),
        strings(table, "anchor"),
    )
    u_star = floats(table, "u_star_rad", unit="rad")
    sigma = floats(table, "sigma_t_s", unit="s")
    airmass = floats(table, "airmass")
    alt = floats(table, "altitude_deg", unit="deg")
    moon = floats(table, "moon_sep_deg", unit="deg")
    exptime, n_exp = floats(table, "exptime_s", unit="s"), floats(table, "n_exp")
    mids, starts, ends = (
        required_times(table, c) for c in ("t_mid_utc", "t_start_utc", "t_end_utc")
    )
    alts = times_utc(table, "t_alt_utc", required=False)
    tdb = strings(table, "t_mid_tdb_bary")
    order = _order(table)
    site = _site_name(table)
    stamp = _dtstamp(table, min(starts, default=None))
    lines = [
        "BEGIN:VCALENDAR",
        "VERSION:2.0",
        f"PRODID:-//ucbplan//ucbplan {_version()}//EN",
        "CALSCALE:GREGORIAN",
        "METHOD:PUBLISH",
    ]
    for i in order:
        mid, start, end = mids[i], starts[i], ends[i]
        s = fmt_sigma(float(sigma[i]))
        desc = [
            f"{names[i]} block {blocks[i]}: {anchors[i]}, u*={u_star[i]:.6g} rad (star 1)",
            f"mid-exposure UTC {iso_ms(mid)} +/- {s} s (1 sigma), at {site}",
            f"barycentric TDB {tdb[i]}",
            f"pi-mode alternative UTC {_alt_text(alts[i])}",
            f"{int(n_exp[i])} x {exptime[i]:g} s; airmass {airmass[i]:.2f}, altitude "
            f"{alt[i]:.1f} deg, Moon separation {moon[i]:.1f} deg",
        ]
        event = [
            "BEGIN:VEVENT",
            f"UID:{safe_name(blocks[i])}@ucbplan",
            f"DTSTAMP:{stamp}",
            f"DTSTART:{_ics_stamp(start.replace(microsecond=0))}",
            f"DTEND:{_ics_stamp(_ceil_second(end))}",
            "SUMMARY:" + ics_escape(f"{names[i]} {anchors[i]} u*={u_star[i]:.3g} +/-{s} s"),
            "DESCRIPTION:" + ics_escape("\n".join(desc)),
            "LOCATION:" + ics_escape(site),
            "TRANSP:OPAQUE",
            "END:VEVENT",
        ]
        lines.extend(event)
    lines.append("END:VCALENDAR")
    text = "".join(ics_fold(line) + "\r\n" for line in lines)
    return ExportResult(text.encode("utf-8"), ".ics", tuple(notes))


def _alt_text(t: datetime | None) -> str:
    return iso_ms(t) if t is not None else "none"


def _ceil_second(t: datetime) -> datetime:
    base = t.replace(microsecond=0)
    return base if base == t else base + timedelta(seconds=1)


# --------------------------------------------------------------------------------------------
# Proposal table and registry
# --------------------------------------------------------------------------------------------


def export_proposal(table: Table, options: ExportOptions) -> ExportResult:
    """Proposal technical-section table per target (:mod:`~ucbplan.observing.exports.proposal`)."""
    from ucbplan.observing.exports.proposal import proposal_table, write_proposal

    notes: list[str] = []
    summary = proposal_table(table, options, notes)
    text = write_proposal(summary, options.proposal_format)
    suffix = {"ecsv": ".ecsv", "csv": ".csv", "latex": ".tex"}[options.proposal_format]
    return ExportResult(text.encode("utf-8"), suffix, tuple(dict.fromkeys(notes)))


def export_ing_cat(table: Table, options: ExportOptions) -> ExportResult:
    """ING (WHT/ISIS) ``.cat`` catalogue, one line per target (see ``proposal.ing_catalogue``)."""
    from ucbplan.observing.exports.proposal import ing_catalogue

    return ExportResult(ing_catalogue(table).encode("ascii"), ".cat")


def export_lco(table: Table, options: ExportOptions) -> ExportResult:
    """LCO/SOAR OCS request-group JSON, TIME_CRITICAL (see ``proposal.lco_requests``)."""
    from ucbplan.observing.exports.proposal import lco_json

    notes: list[str] = []
    acquisition_s(table, options, notes)
    return ExportResult(lco_json(table, options).encode(), ".json", tuple(notes))


Exporter = Callable[[Table, ExportOptions], ExportResult]

#: Export formats by name (``ucbplan export --to NAME``).
EXPORTERS: dict[str, Exporter] = {
    "eso-p2": export_eso_p2,
    "keck-starlist": export_keck_starlist,
    "ics": export_ics,
    "proposal": export_proposal,
    "ing-cat": export_ing_cat,
    "lco": export_lco,
}


def export_blocks(table: Table, to: str, options: ExportOptions | None = None) -> ExportResult:
    """Export a master blocks table in the format named ``to``.

    Raises
    ------
    UcbplanError
        For an unknown format name (the message lists the known ones) or an empty table.
    """
    try:
        exporter = EXPORTERS[to]
    except KeyError:
        raise UcbplanError(
            f"--to: unknown export format {to!r}; expected one of {', '.join(EXPORTERS)}"
        ) from None
    if len(table) == 0:
        raise InputFileError("blocks table has no rows: nothing to export; re-run `ucbplan plan`")
    return exporter(table, options or ExportOptions())
