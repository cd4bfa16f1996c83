"""Issue 11, target files: every kind of nonsense is refused with one clear line.

One test per failure class of the issue ("Hangs and blow-ups", "Accepted nonsense", bare
tracebacks); each asserts the one-line ``FILE: field: …`` form, the field it names and, for the
hangs, that the refusal is fast.
"""

from __future__ import annotations

import copy
import time
from pathlib import Path
from typing import Any

import pytest
import yaml
from astropy import units as u
from support.targets import BASE

from ucbplan.core.epochs import parse_tdb
from ucbplan.errors import InputError, TargetFileError
from ucbplan.targets import load_target, target_from_dict

CATALOGS = Path(__file__).resolve().parents[2] / "catalogs"

# the same minimal valid document as tests/targets/test_target.py (tests/support/targets.py)


def _doc(**lisa: Any) -> dict[str, Any]:
    doc = copy.deepcopy(BASE)
    doc["lisa"].update(lisa)
    return doc


def _write_text(tmp_path: Path, text: str, name: str = "bad.yaml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def _refused(tmp_path: Path, doc: Any, name: str = "bad.yaml") -> str:
    """The one-line message of loading ``doc`` from a file (it must be refused)."""
    path = _write_text(tmp_path, yaml.safe_dump(doc, allow_unicode=True), name)
    with pytest.raises(TargetFileError) as exc:
        load_target(path)
    return _one_line(str(exc.value), name)


def _one_line(msg: str, name: str) -> str:
    assert "\n" not in msg and "\r" not in msg, msg
    assert len(msg) < 400, (len(msg), msg[:500])
    assert name in msg, msg
    return msg


# ------------------------------------------------------------------ reading the file (YAML level)


def test_duplicate_keys_are_refused(tmp_path: Path) -> None:
    text = (
        (CATALOGS / "hm-cnc-simulated.yaml")
        .read_text()
        .replace("  phase: 5.500397", "  phase: 5.500397\n  phase: 1.0")
    )
    path = _write_text(tmp_path, text)
    with pytest.raises(TargetFileError) as exc:
        load_target(path)
    msg = _one_line(str(exc.value), "bad.yaml")
    assert "duplicate key 'phase'" in msg


def test_alias_bomb_is_refused_fast(tmp_path: Path) -> None:
    """704 bytes of nested anchors expanded to 9⁹ strings (70 s and 5 GB before)."""
    lines = ['lol1: &lol1 ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"]']
    for n in range(2, 10):
        lines.append(f"lol{n}: &lol{n} [" + ", ".join([f"*lol{n - 1}"] * 9) + "]")
    text = "\n".join(lines) + "\n"
    assert 650 < len(text.encode()) < 750
    path = _write_text(tmp_path, text)
    start = time.perf_counter()
    with pytest.raises(TargetFileError) as exc:
        load_target(path)
    assert time.perf_counter() - start < 1.0
    assert "aliases" in _one_line(str(exc.value), "bad.yaml")


def test_byte_order_mark_and_exponent_without_point(tmp_path: Path) -> None:
    """A UTF-8 BOM (Windows editors) is accepted; 5e-14 is a number, as in the docs."""
    text = (
        (CATALOGS / "hm-cnc-simulated.yaml")
        .read_text()
        .replace('fdot: "7.073958e-16 Hz / s"', "fdot: 7.073958e-16")
    )
    path = tmp_path / "bom.yaml"
    path.write_bytes(b"\xef\xbb\xbf" + text.encode())
    t = load_target(path)
    ref = load_target(CATALOGS / "hm-cnc-simulated.yaml")
    assert t.params == ref.params and t.name == ref.name == "HM Cnc (simulated)"


def test_not_utf8_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "latin.yaml"
    path.write_bytes(
        (CATALOGS / "hm-cnc-simulated.yaml").read_bytes().replace(b"HM Cnc", b"HM C\xe9nc")
    )
    with pytest.raises(TargetFileError) as exc:
        load_target(path)
    assert "UTF-8" in _one_line(str(exc.value), "latin.yaml")


def test_deeply_nested_junk_is_refused(tmp_path: Path) -> None:
    path = _write_text(tmp_path, "name: X\nnotes: " + "[" * 5000 + "]" * 5000 + "\n")
    with pytest.raises(TargetFileError) as exc:
        load_target(path)
    _one_line(str(exc.value), "bad.yaml")


# ------------------------------------------------------------------ strict schemas


def test_typo_in_covariance_does_not_drop_the_correlations(tmp_path: Path) -> None:
    doc = _doc(
        covariance={
            "sigma": {"phase": 0.02, "fdot": "4.6e-19 Hz / s"},
            "correlaton": {"phase,fdot": -0.7},
        }
    )
    msg = _refused(tmp_path, doc)
    assert "lisa.covariance.correlaton: unknown field" in msg
    assert "did you mean 'correlation'" in msg


@pytest.mark.parametrize(
    ("section", "key", "suggestion"),
    [
        ("", "prority", "priority"),
        ("lisa", "f_gws", "f_gw"),
        ("masses", "m_1", "m1"),
        ("spectroscopy", "sigmav", "sigma_v"),
        ("sky", "dex", "dec"),
    ],
)
def test_unknown_keys_name_the_closest_field(
    tmp_path: Path, section: str, key: str, suggestion: str
) -> None:
    doc = _doc()
    doc["masses"] = {"m1": "0.3 solMass"}
    doc["spectroscopy"] = {"lines": "SB1"}
    (doc[section] if section else doc)[key] = 1
    msg = _refused(tmp_path, doc)
    path = f"{section}.{key}" if section else key
    assert f"bad.yaml: {path}: unknown field; did you mean '{suggestion}'?" in msg


def test_unknown_key_beside_galactic_coordinates(tmp_path: Path) -> None:
    doc = _doc()
    doc["sky"] = {"l": -93.56, "b": -19.19, "bb": 3}
    assert "sky.bb: unknown field" in _refused(tmp_path, doc)
    doc["sky"] = {"l": -93.56, "b": -19.19, "ra": 3}
    assert "sky: " in _refused(tmp_path, doc)


def test_covariance_forms_cannot_be_mixed(tmp_path: Path) -> None:
    """With a matrix, sigma and correlation were silently ignored."""
    cov = {
        "parameters": ["phase"],
        "matrix": [[1e-4]],
        "sigma": {"phase": 0.5},
        "correlation": {"phase,f_gw": 0.5},
    }
    assert "lisa.covariance" in _refused(tmp_path, _doc(covariance=cov))


def test_repeated_correlation_pair_is_refused(tmp_path: Path) -> None:
    cov = {
        "sigma": {"phase": 0.02, "f_gw": 1e-12},
        "correlation": {"phase,f_gw": 0.5, "f_gw,phase": -0.5},
    }
    assert "twice" in _refused(tmp_path, _doc(covariance=cov))


@pytest.mark.parametrize("key", [1, None, 2.5, True])
def test_non_string_keys(key: Any) -> None:
    for section in ("", "lisa", "sky"):
        doc = _doc()
        (doc[section] if section else doc)[key] = 1
        with pytest.raises(TargetFileError) as exc:
            target_from_dict(doc)
        assert "unknown field" in _one_line(str(exc.value), "<target>")


# ------------------------------------------------------------------ units by dimension


def test_f_gw_in_rad_per_s_is_refused(tmp_path: Path) -> None:
    """ω = 2πf in rad/s was read as f in Hz (a factor 2π wrong)."""
    msg = _refused(tmp_path, _doc(f_gw="0.039084 rad / s"))
    assert "lisa.f_gw" in msg and "angular frequency" in msg and "give Hz (f = ω/2π)" in msg


def test_fdot_in_rad_per_s2_is_refused(tmp_path: Path) -> None:
    msg = _refused(tmp_path, _doc(fdot="4.4e-15 rad / s2"))
    assert "lisa.fdot" in msg and "Hz / s" in msg


def test_omega_dot_in_hz_is_refused(tmp_path: Path) -> None:
    msg = _refused(tmp_path, _doc(omega_dot="2.4e-7 Hz"))
    assert "lisa.omega_dot" in msg and "give rad/s" in msg


def test_cos_inclination_as_an_angle_is_refused(tmp_path: Path) -> None:
    msg = _refused(tmp_path, _doc(cos_inclination="48 deg"))
    assert "lisa.cos_inclination" in msg and "cosine" in msg
    assert "cos_inclination: 0.669" in msg


@pytest.mark.parametrize(
    ("lisa", "where", "needle"),
    [
        ({"t_obs": "4 kpc"}, "lisa.t_obs", "a length"),
        ({"distance": "2 s"}, "lisa.distance", '"2.0 kpc"'),
        ({"eta": "0.01 rad"}, "lisa.eta", "dimensionless"),
        ({"phase": "5 s"}, "lisa.phase", "rad"),
        ({"covariance": {"sigma": {"f_gw": "1e-12 rad / s"}}}, "lisa.covariance.sigma.f_gw", "Hz"),
    ],
)
def test_wrong_dimension_names_the_expected_unit(
    tmp_path: Path, lisa: dict[str, Any], where: str, needle: str
) -> None:
    msg = _refused(tmp_path, _doc(**lisa))
    assert f"bad.yaml: {where}: " in msg and needle in msg


def test_equivalent_units_are_still_accepted(tmp_path: Path) -> None:
    t = load_target(
        _write_text(
            tmp_path,
            yaml.safe_dump(
                _doc(
                    f_gw="6.2204944286 mHz",
                    t_obs="4 yr",
                    phase="315 deg",
                    omega_dot="47.2 deg / yr",
                    psi="19.4 deg",
                    distance="2000 pc",
                    cos_inclination="67 %",
                )
            ),
            "ok.yaml",
        )
    )
    assert t.params.f_gw == pytest.approx(6.2204944286e-3)
    assert t.cos_inclination == pytest.approx(0.67)


# ------------------------------------------------------------------ ranges with the reason


def test_eccentricity_of_one_is_refused(tmp_path: Path) -> None:
    msg = _refused(tmp_path, _doc(eta=1.0, kappa=0.0))
    assert "lisa.eta/kappa" in msg and "e = |η + iκ|" in msg


def test_cos_inclination_beyond_one_is_refused(tmp_path: Path) -> None:
    msg = _refused(tmp_path, _doc(cos_inclination=-1.2))
    assert "lisa.cos_inclination" in msg and "[-1, 1]" in msg and "cosine" in msg


@pytest.mark.parametrize("sigma", [-0.02, 0.0, "-1e-12 Hz"])
def test_negative_or_zero_sigma_is_refused(tmp_path: Path, sigma: Any) -> None:
    msg = _refused(tmp_path, _doc(covariance={"sigma": {"phase": 0.02, "f_gw": sigma}}))
    assert "lisa.covariance.sigma.f_gw" in msg and "> 0" in msg


def test_negative_mass_is_refused(tmp_path: Path) -> None:
    doc = _doc()
    doc["masses"] = {"m1": "-0.3 solMass"}
    assert "masses.m1" in _refused(tmp_path, doc)


@pytest.mark.parametrize("value", ["nan", ".nan", "inf", "-.inf", "nan Hz", "1e400 Hz", 10**400])
def test_non_finite_values_are_refused(tmp_path: Path, value: Any) -> None:
    msg = _refused(tmp_path, _doc(f_gw=value))
    assert "lisa.f_gw" in msg


def test_yaml_nan_and_inf_literals(tmp_path: Path) -> None:
    text = yaml.safe_dump(_doc()).replace("phase: 5.5", "phase: .nan")
    with pytest.raises(TargetFileError, match=r"lisa\.phase"):
        load_target(_write_text(tmp_path, text))
    text = yaml.safe_dump(_doc()).replace("phase: 5.5", "phase: 1e400")
    with pytest.raises(TargetFileError, match=r"lisa\.phase"):
        load_target(_write_text(tmp_path, text))


@pytest.mark.parametrize("rho", ["strong", [0.5], None, True, "nan", 1e400, 1.5])
def test_bad_correlation_values_are_refused(tmp_path: Path, rho: Any) -> None:
    """A non-numeric ρ was a bare ValueError traceback."""
    cov = {"sigma": {"phase": 0.02, "f_gw": 1e-12}, "correlation": {"phase,f_gw": rho}}
    msg = _refused(tmp_path, _doc(covariance=cov))
    assert "lisa.covariance.correlation.phase,f_gw" in msg


def test_bad_correlation_list_entries_are_refused(tmp_path: Path) -> None:
    cov = {"sigma": {"phase": 0.02, "f_gw": 1e-12}, "correlation": [["phase", "f_gw", "x"]]}
    assert "lisa.covariance.correlation" in _refused(tmp_path, _doc(covariance=cov))


# ------------------------------------------------------------------ hangs and huge values


def test_padded_t_ref_is_fast(tmp_path: Path) -> None:
    """A t_ref padded with 100 000 spaces hung in the scale-label regex (quadratic)."""
    for padded in (
        "2037-01-01" + " " * 100_000 + "x",
        " " * 100_000,
        "2037-01-01T00:00:00" + " " * 100_000 + "UTC",
    ):
        start = time.perf_counter()
        msg = _refused(tmp_path, _doc(t_ref=padded))
        assert time.perf_counter() - start < 1.0
        assert "lisa.t_ref" in msg


def test_padded_epoch_option_is_fast() -> None:
    start = time.perf_counter()
    with pytest.raises(InputError) as exc:
        parse_tdb("2037-01-01" + " " * 100_000 + "x", "--start")
    assert time.perf_counter() - start < 1.0
    assert len(str(exc.value)) < 400 and str(exc.value).startswith("--start: ")


@pytest.mark.parametrize(
    "epoch",
    [
        "2037-01-01T00:00:00",
        "2037-01-01T00:00:00 TDB",
        "2037-01-01T00:00:00 (TDB)",
        "2037-01-01T00:00:00(TDB)",
        "2037-01-01 00:00:00 tdb",
        "2037-01-01",
        "MJD 65059",
        "mjd 65059 TDB",
        "JD 2465059.5",
        " MJD 65059.0 (TDB) ",
    ],
)
def test_every_tdb_epoch_form_still_parses(epoch: str) -> None:
    t = parse_tdb(epoch)
    assert t.scale == "tdb"
    assert abs(t.mjd - 65059.0) < 1e-9


@pytest.mark.parametrize(
    ("epoch", "offset"),
    [
        ("2037-01-01T00:00:00 UTC", 69.184),
        ("2037-01-01T00:00:00 (TT)", 0.0),
        ("MJD 65059 TAI", 32.184),
        ("2037-01-01T00:00:00 TCB", None),
    ],
)
def test_labelled_epochs_convert(epoch: str, offset: float | None) -> None:
    t = parse_tdb(epoch)
    delta = (t - parse_tdb("2037-01-01T00:00:00")).to_value("s")
    if offset is None:
        assert delta < -10  # TCB runs ahead of TDB by ~ 25 s in 2037
    else:
        assert delta == pytest.approx(offset, abs=2e-3)


@pytest.mark.parametrize(
    "bad", ["", "   ", "MJD", "MJD nan", "JD inf", "MJD 1e300", "2037-13-45", "x" * 1000]
)
def test_bad_epochs_are_one_line_errors(bad: str) -> None:
    with pytest.raises(InputError) as exc:
        parse_tdb(bad, "--start")
    assert len(str(exc.value)) < 400 and str(exc.value).startswith("--start: ")


HUGE = 72_000_000


@pytest.mark.parametrize(
    "where",
    ["name", "lisa.f_gw", "lisa.t_ref", "sky.ra", "lisa.covariance.sigma", "key", "vmag"],
)
def test_huge_value_gives_a_short_message(where: str) -> None:
    """A 72 MB value made a 72 MB error line."""
    huge = "9" * 10 + " " * HUGE + "x"
    doc = _doc()
    if where == "key":
        doc["lisa"][huge] = 1
    elif where == "lisa.covariance.sigma":
        doc["lisa"]["covariance"]["sigma"][huge] = 1.0
    else:
        *parents, key = where.split(".")
        node = doc
        for p in parents:
            node = node[p]
        node[key] = huge
    start = time.perf_counter()
    with pytest.raises(TargetFileError) as exc:
        target_from_dict(doc)
    assert time.perf_counter() - start < 2.0
    _one_line(str(exc.value), "<target>")


def test_huge_file_is_refused_with_a_short_message(tmp_path: Path) -> None:
    path = tmp_path / "huge.yaml"
    path.write_text("name: X\nnotes: '" + "x" * 3_000_000 + "'\n")
    with pytest.raises(TargetFileError) as exc:
        load_target(path)
    _one_line(str(exc.value), "huge.yaml")


# ------------------------------------------------------------------ malformed values


JUNK: list[Any] = [
    [1, 2],
    {"a": 1},
    True,
    None,
    10**400,
    1e400,
    float("nan"),
    "",
    "\x00",
    "é" * 50,
    [[[[["deep"]]]]],
    {"value": 1, "unit": "Hz"},
    "6e-3 Hz" + "\u200b",
    "1 " + "(" * 300 + "Hz" + ")" * 300,
]
JUNK_PATHS = [
    "name",
    "sky",
    "sky.ra",
    "sky.dec",
    "sky.frame",
    "lisa",
    "lisa.t_ref",
    "lisa.t_ref_scale",
    "lisa.t_obs",
    "lisa.t_ref_is",
    "lisa.phase",
    "lisa.f_gw",
    "lisa.covariance",
    "lisa.covariance.sigma",
    "lisa.covariance.sigma.phase",
    "lisa.covariance.correlation",
    "lisa.samples",
    "priority",
    "vmag",
    "masses",
    "masses.m1",
    "spectroscopy",
    "spectroscopy.lines",
    "spectroscopy.K1",
]


@pytest.mark.parametrize("where", JUNK_PATHS)
def test_malformed_values_give_one_line_naming_the_field(tmp_path: Path, where: str) -> None:
    for junk in JUNK:
        doc = _doc()
        doc["masses"] = {"m1": "0.3 solMass"}
        doc["spectroscopy"] = {"lines": "SB1", "K1": "300 km/s"}
        *parents, key = where.split(".")
        node = doc
        for p in parents:
            node = node[p]
        node[key] = junk
        try:
            target_from_dict(doc, tmp_path / "t.yaml")
        except TargetFileError as exc:
            msg = _one_line(str(exc), "t.yaml")
            assert msg.split(": ")[1].split(".")[0] == where.split(".")[0], (junk, msg)


def test_samples_must_be_a_file(tmp_path: Path) -> None:
    (tmp_path / "folder").mkdir()
    for name in ("", ".", "folder", "a\x00b", "x" * 5000):
        doc = _doc(samples=name)
        with pytest.raises(TargetFileError) as exc:
            target_from_dict(doc, tmp_path / "t.yaml")
        assert "lisa.samples" in _one_line(str(exc.value), "t.yaml")


@pytest.mark.parametrize("name", ["two\nlines", "tab\there", "x" * 1000, "   "])
def test_bad_names_are_refused(name: str) -> None:
    doc = _doc()
    doc["name"] = name
    with pytest.raises(TargetFileError) as exc:
        target_from_dict(doc)
    assert "name" in _one_line(str(exc.value), "<target>")


def test_unicode_names_are_accepted() -> None:
    doc = _doc()
    doc["name"] = "ZTF J1539+5027 – Ωμέγα 白矮星"
    assert target_from_dict(doc).name == doc["name"]


def test_overflow_when_moving_to_the_midpoint_is_refused(tmp_path: Path) -> None:
    msg = _refused(tmp_path, _doc(t_ref_is="start", fddot="1e300 Hz / s2"))
    assert "lisa" in msg


# ------------------------------------------------------------------ valid files unchanged


@pytest.mark.parametrize("catalog", ["hm-cnc-simulated.yaml", "fiducial-eccentric.yaml"])
def test_bundled_catalogs_load_to_the_same_target(catalog: str) -> None:
    """The strict loader reads the bundled catalogs exactly as yaml.safe_load did."""
    path = CATALOGS / catalog
    new = load_target(path)
    old = target_from_dict(yaml.safe_load(path.read_text()), path)
    assert new.params == old.params
    assert (new.cov_names, new.cov_matrix.tolist()) == (old.cov_names, old.cov_matrix.tolist())
    assert (new.t_ref - old.t_ref).to_value("s") == 0.0
    assert new.notes == old.notes and new.spectroscopy == old.spectroscopy


@pytest.mark.parametrize(
    ("lisa", "needle"),
    [
        ({"f_gw": "6.22 Hz"}, "lisa.f_gw: must be in (0, 1] Hz"),
        ({"t_obs": "1e12 s"}, "lisa.t_obs: must be positive and at most 100 yr"),
        ({"t_ref": "MJD 2465059.5"}, "a JD given as an MJD?"),
        ({"t_ref": "0001-01-01T00:00:00"}, "lisa.t_ref"),
        ({"t_ref_is": "start", "fdot": "-1e-9 Hz / s"}, "lisa.f_gw: f_gw at the midpoint"),
    ],
)
def test_other_out_of_range_values(tmp_path: Path, lisa: dict[str, Any], needle: str) -> None:
    assert needle in _refused(tmp_path, _doc(**lisa))


def test_velocity_faster_than_light_is_refused(tmp_path: Path) -> None:
    doc = _doc()
    doc["spectroscopy"] = {"lines": "SB1", "K1": 4.3e16}
    assert "below the speed of light" in _refused(tmp_path, doc)


def test_written_targets_read_back(tmp_path: Path) -> None:
    """write → load: an angle in exponent notation (astropy's angle parser refuses
    "1.5e-05 deg"), a name that looks like a number, a sub-millisecond midpoint epoch."""
    from dataclasses import replace

    from ucbplan.targets import write_target

    t = load_target(CATALOGS / "fiducial-injection.yaml")
    t = replace(t, name="1e3", ra_deg=1.5e-5, dec_deg=-2e-300)
    t = replace(t, t_ref=t.t_ref + 0.123456 * u.ms)
    out = tmp_path / "w.yaml"
    write_target(t, out)
    back = load_target(out)
    assert (back.name, back.ra_deg, back.dec_deg) == ("1e3", 1.5e-5, -2e-300)
    assert abs((back.t_ref - t.t_ref).to_value("s")) < 1e-6


@pytest.mark.parametrize(
    "name", ["a\x00b.yaml", "x" * 5000 + ".yaml", "\udcff.yaml", "missing.yaml", "."]
)
def test_unusable_paths_give_one_printable_line(tmp_path: Path, name: str) -> None:
    """A NUL byte was a bare ValueError; a 5000-character path made a 5000-character line; an
    undecodable file name made a message no terminal could print."""
    with pytest.raises(TargetFileError) as exc:
        load_target(tmp_path / name if name != "." else tmp_path)
    msg = str(exc.value)
    assert "\n" not in msg and len(msg) < 400
    msg.encode("utf-8")
