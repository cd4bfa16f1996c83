"""The strategy comparison of ``feasibility`` (and ``plan --compare-strategies``) on stderr."""

from __future__ import annotations

import math
from typing import Any

from rich.markup import escape

from ucbplan.cli._console import err_console, rich_table


def _num(value: float | None, fmt: str) -> str:
    return "-" if value is None or not math.isfinite(value) else format(value, fmt)


def print_comparison(cmp: Any) -> None:
    """One row per strategy: exposure time, Λ_K, exposures and information per visit and per
    hour, and (with a goal) spectra, visits and hours to reach it; then the ratio."""
    goal = cmp.goal is not None
    columns = ["strategy", "exp. [s]", "Λ_K", "exp./visit", "info/h [km⁻²s²/h]"]
    if goal:
        columns += ["spectra", "visits", "hours"]
    title = (
        f"Strategies for {escape(cmp.target)}: σ_v {escape(cmp.sigma_v)}, readout "
        f"{cmp.readout_s:g} s, acquisition {cmp.acquisition_s:g} s, visits ≤ "
        f"{cmp.visit_s / 3600:.2g} h" + (f", goal {escape(cmp.goal)}" if goal else "")
    )
    table = rich_table(title, columns)
    best = cmp.best.name
    for r in cmp.rows:
        row = [
            r.name + ("*" if r.name == best else ""),
            _num(r.exptime_s, ".0f"),
            _num(r.lambda_k, ".3f"),
            str(r.exposures_per_visit) if r.exposures_per_visit else "-",
            _num(r.info_per_hour, ".4g") if r.info_per_visit > 0 else "-",
        ]
        if goal:
            row += [
                str(r.spectra) if r.spectra else "-",
                str(r.visits) if r.visits else "-",
                _num(r.hours, ".2f"),
            ]
        table.add_row(*row)
    err_console.print(table)
    for r in cmp.rows:
        if r.note and r.info_per_visit <= 0:
            err_console.print(f"{r.name}: {escape(r.note)}", soft_wrap=True)
    ratio = cmp.ratio()
    what = "hours untargeted / targeted" if goal else "information per hour, targeted / untargeted"
    if ratio is not None:
        err_console.print(f"phase model gain ({what}): {ratio:.2f}x  (* = best)", soft_wrap=True)
