"""The units an observatory executes: visits of many exposures, and whether a queue can run them.

A blocks table has one row per block (``n_exp`` exposures of ``exptime_s``, one readout apart);
a *unit* is what one acquisition serves: the rows sharing a ``visit_id`` (a visit of many
exposures), else a ``session_id`` (e.g. a u = 0 / π pair), else one row. Every export writes one
observation (OB, request, observation, calendar event group) per unit, so its exposure count
and shutter time add up to the plan's.

A service-mode queue runs a unit's exposures back to back from its first planned start: it
cannot wait between them. The unit is *back to back* when no wait between its exposures (the
time beyond the readout) exceeds :data:`~ucbplan.observing.schedule.settings.QUEUE_WAIT_S`, the
wait ``ucbplan plan --service-mode`` allows. The phase-locked and untargeted cadences are back
to back; a targeted visit (idle waits for the next anchor) or a session of two anchors is not,
and runs as planned only in visitor mode: run back to back, exposure k would start early by the
waits before it (``drift_s`` at most).
"""

from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime, timedelta

import numpy as np
from astropy.table import Table

from ucbplan.observing.exports.columns import floats, required_times, strings
from ucbplan.observing.exports.interface import ExportOptions
from ucbplan.observing.schedule.settings import QUEUE_WAIT_S

#: The note of a format without exposure fields (``fmt``: its name, ``mark``: its comment mark).
NO_EXPOSURE_FIELD = (
    "{fmt}: the format has no exposure time or count field: each block's exposures "
    "(n x t s) and each target's totals are in its {mark} comment lines; set them in the "
    "instrument software"
)


@dataclass(frozen=True, slots=True)
class ExportUnit:
    """One acquisition and the exposures after it.

    Attributes
    ----------
    unit_id : str
        ``visit_id``, else ``session_id``, else ``block_id`` of its first row.
    target : str
        Target name.
    rows : tuple of int
        Table rows of the unit, in start order.
    exptimes_s : tuple of float
        Exposure time of every exposure [s], in time order.
    starts : tuple of datetime
        Planned start of every exposure (UTC).
    end : datetime
        End of the last exposure (UTC).
    drift_s : float
        Largest early start of an exposure when the unit runs back to back from its first
        start: the sum of the waits planned before it [s].
    max_wait_s : float
        Longest single wait between two exposures beyond the readout [s].
    half_width_s : float
        The unit's timing window half-width, max(k·σ_t, floor), of its first row [s].
    """

    unit_id: str
    target: str
    rows: tuple[int, ...]
    exptimes_s: tuple[float, ...]
    starts: tuple[datetime, ...]
    end: datetime
    drift_s: float
    max_wait_s: float
    half_width_s: float

    @property
    def n_exposures(self) -> int:
        """Number of exposures."""
        return len(self.exptimes_s)

    @property
    def shutter_s(self) -> float:
        """Total exposure (shutter-open) time [s]."""
        return float(sum(self.exptimes_s))

    @property
    def start(self) -> datetime:
        """Start of the first exposure (UTC)."""
        return self.starts[0]

    @property
    def back_to_back(self) -> bool:
        """Whether a queue running the exposures back to back executes them as planned (no wait
        above :data:`QUEUE_WAIT_S`, module notes)."""
        return self.max_wait_s <= QUEUE_WAIT_S


def exposure_runs(unit: ExportUnit) -> list[tuple[float, int]]:
    """(exposure time [s], count) of each run of equal consecutive exposure times."""
    runs: list[tuple[float, int]] = []
    for t in unit.exptimes_s:
        if runs and runs[-1][0] == t:
            runs[-1] = (t, runs[-1][1] + 1)
        else:
            runs.append((t, 1))
    return runs


def _keys(table: Table) -> list[str]:
    """The unit key of every row: visit, else session, else block id."""
    visits, sessions = strings(table, "visit_id"), strings(table, "session_id")
    blocks = strings(table, "block_id")
    return [
        f"v:{v}" if v else (f"s:{t}\x00{s}" if s else f"b:{b}")
        for v, s, b, t in zip(visits, sessions, blocks, strings(table, "target"), strict=True)
    ]


def _row_exposures(
    start: datetime, end: datetime, n_exp: int, exptime: float, readout: float
) -> list[datetime]:
    """Start of each of a block's ``n_exp`` exposures (one ``readout`` apart; without a readout
    column the dead time is spread evenly between the block's start and end)."""
    if n_exp > 1 and not np.isfinite(readout):
        readout = ((end - start).total_seconds() - n_exp * exptime) / (n_exp - 1)
    step = exptime + (readout if np.isfinite(readout) else 0.0)
    return [start + timedelta(seconds=k * step) for k in range(n_exp)]


@dataclass(frozen=True, slots=True)
class _Cols:
    starts: list[datetime]
    ends: list[datetime]
    exptime: np.ndarray
    n_exp: np.ndarray
    readout: np.ndarray


def _exposures(
    rows: list[int], c: _Cols
) -> tuple[list[datetime], list[float], tuple[float, float]]:
    """Every exposure's start and time of ``rows`` (start order), and the drift and longest
    wait [s] (module notes)."""
    times: list[datetime] = []
    exps: list[float] = []
    drift = longest = 0.0
    for k, j in enumerate(rows):
        if k:  # the wait between the previous row's last exposure and this row's first
            prev = rows[k - 1]
            readout = float(c.readout[prev]) if np.isfinite(c.readout[prev]) else 0.0
            wait = max((c.starts[j] - c.ends[prev]).total_seconds() - readout, 0.0)
            drift, longest = drift + wait, max(longest, wait)
        count = int(c.n_exp[j])
        times += _row_exposures(c.starts[j], c.ends[j], count, c.exptime[j], c.readout[j])
        exps += [float(c.exptime[j])] * count
    return times, exps, (drift, longest)


def export_units(table: Table, options: ExportOptions) -> list[ExportUnit]:
    """The units of ``table`` (module notes), in start order."""
    c = _Cols(
        required_times(table, "t_start_utc"),
        required_times(table, "t_end_utc"),
        floats(table, "exptime_s", unit="s"),
        floats(table, "n_exp"),
        floats(table, "readout_s", default=np.nan, unit="s"),
    )
    sigma = floats(table, "sigma_t_s", unit="s")
    groups: dict[str, list[int]] = {}
    for i, key in enumerate(_keys(table)):
        groups.setdefault(key, []).append(i)
    ids, names = strings(table, "visit_id"), strings(table, "target")
    sessions, blocks = strings(table, "session_id"), strings(table, "block_id")
    units = []
    for rows in groups.values():
        rows.sort(key=lambda j: (c.starts[j], j))
        first = rows[0]
        times, exps, (drift, longest) = _exposures(rows, c)
        half = max(options.tolerance_sigma * float(sigma[first]), options.tolerance_floor_s)
        units.append(
            ExportUnit(
                ids[first] or sessions[first] or blocks[first],
                names[first],
                tuple(rows),
                tuple(exps),
                tuple(times),
                max(c.ends[j] for j in rows),
                drift,
                longest,
                half,
            )
        )
    return sorted(units, key=lambda un: (un.start, un.rows[0]))


def exposure_texts(table: Table) -> list[str]:
    """``exp N x T s`` of every row (its ``n_exp`` exposures of ``exptime_s``)."""
    exptime, n_exp = floats(table, "exptime_s", unit="s"), floats(table, "n_exp")
    return [f"exp {int(n)}x{t:g} s" for n, t in zip(n_exp, exptime, strict=True)]


def target_totals(table: Table) -> dict[str, str]:
    """Per target: ``N exposures, S s shutter in V visits`` over the whole table."""
    exptime, n_exp = floats(table, "exptime_s", unit="s"), floats(table, "n_exp")
    count: dict[str, int] = {}
    shutter: dict[str, float] = {}
    for name, n, t in zip(strings(table, "target"), n_exp, exptime, strict=True):
        count[name] = count.get(name, 0) + int(n)
        shutter[name] = shutter.get(name, 0.0) + int(n) * float(t)
    visits: dict[str, set[str]] = {}
    for name, key in zip(strings(table, "target"), _keys(table), strict=True):
        visits.setdefault(name, set()).add(key)
    return {
        name: f"{_plural(count[name], 'exposure')}, {shutter[name]:g} s shutter in "
        f"{_plural(len(visits[name]), 'visit')}"
        for name in count
    }


def _plural(n: int, word: str) -> str:
    return f"{n} {word}{'' if n == 1 else 's'}"
