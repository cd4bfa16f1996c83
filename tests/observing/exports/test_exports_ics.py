"""ICS calendar: the golden file, parsed by ``icalendar`` and checked against the blocks table."""

from __future__ import annotations

from datetime import UTC, datetime, timedelta

import icalendar
import numpy as np
import pytest
from astropy.table import Table
from hypothesis import given, settings
from hypothesis import strategies as st
from support.exports import golden, golden_export, ms, written_table

from ucbplan.observing.exports import ExportOptions, export_blocks
from ucbplan.observing.exports.ics import ics_escape, ics_fold

NAME = "exports_calendar.ics"


@pytest.fixture(scope="module")
def table(tmp_path_factory: pytest.TempPathFactory) -> Table:
    return written_table(tmp_path_factory.mktemp("exports"))


def test_golden(table: Table) -> None:
    assert golden_export(table, NAME) == golden(NAME), (
        f"{NAME} differs; see tests/support/exports.py"
    )


def test_golden_lines_are_crlf_and_folded_at_75_octets() -> None:
    raw = golden(NAME)
    assert raw.endswith(b"\r\n") and raw.count(b"\n") == raw.count(b"\r\n")  # CRLF only
    lines = raw[:-2].split(b"\r\n")
    assert all(len(line) <= 75 for line in lines)
    assert any(line.startswith(b" ") for line in lines)  # long DESCRIPTIONs were folded


def _utc_of(value: datetime) -> datetime:
    assert value.utcoffset() == timedelta(0), f"{value} is not UTC"
    return value.astimezone(UTC)


def _second(text: str, up: bool) -> datetime:
    """An ISO time rounded down (or up) to a whole second, in numpy datetime64 arithmetic (not the
    exporter's datetime code)."""
    exact = ms(text)
    second = exact.astype("datetime64[s]")  # floor for dates after 1970
    if up and second != exact:
        second += np.timedelta64(1, "s")
    return second.astype(datetime).replace(tzinfo=UTC)


def test_golden_parses_as_a_calendar_of_the_blocks(table: Table) -> None:
    cal = icalendar.Calendar.from_ical(golden(NAME))
    events = cal.walk("VEVENT")
    assert len(events) == len(table)
    rows = {f"{r['block_id']}@ucbplan": r for r in table}
    for event in events:
        row = rows.pop(str(event["UID"]))
        start = _utc_of(event.decoded("DTSTART"))
        end = _utc_of(event.decoded("DTEND"))
        # The block's UTC start and end, rounded outward to whole seconds.
        assert (start, end) == (_second(row["t_start_utc"], False), _second(row["t_end_utc"], True))
        assert _utc_of(event.decoded("DTSTAMP")) == datetime(2036, 12, 1, 12, tzinfo=UTC)
        assert str(event["LOCATION"]) == "Paranal"
        description = str(event["DESCRIPTION"]).split("\n")  # unescaped by the parser
        assert description[0].startswith(
            f"{row['target']} block {row['block_id']}: {row['anchor']}, "
        )
        assert f"mid-exposure UTC {row['t_mid_utc']} " in description[1]
        assert description[2] == f"barycentric TDB {row['t_mid_tdb_bary']}"
        assert str(row["target"]) in str(event["SUMMARY"])
    assert not rows


def test_ics_description_escapes(table: Table) -> None:
    raw = export_blocks(table, "ics", ExportOptions()).content.decode()
    lines = raw.replace("\r\n ", "").split("\r\n")
    desc = next(ln for ln in lines if ln.startswith("DESCRIPTION:"))
    assert "quadrature\\, u*=0 rad" in desc
    assert "+/- 0.6 s (1 sigma)\\, at Paranal" in desc
    assert "\\n" in desc


def test_ics_without_created_stamp_uses_first_start(table: Table) -> None:
    t = Table(table, copy=True)
    t.meta = {}
    cal = icalendar.Calendar.from_ical(export_blocks(t, "ics", ExportOptions()).content)
    stamps = {_utc_of(e.decoded("DTSTAMP")) for e in cal.walk("VEVENT")}
    assert stamps == {datetime(2037, 1, 15, 1, 1, 38, tzinfo=UTC)}  # first start, to the second


# Any text without control characters (RFC 5545 TEXT allows none but the escaped newline).
_TEXT = st.text(
    alphabet=st.one_of(st.characters(blacklist_categories=("Cs", "Cc")), st.just("\n")),
    max_size=300,
)


@given(_TEXT)
@settings(max_examples=200, deadline=None)
def test_ics_fold_round_trip(text: str) -> None:
    line = "DESCRIPTION:" + ics_escape(text)
    folded = ics_fold(line)
    parts = folded.encode("utf-8").split(b"\r\n")
    assert all(len(p) <= 75 for p in parts)  # each part decodes: never split inside a character
    assert folded.replace("\r\n ", "") == line
    # icalendar unfolds and unescapes it back to the text (its parser, not ours).
    event = icalendar.Event.from_ical(f"BEGIN:VEVENT\r\n{folded}\r\nEND:VEVENT\r\n")
    assert str(event["DESCRIPTION"]) == text
