"""The fast readers of target-file values give astropy's floats bit for bit (issue 34).

:mod:`ucbplan.targets.fastvalues` reads the common spellings of quantities, angles and epochs
without astropy's parsers, and :func:`ucbplan.inputs.load_yaml` reads anchor-free text with
libyaml; each must give exactly what the slow way gives (or decline, None), on the schema's own
units and on generated spellings.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import pytest
import yaml
from astropy import units as u
from astropy.coordinates import Angle
from hypothesis import given, settings
from hypothesis import strategies as st

from ucbplan.core.epochs import epoch_in_scale
from ucbplan.inputs import _FastLoader, _load_fast, _StrictLoader
from ucbplan.targets.fastvalues import cached_epoch, quantity_in, sexagesimal_deg
from ucbplan.targets.schema import FIELDS

CATALOGS = Path(__file__).resolve().parents[2] / "catalogs"
#: Every unit a quantity of the schema is read in, and spellings users write for them.
SCHEMA_UNITS = sorted({f.unit for f in FIELDS if f.kind == "quantity" and f.unit is not None})
SPELLINGS = [
    "Hz", "mHz", "Hz / s", "Hz/s", "Hz s-1", "Hz / s2", "Hz / s**2", "1 / s", "rad / s",
    "rad/s", "deg / yr", "s", "d", "day", "yr", "min", "h", "kpc", "pc", "km/s", "km / s",
    "m / s", "solMass", "M_sun", "rad", "deg", "arcsec", "mas", "mag", "", "s / s", "cycle",
    "foo", "Hz)", "kpc2", "Jy",
]  # fmt: skip


def _astropy_value(text: str, unit: str) -> float | None:
    """``Quantity(text).to_value(unit)`` as the slow path computes it (None: it refuses)."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            q = u.Quantity(text)
            return float(q.to_value(u.Unit(unit)))
    except Exception:
        return None


@pytest.mark.parametrize("unit", SCHEMA_UNITS)
@pytest.mark.parametrize("spelling", SPELLINGS)
def test_every_schema_unit_and_spelling_converts_as_astropy(unit: str, spelling: str) -> None:
    for number in ("1", "6.2204944286e-3", "-1.065650e-26", "126232599.05", ".5", "7E+3"):
        text = f"{number} {spelling}"
        fast = quantity_in(text, unit)
        if fast is not None:  # declining is always allowed; a value must be astropy's
            assert fast == _astropy_value(text, unit), text


@settings(max_examples=300, deadline=None, derandomize=True)
@given(
    st.floats(allow_nan=False, allow_infinity=False, width=64),
    st.sampled_from(SPELLINGS),
    st.sampled_from(SCHEMA_UNITS),
    st.sampled_from(["{} {}", "{}{}", " {}  {} ", "{}. {}", "{}e5{}", "{}.{}"]),
)
def test_generated_quantities_convert_as_astropy(
    x: float, spelling: str, unit: str, form: str
) -> None:
    text = form.format(repr(x), spelling)
    fast = quantity_in(text, unit)
    if fast is not None:
        assert fast == _astropy_value(text, unit), text


def test_a_bare_number_or_an_unknown_unit_is_left_to_astropy() -> None:
    assert quantity_in("5", "Hz") is None
    assert quantity_in("5 foo", "Hz") is None
    assert quantity_in("5 km", "Hz") is None  # the wrong dimension: astropy's message
    assert quantity_in("nan Hz", "Hz") is None
    assert quantity_in("[1, 2] Hz", "Hz") is None
    assert quantity_in("1.5.3 Hz", "Hz") is None


def _astropy_angle(text: str, hours: bool) -> float:
    unit = u.hourangle if hours and ":" in text else (u.deg if ":" in text else None)
    return float(Angle(text, unit=unit).to_value(u.deg))


@settings(max_examples=400, deadline=None, derandomize=True)
@given(
    st.sampled_from(["", "+", "-"]),
    st.integers(0, 99),
    st.integers(0, 59),
    st.one_of(st.integers(0, 59), st.floats(0, 59.999999, allow_nan=False)),
    st.sampled_from(["h", "d", ":"]),
    st.booleans(),
)
def test_sexagesimal_angles_sum_as_astropy(
    sign: str, first: int, minutes: int, seconds: float, sep: str, hours: bool
) -> None:
    sec = f"{seconds}" if isinstance(seconds, int) else f"{seconds:.6f}"
    text = (
        f"{sign}{first:02d}:{minutes:02d}:{sec}"
        if sep == ":"
        else f"{sign}{first:02d}{sep}{minutes:02d}m{sec}s"
    )
    fast = sexagesimal_deg(text, hours)
    if fast is not None:
        assert fast == _astropy_angle(text, hours), text
    else:  # declined only where astropy warns or refuses (hours ≥ 24)
        assert first >= 24 and (sep == "h" or (sep == ":" and hours)), text


def test_angles_astropy_warns_about_are_left_to_astropy() -> None:
    for text in ("12h60m00s", "12d00m60s", "24:00:00", "12h30m", "12 30 00", "12h30m00sN"):
        assert sexagesimal_deg(text, True) is None, text
    assert sexagesimal_deg("-00d30m00s", False) == -0.5


def test_a_cached_epoch_is_a_copy_each_time() -> None:
    calls = []

    def read() -> object:
        calls.append(1)
        return epoch_in_scale("2031-05-06T07:08:09", "tdb", isot_if_t=True)

    a = cached_epoch("2031-05-06T07:08:09", "tdb", True, read)  # type: ignore[arg-type]
    b = cached_epoch("2031-05-06T07:08:09", "tdb", True, read)  # type: ignore[arg-type]
    assert len(calls) == 1 and a is not b and a == b
    a.precision = 6  # a caller changing its copy changes no other target's epoch
    assert b.precision == 3


YAML_TEXTS = [
    "a: 1\nb: [1, 2, {c: 5e-14}]\n",
    "x: 1e-6\ny: -2E+3\nz: 1_000\nw: 0x1f\nv: .inf\nu: ~\nt: 2037-01-01\n",
    "a: 'q'\nb: \"\\u00e9\"\nc: |\n  text\n  more\nd: >-\n  folded\n",
    "- 1\n- - 2\n  - 3\n",
    "a: 1\na: 2\n",
    "a: [1, 2\n",
    "a:\tb\n",
    "? [1, 2]\n: 3\n",
    "a: !!str 5\nb: !!float 1\n",
    "a: <<\n",
    "<<: {a: 1}\nb: 2\n",
    "\ufeffa: 1\n",
    "a: 1\n---\nb: 2\n",
    "a: \u2028b\n",
    "a: \x85\n",
    "'a': 1\n\"a\": 2\n",
    "=: x\n",
    "a: {=: 2, b: 1}\n",
]


@pytest.mark.parametrize("text", YAML_TEXTS)
def test_libyaml_reads_as_the_strict_reader_or_declines(text: str) -> None:
    for documents in (False, True):
        fast = _load_fast(text, documents)
        if fast is None:
            continue
        loader = _StrictLoader(text)
        try:
            if documents:
                slow = []
                while loader.check_data():
                    slow.append(loader.get_data())
            else:
                slow = loader.get_single_data()
        finally:
            loader.dispose()
        assert fast[0] == slow and repr(fast[0]) == repr(slow), text


@pytest.mark.parametrize("path", sorted(CATALOGS.rglob("*.yaml")), ids=lambda p: p.name)
def test_the_bundled_catalogs_read_alike(path: Path) -> None:
    text = path.read_text(encoding="utf-8")
    assert _load_fast(text, False) == (yaml.load(text, Loader=_StrictLoader),)
    assert issubclass(_FastLoader, yaml.CSafeLoader)


#: Characters that steer YAML's grammar, and a few plain ones.
_YAML_ALPHABET = ": -[]{},#'\"!*?|>\n\t%@`=~.0123456789eaxyz\\\u00e9\u2028"


@settings(max_examples=1000, deadline=None, derandomize=True)
@given(st.text(alphabet=_YAML_ALPHABET, max_size=40))
def test_generated_yaml_reads_as_the_strict_reader_or_declines(text: str) -> None:
    fast = _load_fast(text, False)
    if fast is None:
        return
    loader = _StrictLoader(text)
    try:
        slow = loader.get_single_data()
    finally:
        loader.dispose()
    assert repr(fast[0]) == repr(slow), text


#: Plain words YAML's resolvers read as other than text, or nearly so.
_WORDS = ["yes", "No", "on", "OFF", "~", "null", "Null", "1e5", "0x1F", "0o17", "1_000",
          "1:30", "-.inf", ".NaN", "2037-01-01", "2037-01-01T00:00:00", "<<", "=", "+1", "1.",
          "e5"]  # fmt: skip
_SCALARS = st.one_of(
    st.sampled_from(_WORDS),
    st.text(alphabet="abc019.-+:eE_ ", max_size=8),
    st.integers(),
    st.floats(),
    st.booleans(),
    st.none(),
)
_DOCS = st.recursive(
    _SCALARS,
    lambda kids: st.lists(kids, max_size=4) | st.dictionaries(_SCALARS, kids, max_size=4),
    max_leaves=20,
)


def _all_documents(loader: _StrictLoader) -> list[object]:
    docs = []
    while loader.check_data():
        docs.append(loader.get_data())
    return docs


@settings(max_examples=300, deadline=None, derandomize=True)
@given(_DOCS, st.sampled_from([None, True, False]))
def test_generated_documents_read_as_the_strict_reader_or_decline(doc: object, flow: bool) -> None:
    """Whole documents, plain words unquoted (what the event reader resolves itself), two
    documents of a stream as one list."""
    text = yaml.safe_dump(doc, default_flow_style=flow)
    text = text.replace("'", "") if all(w not in text for w in ("''", ": ", "#")) else text
    for documents, body in ((False, text), (True, f"{text}---\n{text}")):
        fast = _load_fast(body, documents)
        if fast is None:
            continue
        loader = _StrictLoader(body)
        try:
            slow = loader.get_single_data() if not documents else _all_documents(loader)
        finally:
            loader.dispose()
        assert repr(fast[0]) == repr(slow), body


def test_loading_the_bundled_targets_imports_no_coordinates() -> None:
    """Angles with a unit ("108.3 deg") are read without astropy.coordinates (27 ms cold)."""
    import subprocess
    import sys

    code = (
        "import sys; from ucbplan.targets import load_target_files; "
        f"load_target_files({[str(p) for p in sorted(CATALOGS.glob('*.yaml'))]!r}); "
        "print('astropy.coordinates' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


@settings(max_examples=2000, deadline=None, derandomize=True)
@given(st.text(alphabet="0123456789.+-eE Hzkm/s\t\n\u00a0[", max_size=16))
def test_the_quantity_split_is_the_pattern_s(text: str) -> None:
    """The split without the regular expression is the pattern's, whatever the text."""
    from ucbplan.targets.fastvalues import _QUANTITY, _split_quantity

    m = _QUANTITY.fullmatch(text)
    assert _split_quantity(text) == (None if m is None else (m.group(1), m.group(2)))
    spaced = f"{text.strip()} Hz"  # the usual spelling, where the fast split applies
    m = _QUANTITY.fullmatch(spaced)
    assert _split_quantity(spaced) == (None if m is None else (m.group(1), m.group(2)))
