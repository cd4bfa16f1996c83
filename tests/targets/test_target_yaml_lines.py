"""The line reader of target files' YAML subset (ucbplan.inputs._load_lines, issue 34): where it
reads a text, the document is the one the strict reader (PyYAML's SafeLoader) builds, value for
value, type for type and in order; elsewhere it declines. Texts: the bundled catalogs, the
differential corpus, and both edited a character or a line at a time."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st
from target_corpus import corpus

from ucbplan.inputs import _load_fast, _load_lines, _non_printable, _StrictLoader

ROOT = Path(__file__).resolve().parents[2]
CATALOG_TEXTS = [p.read_text("utf-8") for p in sorted(ROOT.glob("catalogs/**/*.yaml"))]
#: Block-style dumps of corpus documents (single ones), as a user's tool might write them.
DUMPED = [
    yaml.safe_dump(docs[0], allow_unicode=True, sort_keys=False, default_flow_style=flow)
    for docs in corpus(60, seed=9)[0]
    if len(docs) == 1
    for flow in (False, None)
]
#: Catalogs: documents joined by "---" lines (the first with one before it, or not).
JOINED = [
    ("---\n" if k % 2 else "") + "---\n".join(DUMPED[k : k + 1 + k % 3])
    for k in range(0, len(DUMPED), 7)
]
TEXTS = CATALOG_TEXTS + DUMPED + JOINED
#: Characters that steer YAML's grammar, and a few plain ones.
ALPHABET = ": -[]{},#'\"!*?|>\n\t%@`=~.0123456789eEaxyz_()/+\\\u00e9\u2028\r\x00\ufeff"


def _strict(text: str) -> list[object]:
    """Every document of ``text`` as the strict reader builds them."""
    loader = _StrictLoader(text)
    try:
        docs = []
        while loader.check_data():
            docs.append(loader.get_data())
        return docs
    finally:
        loader.dispose()


def _same_as_strict(text: str) -> bool:
    """Whether the line reader declines ``text`` (False) or reads it as the strict reader."""
    got = _load_lines(text)
    if got is None or yaml.reader.Reader.NON_PRINTABLE.search(text):
        return False  # the readers' callers refuse non-printable text first
    want = _strict(text)  # raises if the line reader took a text YAML refuses
    assert repr(got) == repr(want), text  # (NaN is not equal to itself)
    for documents, wrap in ((False, want[0]), (True, want)):
        fast = _load_fast(text, documents)  # None: the strict reader reads it (a ? or > …)
        assert fast is None or repr(fast) == repr((wrap,)), text
        assert documents or len(want) == 1 or fast is None  # several: the strict reader's error
    return True


def test_the_bundled_targets_and_dumped_documents_are_read_alike() -> None:
    taken = sum(_same_as_strict(text) for text in TEXTS)
    assert taken >= len(TEXTS) // 4  # the subset is what target files are written in
    assert sum(_same_as_strict(text) for text in JOINED) >= len(JOINED) // 4


@pytest.mark.parametrize(
    "text",
    [
        "a: 1\nb:\n  c: 2\n d: 3\n",  # an indentation no mapping has
        "a: 1\n  b: 2\n",  # a plain value continued on the next line
        "a: - 1\n",
        "a: -\n",
        "a:#c\n",
        "a: b#c\n",
        'a: "b"#c\n',
        "a: 1\na: 2\n",
        "a: {b: 1, b: 2}\n",
        "a: {b: }\n",
        "a: {b:1}\n",
        "a: 1\n...\n",
        "  a: 1\n",
        "a: 'it''s'\n",
        'a: "x\\ty"\n',
        "a: 1\r\nb: 2\n",
        "a: b: c\n",
        "? a\n: 1\n",
        "a: ,b\n",
        "---\n---\na: 1\n",
        "a: 1\n---\n",
        "a: 1\n--- \nb: 2\n",
        "a: 1\n---\n\n---\nb: 2\n",
        "a: 1\n--- # c\nb: 2\n",
        "a: 1\n...\n---\nb: 2\n",
        "a: {b: c, d}\n",
    ],
)
def test_what_the_subset_leaves_to_yaml(text: str) -> None:
    assert _load_lines(text) is None


@pytest.mark.parametrize(
    ("text", "doc"),
    [
        ("on: yes\nnull: Null x\nNo: 1_000\n", {True: True, None: "Null x", False: 1000}),
        ("a:\nb: 2037-01-01\n", {"a": None, "b": __import__("datetime").date(2037, 1, 1)}),
        ("a:   # c\n  b: 1e5\n  c: .5\n", {"a": {"b": 100000.0, "c": 0.5}}),
        ("a: {b: x y , c: 'p: q'}  # {d: 1}\n", {"a": {"b": "x y", "c": "p: q"}}),
        ("a: -5\nb: (x) +y/z\n", {"a": -5, "b": "(x) +y/z"}),
        ("a: Burdge et al. 2019, Nature 571,\n", {"a": "Burdge et al. 2019, Nature 571,"}),
    ],
)
def test_plain_words_resolve_as_yaml_resolves_them(text: str, doc: dict) -> None:
    assert _load_lines(text) == [doc] and _strict(text) == [doc]


def _edited(text: str, edits: list[tuple[int, int, str]]) -> str:
    """``text`` with characters inserted, deleted or lines re-indented."""
    for kind, pos, char in edits:
        pos %= max(len(text), 1)
        if kind == 0:
            text = text[:pos] + char + text[pos:]
        elif kind == 1:
            text = text[:pos] + text[pos + 1 :]
        else:
            start = text.rfind("\n", 0, pos) + 1
            text = text[:start] + char.replace("\n", " ") * 2 + text[start:]
    return text


@settings(max_examples=1000, deadline=None, derandomize=True)
@given(
    st.sampled_from(TEXTS),
    st.lists(
        st.tuples(st.integers(0, 2), st.integers(0, 10**6), st.sampled_from(ALPHABET)),
        min_size=1,
        max_size=3,
    ),
)
def test_edited_texts_are_read_alike_or_declined(text: str, edits: list) -> None:
    _same_as_strict(_edited(text, edits))


def test_the_printable_check_refuses_what_yaml_refuses() -> None:
    """``_non_printable`` (str.isprintable first) against PyYAML's NON_PRINTABLE: every BMP
    code point and a sample of the others, alone and after text."""
    points = [*range(0x10000), *range(0x10000, 0x110000, 97)]
    for c in points:
        for text in (chr(c), f"a: b\n{chr(c)}\n"):
            want = yaml.reader.Reader.NON_PRINTABLE.search(text) is not None
            assert _non_printable(text) == want, hex(c)


def test_documents_split_at_marker_lines() -> None:
    text = "# c\n---\na:\nb: 1\n---\nc: {d: x}\n"
    assert _load_lines(text) == _strict(text) == [{"a": None, "b": 1}, {"c": {"d": "x"}}]
    assert _load_fast(text, False) is None  # the strict reader says "expected a single document"
