"""The observing log: what became of each exposure of a plan (taken, missed or skipped).

The night sheet (a button per exposure row and a "save log" button,
:mod:`ucbplan.observing.night.sheet_html`) and ``ucbplan now --log FILE`` (a keypress per exposure)
write the same small CSV, which ``plan --observed`` / ``replan --observed`` read
(:mod:`ucbplan.api._observed`): one row per exposure marked, in time order, with the columns of
:data:`LOG_COLUMNS`. Exposures not marked are not written (neither taken nor known to be lost).

Each row carries what the information bookkeeping needs: the target, the exposure's own mid-time
(TDB at the barycentre), its exposure time, airmass, Λ_K and the plan's σ_v (replace it by the
measured σ_v when the reduction gives it), and the plan (:func:`plan_id`) and site it belongs
to, so that a log cannot be counted against another plan's targets or another site.
"""

from __future__ import annotations

import csv
import hashlib
import io
import math
import textwrap
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from datetime import datetime, timedelta
from pathlib import Path
from typing import IO, Any

from astropy.table import Table

from ucbplan.errors import InputError, InputFileError, shorten
from ucbplan.io import write_output
from ucbplan.observing.blocks.write import csv_safe_text, csv_unsafe_text
from ucbplan.observing.night.countdown import TimedExposure, plan_exposures
from ucbplan.observing.observatory.sites import Site

#: What may become of an exposure (only ``taken`` counts toward a goal).
STATUSES = ("taken", "missed", "skipped")
#: The key that marks the exposure just started with each status (``ucbplan now --log``).
LOG_KEYS = {"t": "taken", "m": "missed", "s": "skipped"}
#: The log's columns, in order; every writer and the reader use these.
LOG_COLUMNS = (
    "plan_id",
    "site",
    "target",
    "exposure",
    "block_id",
    "t_start_utc",
    "t_mid_tdb_bary",
    "exptime_s",
    "airmass",
    "lambda_k",
    "sigma_v_kms",
    "status",
)
#: Characters of the SHA-256 hex digest kept as the plan's identifier.
_ID_CHARS = 12


def plan_id(table: Table) -> str:
    """The plan's identifier: the first 12 hex digits of the SHA-256 of its blocks' ids and
    start times (the same for the ECSV, CSV and JSON of one plan; a replan is another plan)."""
    text = "\n".join(
        f"{b}|{str(t).strip()}"
        for b, t in zip(table["block_id"], table["t_start_utc"], strict=True)
    )
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:_ID_CHARS]


def _site_name(table: Table) -> str:
    entry = table.meta.get("site") if hasattr(table.meta, "get") else None
    return str(entry.get("name", "")) if isinstance(entry, Mapping) else ""


def _mid_tdb(row: Any, exposure: TimedExposure, index: int) -> str:
    """The exposure's mid-time, TDB at the barycentre: the block's anchor epoch moved by the
    exposure's place in the block (the Rømer delay changes by < 1e-4 s per s: < 0.1 s over a
    block of ≤ 1000 s, 1e-3 rad of an orbit of 10 min)."""
    n_exp = int(row["n_exp"])
    text = str(row["t_mid_tdb_bary"]).strip()
    if n_exp == 1:
        return text
    step = exposure.exptime_s + exposure.readout_s
    t = datetime.fromisoformat(text) + timedelta(seconds=(index - (n_exp - 1) / 2) * step)
    return t.isoformat(timespec="microseconds")


def _iso_ms(t: datetime) -> str:
    return t.strftime("%Y-%m-%dT%H:%M:%S.%f")[:23]


def _number(value: Any) -> str:
    x = float(value)
    return repr(x) if math.isfinite(x) else ""


def log_file_name(table: Table) -> str:
    """The file name the night sheet saves the log of ``table`` as."""
    return f"observing-log-{plan_id(table)}.csv"


def log_cells(
    table: Table, site: Site | None = None
) -> list[tuple[TimedExposure, tuple[str, ...]]]:
    """Every exposure of the plan in time order with its log cells (:data:`LOG_COLUMNS`
    without ``status``; ``site``: as :func:`~ucbplan.observing.night.countdown.plan_exposures`):
    text cells neutralised for spreadsheets (:func:`~ucbplan.observing.blocks.write.csv_safe_text`),
    which :func:`read_log` undoes."""
    rows = {str(r["block_id"]): r for r in table}
    ident, site_name = plan_id(table), _site_name(table)
    sigma = "sigma_v_kms" in table.colnames
    out: list[tuple[TimedExposure, tuple[str, ...]]] = []
    seen: dict[str, int] = {}
    for e in plan_exposures(table, site):
        row = rows[e.block_id]
        k = seen[e.block_id] = seen.get(e.block_id, -1) + 1
        cells = (
            ident,
            csv_safe_text(site_name),
            csv_safe_text(e.target),
            csv_safe_text(e.label),
            csv_safe_text(e.block_id),
            str(row["t_start_utc"]).strip() if k == 0 else _iso_ms(e.start),
            _mid_tdb(row, e, k),
            _number(e.exptime_s),
            _number(e.airmass),
            _number(e.lambda_k),
            _number(row["sigma_v_kms"]) if sigma else "",
        )
        out.append((e, cells))
    return out


def log_text(cells: Sequence[tuple[str, ...]], statuses: Sequence[str]) -> str:
    """The log's CSV text: the header, then the marked rows (a status "" is not written)."""
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(LOG_COLUMNS)
    for row, status in zip(cells, statuses, strict=True):
        if status:
            writer.writerow([*row, status])
    return buf.getvalue()


def is_log(text: str) -> bool:
    """Whether ``text`` is an observing log (its first line is the log's header)."""
    first = text.lstrip("\ufeff").split("\n", 1)[0].strip()
    return first.split(",") == list(LOG_COLUMNS)


#: The log's numeric columns (a blank cell reads as NaN).
_NUMBERS = ("exptime_s", "airmass", "lambda_k", "sigma_v_kms")


def _value(name: str, text: str) -> Any:
    """A cell as read: a number (blank: NaN), or the text a CSV writer neutralised."""
    return (float(text) if text else math.nan) if name in _NUMBERS else csv_unsafe_text(text)


def _check_cell(where: str, i: int, name: str, value: str) -> None:
    """A numeric or time cell of a log row (1-based ``i``), as the reader needs it."""
    expected = None
    if name in _NUMBERS:
        try:
            bad = not math.isfinite(float(value)) or float(value) <= 0
        except ValueError:
            bad = True
        expected = "a positive number" if bad else None
    elif name in ("t_start_utc", "t_mid_tdb_bary"):
        try:
            datetime.fromisoformat(value)
        except ValueError:
            expected = "an ISO time (2040-02-16T01:40:00.000)"
    if expected is not None:
        raise InputFileError(
            f"{where}: row {i}, column {name}: expected {expected}, got {shorten(value, 40)}; "
            "fix the cell (sigma_v_kms: the measured σ_v, km/s)"
        )


def _rows(text: str, where: str) -> list[dict[str, str]]:
    rows = list(csv.reader(io.StringIO(text.lstrip("\ufeff"))))
    out = []
    for i, row in enumerate(rows[1:], start=1):
        if not any(c.strip() for c in row):
            continue
        if len(row) != len(LOG_COLUMNS):
            raise InputFileError(
                f"{where}: row {i}: expected {len(LOG_COLUMNS)} cells "
                f"({', '.join(LOG_COLUMNS)}), got {len(row)}; write the log again"
            )
        cells = dict(zip(LOG_COLUMNS, (c.strip() for c in row), strict=True))
        for name in LOG_COLUMNS[4:-1]:
            if name != "block_id" and (cells["status"] == "taken" or name != "sigma_v_kms"):
                _check_cell(where, i, name, cells[name])
        out.append(cells)
    return out


def read_log(path: Path | str) -> Table:
    """An observing log as a table (``meta``: the ``site`` name and the ``plan_id``).

    Raises
    ------
    InputFileError
        Not a log; a row of the wrong length; a bad number or time (one line naming the row and
        the column); rows of several plans or sites.
    """
    from ucbplan.inputs import read_text

    path = Path(path)
    where = shorten(str(path), 120).strip("'")
    text = read_text(path, "observing log")
    if not is_log(text):
        raise InputFileError(
            f"{where}: expected an observing log (first line {','.join(LOG_COLUMNS)}), got "
            f"{shorten(text.split(chr(10), 1)[0], 60)}; save it with the night sheet's save-log "
            "button or `ucbplan now`'s `log`"
        )
    rows = _rows(text, where)
    table = Table(
        {c: [_value(c, r[c]) for r in rows] for c in LOG_COLUMNS},
        dtype=[float if c in _NUMBERS else str for c in LOG_COLUMNS],
    )
    for name in ("plan_id", "site"):
        values = sorted({r[name] for r in rows})
        if len(values) > 1:
            raise InputFileError(
                f"{where}: column {name}: expected one value (a log of one plan), got "
                f"{shorten(', '.join(values), 80)}; keep one plan's rows per log"
            )
    site = csv_unsafe_text(rows[0]["site"]) if rows else ""
    table.meta["plan_id"] = rows[0]["plan_id"] if rows else ""
    if site:  # a log of a plan without a site (a CSV plan) says none
        table.meta["site"] = {"name": site}
    return table


def check_log_plan(path: Path | str, table: Table) -> None:
    """Refuse an observing log of another plan than ``table`` (a file that is no log, or a log
    without rows, passes: the reader judges it).

    Raises
    ------
    InputError
        ``path`` is a log whose ``plan_id`` is not ``table``'s (one line, naming both).
    """
    from ucbplan.inputs import read_text

    path = Path(path)
    if not is_log(read_text(path, "observing log")):
        return
    theirs, ours = str(read_log(path).meta["plan_id"]), plan_id(table)
    if theirs and theirs != ours:
        raise InputError(
            f"observed {path}: a log of another plan (plan_id {theirs}, this plan {ours}); give "
            "the log of this plan's nights",
            parameter="observed",
        )


def _existing(path: Path) -> Table:
    """The log already at ``path`` (refused when it is another kind of file)."""
    from ucbplan.inputs import read_text

    if not is_log(read_text(path, "observing log")):
        raise InputError(
            f"log {path}: the file exists and is not an observing log; give a new file name, "
            "or `overwrite` to replace it",
            parameter="log",
        )
    return read_log(path)


@dataclass
class ObservingLog:
    """``ucbplan now --log FILE``: the statuses of a plan's exposures, written after each mark.

    Build it with :meth:`open`. :meth:`mark` records a status and rewrites the whole file
    atomically (a temporary beside it, then a rename), so a crash loses no mark.
    """

    path: Path
    exposures: list[TimedExposure]
    cells: list[tuple[str, ...]]
    statuses: list[str] = field(default_factory=list)

    @classmethod
    def open(cls, table: Table, path: Path | str, *, overwrite: bool = False) -> ObservingLog:
        """The log of ``table`` at ``path``, written at once (the header, or the marks kept).

        An existing log of the same plan is continued (its marks kept: ``now`` restarted after
        a crash); another file there is refused unless ``overwrite`` (then it starts empty).

        Raises
        ------
        InputError
            ``path`` holds a log of another plan or site, or another file.
        """
        path = Path(path)
        pairs = log_cells(table)
        log = cls(path, [e for e, _ in pairs], [c for _, c in pairs], [""] * len(pairs))
        if path.exists() and not overwrite:
            log._resume(_existing(path), plan_id(table), _site_name(table))
        log._write()
        return log

    def _resume(self, old: Table, ident: str, site: str) -> None:
        """Take the marks of an existing log of this plan (checked to be this plan's)."""
        theirs = str(old.meta["plan_id"])
        if len(old) and theirs != ident:
            raise InputError(
                f"log {self.path}: a log of another plan (plan_id {theirs}, this plan "
                f"{ident}); give a new file name, or `overwrite` to start it again",
                parameter="log",
            )
        where = {
            (csv_unsafe_text(c[4]), csv_unsafe_text(c[3])): k for k, c in enumerate(self.cells)
        }
        for row in old:
            k = where.get((str(row["block_id"]), str(row["exposure"])))
            if k is None or str(row["site"]) != site:
                raise InputError(
                    f"log {self.path}: exposure {shorten(str(row['exposure']), 30)} at "
                    f"{shorten(str(row['site']), 30)} is not in this plan at {site}; give a "
                    "new file name, or `overwrite` to start it again",
                    parameter="log",
                )
            if str(row["status"]) not in STATUSES:
                raise InputError(
                    f"log {self.path}: exposure {row['exposure']}, column status: expected one "
                    f"of {', '.join(STATUSES)}, got {shorten(str(row['status']), 30)}; fix it, "
                    "or `overwrite` to start the log again",
                    parameter="log",
                )
            self.statuses[k] = str(row["status"])

    def mark(self, exposure: TimedExposure, status: str) -> None:
        """Record ``status`` (:data:`STATUSES`) for ``exposure`` and write the log."""
        if status not in STATUSES:
            raise InputError(
                f"log: expected a status {', '.join(STATUSES)}, got {shorten(status, 30)}",
                parameter="status",
            )
        self.statuses[self.exposures.index(exposure)] = status
        self._write()

    def _write(self) -> None:
        text = log_text(self.cells, self.statuses)

        def _write(handle: IO[str]) -> None:
            handle.write(text)

        write_output(self.path, _write, overwrite=True)


def log_lines(log: ObservingLog, previous: TimedExposure | None, width: int = 100) -> list[str]:
    """The ``log`` entry of a ``now --log`` frame, wrapped to ``width`` columns under its
    10-column tag as the countdown's: the mark of the exposure just started (the one a key
    marks), how many are marked and how many earlier ones are not, and the keys."""
    keys = ", ".join(f"{k} {s}" for k, s in LOG_KEYS.items())
    if previous is None:
        text = f"no exposure started yet; then keys {keys}"
    else:
        k = log.exposures.index(previous)
        unmarked = sum(1 for s in log.statuses[:k] if not s)
        marked = sum(1 for s in log.statuses if s)
        text = (
            f"{previous.label} {log.statuses[k] or 'not marked'}; {marked} marked, "
            f"{unmarked} earlier not; keys {keys}, q quit"
        )
    return textwrap.wrap(text, width, initial_indent=f"{'log':<10}", subsequent_indent=" " * 10)
