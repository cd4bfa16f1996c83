"""A plan's ``not_planned`` (target → night → reason → count) written apart in the ECSV header
(:func:`ucbplan.observing.blocks.ecsv_header.yaml_nested_flow`): the bytes astropy's own writer
(PyYAML) writes, on random mappings of that shape, including lines past libyaml's width."""

from __future__ import annotations

import io
import random

import pytest
from astropy.table import Table

from ucbplan.observing.blocks import ecsv_header
from ucbplan.observing.blocks.write import write_table

REASONS = [
    "altitude/airmass",
    "daylight/twilight",
    "not needed",
    "Moon separation",
    "taken by a higher-priority target",
    "outside the zenith hole",
    "a reason long enough to push a flow mapping past the width of one header line",
]


def _pyyaml_ecsv(table: Table) -> str:
    buf = io.StringIO()
    table.write(buf, format="ascii.ecsv")  # astropy's own writer (PyYAML's emitter)
    return buf.getvalue()


def _ours(table: Table) -> str:
    buf = io.StringIO()
    write_table(table, buf, "ecsv")
    return buf.getvalue()


def _count(rng: random.Random, odd: bool) -> object:
    if odd and rng.random() < 0.3:
        return rng.choice([True, None, 2.5, "7", "many more", -0.0, 10**20, "2040-01-01"])
    return rng.choice([0, 1, 9, 62, 119, 50088, -3])


def _reasons(rng: random.Random, odd: bool) -> dict[str, object]:
    keys = rng.sample(REASONS[:-1], rng.randint(0, 5))
    if rng.random() < 0.1:  # past the width: libyaml breaks the line, PyYAML's path writes it
        keys.append(REASONS[-1])
    if odd and rng.random() < 0.3:
        keys.append(rng.choice(["x: y", "", " lead", "true", "1.5", "é"]))
    return {k: _count(rng, odd) for k in keys}


def _not_planned(rng: random.Random, odd: bool) -> dict[object, object]:
    out: dict[object, object] = {}
    for t in range(rng.randint(1, 4)):
        name = rng.choice([f"UCB{t:02d}", f"HM Cnc {t}", f"J0806-{t}", f"{t}", "null"])
        nights: dict[object, object] = {}
        for d in range(rng.randint(0, 6)):
            night = f"2040-0{1 + d % 9}-1{d}"
            if odd and rng.random() < 0.2:
                night = rng.choice(["night one", 20400101, "2040-01-01T00:00:00"])
            nights[night] = _reasons(rng, odd)
            if odd and rng.random() < 0.1:
                nights[night] = {"deeper": _reasons(rng, odd)}
        out[name] = nights
    return out


@pytest.mark.parametrize("seed", range(60))
def test_not_planned_header_bytes_as_astropy_writes_them(seed: int) -> None:
    rng = random.Random(seed)
    odd = seed % 3 == 0  # every third: kinds the fast path hands back to PyYAML's
    meta = {"alpha": 0.5, "not_planned": _not_planned(rng, odd)}
    if seed % 2:
        meta["visits"] = [{"visit_id": f"V{k:02d}", "exposures": k} for k in range(3)]
    table = Table({"a": [1.5, 2.0]}, meta=meta)
    assert _ours(table) == _pyyaml_ecsv(table)
    apart = ecsv_header.yaml_nested_flow(meta["not_planned"], ecsv_header._yaml_tag)
    TAKEN[odd] += apart is not None


#: How many random mappings the fast path wrote, of plain (False) and odd (True) kinds.
TAKEN = {False: 0, True: 0}


def test_random_mappings_exercised_both_paths() -> None:
    """(Runs after the random ones.) Most plain mappings took the fast path; some odd ones
    were handed back to PyYAML's."""
    assert TAKEN[False] >= 20 and TAKEN[True] < 20


def test_a_plans_not_planned_is_written_apart() -> None:
    """The shape a plan writes takes the fast path (a line past the width included)."""
    reasons = {"Moon separation": 8, "altitude/airmass": 98, "daylight/twilight": 1}
    reasons |= {"not needed": 119, "taken by a higher-priority target": 9}
    mapping = {"UCB00": {"2040-01-30": reasons, "2040-01-31": {}}, "UCB01": {}}
    lines = ecsv_header.yaml_nested_flow(mapping, ecsv_header._yaml_tag)
    assert lines is not None and max(map(len, lines)) > 130
    assert lines[1] == (
        "      '2040-01-30': {Moon separation: 8, altitude/airmass: 98, daylight/twilight: 1, "
        "not needed: 119, taken by a higher-priority target: 9}"
    )
    table = Table({"a": [1.5]}, meta={"not_planned": mapping})
    assert _ours(table) == _pyyaml_ecsv(table)


def test_true_is_not_written_as_one() -> None:
    """Each scalar's text is found once per exact type and value: a count of 1 met first does
    not stand for a later ``True`` (equal to 1 in Python, ``true`` in YAML)."""
    mapping = {"UCB00": {"2040-01-30": {"a": 1, "b": True}, "2040-01-31": {"a": 0, "b": False}}}
    assert ecsv_header.yaml_nested_flow(mapping, ecsv_header._yaml_tag) is None  # PyYAML's
    table = Table({"a": [1.5]}, meta={"not_planned": mapping})
    assert _ours(table) == _pyyaml_ecsv(table)
