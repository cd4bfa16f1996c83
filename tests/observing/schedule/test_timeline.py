"""The placement timeline (issue 34): its free-time check, two neighbours found by bisection in
the sorted taken intervals, answers as the brute-force scan of every interval taken so far."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from ucbplan.observing.schedule.placement import Session, Timeline


def _free_by_scan(taken: list[tuple[float, float]], gap: float, x0: float, x1: float) -> bool:
    """Free when no taken interval, widened by the gap at both ends, overlaps [x0, x1]."""
    return all(not (a < x1 + gap and b > x0 - gap) for a, b in taken)


_X = st.sampled_from([0.0, 60.0, 120.0, 180.0, 300.0]) | st.floats(0, 3600)
#: Sessions and busy blocks last as long as their exposures (> 0 s). A zero-width one is never
#: planned, and only there do the two answers part (it may sit at the start of another, or at
#: the point where two touching busy blocks were merged).
_SPAN = st.tuples(_X, st.sampled_from([30.0, 60.0, 1e-3]) | st.floats(1e-3, 900))


@settings(max_examples=300, deadline=None)
@given(
    st.sampled_from([0.0, -5.0, 60.0, 120.0]) | st.floats(0, 600),
    st.lists(_SPAN, max_size=6),
    st.lists(_SPAN, max_size=40),
)
def test_free_agrees_with_the_scan_of_every_taken_interval(
    overhead: float, busy: list[tuple[float, float]], sessions: list[tuple[float, float]]
) -> None:
    timeline = Timeline(overhead)
    timeline.block_out([(x, x + w) for x, w in busy])
    taken = [(x, x + w) for x, w in busy]
    gap = max(overhead, 0.0)
    for k, (x0, width) in enumerate(sessions):
        x1 = x0 + width
        free = _free_by_scan(taken, gap, x0, x1)
        assert timeline.free(x0, x1) is free
        assert timeline.add(Session(0, 0, (k,), x0, x1)) is free
        if free:
            taken.append((x0, x1))
    assert [(s.x0, s.x1) for s in timeline.placed] == taken[len(busy) :]
