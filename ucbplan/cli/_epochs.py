"""Epoch options shared by commands: one parser for ``--at``, ``--optical-epoch`` and the like."""

from __future__ import annotations

from typing import Any

__all__ = ["epoch_option"]


def epoch_option(text: str, what: str) -> Any:
    """An epoch option as an astropy ``Time`` (TDB).

    ``"BJD_TDB …"``/``"BMJD_TDB …"`` keep full precision (two-part JD; HJD and UTC-based words
    are refused with how to convert); anything else is ISO/MJD/JD TDB, or UTC when labelled so
    (:func:`ucbplan.core.epochs.parse_tdb`).
    """
    from ucbplan.core.epochs import parse_tdb
    from ucbplan.core.timing_epochs import TIMING_EPOCH_WORDS, parse_timing_epoch
    from ucbplan.errors import InputError

    word = text.strip().split(" ", 1)[0].upper().replace("-", "_")
    if word in TIMING_EPOCH_WORDS or word.startswith(("BJD", "BMJD", "HJD", "HMJD")):
        try:
            return parse_timing_epoch(text)
        except ValueError as exc:
            raise InputError(f"{what}: {exc}") from None
    return parse_tdb(text, what)
