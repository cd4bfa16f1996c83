"""Strict input readers: YAML duplicate keys, alias bombs, exponent floats; UTF-8 with BOM."""

from __future__ import annotations

import time
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ucbplan.errors import SchemaError
from ucbplan.inputs import MAX_ALIASES, load_yaml, read_text


def _yaml(tmp_path: Path, text: str) -> Path:
    p = tmp_path / "t.yaml"
    p.write_text(text, encoding="utf-8")
    return p


def test_duplicate_keys_refused(tmp_path: Path) -> None:
    with pytest.raises(SchemaError, match=r"duplicate key 'f_gw' \(lines 2 and 3\)"):
        load_yaml(_yaml(tmp_path, "lisa:\n  f_gw: 1\n  f_gw: 2\n"))


def test_alias_bomb_refused_fast(tmp_path: Path) -> None:
    # 9 levels of 9-fold nesting: 9^9 leaves if expanded; 704 bytes
    lines = ['a0: &a0 ["lol","lol","lol","lol","lol","lol","lol","lol","lol"]']
    for i in range(1, 10):
        lines.append(f"a{i}: &a{i} [" + ",".join([f"*a{i - 1}"] * 9) + "]")
    path = _yaml(tmp_path, "\n".join(lines) + "\n")
    start = time.perf_counter()
    with pytest.raises(SchemaError, match=f"more than {MAX_ALIASES} aliases"):
        load_yaml(path)
    assert time.perf_counter() - start < 1.0  # refused before any expansion


def test_few_aliases_still_fine(tmp_path: Path) -> None:
    doc = load_yaml(_yaml(tmp_path, "a: &x 1\nb: *x\n"))
    assert doc == {"a": 1, "b": 1}


@pytest.mark.parametrize(
    ("text", "value"), [("5e-14", 5e-14), ("-2.373e-11", -2.373e-11), ("1E+3", 1000.0)]
)
def test_exponent_numbers_are_numbers(tmp_path: Path, text: str, value: float) -> None:
    doc = load_yaml(_yaml(tmp_path, f"x: {text}\ny: '{text}'\n"))
    assert doc["x"] == value and isinstance(doc["x"], float)
    assert doc["y"] == text  # quoted stays a string


def test_plain_safe_loader_is_unchanged() -> None:
    import yaml

    assert yaml.safe_load("x: 5e-14")["x"] == "5e-14"  # our resolver did not leak into PyYAML


def test_syntax_error_one_line(tmp_path: Path) -> None:
    with pytest.raises(SchemaError) as err:
        load_yaml(_yaml(tmp_path, "a: [1, 2\nb: 3\n"))
    msg = str(err.value)
    assert "\n" not in msg and "line" in msg and str(tmp_path) in msg


def test_python_tags_refused(tmp_path: Path) -> None:
    with pytest.raises(SchemaError):
        load_yaml(_yaml(tmp_path, "a: !!python/object/apply:os.system ['true']\n"))


def test_bom_and_encodings(tmp_path: Path) -> None:
    p = tmp_path / "v.csv"
    p.write_bytes("\ufeffbjd_tdb,v\n1,2\n".encode())
    assert read_text(p).startswith("bjd_tdb")
    p.write_bytes("name\nHM Cnc \xe9\n".encode("latin-1"))
    with pytest.raises(SchemaError, match=r"not UTF-8.*0xe9.*save the file as UTF-8"):
        read_text(p)
    with pytest.raises(SchemaError, match="file not found"):
        read_text(tmp_path / "nope.csv")
    with pytest.raises(SchemaError, match=r"not a regular file|is a folder"):
        read_text(tmp_path)


@settings(max_examples=200, deadline=None)
@given(st.text(max_size=300))
def test_any_text_gives_data_or_one_line_error(
    tmp_path_factory: pytest.TempPathFactory, s: str
) -> None:
    path = tmp_path_factory.mktemp("y") / "t.yaml"
    path.write_text(s, encoding="utf-8", errors="surrogatepass")
    try:
        load_yaml(path)
    except SchemaError as exc:
        assert "\n" not in str(exc) and len(str(exc)) < 400 + len(str(path))


def test_blank_comments_keeps_the_line_count_and_refuses_a_huge_comment() -> None:
    """One linear reader for # comment lines (issue 33): emptied in place (row numbers hold),
    a comment longer than MAX_COMMENT_CHARS refused in one line naming its line."""
    from ucbplan.errors import SchemaError
    from ucbplan.inputs import MAX_COMMENT_CHARS, blank_comments

    text = "# a\r\nh,k\n  # b # c\n1,2 # not a comment line\n\t#\n"
    assert blank_comments(text, Path("t.csv")) == "\nh,k\n\n1,2 # not a comment line\n\n"
    huge = "h\n1\n #" + "y" * MAX_COMMENT_CHARS + "\n"
    with pytest.raises(SchemaError, match=r"^t.csv: line 3: a comment of 1000002 characters"):
        blank_comments(huge, Path("t.csv"))
