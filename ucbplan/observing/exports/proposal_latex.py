"""The proposal table as a LaTeX ``table`` that fits the text width of a standard page.

Written by hand (astropy's LaTeX writer does not escape column names and cannot wrap a cell).
The target and phase columns are paragraph columns of fixed width that wrap long text; every other
column holds a short number, so the table's width is bounded: :func:`latex_width_pt` estimates it
from Computer Modern glyph widths and the export refuses nothing but states the estimate in the
file. Target: :data:`TEXTWIDTH_PT`, the ``\\textwidth`` of LaTeX's ``article`` class at 10 pt
(the narrowest common proposal page; A4 with 2.5 cm margins gives 455 pt).
"""

from __future__ import annotations

import math

import numpy as np
from astropy.table import Table

from ucbplan.observing.exports.text import fmt_sigma

#: ``\textwidth`` of the ``article`` class at 10 pt [pt].
TEXTWIDTH_PT = 345.0
#: ``\footnotesize`` in a 10 pt document [pt] (1 em of Computer Modern at that size).
FONT_PT = 8.0
#: ``\tabcolsep`` set in the table [pt] (LaTeX's default is 6 pt).
TABCOLSEP_PT = 2.0
#: Widths of the paragraph columns (target, phases) [cm] and in pt (1 cm = 28.45 pt).
P_COLUMNS_CM = {"target": 2.0, "anchors": 1.8}
_PT_PER_CM = 72.27 / 2.54

#: Column key → (header, unit line, alignment); ``p`` columns wrap.
_COLUMNS = {
    "target": ("Target", "", "p"),
    "vmag": ("$V$", "mag", "r"),
    "p_orb_min": (r"$P_\mathrm{orb}$", "min", "r"),
    "sigma_t_mid_s": (r"$\sigma_T$", "s", "r"),
    "anchors": (r"Phases $u_\star$", "rad", "p"),
    "tolerance_rad": ("Tol.", "rad", "r"),
    "n_visits": ("Vis.", "", "r"),
    "integration_h": ("Exp.", "h", "r"),
    "overhead_h": ("Overh.", "h", "r"),
    "idle_h": ("Idle", "h", "r"),
    "total_h": ("Total", "h", "r"),
}
#: Plain-text stand-ins of the math headers for the width estimate (upright, full size).
_HEADER_PROXY = {"$V$": "V", r"$P_\mathrm{orb}$": "Porb", r"$\sigma_T$": "sT"}

#: LaTeX's special characters in text and how to write them.
_LATEX_SPECIAL = {
    "\\": r"\textbackslash{}",
    "_": r"\_",
    "&": r"\&",
    "%": r"\%",
    "#": r"\#",
    "$": r"\$",
    "{": r"\{",
    "}": r"\}",
    "~": r"\textasciitilde{}",
    "^": r"\textasciicircum{}",
}


def _latex_escape(text: str) -> str:
    """Text for a LaTeX table cell: special characters escaped, line breaks and other control
    characters dropped (one pass, so an escape is never escaped again)."""
    return "".join(
        _LATEX_SPECIAL.get(ch, ch)
        for ch in " ".join(text.split())
        if ch.isprintable() and not 0xD800 <= ord(ch) <= 0xDFFF
    )


def _glyph_em(ch: str) -> float:
    """Upper bound of a Computer Modern glyph's width [em] (cmr10 metrics: digits 0.5 em,
    lowercase ≤ 0.556 em but m, w 0.833/0.722, capitals ≤ 0.75 em but M, W 0.917/1.028)."""
    if ch.isdigit():
        return 0.5
    if ch in ".,:;'":
        return 0.278
    if ch in " -()/":
        return 0.389
    if ch in "mw":
        return 0.833
    if ch in "MW":
        return 1.028
    if ch.islower():
        return 0.556
    return 0.778  # capitals and the rest (+, $-$ = 0.778 em)


def _text_pt(text: str) -> float:
    plain = _HEADER_PROXY.get(text, text).replace("$-$", "-")
    return sum(_glyph_em(ch) for ch in plain) * FONT_PT


def _hours(value: float) -> str:
    """Hours to three significant figures at most (0.55, 12.3, 1194): proposals ask for tenths."""
    if not math.isfinite(value):
        return "--"
    return format(value, ".2f" if value < 10 else ".1f" if value < 100 else ".0f")


def _cells(summary: Table) -> dict[str, list[str]]:
    """Every body cell (and the total row) as LaTeX text, by column key."""

    def num(value: object, fmt: str) -> str:
        v = float(value) if value is not np.ma.masked else math.nan  # type: ignore[arg-type]
        return "--" if not math.isfinite(v) else format(v, fmt)

    cols: dict[str, list[str]] = {k: [] for k in _COLUMNS}
    for r in summary:
        cols["target"].append(_latex_escape(str(r["target"])))
        cols["vmag"].append(num(r["vmag"], ".1f"))
        cols["p_orb_min"].append(num(r["p_orb_min"], ".3f"))
        cols["sigma_t_mid_s"].append(fmt_sigma(float(r["sigma_t_mid_s"])))
        phases = [p.split(" ", 1)[-1] for p in str(r["anchors"]).split("; ")]
        cols["anchors"].append(_latex_escape(", ".join(phases).replace(",", ", ")))
        cols["tolerance_rad"].append(num(r["tolerance_rad"], ".3f"))
        cols["n_visits"].append(str(int(r["n_visits"])))
        for key in ("integration_h", "overhead_h", "idle_h", "total_h"):
            cols[key].append(_hours(float(r[key])))
    m = summary.meta
    total = {"target": "Total", "n_visits": str(int(np.sum(summary["n_visits"])))}
    total |= {
        "integration_h": _hours(float(m["total_integration_h"])),
        "overhead_h": _hours(float(m["total_overhead_h"])),
        "idle_h": _hours(float(m["total_idle_h"])),
        "total_h": _hours(float(m["total_h"])),
    }
    for key in cols:
        cols[key].append(total.get(key, ""))
    return cols


def latex_width_pt(summary: Table) -> float:
    """Estimated width of the tabular [pt]: paragraph columns at their set width, the others at
    their widest cell (glyph widths bounded from above, :func:`_glyph_em`), each plus
    2·``\\tabcolsep``."""
    cols = _cells(summary)
    width = 0.0
    for key, (header, unit, align) in _COLUMNS.items():
        if align == "p":
            width += P_COLUMNS_CM[key] * _PT_PER_CM
        else:
            width += max(_text_pt(t) for t in [header, unit, *cols[key]])
        width += 2 * TABCOLSEP_PT
    return width


def proposal_latex(summary: Table) -> str:
    """The proposal summary as a LaTeX ``table`` (no package needed), with a total row."""
    cols = _cells(summary)
    spec = "".join(
        f"p{{{P_COLUMNS_CM[k]}cm}}" if a == "p" else a for k, (_, _, a) in _COLUMNS.items()
    )
    m = summary.meta
    caption = (
        rf"Phase-targeted visits, semester {_latex_escape(str(m['semester']))}: $\sigma_T$ at "
        rf"the semester midpoint {str(m['semester_mid_utc']).replace('T', ' ')} UTC; "
        r"phase tolerance (Tol.); visits (Vis.); open-shutter time (Exp.), overheads "
        r"(acquisition, readout) and idle time (waits for the next phase within a visit); "
        r"total = Exp. + overheads + idle "
        rf"({100 * float(m['efficiency']):.0f}\,\% efficiency)."
    )
    rows = [
        " & ".join(h for h, _, _ in _COLUMNS.values()),
        " & ".join(u for _, u, _ in _COLUMNS.values()),
    ]
    body = [" & ".join(cols[k][i] for k in _COLUMNS) for i in range(len(summary) + 1)]
    lines = [
        f"% ucbplan proposal table: estimated width {latex_width_pt(summary):.0f} pt "
        f"<= {TEXTWIDTH_PT:.0f} pt (article 10 pt \\textwidth)",
        r"\begin{table}",
        r"\centering",
        r"\footnotesize",
        rf"\setlength{{\tabcolsep}}{{{TABCOLSEP_PT:g}pt}}",
        rf"\caption{{{caption}}}",
        rf"\begin{{tabular}}{{{spec}}}",
        r"\hline",
        *(r + r" \\" for r in rows),
        r"\hline",
        *(r + r" \\" for r in body[:-1]),
        r"\hline",
        body[-1] + r" \\",
        r"\hline",
        r"\end{tabular}",
        r"\end{table}",
    ]
    return "\n".join(lines) + "\n"
