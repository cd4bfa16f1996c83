"""Instrument table (configs/instruments.yaml): packaged copy, schema, sources, physical ranges.

Every number in the table must carry a source; a field that could not be confirmed is left out
and named under ``missing:`` (for ``sigma_ref`` ucbplan then requires ``--sigma-v``).
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

import pytest
import yaml

from ucbplan.observing.observatory.sites import get_site, load_sites

REPO = Path(__file__).resolve().parents[3]
CONFIG = REPO / "configs" / "instruments.yaml"
PACKAGED = REPO / "ucbplan" / "data" / "instruments.yaml"

#: Fields every instrument has, either present or named under ``missing:``.
REQUIRED = ("acquisition_s", "readout_s", "min_exptime_s", "extinction_k", "sigma_ref")
#: Fields that must always be present.
ALWAYS = ("telescope", "sites")
#: Instruments issue 9 asks for at least.
EXPECTED = (
    "xshooter-uvb",
    "xshooter-vis",
    "uves",
    "fors2",
    "esi",
    "lris",
    "kcwi",
    "gmos-n",
    "gmos-s",
    "osiris-gtc",
    "isis",
    "weave",
)
#: Open physical ranges (lo, hi) for the numeric fields.
RANGES = {
    "acquisition_s": (0.0, 3600.0),
    "readout_s": (0.0, 600.0),
    "min_exptime_s": (0.0, 3600.0),
    "extinction_k": (0.0, 1.0),
}
SIGMA_REF_KEYS = ("sigma_v_kms", "mag", "band", "exptime_s")
SIGMA_REF_RANGES = {"sigma_v_kms": (0.0, 200.0), "mag": (10.0, 25.0), "exptime_s": (0.0, 36000.0)}


def _table() -> dict[str, dict[str, Any]]:
    doc = yaml.safe_load(CONFIG.read_text(encoding="utf-8"))
    assert isinstance(doc, dict) and isinstance(doc.get("instruments"), dict)
    return doc["instruments"]


INSTRUMENTS = _table()


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def test_packaged_copy_identical_to_configs() -> None:
    # Installed wheels have no configs/: the package reads ucbplan/data/instruments.yaml.
    assert CONFIG.read_bytes() == PACKAGED.read_bytes()


def test_expected_instruments_present_with_short_lowercase_names() -> None:
    assert set(EXPECTED) <= set(INSTRUMENTS)
    for name in INSTRUMENTS:
        assert re.fullmatch(r"[a-z0-9]+(-[a-z0-9]+)*", name), name


@pytest.mark.parametrize("name", sorted(INSTRUMENTS))
def test_required_fields_present_or_declared_missing(name: str) -> None:
    entry = INSTRUMENTS[name]
    for key in ALWAYS:
        assert entry.get(key), f"{name}: {key} is required"
    missing = entry.get("missing", [])
    assert isinstance(missing, list), f"{name}: missing must be a list"
    assert len(missing) == len(set(missing)), f"{name}: duplicate names in missing"
    assert set(missing) <= set(REQUIRED), f"{name}: missing names unknown fields {missing}"
    for key in REQUIRED:
        present = key in entry
        declared = key in missing
        assert present != declared, (
            f"{name}: {key} must be either given (with a source) or listed under missing, "
            f"not {'both' if present else 'neither'}"
        )


@pytest.mark.parametrize("name", sorted(INSTRUMENTS))
def test_every_present_number_has_a_source(name: str) -> None:
    entry = INSTRUMENTS[name]
    sources = entry.get("sources", {})
    assert isinstance(sources, dict), f"{name}: sources must be a mapping"
    numeric = [k for k, v in entry.items() if _is_number(v)]
    if "sigma_ref" in entry:
        numeric.append("sigma_ref")
    for key in numeric:
        text = sources.get(key)
        assert isinstance(text, str) and len(text.strip()) >= 20, (
            f"{name}: {key} has no source (URL, or bibcode with table/section)"
        )
        # A source names where: a URL, a bibcode or a DOI.
        assert re.search(r"https?://|\d{4}[A-Za-z&.]{2,}|10\.\d{4,}/", text), (
            f"{name}: source of {key} names no URL, bibcode or DOI: {text!r}"
        )
    # No orphan sources for fields that are not given.
    for key in sources:
        assert key in entry, f"{name}: source given for absent field {key}"


@pytest.mark.parametrize("name", sorted(INSTRUMENTS))
def test_values_in_physical_ranges(name: str) -> None:
    entry = INSTRUMENTS[name]
    for key, (lo, hi) in RANGES.items():
        if key in entry:
            value = entry[key]
            assert _is_number(value), f"{name}: {key} must be a number, got {value!r}"
            assert lo < value < hi, f"{name}: {key} = {value} outside ({lo}, {hi})"
    if "extinction_k" in entry:
        assert entry.get("extinction_band"), f"{name}: extinction_k needs its extinction_band"
    if "sigma_ref" in entry:
        ref = entry["sigma_ref"]
        assert isinstance(ref, dict), f"{name}: sigma_ref must be a mapping"
        for key in SIGMA_REF_KEYS:
            assert key in ref, f"{name}: sigma_ref needs {key}"
        assert isinstance(ref["band"], str) and ref["band"]
        for key, (lo, hi) in SIGMA_REF_RANGES.items():
            assert _is_number(ref[key]) and lo < ref[key] < hi, f"{name}: sigma_ref.{key}"


@pytest.mark.parametrize("name", sorted(INSTRUMENTS))
def test_site_keys_exist_in_site_table(name: str) -> None:
    sites = INSTRUMENTS[name]["sites"]
    assert isinstance(sites, list) and sites
    known = {s.name for s in load_sites()}
    for key in sites:
        assert get_site(key).name in known  # raises SiteError for an unknown key


def test_site_keys_resolve_to_the_intended_observatories() -> None:
    expected = {
        "paranal": "Paranal",
        "mauna-kea": "Mauna Kea",
        "cerro-pachon": "Cerro Pachon",
        "la-palma": "La Palma (ORM)",
    }
    used = {k for entry in INSTRUMENTS.values() for k in entry["sites"]}
    assert used <= set(expected)
    for key in used:
        assert get_site(key).name == expected[key]


def test_shared_overheads_agree() -> None:
    # One X-shooter acquisition serves both arms; GMOS-N and -S share Gemini's overhead table.
    assert (
        INSTRUMENTS["xshooter-uvb"]["acquisition_s"] == INSTRUMENTS["xshooter-vis"]["acquisition_s"]
    )
    for key in ("acquisition_s", "readout_s"):
        assert INSTRUMENTS["gmos-n"][key] == INSTRUMENTS["gmos-s"][key]
