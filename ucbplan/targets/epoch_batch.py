"""Timing epochs of many target files read in one vectorised :class:`~astropy.time.Time` per
format (issue 34): inside :func:`prebuilt_epochs`, :func:`take_epoch` hands out a T0 read ahead,
the very Time :func:`~ucbplan.core.timing_epochs.parse_timing_epoch` builds for it (the same
jd1/jd2 bits, format and scale: ``tests/targets/test_target_epoch_batch.py``), at the cost of
a slice instead of a Time and its year check of its own.

Read ahead: the spellings ``"BJD_TDB 2458305.6827886"`` (a word of
:data:`~ucbplan.core.timing_epochs.TIMING_EPOCH_WORDS`, unlabelled or labelled TDB, then a plain
decimal) whose year passes the check; any other text, and a text met a second time, is read by
``parse_timing_epoch`` itself, which gives every message.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from typing import Any

import numpy as np
from astropy.time import Time

from ucbplan.core.epochs import YEAR_RANGE, split_scale_label, years_of
from ucbplan.core.timing_epochs import (
    MAX_TIMING_EPOCH_CHARS,
    TIMING_EPOCH_WORDS,
    _split_decimal,
)

#: Inside :func:`prebuilt_epochs`: epoch text → its Time, each handed out once.
_READ: ContextVar[dict[str, Time] | None] = ContextVar("ucbplan_timing_epochs", default=None)


def word_epoch(text: Any) -> tuple[str, float, float] | None:
    """``(format, whole, fraction)`` of a ``"<word> <decimal>"`` epoch as
    ``parse_timing_epoch`` splits it, or None for any other text."""
    if type(text) is not str or len(text) > MAX_TIMING_EPOCH_CHARS:
        return None
    body, label = split_scale_label(text.strip())
    head, _, number = body.partition(" ")
    fmt = TIMING_EPOCH_WORDS.get(head.upper().replace("-", "_"))
    parts = _split_decimal(number.strip()) if fmt and label in (None, "tdb") else None
    return None if parts is None or fmt is None else (fmt, *parts)


def read_ahead(texts: Iterable[Any]) -> dict[str, Time]:
    """The word epochs among ``texts`` (each distinct text once) as TDB Times, one vectorised
    Time per format; those outside the years of the check left out."""
    by_format: dict[str, list[tuple[str, float, float]]] = {}
    for text in dict.fromkeys(t for t in texts if type(t) is str):
        split = word_epoch(text)
        if split is not None:
            by_format.setdefault(split[0], []).append((text, split[1], split[2]))
    out: dict[str, Time] = {}
    for fmt, rows in by_format.items():
        whole = np.array([r[1] for r in rows])
        frac = np.array([r[2] for r in rows])
        try:
            times = Time(whole, frac, format=fmt, scale="tdb")
        except (ValueError, TypeError, OverflowError):  # each read alone says why
            continue
        year = years_of(times.jd1, times.jd2)  # year_of, per epoch
        inside = (YEAR_RANGE[0] <= year) & (year <= YEAR_RANGE[1])
        out.update((rows[k][0], times[k]) for k in np.flatnonzero(inside))
    return out


@contextmanager
def prebuilt_epochs(texts: Iterable[Any]) -> Iterator[None]:
    """Within: the word epochs among ``texts`` are read ahead (:func:`take_epoch`)."""
    token = _READ.set(read_ahead(texts))
    try:
        yield
    finally:
        _READ.reset(token)


def take_epoch(text: Any) -> Time | None:
    """The Time read ahead for ``text`` (once), or None: read it yourself."""
    read = _READ.get()
    if read is None or type(text) is not str:
        return None
    return read.pop(text, None)
