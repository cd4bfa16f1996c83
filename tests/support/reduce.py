"""Velocity-table helpers the reduce tests share."""

from __future__ import annotations

from pathlib import Path

import numpy as np

#: The header of a two-star (SB2) velocity CSV with sessions.
HEADER = "bjd_tdb,exptime_s,v1,sigma_v1,v2,sigma_v2,session\n"
JD = 2465800.0  # 2039-12 TDB: after the fiducial LISA observation (ends 2039-01-01)


def assert_same_velocities(a: object, b: object) -> None:
    """Bit-identical tables: times (jd1, jd2), windows, velocities, σ and session labels."""
    assert a.time.jd1.tobytes() == b.time.jd1.tobytes()  # type: ignore[attr-defined]
    assert a.time.jd2.tobytes() == b.time.jd2.tobytes()  # type: ignore[attr-defined]
    for name in ("window_s", "lambda_k"):
        assert np.array_equal(getattr(a, name), getattr(b, name), equal_nan=True)
    for x, y in zip(a.v + a.sigma, b.v + b.sigma, strict=True):  # type: ignore[attr-defined]
        assert x.tobytes() == y.tobytes()
    assert a.session == b.session and a.window_column == b.window_column  # type: ignore[attr-defined]


def write_velocity_file(tmp_path: Path, text: str, name: str = "v.csv") -> Path:
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    return p


def write_velocity_ecsv(
    tmp_path: Path, body: list[str], header: str = "bjd_tdb v sigma_v exptime_s"
) -> Path:
    names = header.split()
    lines = ["# %ECSV 1.0", "# ---", "# datatype:"]
    lines += [f"# - {{name: {n}, datatype: float64}}" for n in names]
    lines += ["# schema: astropy-2.0", header, *body]
    return write_velocity_file(tmp_path, "\n".join(lines) + "\n", "v.ecsv")
