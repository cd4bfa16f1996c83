"""Velocity-table helpers the reduce tests share."""

from __future__ import annotations

import numpy as np

JD = 2465800.0  # 2039-12 TDB: after the fiducial LISA observation (ends 2039-01-01)


def _same(a: object, b: object) -> None:
    """Bit-identical tables: times (jd1, jd2), windows, velocities, σ and session labels."""
    assert a.time.jd1.tobytes() == b.time.jd1.tobytes()  # type: ignore[attr-defined]
    assert a.time.jd2.tobytes() == b.time.jd2.tobytes()  # type: ignore[attr-defined]
    for name in ("window_s", "lambda_k"):
        assert np.array_equal(getattr(a, name), getattr(b, name), equal_nan=True)
    for x, y in zip(a.v + a.sigma, b.v + b.sigma, strict=True):  # type: ignore[attr-defined]
        assert x.tobytes() == y.tobytes()
    assert a.session == b.session and a.window_column == b.window_column  # type: ignore[attr-defined]
