"""Timing epochs read ahead in one vectorised Time per format (ucbplan.targets.epoch_batch,
issue 34): each the very Time parse_timing_epoch builds alone, bit for bit; the rest left to it."""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st
from support.targets import ztf_j1539_doc
from target_corpus import outcome

from ucbplan.core.timing_epochs import parse_timing_epoch
from ucbplan.targets import load_target_documents, load_target_files
from ucbplan.targets.epoch_batch import prebuilt_epochs, read_ahead, take_epoch

WORDS = ["BJD_TDB", "bjd_tdb", "BMJD_TDB", "MJD_TDB", "JD_TDB", "BJD-TDB", "BJD", "HJD", "X"]
LABELS = ["", " TDB", " (TDB)", " UTC"]


def _same(a: object, b: object) -> bool:
    return all(
        np.asarray(getattr(a, k)).tobytes() == np.asarray(getattr(b, k)).tobytes()
        for k in ("jd1", "jd2")
    ) and (a.scale, a.format, a.precision, a.shape) == (b.scale, b.format, b.precision, b.shape)


epochs = st.builds(
    lambda w, whole, frac, label, pad: f"{pad}{w} {whole}.{frac}{label}{pad}",
    st.sampled_from(WORDS),
    st.one_of(st.integers(0, 10**9), st.sampled_from([2458305, 58305, 2400000, 1, 99999999])),
    st.text("0123456789", max_size=22),
    st.sampled_from(LABELS),
    st.sampled_from(["", " "]),
)


@settings(max_examples=150, deadline=None, derandomize=True)
@given(st.lists(epochs, min_size=1, max_size=12))
def test_epochs_read_ahead_are_those_read_alone(texts: list[str]) -> None:
    ahead = read_ahead(texts)
    for text in texts:
        try:
            alone = parse_timing_epoch(text)
        except ValueError:
            assert text not in ahead
            continue
        if text in ahead:
            assert _same(ahead[text], alone), text
        else:  # only the spellings read ahead are words with a plain decimal
            assert text.split()[0].upper() in ("BJD", "HJD", "X") or "TDB)" in text, text


def test_each_epoch_is_handed_out_once() -> None:
    text = "BJD_TDB 2458305.6827886"
    with prebuilt_epochs([text, text]):
        first = take_epoch(text)
        assert first is not None and _same(first, parse_timing_epoch(text))
        assert take_epoch(text) is None
    assert take_epoch(text) is None


def test_timing_catalog_loads_as_alone(tmp_path: Path) -> None:
    paths = []
    for k in range(6):
        doc = copy.deepcopy(ztf_j1539_doc(f"Z{k}"))
        doc["timing"]["t0"] = f"BJD_TDB 24583{k:02d}.68278{k}6"
        if k == 3:
            doc["timing"]["t0"] = "BJD_TDB 58305.68"  # a JD given as an MJD: the year check
        paths.append(tmp_path / f"z{k}.yaml")
        paths[-1].write_text(yaml.safe_dump(doc), "utf-8")
    alone = outcome(lambda: [t for p in paths for t in load_target_documents(p)])
    assert outcome(lambda: load_target_files(paths)) == alone
    assert alone[0] == "error" and "z3.yaml: timing.t0" in alone[2]
    good = [p for k, p in enumerate(paths) if k != 3]
    many = outcome(lambda: load_target_files(good))
    assert many[0] == "ok" and many == outcome(
        lambda: [t for p in good for t in load_target_documents(p)]
    )
