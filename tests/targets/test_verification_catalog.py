"""The bundled catalog of real verification binaries, `catalogs/verification/` (issue 10, item 6).

A system file goes in only with every number confirmed in its published source and cited in the
file's `references:` (see the folder's README.md). Each file must

- load as a timing target, with a citation (bibcode or DOI) for every number it gives;
- have a sky position that agrees with the J-coordinates of its designation;
- reproduce its published ephemeris: eclipse times from `ucbplan ephemeris predict --anchor
  eclipse` against T0 + Pn + ½PṖn² (+ ⅙P²P̈n³) in exact decimal arithmetic, ≤ 10 µs over
  ±10 years, and the σ_t of the T0, P, Ṗ errors propagated by hand;
- give K's consistent with Kepler's third law when it gives masses, inclination and K's.

The same ephemeris checks run on the synthetic timing example, so they are exercised (and can
fail) whatever the catalog holds. The README's list of files must match the folder, and the
numbers it records as confirmed are checked against each other.
"""

from __future__ import annotations

import json
import math
import re
from decimal import Decimal, getcontext
from pathlib import Path
from typing import Any

import pytest
import yaml
from astropy.time import TimeDelta
from support.cli import run_cli

from ucbplan.targets import load_target

ROOT = Path(__file__).resolve().parents[2]
CATALOG = ROOT / "catalogs" / "verification"
SYN = ROOT / "catalogs" / "examples" / "synthetic-eclipsing.yaml"
FILES = sorted(CATALOG.glob("*.yaml"))


getcontext().prec = 40
DAY = Decimal(86400)
G_SI, C_SI, MSUN_KG = 6.6743e-11, 299792458.0, 1.988409870698051e30
#: A bibcode (19 characters: year, journal, volume, page, initial) or a DOI.
CITATION = re.compile(
    r"\d{4}[A-Za-z&.]{1,5}[A-Za-z0-9.&]*\.{0,4}[A-Z.]?\d*[A-Z]|doi:10\.\d{4,}/\S+"
)
#: Numeric fields that need a `references:` entry when present.
CITED = (
    "timing.t0",
    "timing.period",
    "timing.pdot",
    "timing.pddot",
    "timing.covariance",
    "timing.inclination",
    "timing.distance",
    "timing.eccentricity",
    "masses.m1",
    "masses.m2",
    "spectroscopy.K1",
    "spectroscopy.K2",
    "sky",
)


def _ids(paths: list[Path]) -> list[str]:
    return [p.stem for p in paths]


def _get(doc: dict[str, Any], path: str) -> Any:
    node: Any = doc
    for key in path.split("."):
        if not isinstance(node, dict) or key not in node:
            return None
        node = node[key]
    return node


def _decimal_seconds(text: Any) -> Decimal:
    """A period as written ('414.7915404 s', '0.0048 d' or a bare number of seconds)."""
    value, _, unit = str(text).strip().partition(" ")
    return Decimal(value) * (DAY if unit.strip() == "d" else Decimal(1))


def _decimal_t0_jd(text: str) -> Decimal:
    """T0 as written, BJD_TDB/BMJD_TDB/MJD_TDB, as an exact decimal JD (no float)."""
    word, _, value = text.strip().partition(" ")
    jd = Decimal(value)
    if word.upper() in ("BMJD_TDB", "MJD_TDB"):
        jd += Decimal("2400000.5")
    elif word.upper() != "BJD_TDB":
        pytest.fail(f"T0 {text!r}: this check reads BJD_TDB, BMJD_TDB or MJD_TDB")
    return jd


def _published_jd(doc: dict[str, Any], n: Decimal) -> Decimal:
    """t(n) = T0 + Pn + ½PṖn² + ⅙P²P̈n³ [JD], exact decimal arithmetic from the file's text."""
    tim = doc["timing"]
    p = _decimal_seconds(tim["period"])
    pdot = Decimal(str(tim["pdot"]))
    pddot = Decimal(str(tim.get("pddot", "0")).split(" ")[0])
    dt = p * n + p * pdot * n * n / 2 + p * p * pddot * n * n * n / 6
    return _decimal_t0_jd(str(tim["t0"])) + dt / DAY


def _predict(path: Path, start: str, end: str, out: Path) -> list[dict[str, Any]]:
    code, err = run_cli(
        [
            *("ephemeris", "predict", str(path), "--start", start, "--end", end),
            *("--anchor", "eclipse", "--format", "json", "-o", str(out), "--overwrite"),
        ]
    )
    assert code == 0, err[-600:]
    rows: list[dict[str, Any]] = json.loads(out.read_text())["rows"]
    assert rows, f"no eclipse between {start} and {end}"
    return rows


def _sigma_t_s(target: Any, n: float) -> float:
    """σ of t(n) from the file's σ(T0), σ(P), σ(Ṗ), taken as independent (by hand)."""
    tim = target.timing
    p = tim.ephemeris.period_s
    parts = {"t0": 1.0, "period": n, "pdot": 0.5 * p * n * n}
    total = 0.0
    for name, deriv in parts.items():
        sig = tim.sigma(name)
        total += (deriv * sig) ** 2 if sig is not None else 0.0
    return math.sqrt(total)


def _yaml(path: Path) -> dict[str, Any]:
    doc: dict[str, Any] = yaml.safe_load(path.read_text())
    return doc


@pytest.mark.parametrize("path", [*FILES, SYN], ids=[*_ids(FILES), "synthetic"])
def test_eclipse_times_reproduce_the_published_polynomial(path: Path, tmp_path: Path) -> None:
    """Eclipses ±10 yr around T0 agree with T0 + Pn + ½PṖn² to 10 µs; σ_t matches by hand."""
    doc = _yaml(path)
    target = load_target(path)
    assert target.kind == "timing"
    for years in (-10.0, -1.0, 0.0, 1.0, 10.0):
        start = target.t_ref + TimeDelta(years * 365.25, format="jd") - TimeDelta(60, format="sec")
        end = start + TimeDelta(2.2 * target.period_s, format="sec")
        for row in _predict(path, start.isot, end.isot, tmp_path / "eph.json"):
            n = Decimal(str(row["cycle"]))
            expect = _published_jd(doc, n)
            got = Decimal(row["t_star_bjd_tdb"])
            assert abs(got - expect) * DAY < Decimal("1e-5"), (years, row)
            # the primary eclipse is an integer cycle, the secondary a half-integer one
            assert (n % 1 == 0) == (row["eclipse"] == "primary")
            sig = _sigma_t_s(target, float(n))
            assert row["sigma_t_s"] == pytest.approx(sig, rel=2e-3, abs=1e-6)


@pytest.mark.parametrize("path", FILES, ids=_ids(FILES))
def test_every_number_is_cited(path: Path) -> None:
    _check_citations(path)


def _check_citations(path: Path) -> None:
    doc = _yaml(path)
    target = load_target(path)
    assert target.timing is not None and target.timing.source.strip()
    refs = doc.get("references") or {}
    for field in CITED:
        if _get(doc, field) is not None:
            assert field in refs, f"{path.name}: {field} has no references entry"
    for band in doc.get("magnitudes") or {}:
        assert f"magnitudes.{band}" in refs, f"{path.name}: magnitudes.{band} is not cited"
    for field, cite in refs.items():
        assert CITATION.search(str(cite)), f"{path.name}: {field}: {cite!r} has no bibcode/DOI"


def _designation_deg(name: str) -> tuple[float, float] | None:
    """(ra, dec) [deg] of a 'J hhmm[ss.s]±ddmm[ss.s]' designation, truncated as written."""
    m = re.search(r"J(\d{2})(\d{2})(\d{2}(?:\.\d+)?)?([+-−])(\d{2})(\d{2})(\d{2}(?:\.\d+)?)?", name)
    if m is None:
        return None
    h, mi, s, sign, d, dm, ds = m.groups()
    ra = 15.0 * (int(h) + int(mi) / 60.0 + float(s or 0.0) / 3600.0)
    dec = int(d) + int(dm) / 60.0 + float(ds or 0.0) / 3600.0
    return ra, -dec if sign in "-−" else dec


@pytest.mark.parametrize("path", FILES, ids=_ids(FILES))
def test_sky_position_matches_the_designation(path: Path) -> None:
    _check_designation(path)


def _check_designation(path: Path) -> None:
    target = load_target(path)
    pos = _designation_deg(target.name)
    if pos is None:
        pytest.skip(f"{target.name}: no J-designation in the name")
    ra, dec = pos
    # a designation truncates: hhmm → 1 min of RA (0.25 deg), ±ddmm → 1 arcmin
    assert 0.0 <= (target.ra_deg - ra) * math.cos(math.radians(dec)) < 0.26
    assert 0.0 <= abs(target.dec_deg) - abs(dec) < 1.0 / 60.0 + 1e-9


def _kepler_k_m_s(m_other: float, m_total: float, period_s: float, sin_i: float) -> float:
    """Circular-orbit semi-amplitude of the star whose companion has mass m_other [kg]."""
    return (2.0 * math.pi * G_SI / period_s) ** (1 / 3) * m_other * sin_i / m_total ** (2 / 3)


@pytest.mark.parametrize("path", FILES, ids=_ids(FILES))
def test_published_k_and_masses_follow_kepler(path: Path) -> None:
    _check_kepler(path)


def _check_kepler(path: Path) -> None:
    target = load_target(path)
    spec = target.spectroscopy
    needs = (target.m1_msun, target.m2_msun, target.cos_inclination)
    if spec is None or None in needs or (spec.K1_kms is None and spec.K2_kms is None):
        pytest.skip("no masses + inclination + K to compare")
    m1, m2 = target.m1_msun * MSUN_KG, target.m2_msun * MSUN_KG  # type: ignore[operator]
    sin_i = math.sqrt(1.0 - target.cos_inclination**2)  # type: ignore[operator]
    for k_kms, m_other in ((spec.K1_kms, m2), (spec.K2_kms, m1)):
        if k_kms is not None:
            k = _kepler_k_m_s(m_other, m1 + m2, target.period_s, sin_i) / 1e3
            # published masses carry a few per cent: 10 % is a consistency check, not a fit
            assert k_kms == pytest.approx(k, rel=0.10)


def test_readme_lists_exactly_the_files_in_the_folder() -> None:
    """The README's '## Files' section names every system file, and no other."""
    text = (CATALOG / "README.md").read_text()
    section = text.split("## Files", 1)[1].split("\n## ", 1)[0]
    listed = set(re.findall(r"`([\w.+-]+\.yaml)`", section))
    assert listed == {p.name for p in FILES}
    if not FILES:
        assert "none" in section.lower()


def _pdot_gr(m1_msun: float, m2_msun: float, period_s: float) -> float:
    """Ṗ from GW radiation of a circular binary (Peters 1964): −(192π/5)(2πG𝓜/(c³P))^{5/3}."""
    mc53 = (m1_msun * m2_msun) * MSUN_KG**2 * ((m1_msun + m2_msun) * MSUN_KG) ** (-1 / 3)
    return -(192 * math.pi / 5) * (2 * math.pi * G_SI / (C_SI**3 * period_s)) ** (5 / 3) * mc53


def test_j0651_abstract_numbers_are_consistent() -> None:
    """The README's confirmed numbers for SDSS J0651+2844 (abstract of 2012ApJ...757L..21H):
    P = 765.206543(55) s, M1 = 0.26, M2 = 0.50 Msun give the abstract's GR rate
    (−8.2 ± 1.7)e-12 s/s, and the measured (−9.8 ± 2.8)e-12 s/s lies within 1σ of it."""
    gr = _pdot_gr(0.26, 0.50, 765.206543)
    assert gr == pytest.approx(-8.2e-12, abs=0.05e-12)  # the abstract rounds to 0.1e-12
    assert abs(-9.8e-12 - gr) < 2.8e-12
    # σ(T0) recorded in the README: 9.5e-4 cycles of P = 0.727 s = 8.4e-6 d
    assert 9.5e-4 * 765.206543 == pytest.approx(0.727, abs=5e-4)
    assert 9.5e-4 * 765.206543 / 86400 == pytest.approx(8.4e-6, abs=0.05e-6)


def test_designation_parser_and_citation_pattern() -> None:
    """The helpers above, on known inputs (so the per-file checks can fail)."""
    ra, dec = _designation_deg("ZTF J153932.16+502738.8")  # type: ignore[misc]
    assert ra == pytest.approx(15 * (15 + 39 / 60 + 32.16 / 3600))
    assert dec == pytest.approx(50 + 27 / 60 + 38.8 / 3600)
    assert _designation_deg("SDSS J0651+2844") == pytest.approx((102.75, 28.7333333))
    assert _designation_deg("HM Cnc") is None
    assert CITATION.search("2019Natur.571..528B")
    assert CITATION.search("doi:10.1038/s41586-019-1403-0")
    assert not CITATION.search("Wikipedia")


def _fixture_file(tmp_path: Path, *, k1: str = "405 km/s", cite_pdot: bool = True) -> Path:
    """A made-up, fully cited file in the catalog's form (names and numbers are not real)."""
    refs = {
        "sky": "2000ApJ...500L...1X",
        "timing.t0": "2000ApJ...500L...1X",
        "timing.period": "2000ApJ...500L...1X",
        "timing.covariance": "2000ApJ...500L...1X",
        "timing.inclination": "2000ApJ...500L...1X",
        "masses.m1": "doi:10.1000/example",
        "masses.m2": "doi:10.1000/example",
        "spectroscopy.K1": "doi:10.1000/example",
        "magnitudes.g": "2000ApJ...500L...1X",
    }
    if cite_pdot:
        refs["timing.pdot"] = "2000ApJ...500L...1X"
    doc = {
        "name": "Test J0800-2000",
        "sky": {"ra": "08h00m05s", "dec": "-20d00m30s"},
        "magnitudes": {"g": 19.0},
        "masses": {"m1": "0.6 solMass", "m2": "0.3 solMass"},
        "spectroscopy": {"lines": "SB1", "K1": k1, "sigma_v": "20 km/s"},
        "timing": {
            "t0": "BJD_TDB 2461000.5000000",
            "t0_marks": "primary_eclipse",
            "period": "400.0 s",
            "pdot": -2.0e-11,
            "inclination": "80 deg",
            "covariance": {"sigma": {"t0": "1.0 s", "period": "5e-6 s", "pdot": 1.0e-13}},
            "source": "made-up test file (2000ApJ...500L...1X)",
        },
        "references": refs,
    }
    path = tmp_path / "test-j0800-2000.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return path


def test_checks_pass_on_a_consistent_file(tmp_path: Path) -> None:
    """K1 = 405 km/s is Kepler's for 0.6 + 0.3 Msun, P = 400 s, i = 80 deg (by hand: 404.9)."""
    path = _fixture_file(tmp_path)
    _check_citations(path)
    _check_designation(path)
    _check_kepler(path)


def test_checks_fail_on_an_uncited_number_or_a_wrong_k(tmp_path: Path) -> None:
    with pytest.raises(AssertionError, match=r"timing\.pdot"):
        _check_citations(_fixture_file(tmp_path, cite_pdot=False))
    with pytest.raises(AssertionError):
        _check_kepler(_fixture_file(tmp_path, k1="300 km/s"))
