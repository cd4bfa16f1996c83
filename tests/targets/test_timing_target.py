"""Target files with a ``timing:`` ephemeris: reading, writing, and every bad input one line.

The timing target below is TEST INPUT written from the numbers quoted in issue 10 (ZTF J1539+5027,
Burdge et al. 2019); it is not a catalog entry (the catalog waits for confirmed T0 values).
"""

from __future__ import annotations

import copy
import math
import subprocess
import sys
import time
from decimal import Decimal
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from support.bad_targets import load_doc as _load
from support.bad_targets import refused as _refused
from support.bad_targets import timing_with as _with
from support.targets import ztf_j1539_doc

from ucbplan.core.timing import TimingEphemeris, phase_covariance, to_phase_params
from ucbplan.errors import TargetFileError
from ucbplan.targets import load_target, target_from_dict, write_target

#: ZTF J1539+5027 from the issue text (test input, not a catalog entry).
ZTF_DOC: dict[str, Any] = ztf_j1539_doc()


def test_timing_target_is_the_phase_model_at_t0() -> None:
    t = _load(ZTF_DOC)
    assert t.kind == "timing" and not t.has_pi_mode
    assert t.t_obs_s == 0.0 and t.t_start == t.t_ref == t.t_end
    exact = Decimal("2458305.6827886")
    got = Decimal(float(t.t_ref.jd1)) + Decimal(float(t.t_ref.jd2))
    assert abs(got - exact) * 86400 < Decimal("1e-9")  # s
    eph = TimingEphemeris("primary_eclipse", 414.7915404, -2.373e-11)
    assert t.params == to_phase_params(eph)
    assert t.params.phase == pytest.approx(math.pi)
    timing_cov = np.diag([(8.4e-6 * 86400) ** 2, (2.9e-6) ** 2, (5e-14) ** 2, 0, 0, 0, 0])
    assert np.allclose(t.covariance, phase_covariance(eph, timing_cov), rtol=1e-12, atol=0)
    assert t.cov_names == ("phase", "f_gw", "fdot", "fddot")
    assert t.timing is not None and t.timing.sigma("t0") == pytest.approx(0.72576)
    assert t.timing.source.startswith("Burdge")


def test_lisa_targets_keep_their_kind(hm_cnc_path: Path) -> None:
    t = load_target(hm_cnc_path)
    assert t.kind == "lisa" and t.has_pi_mode and t.timing is None


def test_write_and_read_back(tmp_path: Path) -> None:
    doc = copy.deepcopy(ZTF_DOC)
    doc["timing"]["pddot"] = "1e-21 1 / s"
    doc["timing"]["eccentricity"] = {"eta": 0.001, "kappa": -0.002, "omega_dot": "1e-8 rad / s"}
    doc["timing"]["inclination"] = "84.15 deg"
    doc["timing"]["distance"] = "2.34 kpc"
    doc["timing"]["covariance"]["exact"] = ["pddot", "eta", "kappa", "omega_dot"]  # issue 33
    doc["magnitudes"] = {"g": 20.5, "G": 20.4}
    doc["references"] = {"timing": "2019Natur.571..528B", "magnitudes.g": "Burdge et al. 2019"}
    t = _load(doc, tmp_path)
    out = tmp_path / "written.yaml"
    write_target(t, out)
    text = out.read_text()
    assert "BJD_TDB 2458305.6827886" in text and "lisa" not in text
    back = load_target(out)
    assert back.kind == "timing"
    assert float((back.t_ref - t.t_ref).to_value("s")) == 0.0
    assert back.params == t.params
    assert np.allclose(back.covariance, t.covariance, rtol=1e-14, atol=0)
    assert back.cos_inclination == pytest.approx(t.cos_inclination, rel=1e-14)
    assert back.distance_kpc == t.distance_kpc
    assert back.magnitudes == t.magnitudes and back.references == t.references


def test_magnitudes_and_the_vmag_alias() -> None:
    doc = copy.deepcopy(ZTF_DOC)
    doc["vmag"] = 20.7
    t = _load(doc)
    assert t.vmag == 20.7 and t.magnitudes == {"V": 20.7}
    doc["magnitudes"] = {"V": 20.7, "g": 20.3}
    assert _load(doc).magnitudes == {"V": 20.7, "g": 20.3}
    doc["magnitudes"] = {"g": 20.3}
    assert _load(doc).vmag == 20.7
    del doc["vmag"]
    doc["magnitudes"] = {"V": 19.0}
    assert _load(doc).vmag == 19.0


def test_vmag_and_magnitudes_v_must_agree() -> None:
    doc = copy.deepcopy(ZTF_DOC)
    doc["vmag"] = 20.7
    doc["magnitudes"] = {"V": 20.1}
    assert "vmag" in _refused(doc) and "differ" in _refused(doc)


def test_validate_cli_one_line_exit_2(tmp_path: Path) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text(yaml.safe_dump(_with("timing.t0", "HJD 2458305.6827886")))
    proc = subprocess.run(
        [sys.executable, "-m", "ucbplan", "validate", str(bad)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr
    lines = [ln for ln in proc.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and "bad.yaml: timing.t0:" in lines[0]


# ------------------------------------------------------------------ property test

#: Values that stress the readers: numbers, units of every dimension, epochs, junk.
VALUES = st.one_of(
    st.sampled_from(
        [
            0,
            -1,
            1e300,
            float("nan"),
            float("inf"),
            True,
            None,
            "",
            "414 s",
            "0.0048 d",
            "6e-3 Hz",
            "-2.373e-11",
            "5e-14",
            "1e-21 1 / s",
            "84 deg",
            "BJD_TDB 2458305.6827886",
            "BMJD_TDB 2458305.6827886",
            "HJD 2458305.68",
            "2018-07-06T04:23:12 TDB",
            "2018-07-06T04:23:12",
            "primary_eclipse",
            "secondary_eclipse",
            "x" * 5000,
            [1, 2],
            {"a": 1},
            {"t0": "1 s"},
            {"period": 0.1},
        ]
    ),
    st.text(max_size=20),
    st.floats(),
    st.integers(),
)
PATHS = [
    "timing",
    "timing.t0",
    "timing.t0_marks",
    "timing.period",
    "timing.pdot",
    "timing.pddot",
    "timing.covariance",
    "timing.covariance.sigma",
    "timing.covariance.sigma.t0",
    "timing.covariance.sigma.pdot",
    "timing.covariance.correlation",
    "timing.covariance.parameters",
    "timing.covariance.matrix",
    "timing.eccentricity",
    "timing.inclination",
    "timing.distance",
    "timing.source",
    "timing.nonsense",
    "magnitudes",
    "references",
    "vmag",
]


@given(st.lists(st.tuples(st.sampled_from(PATHS), VALUES), min_size=1, max_size=3))
@settings(
    max_examples=150,
    deadline=2000,
    derandomize=True,
    suppress_health_check=[HealthCheck.too_slow],
)
def test_mutated_timing_targets_load_or_fail_in_one_line(edits: list[tuple[str, Any]]) -> None:
    """Either a Target, or a TargetFileError of one line < 400 chars naming the file and a
    field of the section that was changed; never another exception; fast."""
    doc = copy.deepcopy(ZTF_DOC)
    for path, value in edits:
        *parents, key = path.split(".")
        node: Any = doc
        for p in parents:
            if not isinstance(node.get(p), dict):
                node[p] = {}
            node = node[p]
        node[key] = value
    start = time.perf_counter()
    try:
        t = target_from_dict(doc, Path("t.yaml"))
    except TargetFileError as exc:
        msg = str(exc)
        assert "\n" not in msg and len(msg) < 400
        field = msg.split(": ")[1]
        assert field.split(".")[0].split("/")[0] in {p.split(".")[0] for p, _ in edits} | {
            "lisa"
        }, (msg, edits)
    else:
        assert t.kind == "timing"
        assert np.all(np.isfinite(t.covariance)) and np.all(np.isfinite(t.params.as_array()))
    assert time.perf_counter() - start < 2.0
