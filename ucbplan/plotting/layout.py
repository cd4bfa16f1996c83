"""Layout checks of a figure: text that overprints, leaves the figure or hides the curves.

:func:`layout_problems` draws a figure once (Agg) and reads the window extents of its text boxes —
titles, axis labels, tick labels, annotations, legends — in display pixels. It reports pairs that
overlap, boxes outside the figure, legends lying on a curve, and axes whose tick labels carry no
axis label with a unit in brackets (``[deg]``, ``[1]``...). The tests run it on every figure the
project writes; it never changes the figure.
"""

from __future__ import annotations

import re
from itertools import combinations
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from matplotlib.figure import Figure
    from matplotlib.transforms import Bbox

#: Overlap smaller than this [display px] on either side is not reported (anti-aliasing).
_SLACK_PX = 1.0
#: Fraction of a curve's points under a legend above which the legend hides the curve.
_HIDDEN_FRACTION = 0.02
#: A unit in brackets: ``[deg]``, ``[km/s]``, ``[1]``.
_UNIT = re.compile(r"\[[^\]]+\]")


def _drawn_ticks(axis: Any) -> list[Any]:
    """The ticks matplotlib draws (inside the view limits); ``get_ticklabels`` also lists others."""
    return list(axis._update_ticks())


def _boxes(fig: Figure, renderer: Any) -> list[tuple[str, Bbox]]:
    """Every visible, non-empty text box of ``fig`` and its legends, with a short name."""
    out: list[tuple[str, Bbox]] = []

    def add(name: str, artist: Any) -> None:
        if artist is None or not artist.get_visible():
            return
        if hasattr(artist, "get_text") and not artist.get_text().strip():
            return
        out.append((name, artist.get_window_extent(renderer)))

    for t in fig.texts:
        add(f"figure text {t.get_text()!r}", t)
    for leg in fig.legends:
        add("figure legend", leg)
    for k, ax in enumerate(fig.axes):
        if not ax.get_visible():
            continue
        where = f"axes {k}"
        titles: list[Any] = [getattr(ax, n, None) for n in ("title", "_left_title", "_right_title")]
        for title in titles:
            add(f"{where} title {getattr(title, 'get_text', str)()!r}", title)
        add(f"{where} x label", ax.xaxis.label)
        add(f"{where} y label", ax.yaxis.label)
        for name, axis in (("x", ax.xaxis), ("y", ax.yaxis)):
            for tick in _drawn_ticks(axis):
                for lab in (tick.label1, tick.label2):
                    add(f"{where} {name} tick {lab.get_text()!r}", lab)
            add(f"{where} {name} offset text", axis.get_offset_text())
        for t in ax.texts:
            add(f"{where} text {t.get_text()!r}", t)
        add(f"{where} legend", ax.get_legend())
    return out


def _overlap(a: Bbox, b: Bbox) -> bool:
    return (
        min(a.x1, b.x1) - max(a.x0, b.x0) > _SLACK_PX
        and min(a.y1, b.y1) - max(a.y0, b.y0) > _SLACK_PX
    )


def _outside(fig: Figure, box: Bbox) -> bool:
    f = fig.bbox
    return (
        box.x0 < f.x0 - _SLACK_PX
        or box.y0 < f.y0 - _SLACK_PX
        or box.x1 > f.x1 + _SLACK_PX
        or box.y1 > f.y1 + _SLACK_PX
    )


def _inside(pix: np.ndarray, box: Bbox) -> np.ndarray:
    """Which display points lie strictly inside ``box``."""
    x, y = pix[:, 0], pix[:, 1]
    return np.asarray((x > box.x0) & (x < box.x1) & (y > box.y0) & (y < box.y1))


def _drawn_points(ax: Any) -> list[tuple[str, np.ndarray]]:
    """Display coordinates of what an axes draws as data: lines (≥ 10 points), scatter offsets
    and unfilled contour lines, each with its label. Filled areas (shading, bands) are not data
    a legend may not cover."""
    from matplotlib.collections import PathCollection
    from matplotlib.contour import ContourSet

    out = []
    for line in ax.get_lines():
        xy = np.asarray(line.get_xydata(), dtype=float)
        if len(xy) >= 10 and line.get_visible():
            out.append((f"curve {line.get_label()!r}", line.get_transform().transform(xy)))
    for coll in ax.collections:
        if isinstance(coll, ContourSet) and not coll.filled:
            verts = [np.asarray(p.vertices, dtype=float) for p in coll.get_paths()]
            verts = [v.reshape(-1, 2) for v in verts if v.size]
            if verts:
                out.append(("contour", coll.get_transform().transform(np.concatenate(verts))))
        elif isinstance(coll, PathCollection):
            xy = np.asarray(coll.get_offsets(), dtype=float).reshape(-1, 2)
            if len(xy) >= 10:
                pix = coll.get_offset_transform().transform(xy)
                out.append((f"points {coll.get_label()!r}", pix))
    return out


def _hidden_curves(fig: Figure, renderer: Any) -> list[str]:
    """Legends that cover more than :data:`_HIDDEN_FRACTION` of a curve's drawn points."""
    problems = []
    for k, ax in enumerate(fig.axes):
        leg = ax.get_legend()
        if leg is None or not leg.get_visible():
            continue
        box = leg.get_window_extent(renderer)
        for name, pix in _drawn_points(ax):
            pts = pix[_inside(pix, ax.bbox) & np.all(np.isfinite(pix), axis=1)]
            if len(pts) == 0:
                continue
            under = _inside(pts, box)
            if under.mean() > _HIDDEN_FRACTION:
                problems.append(f"axes {k}: legend hides {100 * under.mean():.0f} % of {name}")
    return problems


def _unlabelled(fig: Figure) -> list[str]:
    """Axes with tick labels but no axis label carrying a unit in brackets."""
    problems = []
    for k, ax in enumerate(fig.axes):
        if not ax.get_visible() or not ax.axison:
            continue
        for name, axis in (("x", ax.xaxis), ("y", ax.yaxis)):
            ticks = [lab for t in _drawn_ticks(axis) for lab in (t.label1, t.label2)]
            if not any(lab.get_visible() and lab.get_text().strip() for lab in ticks):
                continue
            label = axis.label.get_text() if axis.label.get_visible() else ""
            if not _UNIT.search(label):
                problems.append(f"axes {k}: {name} axis label {label!r} has no [unit]")
    return problems


def layout_problems(fig: Figure, *, check_units: bool = True) -> list[str]:
    """What is wrong with the layout of ``fig`` (empty list: nothing).

    Draws the figure (Agg canvas) and checks, in display pixels:

    * no two text boxes (titles, axis and tick labels, texts, annotations, legends) overlap by more
      than 1 px both ways;
    * every box lies inside the figure;
    * no legend covers more than 2 % of the drawn points of a curve of its axes;
    * (``check_units``) every axis that shows tick labels has a label with a unit in brackets.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure, as it would be saved.
    check_units : bool
        Also require ``[unit]`` in axis labels.

    Returns
    -------
    list of str
        One line per problem, naming the artists.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = fig.canvas if isinstance(fig.canvas, FigureCanvasAgg) else FigureCanvasAgg(fig)
    canvas.draw()
    renderer = canvas.get_renderer()
    boxes = _boxes(fig, renderer)
    problems = [f"{name} lies outside the figure" for name, box in boxes if _outside(fig, box)]
    problems += [
        f"{na} overlaps {nb}" for (na, a), (nb, b) in combinations(boxes, 2) if _overlap(a, b)
    ]
    problems += _hidden_curves(fig, renderer)
    if check_units:
        problems += _unlabelled(fig)
    return problems
