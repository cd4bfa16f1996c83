"""Horizons of many targets in one call: the long table (target × anchor × α) and catalogs."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from ucbplan.core.forecast import horizon_table
from ucbplan.core.validity_batch import HORIZON_COLUMNS, horizon_json, horizon_rows, horizons
from ucbplan.errors import InputError, TargetFileError
from ucbplan.targets import load_target, load_target_documents

if TYPE_CHECKING:
    from astropy.table import Table

CATALOGS = Path(__file__).resolve().parents[2] / "catalogs"
TIMING = CATALOGS / "examples" / "synthetic-eclipsing.yaml"


def test_long_table_equals_the_one_target_rows(hm_cnc_path: Path, eccentric_path: Path) -> None:
    """Every row equals :func:`horizon_table` of its target (the independent per-target path),
    to 1e-12 relative (same root search; only the batching differs), including the before-T0
    horizons of a timing ephemeris; a LISA row has NaN there and no such JSON keys."""
    targets = [load_target(p) for p in (hm_cnc_path, TIMING, eccentric_path)]
    tab = horizons(targets, sigma_v=20.0, k_eff=300.0, alphas=(0.5, 1.0, 2.0))
    assert tab.colnames == [c[0] for c in HORIZON_COLUMNS]
    assert len(tab) == 3 * 2 * 3
    for k, t in enumerate(targets):
        mine = tab[6 * k : 6 * k + 6]
        ref = horizon_table(t, 20.0, 300.0, alphas=(0.5, 1.0, 2.0))
        for row, r in zip(mine, ref, strict=True):
            assert row["target"] == t.name and row["file"] == str(t.source)
            assert (row["anchor"], row["alpha"]) == (r.anchor, r.alpha)
            for key, want in r.as_dict().items():
                if isinstance(want, float):
                    assert row[key] == pytest.approx(want, rel=1e-12), key
            if t.kind == "lisa":
                assert math.isnan(row["t_valid_before_days"])
    rows = horizon_rows(tab)
    assert "t_valid_before_days" not in rows[0] and rows[6]["t_valid_before_days"] > 0


def test_missing_spectroscopy_names_the_target(hm_cnc_path: Path) -> None:
    t = dataclasses.replace(load_target(hm_cnc_path), spectroscopy=None, name="bare")
    with pytest.raises(InputError, match=r"^bare: no RV precision; give sigma_v"):
        horizons([t])
    with pytest.raises(InputError, match=r"^bare: no semi-amplitude; give k_eff"):
        horizons([t], sigma_v=15.0)
    with pytest.raises(InputError, match="must be smaller than k_eff"):
        horizons([t], sigma_v=500.0, k_eff=400.0)
    with pytest.raises(InputError, match="at least one target"):
        horizons([])


def test_a_catalog_is_its_documents(tmp_path: Path, hm_cnc_path: Path) -> None:
    text = hm_cnc_path.read_text(encoding="utf-8")
    cat = tmp_path / "cat.yaml"
    cat.write_text(text + "\n---\n" + text.replace("HM Cnc (simulated)", "copy") + "\n---\n")
    got = load_target_documents(cat)
    assert [t.name for t in got] == ["HM Cnc (simulated)", "copy"]
    assert load_target_documents(hm_cnc_path)[0].params == load_target(hm_cnc_path).params
    cat.write_text("---\n---\n")
    with pytest.raises(TargetFileError, match="no target in this file"):
        load_target_documents(cat)


@settings(
    max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    st.lists(
        st.one_of(
            st.just("good"),
            st.text(alphabet="ab:{}[]-#\n '\"&*!0123456789.", max_size=40),
        ),
        min_size=1,
        max_size=4,
    )
)
def test_fuzzed_catalogs_load_or_fail_in_one_line(tmp_path: Path, docs: list[str]) -> None:
    """Any document mix loads or raises one :class:`TargetFileError` line (never another
    exception); an error in a later document of a catalog names that document."""
    good = (CATALOGS / "hm-cnc-simulated.yaml").read_text(encoding="utf-8")
    path = tmp_path / "fuzz.yaml"
    path.write_text("\n---\n".join(good if d == "good" else d for d in docs), encoding="utf-8")
    try:
        got = load_target_documents(path)
    except TargetFileError as exc:
        assert "\n" not in str(exc) and "fuzz.yaml" in str(exc)
    else:
        assert 1 <= len(got) <= len(docs)


def _row_by_row(tab: Table) -> str:
    """The JSON text the row-by-row way: ``json.dumps`` of :func:`horizon_rows`, a row a line."""
    rows = [json.dumps(r, allow_nan=False, ensure_ascii=False) for r in horizon_rows(tab)]
    return "[\n" + ",\n".join(rows) + "\n]\n"


@pytest.fixture(scope="module")
def mixed_table() -> Table:
    """LISA and timing targets, one with quotes, a backslash and non-ASCII in its name."""
    t = load_target(CATALOGS / "hm-cnc-simulated.yaml")
    odd = dataclasses.replace(t, name='Qé "x" \\ ☃')
    return horizons([t, load_target(TIMING), odd], sigma_v=20.0, k_eff=300.0)


def test_columnar_json_is_the_row_by_row_json(mixed_table: Table) -> None:
    """:func:`horizon_json` (built by column) is byte for byte ``json.dumps`` of the rows, and
    reads back as them (NaN as null, a LISA row without the before-T0 keys)."""
    text = horizon_json(mixed_table)
    assert text == _row_by_row(mixed_table)
    assert json.loads(text) == horizon_rows(mixed_table)
    lisa = mixed_table[mixed_table["kind"] == "lisa"]
    assert horizon_json(lisa) == _row_by_row(lisa)  # one kind of target only


@settings(max_examples=60, deadline=None)
@given(
    hnp.arrays(
        np.float64,
        (12, 2),
        elements=st.one_of(
            st.floats(allow_infinity=False),
            st.sampled_from([0.0, -0.0, 0.5, 1.0, float("nan"), 1e-300, 5e-324]),
        ),
    )
)
def test_columnar_json_floats_any_value(mixed_table: Table, values: np.ndarray) -> None:
    """Any finite float, NaN, 0.0 and -0.0 (which compare equal but print apart) and repeats:
    each column's values are written exactly as ``json`` writes them."""
    tab = mixed_table.copy()
    tab["t_valid_days"] = values[:, 0]
    tab["dt_u_before_s"] = values[:, 1]
    assert horizon_json(tab) == _row_by_row(tab)
