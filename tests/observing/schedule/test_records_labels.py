"""Block, session and visit identifiers made over whole arrays (issue 34) against the
per-session loop they replace: the same texts, numbers and text widths, in the same order."""

from __future__ import annotations

from collections import Counter
from types import SimpleNamespace
from typing import Any

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from ucbplan.observing.schedule.placement import Session
from ucbplan.observing.schedule.records import _labels, slug


def _reference(placed: list[Session], runs: list[Any], spans: list[Any]) -> dict[int, Any]:
    """The per-session loop: each session's blocks numbered per target and night."""
    blocks: Counter[tuple[int, int]] = Counter()
    sessions: Counter[tuple[int, int]] = Counter()
    out: dict[int, tuple[list[int], list[tuple[str, str, str, str]]]] = {}
    for s in sorted(placed, key=lambda s: (s.target_i, s.x0)):
        key = (s.target_i, s.night_i)
        label = spans[s.night_i].label
        prefix = f"{slug(runs[s.target_i].target.name)}-{label.replace('-', '')}"
        js, labels = out.setdefault(s.target_i, ([], []))
        sessions[key] += 1
        for j in s.idx:
            blocks[key] += 1
            js.append(j)
            labels.append(
                (label, f"{prefix}-{blocks[key]:02d}", f"{prefix}-S{sessions[key]:02d}",
                 f"{prefix}-V{sessions[key]:02d}")
            )  # fmt: skip
    texts = {
        i: [np.array(v, dtype=str) for v in zip(*rows, strict=True)] for i, (_, rows) in out.items()
    }
    return {i: (np.asarray(js, dtype=np.int64), texts[i]) for i, (js, _) in out.items()}


_NAMES = ["HM Cnc", "V407 Vul", "A", "ZTF J1539+5027", "x-y"]
_SESSION = st.tuples(
    st.integers(0, 4),  # target
    st.integers(0, 3),  # night
    st.integers(0, 400),  # first candidate
    st.booleans(),  # a pair
    st.sampled_from([0.0, -0.0, 100.0, 100.5, 3e5, 1e6]) | st.floats(0, 1e6),
)


@settings(max_examples=200, deadline=None)
@given(st.lists(_SESSION, max_size=60), st.integers(1, 130))
def test_labels_as_the_per_session_loop_makes_them(rows: list[tuple], many: int) -> None:
    placed = [
        Session(t, n, (j, j + 1) if pair else (j,), x0, x0 + 60.0) for t, n, j, pair, x0 in rows
    ]
    placed += [Session(4, 2, (k,), 5e5 + k, 5e5 + k + 1) for k in range(many)]  # 3-digit ids
    runs = [SimpleNamespace(target=SimpleNamespace(name=n)) for n in _NAMES]
    spans = [SimpleNamespace(label=f"2040-01-{d:02d}") for d in (1, 2, 3, 10)]
    got, want = _labels(placed, runs, spans), _reference(placed, runs, spans)
    assert list(got) == list(want)
    for i, (js, labels) in got.items():
        assert js.tolist() == want[i][0].tolist()
        for ours, theirs in zip(labels, want[i][1], strict=True):
            assert ours.dtype == theirs.dtype
            assert ours.tolist() == theirs.tolist()
    assert _labels([], runs, spans) == {}
