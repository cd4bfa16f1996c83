"""Target files: every case of the bad-input corpus (tests/support/bad_targets.py) is refused in one
line that names the field and says what was expected."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
import yaml
from support.bad_targets import DOCUMENTS, LISA_FIELDS, TIMING_FIELDS, refused, timing_with
from support.targets import BASE

from ucbplan.errors import TargetFileError
from ucbplan.targets import load_target


def _write(tmp_path: Path, doc: dict, name: str = "t.yaml") -> Path:
    path = tmp_path / name
    path.write_text(yaml.safe_dump(doc))
    return path


def _with(**lisa) -> dict:
    doc = {**BASE, "lisa": {**BASE["lisa"], **lisa}}
    return doc


@pytest.mark.parametrize(("lisa", "needle"), LISA_FIELDS)
def test_bad_input_one_line_errors(tmp_path: Path, lisa: dict, needle: str) -> None:
    path = _write(tmp_path, _with(**lisa), "bad.yaml")
    with pytest.raises(TargetFileError) as exc:
        load_target(path)
    msg = str(exc.value)
    assert msg.startswith("bad.yaml: ")
    assert needle in msg
    assert "\n" not in msg


@pytest.mark.parametrize(("doc", "needle"), DOCUMENTS)
def test_bad_top_level(tmp_path: Path, doc: object, needle: str) -> None:
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(doc))
    with pytest.raises(TargetFileError, match=None) as exc:
        load_target(path)
    assert needle in str(exc.value)


@pytest.mark.parametrize(
    ("path", "value", "words"),
    TIMING_FIELDS,
    ids=[f"{p}-{i}" for i, (p, _, _) in enumerate(TIMING_FIELDS)],
)
def test_bad_input_is_one_line_naming_the_field(path: str, value: Any, words: list[str]) -> None:
    msg = refused(timing_with(path, value))
    for w in words:
        assert w in msg, (w, msg)
