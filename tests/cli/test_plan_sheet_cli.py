"""``plan --plot/--sheet/--tz`` through the CLI (issue 15): every night charted, a night sheet per
night, the site's zone replaced; a wrong suffix fails before any file is written."""

from __future__ import annotations

from html.parser import HTMLParser
from pathlib import Path

from astropy.table import Table
from support.cli import run_cli
from typer.testing import CliRunner

from ucbplan.cli.app import app

ROOT = Path(__file__).resolve().parents[2]
HM = ROOT / "catalogs" / "hm-cnc-simulated.yaml"
BASE = ["plan", str(HM), "--site", "paranal", "--night", "2040-02-15", "--nights", "2"]


class _Text(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.text: list[str] = []

    def handle_data(self, data: str) -> None:
        self.text.append(data)


def test_plot_sheet_and_tz(tmp_path: Path) -> None:
    out, pdf, html = tmp_path / "b.ecsv", tmp_path / "n.pdf", tmp_path / "s.html"
    args = [*BASE, "-o", str(out), "--plot", str(pdf), "--sheet", str(html), "--tz", "UTC"]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    table = Table.read(out, format="ascii.ecsv")
    assert set(table["timezone"]) == {"UTC"}
    # with UTC as the zone, local time equals UTC time
    assert all(
        str(a)[11:19] == str(b)[11:19]
        for a, b in zip(table["t_mid_local"], table["t_mid_utc"], strict=True)
    )
    assert pdf.read_bytes().count(b"/Type /Page\n") + pdf.read_bytes().count(b"/Type /Page ") >= 2
    parser = _Text()
    parser.feed(html.read_text(encoding="utf-8"))
    text = " ".join(parser.text)
    assert "2040-02-16" in text and "2040-02-17" in text  # both nights' UTC dates


def test_wrong_sheet_suffix_fails_before_planning(tmp_path: Path) -> None:
    out, sheet = tmp_path / "b.ecsv", tmp_path / "s.docx"
    code, err = run_cli([*BASE, "-o", str(out), "--sheet", str(sheet)])
    assert code == 2 and "--sheet" in err.strip().splitlines()[-1]
    assert not out.exists() and not sheet.exists()
