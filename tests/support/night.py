"""The night sheet and countdown: plans, instants and readers their tests share."""

from __future__ import annotations

import re
from html.parser import HTMLParser
from typing import Any

from astropy import units as u
from astropy.table import Table
from astropy.time import Time


def _nights(table: Table, starts: list[tuple[Time, Time, str]]) -> list[str]:
    by_start = {str(r["t_start_utc"])[:19]: str(r["night"]) for r in table}
    return [by_start[s.isot[:19]] for s, _, _ in starts]


def table_starts(table: Table) -> list[tuple[Time, Time, str]]:
    """(start, end, target) of every exposure from the table, astropy arithmetic, time order."""
    out = []
    for row in table:
        t0 = Time(str(row["t_start_utc"]), scale="utc")
        step = float(row["exptime_s"]) + float(row["readout_s"])
        for k in range(int(row["n_exp"])):
            start = t0 + k * step * u.s
            out.append((start, start + float(row["exptime_s"]) * u.s, str(row["target"])))
    out.sort(key=lambda x: x[0].jd1 + x[0].jd2)
    return out


#: The named instants of :func:`instants`, in its order (the tests that visit each one).
INSTANT_NAMES = (
    "before the first",
    "just before a start",
    "during an exposure",
    "between exposures",
    "between visits",
    "between nights",
    "after the last",
)


def instants(table: Table) -> dict[str, Time]:
    """Named instants of the issue: before, during, between exposures, visits and nights, after."""
    starts = table_starts(table)
    first, second = starts[0], starts[1]
    nights = sorted(set(table["night"]))
    night2 = min(
        s[0] for s, n in zip(starts, _nights(table, starts), strict=True) if n == nights[1]
    )
    targets = [s[2] for s in starts]
    switch = next(k for k in range(1, len(starts)) if targets[k] != targets[k - 1])
    out = {
        "before the first": first[0] - 2 * u.h,
        "just before a start": first[0] - 7.3 * u.s,
        "during an exposure": first[0] + 14.6 * u.s,
        "between exposures": first[1] + 0.5 * (second[0] - first[1]),
        "between visits": starts[switch - 1][1] + 0.5 * (starts[switch][0] - starts[switch - 1][1]),
        "between nights": night2 - 10 * u.h,
        "after the last": starts[-1][1] + 1 * u.min,
    }
    assert tuple(out) == INSTANT_NAMES
    return out


def expected(table: Table, at: Time) -> tuple[Time, str] | None:
    """The first start at or after ``at`` and its target (None after the last)."""
    later = [(s, target) for s, _, target in table_starts(table) if (s - at).to_value(u.s) >= 0]
    return later[0] if later else None


def seconds_of(text: str) -> int:
    """``1 h 02 min 05 s`` / ``2 min 13 s`` / ``45 s`` in seconds."""
    m = re.fullmatch(r"(?:(\d+) h )?(?:(\d+) min )?(\d+) s", text)
    assert m is not None, text
    h, mi, s = (int(g) if g else 0 for g in m.groups())
    return 3600 * h + 60 * mi + s


class SheetReader(HTMLParser):
    """Reads a night sheet (the written file or a browser's DOM dump): per <section> its h2,
    images and visits (h3, the assistant's lines, rows with their attributes and cells), and the
    text and attributes of every element with an id (the clock)."""

    def __init__(self) -> None:
        super().__init__()
        self.sections: list[dict[str, Any]] = []
        self.urls: list[str] = []
        self.ids: dict[str, dict[str, Any]] = {}
        self._text: list[str] | None = None
        self._open: list[tuple[str, str | None]] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        a = {k: v or "" for k, v in attrs}
        if tag == "br":
            if self._text is not None:
                self._text.append("\n")
            return
        self.urls += [v or "" for k, v in attrs if k in ("src", "href")]
        if "id" in a:
            self.ids[a["id"]] = {"attrs": a, "text": ""}
        if tag not in ("br", "img", "meta"):
            self._open.append((tag, a.get("id")))
        if tag == "section":
            self.sections.append({"h2": "", "img": [], "visits": []})
        elif tag == "img" and self.sections:
            self.sections[-1]["img"].append(a.get("src", ""))
        elif tag == "h3":
            self.sections[-1]["visits"].append({"h3": "", "tell": [], "about": "", "rows": []})
        elif tag == "tr" and "data-start" in a:
            self.sections[-1]["visits"][-1]["rows"].append({"attrs": a, "cells": []})
        if tag in ("td", "h2", "h3") or (tag == "p" and self.sections):
            self._text = []

    def handle_endtag(self, tag: str) -> None:
        if self._open and self._open[-1][0] == tag:
            self._open.pop()
        if self._text is None:
            return
        text = "".join(self._text)
        visits = self.sections[-1]["visits"] if self.sections else []
        if tag == "td" and visits and visits[-1]["rows"]:
            visits[-1]["rows"][-1]["cells"].append(text)
        elif tag == "h2":
            self.sections[-1]["h2"] = text
        elif tag == "h3":
            visits[-1]["h3"] = text
        elif tag == "p" and visits:
            key = "tell" if visits[-1]["about"] else "about"
            visits[-1][key] = text.split("\n") if key == "tell" else text
        if tag in ("td", "h2", "h3", "p"):
            self._text = None

    def handle_data(self, data: str) -> None:
        if self._text is not None:
            self._text.append(data)
        for _, ident in self._open:
            if ident is not None:
                self.ids[ident]["text"] += data
