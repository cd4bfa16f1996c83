"""Text the export formats write: ISO times, safe names, short σ's (sexagesimal angles:
:func:`ucbplan.observing.blocks.cells.sexagesimal`, the blocks table's own)."""

from __future__ import annotations

import math
import unicodedata
from datetime import datetime, timedelta

from ucbplan.errors import InputFileError, shorten

# Text formats
# --------------------------------------------------------------------------------------------


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


def safe_name(name: str, max_len: int | None = None) -> str:
    """Spaces → underscores, control characters dropped (optionally truncated), for catalogue
    and OB names."""
    text = "_".join("".join(ch for ch in name if ch.isprintable() or ch.isspace()).split())
    return text[:max_len] if max_len else text


#: Dash-like characters written as ``-`` in ASCII names (hyphens, en/em dashes, minus signs).
_DASHES = dict.fromkeys(
    map(ord, "\u2010\u2011\u2012\u2013\u2014\u2015\u2212\ufe58\ufe63\uff0d"), "-"
)
#: Letters NFKD does not decompose, spelled in ASCII.
_LETTERS = str.maketrans(
    {
        "ß": "ss",
        "æ": "ae",
        "Æ": "AE",
        "œ": "oe",
        "Œ": "OE",
        "ø": "o",
        "Ø": "O",
        "đ": "d",
        "Đ": "D",
        "ł": "l",
        "Ł": "L",
        "þ": "th",
        "Þ": "Th",
        "ı": "i",
        "ð": "d",
        "Ð": "D",
    }
)


def ascii_name(name: str) -> str:
    """``name`` in printable ASCII: dashes → ``-``, accents dropped (Unicode NFKD), a few
    letters spelled out (ß → ss, ø → o), any other non-ASCII character → ``_``; control
    characters dropped."""
    text = unicodedata.normalize("NFKD", name.translate(_DASHES).translate(_LETTERS))
    text = "".join(ch for ch in text if not unicodedata.combining(ch))
    text = "".join(ch if ch.isascii() else "_" for ch in text.translate(_DASHES))
    return "".join(ch for ch in text if ch.isprintable() or ch.isspace())


def ascii_text(text: str) -> str:
    """Free text (a site name, an anchor) as one line of printable ASCII (see
    :func:`ascii_name`)."""
    return " ".join(ascii_name(text).split())


def ascii_names(
    names: list[str],
    fmt: str,
    notes: list[str],
    max_len: int | None = None,
    drop: str = "",
    what: str = "target",
) -> dict[str, str]:
    """The ASCII catalogue name of each distinct target name for a format that takes ASCII only.

    Names are transliterated (:func:`ascii_name`, with a note), characters in ``drop`` become
    ``_``, white space ``_`` (:func:`safe_name`) and names are cut to ``max_len`` (with a note).

    Raises
    ------
    InputFileError
        A name without any ASCII letter or digit, or two names that become the same (both named).
    """
    out: dict[str, str] = {}
    owner: dict[str, str] = {}
    for name in dict.fromkeys(names):
        text = ascii_name(name)
        for ch in drop:
            text = text.replace(ch, "_")
        text = safe_name(text)
        if not any(ch.isalnum() for ch in text):
            raise InputFileError(
                f"{fmt}: {what} {shorten(name, 60)} has no ASCII spelling ({fmt} takes ASCII "
                "names only); give it an ASCII name in its target file"
            )
        if text != safe_name(name):
            notes.append(f"{fmt}: {what} {shorten(name, 60)} written as {text!r} (ASCII only)")
        if max_len and len(text) > max_len:
            notes.append(f"{fmt}: name {shorten(text, 60)} truncated to {max_len} characters")
            text = text[:max_len]
        if owner.setdefault(text, name) != name:
            raise InputFileError(
                f"{fmt}: {what}s {shorten(owner[text], 60)} and {shorten(name, 60)} both become "
                f"{text!r}"
                + (f" ({max_len}-character limit)" if max_len else "")
                + "; rename one in its target file"
            )
        out[name] = text
    return out


def fmt_sigma(sigma_s: float) -> str:
    """σ with two significant figures (``0.6``, ``0.63``, ``12``) [s]."""
    if not math.isfinite(sigma_s):
        return "nan"
    return f"{sigma_s:.0f}" if sigma_s >= 10 else f"{sigma_s:.2g}"
