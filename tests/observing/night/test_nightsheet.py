"""Night charts of every night and the night sheet (PDF one page per night, self-contained HTML).

The plan is a real 3-night ``ucbplan plan`` table (HM Cnc from Paranal, one quadrature session of
two blocks per night). Independent checks: the chart's edges are placed against the Sun's
altitude from astropy's own AltAz transform; the HTML is read back with ``html.parser``; PDF pages
are counted in the file's own page objects.
"""

from __future__ import annotations

import base64
import re
from pathlib import Path

import numpy as np
import pytest
from astropy import units as u
from astropy.coordinates import AltAz, get_sun
from astropy.table import Table, vstack
from astropy.time import Time
from support.night import SheetReader
from typer.testing import CliRunner

from ucbplan.cli.app import app
from ucbplan.errors import InputError, OutputExistsError
from ucbplan.observing.blocks.read import read_blocks
from ucbplan.observing.constraints import AirmassConstraint, ConstraintSet
from ucbplan.observing.night import chart as nightplot
from ucbplan.observing.night import sheet as nightsheet
from ucbplan.observing.night.chart import (
    chart_figure,
    group_visits,
    night_chart,
    write_night_charts,
)
from ucbplan.observing.night.countdown import visit_exposures
from ucbplan.observing.night.sheet import write_night_sheet
from ucbplan.observing.observatory.sites import Site, get_site
from ucbplan.plotting import pyplot
from ucbplan.plotting.layout import layout_problems

pytestmark = [
    pytest.mark.filterwarnings("ignore::erfa.ErfaWarning"),
    pytest.mark.filterwarnings("ignore::astropy.utils.exceptions.AstropyWarning"),
]

HM = Path(__file__).resolve().parents[3] / "catalogs" / "hm-cnc-simulated.yaml"
NIGHTS = ("2040-02-15", "2040-02-16", "2040-02-17")


@pytest.fixture(scope="module")
def table(tmp_path_factory: pytest.TempPathFactory) -> Table:
    out = tmp_path_factory.mktemp("plan") / "b.ecsv"
    args = ["plan", str(HM), "--site", "paranal", "--night", NIGHTS[0], "--nights", "3"]
    res = CliRunner().invoke(app, [*args, "--format", "ecsv", "-o", str(out)])
    assert res.exit_code == 0, res.output
    return read_blocks(out)


@pytest.fixture
def site() -> Site:
    return get_site("paranal")


def _pdf_pages(path: Path) -> int:
    return len(re.findall(rb"/Type\s*/Page[^s]", path.read_bytes()))


# -- visits ---------------------------------------------------------------------------------------


def test_visits_group_by_session_then_by_visit_id(table: Table, site: Site) -> None:
    by_session = group_visits(table, site)
    assert list(by_session) == list(NIGHTS)
    assert [len(v) for v in by_session.values()] == [1, 1, 1]
    assert all(len(v[0].rows) == 2 for v in by_session.values())
    split = table.copy()
    split["visit_id"] = [f"V{k}" for k in range(len(split))]
    assert [len(v) for v in group_visits(split, site).values()] == [2, 2, 2]
    one = table.copy()
    one["visit_id"] = "V"  # one id over three nights: still one visit per night
    assert [len(v) for v in group_visits(one, site).values()] == [1, 1, 1]


def test_table_without_positions_is_a_one_line_error(table: Table, site: Site) -> None:
    bare = table.copy()
    bare.remove_columns(["ra_deg", "dec_deg"])
    with pytest.raises(InputError, match="expected the columns ra_deg, dec_deg"):
        night_chart(bare, site)


def test_night_falls_back_to_local_evening_date(table: Table, site: Site) -> None:
    bare = table.copy()
    bare.remove_column("night")
    assert list(group_visits(bare, site)) == list(NIGHTS)


# -- charts ---------------------------------------------------------------------------------------


def _sun_alt_deg(site: Site, iso: str) -> float:
    t = Time(iso, scale="utc")
    frame = AltAz(obstime=t, location=site.location)
    return float(get_sun(t).transform_to(frame).alt.to_value(u.deg))


def test_chart_spans_sunset_to_sunrise_not_24_hours(table: Table, site: Site) -> None:
    """Edges 20 min outside sunset/sunrise: astropy's Sun is within ±1° of the horizon there
    (the Sun moves ~0.2°/min at Paranal; the edges are found on a 1-min grid)."""
    chart = night_chart(table, site)[0]
    fig = chart_figure([chart], site)
    ax = fig.axes[0]
    lo_h, hi_h = ax.get_xlim()
    assert 10.0 < hi_h - lo_h < 13.0  # a Paranal February night: ~11 h of dark + 40 min
    start = chart.window.start
    edges = [(start + (h * 3600 + s) * u.s).isot for h, s in ((lo_h, 1200), (hi_h, -1200))]
    for iso in edges:
        assert abs(_sun_alt_deg(site, iso)) < 1.0, iso
    assert "2040-02-15" in ax.get_xlabel() and "UTC" in ax.get_xlabel()
    pyplot().close(fig)


def test_chart_draws_visits_anchor_ticks_and_limits(table: Table, site: Site) -> None:
    cs = ConstraintSet(airmass=AirmassConstraint(max_airmass=1.5))
    chart = night_chart(table, site)[1]
    fig = chart_figure([chart], site, cs)
    ax = fig.axes[0]
    labels = {t.get_text() for t in ax.get_legend().get_texts()}
    assert {"Moon", "airmass 1.5", "visit (number)", "anchor epoch (block centre)"} <= labels
    ticks = [ln for ln in ax.get_lines() if ln.get_marker() == "|" and len(ln.get_xdata())]
    assert sum(len(ln.get_xdata()) for ln in ticks) == len(chart.visits[0].rows)
    assert layout_problems(fig) == []
    pyplot().close(fig)


def test_close_visits_get_numbers_that_do_not_overprint(table: Table, site: Site) -> None:
    """Each block its own visit: two visits 2.7 min apart, numbered 1 and 2 on two rows."""
    split = table.copy()
    split["visit_id"] = [f"V{k}" for k in range(len(split))]
    fig = chart_figure(night_chart(split, site)[:1], site)
    numbers = [t for t in fig.axes[0].texts if t.get_text().isdigit()]
    assert [t.get_text() for t in numbers] == ["1", "2"]
    assert numbers[0].get_position()[1] != numbers[1].get_position()[1]
    assert layout_problems(fig) == []
    pyplot().close(fig)


def test_every_night_charted_png_panels_and_pdf_pages(
    table: Table, site: Site, tmp_path: Path
) -> None:
    png, pdf = tmp_path / "n.png", tmp_path / "n.pdf"
    assert write_night_charts(table, site, png) == 3
    assert png.read_bytes()[:4] == b"\x89PNG"
    assert write_night_charts(table, site, pdf) == 3
    assert _pdf_pages(pdf) == 3
    fig = chart_figure(night_chart(table, site), site)
    assert len(fig.axes) == 3
    assert layout_problems(fig) == []
    pyplot().close(fig)
    with pytest.raises(OutputExistsError):
        write_night_charts(table, site, png)


def test_chart_refuses_other_formats(table: Table, site: Site, tmp_path: Path) -> None:
    with pytest.raises(InputError, match=r"^plot: expected a \.png, \.pdf or \.svg file"):
        write_night_charts(table, site, tmp_path / "n.jpg")
    assert nightplot.chart_format(Path("n.SVG")) == "svg"
    assert not list(tmp_path.iterdir())


def test_too_many_nights_for_one_image(
    table: Table, site: Site, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(nightplot, "MAX_PANELS", 2)
    with pytest.raises(InputError, match=r"give a \.pdf path"):
        write_night_charts(table, site, tmp_path / "n.png")
    assert not (tmp_path / "n.png").exists()


# -- the night sheet ------------------------------------------------------------------------------


def test_night_events_against_astropy_altaz(table: Table, site: Site) -> None:
    """Each reported crossing, evaluated with astropy's own AltAz (geometric, no refraction),
    lies within 0.3° of its altitude (1-min grid, linear interpolation; Sun 15°/h at most)."""
    from astropy.coordinates import get_body

    chart = night_chart(table, site)[0]
    events, illum = nightsheet.night_events(chart, site)
    names = [name for name, _ in events]
    assert names[:4] == [
        "sunset",
        "civil twilight ends",
        "nautical twilight ends",
        "astronomical twilight ends",
    ]
    assert names[-1] == "sunrise" and "moonset" in names
    levels = {"sunset": 0.0, "sunrise": 0.0, "civil": -6.0, "nautical": -12.0}
    levels |= {"astronomical": -18.0}
    for name, iso in events:
        t = Time(iso, scale="utc")
        frame = AltAz(obstime=t, location=site.location)
        if name.startswith("moon"):
            alt = get_body("moon", t, site.location).transform_to(frame).alt.to_value(u.deg)
            assert abs(alt) < 0.5, (name, iso, alt)
        else:
            level = levels[name.split()[0]]
            assert abs(_sun_alt_deg(site, iso) - level) < 0.3, (name, iso)
    assert 0.0 <= illum <= 1.0
    line = nightsheet.sky_line(chart, site)
    assert line.startswith("Sun and Moon (UTC, from 2040-02-15): sunset ")
    sunset = dict(events)["sunset"]
    fig = chart_figure([chart], site)
    assert f"sunset {nightplot.hhmm(sunset)}," in fig.axes[0].get_title()  # chart and sheet agree
    pyplot().close(fig)


def test_html_sheet_is_self_contained_and_says_what_to_do(
    table: Table, site: Site, tmp_path: Path
) -> None:
    """Per night the chart, per visit a heading, two lines for the assistant and one row per
    exposure whose start, end and anchor are the blocks table's (read back with html.parser)."""
    path = tmp_path / "night.html"
    assert write_night_sheet(table, site, path) == 3
    text = path.read_text(encoding="utf-8")
    reader = SheetReader()
    reader.feed(text)
    assert [s["h2"] for s in reader.sections] == [f"Paranal, night of {n}" for n in NIGHTS]
    assert all(u.startswith("data:image/png;base64,") for u in reader.urls)  # no network
    assert "<script src" not in text and "http" not in text.split("<body>")[1].split("<img")[0]
    for night, section in zip(NIGHTS, reader.sections, strict=True):
        (img,) = section["img"]
        assert base64.b64decode(img.split(",", 1)[1])[:4] == b"\x89PNG"
        (visit,) = section["visits"]
        rows = table[table["night"] == night]
        first = str(min(rows["t_start_utc"]))
        key = "visit_id" if "visit_id" in rows.colnames else "session_id"  # planner's visit id
        short = str(rows[key][0]).rsplit("-", 1)[-1]
        assert visit["h3"] == f"Visit 1: HM Cnc (simulated) ({short}), {first[:10]} UTC"
        assert f"RA {rows['ra_hms'][0]}, Dec {rows['dec_dms'][0]} (ICRS)" in visit["about"]
        tell = visit["tell"]
        assert len(tell) == 2
        start = Time(first, scale="utc") + 0.5 * u.s  # HH:MM:SS rounded to the second
        sigma = max(rows["sigma_t_s"])
        assert tell[0] == f"Acquire by {start.isot[11:19]} UTC, then 2 × 60 s."  # no readout
        assert tell[1].startswith(f"Starts are phase-critical ±{sigma:.2g} s: start each exposure")
        assert len(visit["rows"]) == len(rows)  # one row per exposure (n_exp = 1 here)
        for cell_row, row in zip(visit["rows"], rows, strict=True):
            _, begin, end, anchor, airmass, lam, sig, status, log = cell_row["cells"]
            assert log == "takenmissedskipped"  # the observing log's buttons
            t0 = Time(str(row["t_start_utc"]), scale="utc")
            assert begin == (t0 + 0.5 * u.s).isot[11:19]
            assert end == (t0 + (float(row["exptime_s"]) + 0.5) * u.s).isot[11:19]
            assert anchor.startswith(f"quadrature u★={row['u_star_rad']:.3f} (")
            assert str(row["t_mid_utc"])[11:19] in anchor
            assert (airmass, lam) == (f"{row['airmass']:.2f}", f"{row['lambda_k']:.3f}")
            assert sig == f"{row['sigma_t_s']:.2g}" and status == ""  # filled by the clock
            assert int(cell_row["attrs"]["data-start"]) == round(t0.unix * 1000)


def test_html_sheet_prints_a_page_per_night_in_portrait(
    table: Table, site: Site, tmp_path: Path
) -> None:
    path = tmp_path / "night.html"
    write_night_sheet(table, site, path)
    text = path.read_text(encoding="utf-8")
    assert "@page{size:portrait" in text  # A4 or Letter, whichever the printer has
    assert "section.night{break-before:page}" in text
    assert "@media print{#clock,.status,.log{display:none}" in text  # no stale clock on paper


def test_pdf_sheet_has_one_page_per_night(table: Table, site: Site, tmp_path: Path) -> None:
    path = tmp_path / "night.pdf"
    assert write_night_sheet(table, site, path) == 3
    assert path.read_bytes()[:5] == b"%PDF-"
    assert _pdf_pages(path) == 3
    with pytest.raises(OutputExistsError):
        write_night_sheet(table, site, path)
    assert write_night_sheet(table, site, path, overwrite=True) == 3


def test_pdf_sheet_continues_a_long_night_on_more_pages(
    table: Table, site: Site, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(nightsheet, "_LINES_PER_PAGE", 2)
    monkeypatch.setattr(nightsheet, "_LINES_PER_CONTINUATION", 3)
    path = tmp_path / "night.pdf"
    write_night_sheet(table, site, path)
    head = len(nightsheet._wrap(nightsheet.plan_note(table))) + 1
    lines = [
        head
        + len(nightsheet._wrap(nightsheet.sky_line(c, site)))
        + 1
        + len(nightsheet._text_lines(c, table.meta))
        for c in night_chart(table, site)
    ]
    assert _pdf_pages(path) == sum(1 + int(np.ceil((n - 2) / 3)) for n in lines)


def test_pdf_text_has_a_row_per_exposure(table: Table, site: Site) -> None:
    for chart in night_chart(table, site):
        text = nightsheet._text_lines(chart, table.meta)
        (visit,) = chart.visits
        for row in visit.rows:
            start = (Time(str(row["t_start_utc"]), scale="utc") + 0.5 * u.s).isot[11:19]
            rows = [line.split() for line in text if re.match(r"^  V\d+/\d+ ", line)]
            assert sum(1 for cells in rows if cells[1] == start) == 1
        assert all(len(line) <= nightsheet._WIDTH for line in text)


def _crowded(table: Table, n: int) -> Table:
    """The first night's session repeated ``n`` times, 30 min apart, as ``n`` visits."""
    first = table[table["night"] == NIGHTS[0]]
    parts = []
    for k in range(n):
        part = first.copy()
        for name in ("t_start_utc", "t_mid_utc", "t_end_utc"):
            shifted = Time(list(part[name]), scale="utc") + (k * 30 - 120) * u.min
            part[name] = [t.isot for t in shifted]
        part["visit_id"] = f"V{k:02d}"
        part["block_id"] = [f"{b}-{k}" for b in part["block_id"]]
        parts.append(part)
    return vstack(parts)


def test_pdf_pages_of_a_crowded_night_are_laid_out(table: Table, site: Site) -> None:
    """Twelve visits: numbers in rows on the chart, the list continued on a second page, and no
    text of any page overprinting another or leaving the page."""
    crowded = _crowded(table, 12)
    (chart,) = night_chart(crowded, site)
    pages = nightsheet._pdf_pages(chart, site, None, nightsheet.plan_note(crowded), crowded.meta)
    assert len(pages) >= 2
    for fig in pages:
        assert layout_problems(fig) == []
        pyplot().close(fig)


def test_instruction_with_acquisition_time_and_magnitude(table: Table, site: Site) -> None:
    rich = table.copy()
    rich["acq_s"] = 300.0
    rich["vmag"] = 13.94
    visit = group_visits(rich, site)[NIGHTS[0]][0]
    exposures = visit_exposures(visit, rich.meta)
    start = Time(visit.start_utc, scale="utc")
    acquire = (start - 299.5 * u.s).isot  # independent: astropy's own time arithmetic, rounded
    about = nightsheet.visit_about(visit, exposures)
    assert f"acquisition starts {acquire[11:19]} UTC" in about
    assert "V = 13.9 mag" in about
    first, _ = nightsheet.visit_instruction(exposures)
    assert first.startswith(f"Acquire by {(start + 0.5 * u.s).isot[11:19]} UTC, then 2 × 60 s")


@pytest.mark.parametrize(
    ("name", "fmt"), [("n.pdf", "pdf"), ("n.HTML", "html"), ("n.htm", "html"), ("n.png", None)]
)
def test_sheet_format_by_suffix(name: str, fmt: str | None) -> None:
    if fmt is None:
        with pytest.raises(
            InputError, match=r"^sheet: expected a \.pdf or \.html file, got .n\.png"
        ):
            nightsheet.sheet_format(Path(name))
    else:
        assert nightsheet.sheet_format(Path(name)) == fmt


def test_sheet_refuses_other_formats_and_empty_plans(
    table: Table, site: Site, tmp_path: Path
) -> None:
    with pytest.raises(InputError, match=r"\.pdf or \.html"):
        write_night_sheet(table, site, tmp_path / "night.png")
    with pytest.raises(InputError, match="no blocks"):
        write_night_sheet(table[:0], site, tmp_path / "night.pdf")
    assert not list(tmp_path.iterdir())


def test_night_without_darkness_spans_the_whole_day() -> None:
    """Svalbard at midsummer: the Sun never sets, so the chart spans local noon to noon (24 h)
    instead of failing to find a sunset."""
    from datetime import date

    from ucbplan.observing.night.chart import plot_night
    from ucbplan.targets import load_target

    svalbard = Site("Svalbard", 15.6, 78.2, 500.0, "Arctic/Longyearbyen")
    fig = plot_night([load_target(HM)], svalbard, date(2040, 6, 21), [], 2.0)
    lo, hi = fig.axes[0].get_xlim()
    assert hi - lo == pytest.approx(24.0)
    assert "sunset" not in fig.axes[0].get_title()
    assert layout_problems(fig) == []  # 2-hourly ticks over 24 h
    pyplot().close(fig)


def test_instruction_of_a_one_hour_visit(telescope_plan: Path, site: Site) -> None:
    """The issue's plan: 'acquire by, then N × T s with R s readout', N counting exposures."""
    plan = read_blocks(telescope_plan)
    visit = group_visits(plan, site)["2040-02-15"][0]
    rows = plan[plan["visit_id"] == visit.visit_id]
    t = float(rows["exptime_s"][0])
    shown = f"{t:.0f}" if abs(t - round(t)) < 1e-3 else f"{t:.1f}"  # whole seconds when whole
    first, second = nightsheet.visit_instruction(visit_exposures(visit, plan.meta))
    start = (Time(visit.start_utc, scale="utc") + 0.5 * u.s).isot[11:19]
    n = int(np.sum(rows["n_exp"]))
    assert first == f"Acquire by {start} UTC, then {n} × {shown} s with 45 s readout."
    assert second.startswith(f"Starts are phase-critical ±{max(rows['sigma_t_s']):.2g} s")
