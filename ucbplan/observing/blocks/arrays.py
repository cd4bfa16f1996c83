"""Blocks as columns: every :class:`~ucbplan.observing.blocks.block.Block` field as one array.

The planner builds its blocks as columns (one array per field, times as array ``Time``) and the
blocks table, the visit summaries and the information sums read the columns directly: a plan of
thousands of exposures then costs array operations, not one astropy scalar per time per block
(~25 µs each). :class:`BlockList` is the ``Sequence[Block]`` a plan hands out: it makes the
:class:`Block` records from its columns on first access only. :func:`block_columns` gives the
columns of any sequence of blocks (a plain list is converted once).
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass, fields
from typing import Any, overload

import erfa
import numpy as np
from astropy.time import Time
from numpy.typing import NDArray

from ucbplan.observing.blocks.block import Block

#: The :class:`Block` fields that are times, and the scale each is kept in.
TIME_FIELDS: dict[str, str] = {
    "t_mid_utc": "utc",
    "t_start_utc": "utc",
    "t_end_utc": "utc",
    "t_mid_tdb_bary": "tdb",
    "t_alt_utc": "utc",
}

#: The other :class:`Block` fields and the array type each is kept as.
VALUE_FIELDS: dict[str, Any] = {
    f.name: (int if f.type == "int" else float if f.type == "float" else str)
    for f in fields(Block)
    if f.name not in TIME_FIELDS
}


def jd_parts(times: Sequence[Time], scale: str | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Two-part Julian dates of scalar Times as stored, in ``scale`` (None: each in its own).

    Read from astropy's format object (``Time._time``) when there is one: ``Time.jd1`` costs
    ~10 µs a call in shape handling, ~2 s for the times of a semester's blocks table."""
    scaled = [t if scale is None or t.scale == scale else getattr(t, scale) for t in times]
    stored = [getattr(t, "_time", t) for t in scaled]
    return (
        np.array([t.jd1 for t in stored], dtype=float),
        np.array([t.jd2 for t in stored], dtype=float),
    )


def isot(times: Time, precision: int) -> list[str]:
    """``times.isot`` with ``precision`` decimals of the second, text for text: astropy's ISO
    format string filled from one ``erfa.d2dtf`` over the Julian dates as stored (astropy fills
    it one time at a time, ~15 µs each)."""
    return isot_array(times, precision).tolist()


def isot_array(times: Time, precision: int) -> NDArray[np.str_]:
    """:func:`isot` as a numpy text array, its digits made by array arithmetic for years of four
    digits (the format string filled time by time for others)."""
    scale = times.scale.upper().encode("ascii")
    jd1, jd2 = np.atleast_1d(times.jd1), np.atleast_1d(times.jd2)
    year, month, day, hmsf = erfa.d2dtf(scale, precision, jd1, jd2)
    parts = [year, month, day, hmsf["h"], hmsf["m"], hmsf["s"]]
    if precision > 0:
        parts.append(hmsf["f"])
    if not year.size or not bool(np.all((year >= 1000) & (year <= 9999))):
        fmt = "{:d}-{:02d}-{:02d}T{:02d}:{:02d}:{:02d}" + (
            f".{{:0{precision}d}}" if precision > 0 else ""
        )
        texts = [fmt.format(*p) for p in zip(*(a.tolist() for a in parts), strict=True)]
        return np.array(texts, dtype=str) if texts else np.array([], dtype="U1")
    text = _digit_text(parts, [4, 2, 2, 2, 2, 2, precision][: len(parts)], b"--T::.")
    return text.view(f"S{text.shape[1]}").ravel().astype(str)


def _digit_text(parts: list[NDArray[Any]], widths: list[int], seps: bytes) -> NDArray[np.uint8]:
    """One row of ASCII per element: each part's non-negative integers below ``10**width`` as
    ``width`` digits, the parts apart by ``seps`` (all digits found in one array pass)."""
    part = np.repeat(np.arange(len(widths)), widths)  # the part of each digit
    powers = 10 ** np.concatenate([np.arange(w - 1, -1, -1, dtype=np.int64) for w in widths])
    digits = (np.stack(parts, axis=1).astype(np.int64)[:, part] // powers) % 10
    starts = np.cumsum([0] + [w + 1 for w in widths[:-1]])  # where each part's digits start
    where = np.concatenate([np.arange(s, s + w) for s, w in zip(starts, widths, strict=True)])
    text = np.empty((parts[0].size, sum(widths) + len(widths) - 1), dtype=np.uint8)
    text[:, where] = digits + ord("0")
    text[:, starts[1:] - 1] = np.frombuffer(seps[: len(widths) - 1], dtype=np.uint8)
    return text


def time_array(times: Sequence[Time], scale: str) -> Time:
    """Scalar Times as one array Time in ``scale`` with exactly their two-part Julian dates.

    Arithmetic and formatting of the array then give, element by element, what the scalars
    give, at the cost of one attribute read per time instead of one astropy operation."""
    jd1, jd2 = jd_parts(times, scale)
    out = Time(jd1, jd2, format="jd", scale=scale)
    if np.array_equal(out.jd1, jd1) and np.array_equal(out.jd2, jd2):
        return out
    # Time() re-split some date: concatenate the scalars as they are (slower, same values)
    return Time([t if t.scale == scale else getattr(t, scale) for t in times])


@dataclass(frozen=True)
class BlockColumns:
    """The fields of ``n`` blocks: ``values`` (by field name, arrays of float, int or str),
    ``times`` (by field name, array ``Time`` in the scale of :data:`TIME_FIELDS`, each with the
    Julian-date split of the block's own time) and ``has_alt`` (the block has a π-mode
    alternative ``t_alt_utc``; where it has none, ``times['t_alt_utc']`` holds its centre)."""

    values: dict[str, NDArray[Any]]
    times: dict[str, Time]
    has_alt: NDArray[np.bool_]

    def __len__(self) -> int:
        return int(self.has_alt.size)

    @classmethod
    def from_blocks(cls, blocks: Sequence[Block]) -> BlockColumns:
        """The columns of Block records (each time converted to its column's scale)."""
        values = {
            name: np.array([getattr(b, name) for b in blocks], dtype=kind)
            for name, kind in VALUE_FIELDS.items()
        }
        has_alt = np.array([b.t_alt_utc is not None for b in blocks], dtype=bool)
        times = {}
        for name, scale in TIME_FIELDS.items():
            if name == "t_alt_utc":
                got = [b.t_alt_utc if b.t_alt_utc is not None else b.t_mid_utc for b in blocks]
            else:
                got = [getattr(b, name) for b in blocks]
            times[name] = time_array(got, scale) if blocks else Time([], format="jd", scale=scale)
        return cls(values, times, has_alt)

    @classmethod
    def concat(cls, parts: Sequence[BlockColumns]) -> BlockColumns:
        """One set of columns, ``parts`` one after the other."""
        if len(parts) == 1:
            return parts[0]
        if not parts:
            return cls.from_blocks([])
        values = {k: np.concatenate([p.values[k] for p in parts]) for k in VALUE_FIELDS}
        times = {}
        for name, scale in TIME_FIELDS.items():
            jd1 = np.concatenate([p.times[name].jd1 for p in parts])
            jd2 = np.concatenate([p.times[name].jd2 for p in parts])
            where = parts[0].times[name].location  # the site's, shared by a plan's times
            same = all(p.times[name].location is where for p in parts)
            joined = Time(jd1, jd2, format="jd", scale=scale, location=where if same else None)
            if not (same and np.array_equal(joined.jd1, jd1) and np.array_equal(joined.jd2, jd2)):
                joined = Time([p.times[name] for p in parts])  # keeps every split and location
            times[name] = joined
        return cls(values, times, np.concatenate([p.has_alt for p in parts]))

    def take(self, idx: NDArray[np.int64]) -> BlockColumns:
        """The blocks ``idx``, in that order."""
        return BlockColumns(
            {k: v[idx] for k, v in self.values.items()},
            {k: t[idx] for k, t in self.times.items()},
            self.has_alt[idx],
        )

    def time_order(self) -> NDArray[np.int64]:
        """Indices in time order of the block centres (stable: equal centres keep their order),
        as a sort on the stored two-part Julian dates."""
        mid = self.times["t_mid_utc"]
        return np.lexsort((mid.jd2, mid.jd1)).astype(np.int64)

    def lists(self, *names: str) -> list[list[Any]]:
        """Value columns as lists of plain Python values."""
        return [self.values[n].tolist() for n in names]

    def records(self) -> list[Block]:
        """One :class:`Block` per row."""
        n = len(self)
        cells = {k: v.tolist() for k, v in self.values.items()}
        times = {k: list(t) if n else [] for k, t in self.times.items()}
        has_alt = self.has_alt.tolist()
        out = []
        for i in range(n):
            kw = {k: v[i] for k, v in cells.items()}
            kw.update({k: v[i] for k, v in times.items()})
            if not has_alt[i]:
                kw["t_alt_utc"] = None
            out.append(Block(**kw))
        return out


class BlockList(Sequence[Block]):
    """Planned blocks held as :class:`BlockColumns`; the :class:`Block` records are made on
    first access. Compares equal to any sequence of the same blocks."""

    def __init__(self, columns: BlockColumns) -> None:
        self.columns = columns
        self._records: list[Block] | None = None

    def _rows(self) -> list[Block]:
        if self._records is None:
            self._records = self.columns.records()
        return self._records

    def __len__(self) -> int:
        return len(self.columns)

    @overload
    def __getitem__(self, k: int) -> Block: ...

    @overload
    def __getitem__(self, k: slice) -> list[Block]: ...

    def __getitem__(self, k: int | slice) -> Block | list[Block]:
        return self._rows()[k]

    def __iter__(self) -> Iterator[Block]:
        return iter(self._rows())

    def __eq__(self, other: object) -> bool:
        if isinstance(other, Sequence) and not isinstance(other, str):
            return len(self) == len(other) and list(self) == list(other)
        return NotImplemented

    __hash__ = None  # type: ignore[assignment]  # mutable cache, compared by value

    def __repr__(self) -> str:
        return f"BlockList({len(self)} blocks)"


def block_columns(blocks: Sequence[Block]) -> BlockColumns:
    """The columns of ``blocks`` (a :class:`BlockList`'s own, else converted once)."""
    if isinstance(blocks, BlockList):
        return blocks.columns
    return BlockColumns.from_blocks(blocks)
