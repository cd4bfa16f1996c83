"""``Plan._repr_html_``: the plan's summary as one small HTML table, every text escaped."""

from __future__ import annotations

import html
from collections.abc import Mapping, Sequence
from typing import Any

from ucbplan.api._plan_records import GoalRecord, StrategyRecord

#: The summary's rows: key of the summary, label.
_ROWS = (
    ("targets", "targets"),
    ("nights", "nights"),
    ("visits", "visits"),
    ("exposures", "exposures"),
    ("hours", "hours (shutter + overheads + idle)"),
)


def _e(text: object) -> str:
    return html.escape(str(text), quote=True)


def _row(*cells: object, head: bool = False) -> str:
    tag = "th" if head else "td"
    return "<tr>" + "".join(f"<{tag}>{_e(c)}</{tag}>" for c in cells) + "</tr>"


def _goal_text(goal: GoalRecord) -> str:
    if goal.relative:
        return f"{100 * float(goal.expected.value):.3g} %"
    unit = goal.expected.unit.to_string().replace(" / ", "/")
    return f"{float(goal.expected.value):.3g} {unit}".strip()


def summary_html(
    title: str,
    summary: Mapping[str, Any],
    goals: Sequence[GoalRecord],
    strategies: Sequence[StrategyRecord],
) -> str:
    """The summary (counts, hours), each goal's promised σ and each strategy's fraction of the
    best, as an HTML table with ``title`` as its caption."""
    rows = [_row(label, f"{summary[key]:.2f}" if key == "hours" else summary[key])
            for key, label in _ROWS]  # fmt: skip
    for g in goals:
        rows.append(
            _row(f"goal {g.description}: {g.target}", f"{_goal_text(g)} ({g.n_spectra} spectra)")
        )
    for s in strategies:
        mark = " (planned)" if s.chosen else ""
        share = f"{s.fraction_of_best:.0%} of best" if s.possible else f"not possible: {s.note}"
        rows.append(_row(f"strategy {s.strategy}{mark}: {s.target}", share))
    body = "".join(rows)
    return f"<table><caption>{_e(title)}</caption><tbody>{body}</tbody></table>"
