"""The HTML night sheet: one self-contained page, printable, with a live clock.

:func:`render_html` lays out what :mod:`ucbplan.observing.night.sheet` prepared — per night the
chart (a base64 PNG) and per visit a short header, two lines for the night assistant and one
table row per exposure (:data:`EXPOSURE_COLUMNS`, :func:`exposure_cells`, shared with the PDF).

The page carries its own CSS and a small plain JavaScript clock (no network asset, works from
``file://`` offline): a UTC clock, the next exposure start and a countdown to it, the running
and next rows highlighted, ended rows marked, and — while an exposure should be running — what
to do if its start was missed. ``?now=2027-06-15T08:20:00Z`` starts the clock at that instant
(rehearsal, tests), and it runs on from there; the page says so. The clock reads the rows'
``data-start``/``data-end`` (UTC milliseconds since 1970, as JavaScript's ``Date`` counts them)
and follows :func:`ucbplan.observing.night.countdown.what_next`: the next start is the first at or
after now. Printed (A4 or Letter, portrait), each night starts a page and the clock is hidden.
"""

from __future__ import annotations

import html
import json
from collections.abc import Sequence
from dataclasses import dataclass
from datetime import datetime

from ucbplan.observing.night.countdown import TimedExposure, hms
from ucbplan.observing.night.observing_log import STATUSES

#: Columns of the exposure table, one row per exposure (HTML and PDF).
EXPOSURE_COLUMNS = ("#", "start UTC", "end UTC", "anchor (epoch UTC)", "airmass", "Λ_K", "σ_t [s]")


@dataclass(frozen=True, slots=True)
class SheetVisit:
    """A visit on the sheet: heading, one line about the target, two lines for the assistant,
    its exposures in time order, and their observing-log cells
    (:func:`ucbplan.observing.night.observing_log.log_cells`; empty: no log buttons)."""

    heading: str
    about: str
    tell: tuple[str, ...]
    exposures: tuple[TimedExposure, ...]
    log: tuple[tuple[str, ...], ...] = ()


@dataclass(frozen=True, slots=True)
class SheetNight:
    """A night on the sheet: heading, the Sun and Moon line, the chart (base64 PNG), visits."""

    heading: str
    sky: str
    chart_png: str
    visits: tuple[SheetVisit, ...]


def exposure_cells(e: TimedExposure) -> tuple[str, ...]:
    """The cells of an exposure's row (:data:`EXPOSURE_COLUMNS`): times HH:MM:SS UTC (rounded
    to the second), the anchor with u★ [rad] and its epoch (ms cut to 0.1 s)."""
    epoch = e.anchor_utc.strftime("%H:%M:%S.%f")[:10]
    return (
        e.label,
        hms(e.start),
        hms(e.end),
        f"{e.anchor} u★={e.u_star_rad:.3f} ({epoch})",
        f"{e.airmass:.2f}",
        f"{e.lambda_k:.3f}",
        f"{e.sigma_t_s:.2g}",
    )


def _ms(t: datetime) -> int:
    """UTC milliseconds since 1970 (POSIX, as JavaScript's ``Date``)."""
    return round(t.timestamp() * 1000)


_STYLE = """
body{font-family:sans-serif;font-size:11pt;color:#000;background:#fff;max-width:190mm;
margin:0 auto;padding:0 4mm}
h1{font-size:15pt}h2{font-size:13pt;margin:.6em 0 .2em}h3{font-size:11.5pt;margin:.9em 0 .2em}
p{margin:.2em 0}img{max-width:100%;max-height:105mm;display:block}
table{border-collapse:collapse;width:100%;font-variant-numeric:tabular-nums}
th,td{border:1px solid #000;padding:1px 4px;text-align:right;white-space:nowrap}
td:nth-child(4),th:nth-child(4){text-align:left}
.tell{border-left:4px solid #000;padding-left:6px;font-weight:bold}
.status{text-align:left;min-width:7em}
td.log{text-align:left}td.log button{font-size:9pt;padding:0 3px;margin:0 1px}
tr[data-status=taken] button[data-status=taken],tr[data-status=missed] button[data-status=missed],
tr[data-status=skipped] button[data-status=skipped]{background:#000;color:#fff;font-weight:bold}
#save-log{font-size:11pt;margin-top:2px}
tr.done{color:#666;text-decoration:line-through}
tr.running td{font-weight:bold;border-top:3px double #000;border-bottom:3px double #000}
tr.next td{font-weight:bold;border-top:3px solid #000;border-bottom:3px solid #000;
background:#ffd}
#clock{position:sticky;top:0;background:#fff;border:2px solid #000;padding:4px 8px;
margin:4px 0;font-size:14pt;z-index:1}
#utc,#countdown{font-size:20pt;font-weight:bold;font-variant-numeric:tabular-nums}
#rehearsal{display:block;color:#a00;font-weight:bold;font-size:11pt}#rehearsal:empty{display:none}#advice{font-size:12pt}
section.night{break-before:page}section.night:first-of-type{break-before:auto}
.visit{break-inside:avoid-page}tr{break-inside:avoid}thead{display:table-header-group}
@page{size:portrait;margin:12mm}
@media print{#clock,.status,.log{display:none}body{max-width:none;font-size:9.5pt}
tr.next td,tr.running td{font-weight:normal;border:1px solid #000;background:none}
tr.done{color:#000;text-decoration:none}}
"""

_CLOCK_HTML = (
    '<div id="clock" role="timer" aria-live="off">'
    '<div><span id="rehearsal"></span>UTC <span id="utc">--:--:--</span></div>'
    '<div>next start <span id="next">&ndash;</span> in <span id="countdown">&ndash;</span></div>'
    '<div id="advice"></div>{log}</div>'
    "<noscript><p>The live clock needs JavaScript; the times below are UTC.</p></noscript>"
)
#: The "save log" button: the log's columns
#: (:data:`ucbplan.observing.night.observing_log.LOG_COLUMNS`) and its file name are read from it by
#: :data:`_LOG_SCRIPT`.
_SAVE_HTML = (
    '<button type="button" id="save-log" data-columns="{columns}" data-file="{file}">'
    "save log</button>"
)

#: The live clock (plain JavaScript, no library, no network; see the module docstring).
_SCRIPT = r"""
(function () {
  "use strict";
  var rows = Array.prototype.slice.call(document.querySelectorAll("tr[data-start]"));
  var q = /[?&]now=([^&#]*)/.exec(window.location.search);
  var offset = 0, rehearsal = "";
  if (q) {
    var text = decodeURIComponent(q[1]).trim().replace(" ", "T");
    if (!/([zZ]|[+-]\d\d:?\d\d)$/.test(text)) { text += "Z"; }
    var base = Date.parse(text);
    if (isNaN(base)) {
      rehearsal = "?now= not understood (use 2027-06-15T08:20:00Z); computer clock. ";
    } else {
      offset = base - Date.now();
      rehearsal = "REHEARSAL clock (?now=" + decodeURIComponent(q[1]) + ") ";
    }
  }
  function pad(n) { return (n < 10 ? "0" : "") + n; }
  function hms(ms) {
    var d = new Date(Math.round(ms / 1000) * 1000);
    return pad(d.getUTCHours()) + ":" + pad(d.getUTCMinutes()) + ":" + pad(d.getUTCSeconds());
  }
  function ymd(ms) { return new Date(ms).toISOString().slice(0, 10); }
  function wait(seconds) {
    var s = Math.max(Math.round(seconds), 0);
    var h = Math.floor(s / 3600), m = Math.floor((s % 3600) / 60), x = s % 60;
    if (h) { return h + " h " + pad(m) + " min " + pad(x) + " s"; }
    return m ? m + " min " + x + " s" : x + " s";
  }
  function el(id) { return document.getElementById(id); }
  function tick() {
    var now = Date.now() + offset;
    var next = null, running = null;
    rows.forEach(function (r) {
      var s = +r.getAttribute("data-start"), e = +r.getAttribute("data-end");
      var state = e <= now ? "done" : s < now ? "running" : "";
      if (!state && (!next || s < +next.getAttribute("data-start"))) { next = r; }
      if (state === "running") { running = r; }
      r.className = state;
    });
    if (next) { next.className = "next"; }
    rows.forEach(function (r) {
      var c = r.className;
      r.querySelector(".status").textContent =
        c === "done" ? "ended" : c === "running" ? "exposing?" : c === "next" ? "NEXT" : "";
    });
    var clock = el("clock");
    clock.setAttribute("data-now", String(now));
    el("rehearsal").textContent = rehearsal;
    el("utc").textContent = ymd(now) + " " + hms(now);
    var advice = "";
    if (next) {
      var start = +next.getAttribute("data-start");
      var seconds = Math.round((start - now) / 1000);
      clock.setAttribute("data-next", next.getAttribute("data-label"));
      clock.setAttribute("data-seconds", String(seconds));
      el("next").textContent = next.getAttribute("data-target") + " " +
        next.getAttribute("data-label") + " at " + hms(start) + " UTC" +
        (ymd(start) === ymd(now) ? "" : " (" + ymd(start) + ")");
      el("countdown").textContent = wait((start - now) / 1000);
      var acq = next.getAttribute("data-acq");
      if (acq && +acq > now) {
        advice = "New visit: acquisition starts " + hms(+acq) + " UTC. ";
      }
      if (running) {
        advice += running.getAttribute("data-label") + " should be exposing since " +
          hms(+running.getAttribute("data-start")) + " UTC. Start missed? Do not start it " +
          "late: start " + next.getAttribute("data-label") + " at " + hms(start) +
          " UTC (anchor " + next.getAttribute("data-anchor") + ").";
      }
    } else {
      clock.setAttribute("data-next", "");
      clock.removeAttribute("data-seconds");
      el("next").textContent = "none";
      el("countdown").textContent = "\u2013";
      advice = "The plan is over" + (running ? " when " +
        running.getAttribute("data-label") + " ends." : ".");
    }
    el("advice").textContent = advice;
  }
  tick();
  window.setInterval(tick, 250);
})();
"""

#: The observing log (plain JavaScript, no network): a button per status on each exposure row
#: marks it (again: unmarks it; kept in the browser's localStorage across reloads), and "save
#: log" downloads the marked rows as CSV (a Blob, as
#: :func:`ucbplan.observing.night.observing_log.log_text` writes it: rows in time order, cells
#: quoted only when they hold a comma, quote or newline).
_LOG_SCRIPT = r"""
(function () {
  "use strict";
  var save = document.getElementById("save-log");
  if (!save) { return; }
  var rows = Array.prototype.slice.call(document.querySelectorAll("tr[data-log]"));
  var key = "ucbplan-log-" + save.getAttribute("data-file");
  var kept = {};
  try { kept = JSON.parse(window.localStorage.getItem(key) || "{}"); } catch (e) { kept = {}; }
  function id(r) { return r.getAttribute("data-log"); }
  function count() {
    var n = rows.filter(function (r) { return r.getAttribute("data-status"); }).length;
    save.textContent = "save log (" + n + " marked)";
  }
  function mark(r, status) {
    if (status) {
      r.setAttribute("data-status", status);
      kept[id(r)] = status;
    } else {
      r.removeAttribute("data-status");
      delete kept[id(r)];
    }
    try { window.localStorage.setItem(key, JSON.stringify(kept)); } catch (e) { /* no storage */ }
    count();
  }
  rows.forEach(function (r) {
    if (kept[id(r)]) { r.setAttribute("data-status", kept[id(r)]); }
    r.querySelectorAll("button[data-status]").forEach(function (b) {
      b.addEventListener("click", function () {
        var s = b.getAttribute("data-status");
        mark(r, r.getAttribute("data-status") === s ? "" : s);
      });
    });
  });
  function cell(text) {
    return /[",\r\n]/.test(text) ? "\"" + text.replace(/"/g, "\"\"") + "\"" : text;
  }
  save.addEventListener("click", function () {
    var lines = [save.getAttribute("data-columns")];
    rows.slice().sort(function (a, b) {
      return +a.getAttribute("data-start") - +b.getAttribute("data-start");
    }).forEach(function (r) {
      var s = r.getAttribute("data-status");
      if (s) { lines.push(JSON.parse(id(r)).concat([s]).map(cell).join(",")); }
    });
    var blob = new Blob([lines.join("\n") + "\n"], {type: "text/csv"});
    var a = document.createElement("a");
    a.href = URL.createObjectURL(blob);
    a.download = save.getAttribute("data-file");
    document.body.appendChild(a);
    a.click();
    a.remove();
  });
  count();
})();
"""

#: The status buttons of an exposure row (:data:`ucbplan.observing.night.observing_log.STATUSES`).
_STATUS_BUTTONS = "".join(f'<button type="button" data-status="{s}">{s}</button>' for s in STATUSES)


def _row(e: TimedExposure, log: tuple[str, ...] | None) -> str:
    a = html.escape
    acq = f' data-acq="{_ms(e.acq_start)}"' if e.first_of_visit and e.acq_start else ""
    cells = "".join(f"<td>{a(c)}</td>" for c in exposure_cells(e))
    data = f' data-log="{a(json.dumps(log, ensure_ascii=False))}"' if log else ""
    buttons = f'<td class="log">{_STATUS_BUTTONS}</td>' if log else ""
    return (
        f'<tr data-start="{_ms(e.start)}" data-end="{_ms(e.end)}" data-label="{a(e.label)}" '
        f'data-target="{a(e.target)}" data-anchor="{a(e.anchor)}"{acq}{data}>{cells}'
        f'<td class="status"></td>{buttons}</tr>'
    )


def _visit(v: SheetVisit) -> str:
    a = html.escape
    head = "".join(f"<th>{a(c)}</th>" for c in EXPOSURE_COLUMNS)
    tell = "<br>".join(a(line) for line in v.tell)
    logs = v.log or (None,) * len(v.exposures)
    rows = "".join(_row(e, log) for e, log in zip(v.exposures, logs, strict=True))
    log_head = '<th class="log">log</th>' if v.log else ""
    return (
        f'<div class="visit"><h3>{a(v.heading)}</h3><p>{a(v.about)}</p>'
        f'<p class="tell">{tell}</p></div>'
        f'<table><thead><tr>{head}<th class="status">now</th>{log_head}</tr></thead>'
        f"<tbody>{rows}</tbody></table>"
    )


def _night(n: SheetNight) -> str:
    a = html.escape
    return (
        f'<section class="night"><h2>{a(n.heading)}</h2><p>{a(n.sky)}</p>'
        f'<img alt="altitude chart: {a(n.heading)}" src="data:image/png;base64,{n.chart_png}">'
        f"{''.join(_visit(v) for v in n.visits)}</section>"
    )


def render_html(
    title: str,
    note: str,
    nights: Sequence[SheetNight],
    log: tuple[Sequence[str], str] | None = None,
) -> str:
    """The whole page: title, the plan's note, the clock, then night by night; with ``log``
    (the log's columns and file name), the "save log" button and its script."""
    a = html.escape
    save, script = "", ""
    if log is not None:
        save = _SAVE_HTML.format(columns=a(",".join(log[0])), file=a(log[1]))
        script = f"<script>{_LOG_SCRIPT}</script>"
    return (
        '<!DOCTYPE html><html lang="en"><head><meta charset="utf-8">'
        '<meta name="viewport" content="width=device-width,initial-scale=1">'
        f"<title>{a(title)}</title><style>{_STYLE}</style></head>"
        f"<body><h1>{a(title)}</h1><p>{a(note)}</p>{_CLOCK_HTML.replace('{log}', save)}"
        f"{''.join(_night(n) for n in nights)}<script>{_SCRIPT}</script>{script}</body></html>\n"
    )
