"""Property tests of target files (issue 11): mutated catalogs and generated valid targets.

(a) Mutations of the bundled catalogs (a key deleted, an unknown key added, a value replaced by
    arbitrary YAML, a key renamed with a typo) either load or raise :class:`TargetFileError` with
    one line under 400 characters that names the file and the field; never another exception,
    each in under 2 s. Mutations of their text (lines duplicated or deleted, tags, anchors and
    odd scalars inserted) likewise load or fail with one line naming the file.
(b) Targets generated from the schema's ranges always load, and write → load gives them back.

The default run tries a few dozen examples per property; ``-m slow`` runs thousands.
"""

from __future__ import annotations

import copy
import datetime as dt
import math
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from ucbplan.errors import TargetFileError
from ucbplan.targets import Target, load_target, write_target
from ucbplan.targets.schema import COVARIANCE_PARAMETERS, field
from ucbplan.targets.values import Ctx
from ucbplan.targets.write import _Dumper

CATALOGS = Path(__file__).resolve().parents[2] / "catalogs"
CATALOG_NAMES = ("hm-cnc-simulated.yaml", "fiducial-eccentric.yaml", "fiducial-injection.yaml")
DOCS = {name: yaml.safe_load((CATALOGS / name).read_text()) for name in CATALOG_NAMES}

# No per-example deadline: under load one example took 2.6 s against the old 2-s deadline (a
# timing-dependent failure); both profiles are derandomized, so every run checks the same cases.
QUICK = settings(
    max_examples=100,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
    derandomize=True,
)
THOROUGH = settings(
    max_examples=1500,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
    derandomize=True,
)

# ------------------------------------------------------------------ arbitrary YAML values

UNIT_TEXT = [
    "6.2204944286e-3 Hz",
    "0.039 rad / s",
    "2.4e-7 Hz",
    "1.5e-6 rad/s",
    "48 deg",
    "0.67",
    "4 yr",
    "126232599.05 s",
    "2 kpc",
    "1 solMass",
    "585 km/s",
    "7e-16 Hz / s",
    "1e-26 Hz / s2",
    "nan",
    ".nan",
    "inf",
    "-.inf",
    "nan Hz",
    "1e400",
    "1e400 Hz",
    "-1",
    "0",
    "1e-320",
    "08h06m23.2s",
    "+15d27m30s",
    "25h",
    "2037-01-01T00:00:00",
    "2037-01-01T00:00:00 UTC",
    "2037-01-01T00:00:00 TCB",
    "MJD 65059",
    "JD 2465059.5",
    "MJD 2465059.5",
    "SB1",
    "sb2",
    "start",
    "midpoint",
    "utc",
    "tcb",
    "icrs",
    "galactic",
    "phase,fdot",
    "posterior.ecsv",
    "",
    "1 " + "(" * 60 + "Hz" + ")" * 60,
]

#: Text: unicode (no surrogates), padding around units, long runs.
TEXT = st.one_of(
    st.text(max_size=30),
    st.sampled_from(UNIT_TEXT),
    st.builds(
        lambda pad, body, where: (
            pad + body if where == 0 else body + pad if where == 1 else body[:3] + pad + body[3:]
        ),
        st.builds(
            lambda char, n: char * n,
            st.sampled_from(" \t0(é\u3000"),
            st.sampled_from([500, 20_000]),
        ),
        st.sampled_from(UNIT_TEXT),
        st.integers(0, 2),
    ),
)
SCALARS = st.one_of(
    st.integers(),
    st.integers(min_value=10**300, max_value=10**450),
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0.0, -0.0, 1e308, -1e308, 5e-324, 0.5, 1.0, 2.0, 0.1]),
    TEXT,
    st.booleans(),
    st.none(),
)
KEYS = st.one_of(
    st.text(max_size=12), st.integers(), st.none(), st.booleans(), st.floats(allow_nan=False)
)
VALUES = st.recursive(
    SCALARS,
    lambda inner: st.one_of(st.lists(inner, max_size=4), st.dictionaries(KEYS, inner, max_size=4)),
    max_leaves=12,
)


# ------------------------------------------------------------------ mutations


def _paths(node: Any, prefix: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    """Every key path (mapping keys and list indices) below ``node``."""
    out: list[tuple[Any, ...]] = []
    items = (
        node.items()
        if isinstance(node, dict)
        else enumerate(node)
        if isinstance(node, list)
        else ()
    )
    for key, value in items:
        out.append((*prefix, key))
        out += _paths(value, (*prefix, key))
    return out


def _mappings(node: Any, prefix: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    """Paths of the mappings inside ``node`` (the root is ``()``)."""
    out = [prefix] if isinstance(node, dict) else []
    items = (
        node.items()
        if isinstance(node, dict)
        else enumerate(node)
        if isinstance(node, list)
        else ()
    )
    for key, value in items:
        out += _mappings(value, (*prefix, key))
    return out


def _at(doc: Any, path: tuple[Any, ...]) -> Any:
    for key in path:
        doc = doc[key]
    return doc


def _typo(key: str, kind: int, pos: int, char: str) -> str:
    if not key:
        return char
    pos %= len(key)
    if kind == 0:
        return key[:pos] + key[pos + 1 :]  # deletion
    if kind == 1 and len(key) > 1:
        pos = min(pos, len(key) - 2)  # swap neighbours
        return key[:pos] + key[pos + 1] + key[pos] + key[pos + 2 :]
    if kind == 2:
        return key[:pos] + char + key[pos:]  # insertion
    return key.upper() if key != key.upper() else key + char


@st.composite
def mutated(draw: Callable[..., Any], name: str) -> tuple[Any, set[str]]:
    """A catalog document with one mutation, and the top-level names the error may cite."""
    doc = copy.deepcopy(DOCS[name])
    kind = draw(st.sampled_from(["delete", "add", "replace", "rename"]))
    if kind == "add":
        where = draw(st.sampled_from(_mappings(doc)))
        key = draw(st.one_of(st.sampled_from(["correlaton", "f_gws", "frame", "phase", "l"]), KEYS))
        _at(doc, where)[key] = draw(VALUES)
        top = where[0] if where else key
        return doc, {Ctx.key(top)}
    path = draw(st.sampled_from(_paths(doc)))
    parent, key = _at(doc, path[:-1]), path[-1]
    if kind == "delete":
        del parent[key]
    elif kind == "replace":
        parent[key] = draw(VALUES)
    elif isinstance(parent, dict):  # rename with a typo (lists: replace the entry)
        new = _typo(
            str(key), draw(st.integers(0, 3)), draw(st.integers(0, 40)), draw(st.characters())
        )
        value = parent.pop(key)
        if new in parent:
            return doc, {Ctx.key(path[0])}
        parent[new] = value
        return doc, {Ctx.key(path[0]), Ctx.key(new)}
    else:
        parent[key] = draw(VALUES)
    return doc, {Ctx.key(path[0])}


def _keys_as_read(text: str) -> set[str]:
    """Top-level keys as YAML reads the dumped text back (PyYAML dumps a key holding U+0085
    unquoted, and reading folds that line break into a space), in both spellings an error uses."""
    from ucbplan.errors import shorten

    try:
        back = yaml.safe_load(text)
    except yaml.YAMLError:
        return set()
    if not isinstance(back, dict):
        return set()
    return {str(k) for k in back} | {shorten(k, 60) for k in back}


def _check_mutation(tmp_path: Path, doc: Any, tops: set[str]) -> None:
    path = tmp_path / "t.yaml"
    text = yaml.safe_dump(doc, allow_unicode=True, sort_keys=False)
    path.write_text(text, encoding="utf-8")
    tops = tops | _keys_as_read(text)
    start = time.perf_counter()
    try:
        load_target(path)
    except TargetFileError as exc:
        msg = str(exc)
        assert "\n" not in msg and "\r" not in msg, msg
        assert len(msg) < 400, msg
        if msg.startswith(f"{path}: "):  # refused by the YAML reader: names the file
            assert "YAML" in msg, msg
        else:
            assert msg.startswith("t.yaml: "), msg
            head = msg[len("t.yaml: ") :]
            assert any(head.startswith(t) for t in (*tops, "<top>")), (tops, msg)
    assert time.perf_counter() - start < 2.0


@pytest.mark.parametrize("name", CATALOG_NAMES)
def test_mutated_catalogs_load_or_fail_with_one_line(tmp_path: Path, name: str) -> None:
    @QUICK
    @given(mutated(name))
    def run(case: tuple[Any, set[str]]) -> None:
        _check_mutation(tmp_path, *case)

    run()


@pytest.mark.slow
@pytest.mark.parametrize("name", CATALOG_NAMES)
def test_mutated_catalogs_thoroughly(tmp_path: Path, name: str) -> None:
    @THOROUGH
    @given(mutated(name))
    def run(case: tuple[Any, set[str]]) -> None:
        _check_mutation(tmp_path, *case)

    run()


# ------------------------------------------------------------------ mutations of the YAML text

#: Text a hand-edited file may contain: tags, anchors, merge keys, flow syntax, odd scalars.
SNIPPETS = [
    "!!binary aGVsbG8=",
    "!!set {a, b}",
    "!!omap [a: 1]",
    "!!python/object:os.system x",
    "&a [1, 2]",
    "*a",
    "<<: {phase: 1}",
    "? [a, b]\n: 1",
    "1e400",
    ".nan",
    "-.inf",
    "0x1F",
    "0o17",
    "1_000",
    "2037-01-01 00:00:00 +02:00",
    "~",
    "[" * 50,
    "{",
    '"\\ud800"',
    "\t",
    "\ufeff",
    "phase: 1",
    "  correlaton: {phase,fdot: -0.7}",
    "'48 deg'",
]


@st.composite
def mutated_text(draw: Callable[..., Any], name: str) -> str:
    """The catalog's text with a line duplicated or deleted, or a snippet inserted."""
    lines = (CATALOGS / name).read_text().splitlines()
    i = draw(st.integers(0, len(lines) - 1))
    kind = draw(st.sampled_from(["duplicate", "delete", "insert", "replace_value"]))
    if kind == "duplicate":
        lines.insert(i, lines[i])
    elif kind == "delete":
        del lines[i]
    elif kind == "insert":
        snippet = draw(st.one_of(st.sampled_from(SNIPPETS), st.text(max_size=20)))
        col = draw(st.integers(0, len(lines[i])))
        lines[i] = lines[i][:col] + snippet + lines[i][col:]
    else:
        key, sep, _ = lines[i].partition(":")
        if sep:
            lines[i] = f"{key}: {draw(st.one_of(st.sampled_from(SNIPPETS), st.text(max_size=20)))}"
    return "\n".join(lines) + "\n"


def _check_text(tmp_path: Path, text: str) -> None:
    path = tmp_path / "t.yaml"
    path.write_text(text, encoding="utf-8", errors="surrogatepass")
    start = time.perf_counter()
    try:
        load_target(path)
    except TargetFileError as exc:
        msg = str(exc)
        assert "\n" not in msg and "\r" not in msg and len(msg) < 400, msg
        assert msg.startswith((f"{path}: ", "t.yaml: ")), msg
        msg.encode("utf-8")  # printable
    assert time.perf_counter() - start < 2.0


@pytest.mark.parametrize("name", CATALOG_NAMES)
def test_mutated_catalog_text_loads_or_fails_with_one_line(tmp_path: Path, name: str) -> None:
    @QUICK
    @given(mutated_text(name))
    def run(text: str) -> None:
        _check_text(tmp_path, text)

    run()


@pytest.mark.slow
@pytest.mark.parametrize("name", CATALOG_NAMES)
def test_mutated_catalog_text_thoroughly(tmp_path: Path, name: str) -> None:
    @THOROUGH
    @given(mutated_text(name))
    def run(text: str) -> None:
        _check_text(tmp_path, text)

    run()


# ------------------------------------------------------------------ valid targets from the schema


def _inside(path: str, low: float | None = None, high: float | None = None) -> st.SearchStrategy:
    """Finite floats inside the schema range of ``path`` (narrowed by ``low``/``high``)."""
    b = field(path).bounds
    lo = max(b.low if b else -math.inf, -1e6 if low is None else low)
    hi = min(b.high if b else math.inf, 1e6 if high is None else high)
    return st.floats(
        lo,
        hi,
        exclude_min=bool(b and b.low_open and lo == b.low),
        exclude_max=bool(b and b.high_open and hi == b.high),
        allow_nan=False,
    )


def _written(path: str, x: float, as_text: bool) -> float | str:
    """``x`` bare (in the field's unit) or as a quantity string with that unit."""
    unit = field(path).unit
    return f"{x!r} {unit}" if as_text and unit else x


NAME = st.text(
    st.characters(blacklist_categories=("Cc", "Cs", "Zl", "Zp")), min_size=1, max_size=40
).filter(str.strip)
EPOCH = st.datetimes(min_value=dt.datetime(2000, 1, 1), max_value=dt.datetime(2099, 12, 31)).map(
    lambda d: d.isoformat(timespec="milliseconds")
)
SCALES_OF_T_REF = st.sampled_from([None, *field("lisa.t_ref_scale").choices])


@st.composite
def valid_targets(draw: Callable[..., Any]) -> dict[str, Any]:
    """A target document inside every schema range (σ-form or matrix-form covariance)."""
    text = st.booleans()
    doc: dict[str, Any] = {"name": draw(NAME)}
    if draw(st.booleans()):
        doc["sky"] = {
            "ra": _written("sky.ra", draw(_inside("sky.ra", high=359.999)), draw(text)),
            "dec": _written("sky.dec", draw(_inside("sky.dec")), draw(text)),
        }
    else:
        doc["sky"] = {"l": draw(st.floats(-360, 360)), "b": draw(_inside("sky.b"))}
    t_obs = draw(_inside("lisa.t_obs", low=1e4))
    f_gw = draw(st.floats(1e-5, 0.1))
    fdot = draw(st.floats(-1e-13, 1e-13))
    fddot = draw(st.floats(-1e-24, 1e-24))
    ref_is = draw(st.sampled_from(field("lisa.t_ref_is").choices))
    half = t_obs / 2 if ref_is == "start" else 0.0
    assume(f_gw + fdot * half + fddot * half**2 / 2 > 1e-6)
    ecc, omega = draw(st.floats(0, 0.0999)), draw(st.floats(0, 2 * math.pi))
    lisa: dict[str, Any] = {
        "t_ref": draw(EPOCH),
        "t_obs": _written("lisa.t_obs", t_obs, draw(text)),
        "t_ref_is": ref_is,
        "phase": draw(st.floats(-100, 100)),
        "f_gw": _written("lisa.f_gw", f_gw, draw(text)),
        "fdot": _written("lisa.fdot", fdot, draw(text)),
        "fddot": _written("lisa.fddot", fddot, draw(text)),
        "eta": ecc * math.sin(omega),
        "kappa": ecc * math.cos(omega),
        "omega_dot": _written("lisa.omega_dot", draw(st.floats(-1e-5, 1e-5)), draw(text)),
        "cos_inclination": draw(_inside("lisa.cos_inclination")),
        "amplitude": draw(st.floats(1e-25, 1e-18)),
        "psi": draw(st.floats(-math.pi, math.pi)),
        "distance": _written("lisa.distance", draw(st.floats(0.01, 100)), draw(text)),
    }
    scale = draw(SCALES_OF_T_REF)
    if scale is not None:
        lisa["t_ref_scale"] = scale
    lisa["covariance"] = draw(st.one_of(st.none(), _sigma_form(), _matrix_form()))
    if lisa["covariance"] is None:
        del lisa["covariance"]
    doc["lisa"] = lisa
    if draw(st.booleans()):
        doc["priority"] = draw(_inside("priority", high=100))
        doc["vmag"] = draw(st.floats(-5, 30))
    if draw(st.booleans()):
        doc["masses"] = {
            "m1": _written("masses.m1", draw(_inside("masses.m1", high=3)), draw(text)),
            "m2": _written("masses.m2", draw(_inside("masses.m2", high=3)), draw(text)),
        }
    if draw(st.booleans()):
        doc["spectroscopy"] = {
            "lines": draw(st.sampled_from(field("spectroscopy.lines").choices)),
            "K1": _written("spectroscopy.K1", draw(_inside("spectroscopy.K1", high=3000)), True),
            "sigma_v": draw(_inside("spectroscopy.sigma_v", high=500)),
        }
    doc["notes"] = draw(st.text(max_size=20))
    return doc


#: Realistic σ scales of each covariance parameter (SI), spanning ~10⁴⁰.
_SIGMA_SCALE = {
    "phase": 1e-2,
    "f_gw": 1e-11,
    "fdot": 1e-18,
    "fddot": 1e-27,
    "eta": 1e-3,
    "kappa": 1e-3,
    "omega_dot": 1e-9,
    "cos_inclination": 1e-2,
    "amplitude": 1e-23,
    "psi": 1e-2,
}


def _names() -> st.SearchStrategy:
    return st.lists(st.sampled_from(COVARIANCE_PARAMETERS), min_size=1, max_size=6, unique=True)


@st.composite
def _sigma_form(draw: Callable[..., Any]) -> dict[str, Any]:
    names = draw(_names())
    sigma = {n: _SIGMA_SCALE[n] * draw(st.floats(0.01, 100)) for n in names}
    cov: dict[str, Any] = {"sigma": sigma}
    if len(names) >= 2 and draw(st.booleans()):
        cov["correlation"] = {f"{names[0]},{names[1]}": draw(st.floats(-0.99, 0.99))}
    return cov


@st.composite
def _matrix_form(draw: Callable[..., Any]) -> dict[str, Any]:
    names = draw(_names())
    n = len(names)
    a = np.array(draw(st.lists(st.floats(-1, 1), min_size=n * n, max_size=n * n))).reshape(n, n)
    m = a @ a.T + 0.1 * np.eye(n)
    d = np.sqrt(np.diag(m))
    corr = m / np.outer(d, d)
    corr = 0.5 * (corr + corr.T)
    sig = np.array([_SIGMA_SCALE[k] * draw(st.floats(0.01, 100)) for k in names])
    mat = corr * np.outer(sig, sig)
    return {"parameters": names, "matrix": [[float(x) for x in row] for row in mat]}


def _same(t1: Target, t2: Target) -> None:
    assert t2.name == t1.name
    assert (t2.ra_deg, t2.dec_deg) == pytest.approx((t1.ra_deg, t1.dec_deg), abs=1e-12)
    assert t2.params.as_array().tolist() == t1.params.as_array().tolist()
    assert abs((t2.t_ref - t1.t_ref).to_value("s")) <= 1e-6
    assert t2.t_obs_s == t1.t_obs_s
    assert t2.cov_names == t1.cov_names
    assert np.array_equal(t2.cov_matrix, t1.cov_matrix)
    extras = ("cos_inclination", "amplitude", "psi", "distance_kpc", "m1_msun", "m2_msun")
    assert [getattr(t2, k) for k in extras] == [getattr(t1, k) for k in extras]
    assert (t2.priority, t2.vmag, t2.spectroscopy) == (t1.priority, t1.vmag, t1.spectroscopy)
    assert t2.ref_shift_s == 0.0


def _check_valid(tmp_path: Path, doc: dict[str, Any]) -> None:
    src = tmp_path / "gen.yaml"
    # a generated name such as "0E0" is text: dump it the way ucbplan's writer does (quoted),
    # since ucbplan reads an unquoted 0E0 as a number
    src.write_text(
        yaml.dump(doc, Dumper=_Dumper, allow_unicode=True, sort_keys=False), encoding="utf-8"
    )
    start = time.perf_counter()
    t1 = load_target(src)
    out = tmp_path / "written.yaml"
    write_target(t1, out, overwrite=True)
    t2 = load_target(out)
    assert time.perf_counter() - start < 2.0
    _same(t1, t2)


def test_valid_targets_load_and_round_trip(tmp_path: Path) -> None:
    @QUICK
    @given(valid_targets())
    def run(doc: dict[str, Any]) -> None:
        _check_valid(tmp_path, doc)

    run()


@pytest.mark.slow
def test_valid_targets_thoroughly(tmp_path: Path) -> None:
    @THOROUGH
    @given(valid_targets())
    def run(doc: dict[str, Any]) -> None:
        _check_valid(tmp_path, doc)

    run()
