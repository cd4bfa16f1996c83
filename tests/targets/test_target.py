"""Target-file parsing and validation: each bad-input class gets a one-line, actionable error."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import yaml
from astropy import units as u
from astropy.time import Time
from support.targets import BASE

from ucbplan.core.constants import L_B
from ucbplan.errors import TargetFileError
from ucbplan.targets import load_target, target_to_dict, write_target

CATALOGS = Path(__file__).resolve().parents[2] / "catalogs"


def _write(tmp_path: Path, doc: dict, name: str = "t.yaml") -> Path:
    path = tmp_path / name
    path.write_text(yaml.safe_dump(doc))
    return path


def _with(**lisa) -> dict:
    doc = {**BASE, "lisa": {**BASE["lisa"], **lisa}}
    return doc


def test_loads_bundled_catalogs(hm_cnc_path: Path, eccentric_path: Path) -> None:
    t = load_target(hm_cnc_path)
    assert t.params.f_gw == pytest.approx(6.2204944286e-3, rel=1e-15)
    assert t.params.fddot == pytest.approx(-1.06565e-26)
    assert t.t_ref.scale == "tdb"
    assert math.sqrt(t.covariance[1, 1]) == pytest.approx(7.7e-12)
    e = load_target(eccentric_path)
    assert e.params.eccentricity == pytest.approx(math.hypot(8.249643e-3, 4.524585e-3))
    assert e.covariance[0, 2] == pytest.approx(-0.7 * 0.001978 * 3.41e-19)


def test_bare_numbers_and_pyyaml_string_exponents(tmp_path: Path) -> None:
    """PyYAML reads 1e-6 (no decimal point) as a string: it must still be a number."""
    text = (
        "name: X\nsky: {ra: 121.5967, dec: 15.458}\nlisa:\n  t_ref: 2037-01-01T00:00:00\n"
        "  t_obs: 1e8\n  phase: 1\n  f_gw: 6e-3\n  fdot: 7e-16\n  eta: 1e-3\n"
    )
    path = tmp_path / "x.yaml"
    path.write_text(text)
    t = load_target(path)
    assert t.params.f_gw == 6e-3 and t.params.fdot == 7e-16 and t.params.eta == 1e-3
    assert t.t_obs_s == 1e8
    assert t.ra_deg == pytest.approx(121.5967)


def test_unsafe_yaml_is_not_executed(tmp_path: Path) -> None:
    path = tmp_path / "evil.yaml"
    path.write_text("!!python/object/apply:os.system ['echo pwned']\n")
    with pytest.raises(TargetFileError, match="not valid YAML"):
        load_target(path)


def test_missing_file_and_bad_yaml(tmp_path: Path) -> None:
    with pytest.raises(TargetFileError, match="file not found"):
        load_target(tmp_path / "nope.yaml")
    p = tmp_path / "broken.yaml"
    p.write_text("name: [unclosed\n")
    with pytest.raises(TargetFileError, match="line"):
        load_target(p)


def test_start_reference_is_moved_to_midpoint(tmp_path: Path) -> None:
    """t_ref_is: start → parameters and t_ref at the midpoint (Sec. 4.1 transform)."""
    doc = _with(t_ref_is="start", fddot="1e-26 Hz / s2")
    t = load_target(_write(tmp_path, doc))
    half = 126232599.05 / 2
    assert (t.t_ref - load_target(_write(tmp_path, _with(), "m.yaml")).t_ref).to_value("s") == (
        pytest.approx(half, abs=1e-6)
    )
    assert t.params.f_gw == pytest.approx(
        6.2204944286e-3 + 7.073958e-16 * half + 1e-26 * half**2 / 2
    )
    # σ_f at the midpoint includes the phase-frequency covariance propagated (σ_ḟ = 0 here)
    assert math.sqrt(t.covariance[1, 1]) == pytest.approx(7.7e-12)
    assert t.covariance[0, 1] == pytest.approx(2 * math.pi * half * 7.7e-12**2)


def test_explicit_scales_are_converted(tmp_path: Path) -> None:
    """UTC and TCB epochs convert when stated; TCB rates rescale by (1 − L_B)^−n."""
    t_utc = load_target(_write(tmp_path, _with(t_ref="2037-01-01T00:00:00", t_ref_scale="utc")))
    t_tdb = load_target(_write(tmp_path, _with(), "b.yaml"))
    assert (t_utc.t_ref - t_tdb.t_ref).to_value("s") == pytest.approx(69.184, abs=2e-3)
    t_tcb = load_target(_write(tmp_path, _with(t_ref_scale="tcb"), "c.yaml"))
    assert t_tcb.params.f_gw == pytest.approx(6.2204944286e-3 / (1 - L_B), rel=1e-15)
    assert t_tcb.notes["t_ref_converted_from"] == "tcb"


@pytest.mark.parametrize("catalog", ["fiducial-eccentric.yaml", "fiducial-injection.yaml"])
def test_round_trip_write_and_load(tmp_path: Path, catalog: str) -> None:
    """What write_target writes, load_target reads back to the same target (both catalogs: one
    midpoint-, one start-referenced)."""
    t = load_target(CATALOGS / catalog)
    out = tmp_path / "copy.yaml"
    write_target(t, out)
    t2 = load_target(out)
    # written at the midpoint: read back without a second shift
    assert t2.ref_shift_s == 0.0
    assert np.allclose(t2.params.as_array(), t.params.as_array(), rtol=1e-15, atol=0)
    assert np.allclose(t2.covariance, t.covariance, rtol=1e-12, atol=0)
    assert abs((t2.t_ref - t.t_ref).to_value("s")) < 1e-6
    assert t2.t_obs_s == t.t_obs_s
    assert (t2.name, t2.ra_deg, t2.dec_deg) == (t.name, t.ra_deg, t.dec_deg)
    assert (t2.cos_inclination, t2.amplitude, t2.psi) == (t.cos_inclination, t.amplitude, t.psi)
    assert (t2.distance_kpc, t2.m1_msun, t2.m2_msun) == (t.distance_kpc, t.m1_msun, t.m2_msun)
    assert (t2.priority, t2.vmag, t2.spectroscopy) == (t.priority, t.vmag, t.spectroscopy)
    from ucbplan.errors import OutputExistsError

    with pytest.raises(OutputExistsError):
        write_target(t, out)


def test_start_referenced_target_is_written_at_its_midpoint(tmp_path: Path) -> None:
    """The injection is referenced to 2035-01-01 (start) with T = 126232599.054 s: the written
    file holds t_ref = start + T/2 and the Taylor-shifted f (Sec. 4.1)."""
    t = load_target(CATALOGS / "fiducial-injection.yaml")
    doc = target_to_dict(t)
    half = 126232599.054 / 2
    mid = Time("2035-01-01T00:00:00", scale="tdb") + half * u.s
    assert abs((Time(doc["lisa"]["t_ref"], scale="tdb") - mid).to_value("s")) < 1e-3
    assert doc["lisa"]["t_ref_is"] == "midpoint"
    f_mid = 8.406186457145e-3 + 1.6404896699184233e-15 * half
    assert float(doc["lisa"]["f_gw"].split()[0]) == pytest.approx(f_mid, rel=1e-14)
    assert doc["lisa"]["f_gw"].endswith(" Hz")


def test_correlation_list_form(tmp_path: Path) -> None:
    cov = {
        "sigma": {"phase": 0.1, "fdot": "1e-18 Hz / s"},
        "correlation": [["phase", "fdot", -0.5]],
    }
    t = load_target(_write(tmp_path, _with(covariance=cov)))
    assert t.covariance[0, 2] == pytest.approx(-0.5 * 0.1 * 1e-18)
