"""Reading input files defensively: size limits, UTF-8 (with or without BOM), strict YAML.

Every YAML file ucbplan reads (target files, site tables, instrument tables, EM priors) goes
through :func:`load_yaml`, which

- reads only YAML's safe subset and refuses files larger than :data:`MAX_YAML_BYTES`;
- refuses duplicate keys (YAML would silently keep the last one);
- refuses more than :data:`MAX_ALIASES` aliases, so a few hundred bytes of nested anchors cannot
  expand into gigabytes ("billion laughs");
- reads numbers written without a decimal point, such as ``5e-14``, as numbers (plain YAML 1.1
  reads them as strings).

It reads the block-mapping subset target files are written in line by line (:func:`_load_lines`),
other text through libyaml's events, and gives anything unusual, and every error, to the strict
reader (PyYAML's SafeLoader), whose documents all three give.

Text tables go through :func:`read_text`, which accepts UTF-8 with or without a byte-order mark
and refuses other encodings with a message saying how to convert. Option values and table cells
are range-checked with :func:`check_range` / :func:`check_int` (one line naming the option, the
range with its unit and reason, and the value).
"""

from __future__ import annotations

import math
import re
import stat
from pathlib import Path
from typing import Any, TypeGuard

import numpy as np
import yaml

from ucbplan.errors import InputError, SchemaError, shorten

#: Largest YAML input [bytes]; target and configuration files are a few kB.
MAX_YAML_BYTES = 2_000_000
#: Largest text table [bytes] (10⁷ spectra of ~60 bytes).
MAX_TEXT_BYTES = 2_000_000_000
#: Most aliases (``*name``) one YAML file may use.
MAX_ALIASES = 50
#: Longest ``#`` comment line of a text table [characters]: a note, not data (issue 33).
MAX_COMMENT_CHARS = 1_000_000

#: A ``#`` comment line (white space before the ``#`` allowed), without its newline.
_COMMENT_LINE = re.compile(r"^[^\S\n]*#[^\n]*", re.MULTILINE)

#: Numbers written with an exponent but no decimal point (``5e-14``), which load_yaml reads as
#: floats (plain YAML 1.1 reads them as strings); writers must quote text that matches.
EXPONENT_FLOAT = re.compile(r"^[-+]?(?:[0-9][0-9_]*)(?:\.[0-9_]*)?[eE][-+]?[0-9]+$")


def _refuse_duplicate_keys(node: yaml.MappingNode, construct: Any) -> None:
    """Raise on a key given twice in ``node`` (YAML would silently keep the last one)."""
    seen: dict[Any, int] = {}
    for key_node, _ in node.value:
        key = construct(key_node, deep=True)
        try:
            hash(key)
        except TypeError:
            continue  # let the base class report an unhashable key
        if key in seen:
            line = key_node.start_mark.line + 1
            raise yaml.YAMLError(f"duplicate key {key!r} (lines {seen[key]} and {line}); keep one")
        seen[key] = key_node.start_mark.line + 1


class _StrictLoader(yaml.SafeLoader):
    """SafeLoader with an alias budget, duplicate-key check and exponent-only floats."""

    def __init__(self, stream: str) -> None:
        super().__init__(stream)
        self.aliases_seen = 0

    def compose_node(self, parent: Any, index: Any) -> Any:
        if self.check_event(yaml.AliasEvent):
            self.aliases_seen += 1
            if self.aliases_seen > MAX_ALIASES:
                mark = self.peek_event().start_mark
                raise yaml.YAMLError(
                    f"more than {MAX_ALIASES} aliases (line {mark.line + 1}); write the values "
                    "out instead of using anchors"
                )
        return super().compose_node(parent, index)

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict[Any, Any]:
        _refuse_duplicate_keys(node, self.construct_object)
        return super().construct_mapping(node, deep=deep)


#: Whether PyYAML has libyaml (the fast path needs it; without it the strict reader reads all).
_FAST_LOADER = bool(getattr(yaml, "__with_libyaml__", False))
_CSafeLoader: Any = yaml.CSafeLoader if _FAST_LOADER else yaml.SafeLoader


#: Outside comments, text with these goes to the strict reader: anchors (``&``, the alias
#: budget), and what libyaml reads differently: tabs (it accepts them where the strict reader
#: refuses them), tags (``!`` on an empty value: "" against None), block scalars (``|#``) and
#: complex keys (``?`` continuing a flow scalar).
_STRICT_CHARS = "&!|>?\t"
_STRICT_ONLY = re.compile(f"[{re.escape(_STRICT_CHARS)}]")
#: A comment: ``#`` at the start of a line or after a space, with no quote up to the line's end
#: (inside a quoted value the text is the value's, where these characters do nothing) and no
#: line break YAML has but ``$`` has not.
_COMMENT = re.compile("(?m)(?:^|[ ])#[^'\"\r\n\x85\u2028\u2029]*\r?$")


class _Refused(Exception):
    """What the event reader leaves to the strict reader (anchors, aliases, tags, merge and
    value keys, a key given twice, an unhashable key)."""


#: Tags of plain scalars the event reader builds with SafeConstructor's own methods; any other
#: (``<<`` merges, ``=`` values) goes to the strict reader, whose order decides.
_SCALAR_TAGS = frozenset(
    f"tag:yaml.org,2002:{t}" for t in ("null", "bool", "int", "float", "timestamp")
)
_STR_TAG = "tag:yaml.org,2002:str"


class _FastLoader(_CSafeLoader):
    """The same reading with libyaml's parser, for text without anchors (so without aliases)
    or characters the strict reader refuses: :func:`load_yaml` tries it first and falls back to
    :class:`_StrictLoader`, which gives every error its message, on any failure.

    The documents are built straight from libyaml's events (no node tree, no constructor
    generators): each plain scalar's tag resolved by the loader's own resolver and built by
    SafeConstructor's own method, so the values are those ``yaml.load`` gives; anything else
    raises :class:`_Refused`."""

    def documents(self) -> list[Any]:
        """Every document of the stream."""
        self.get_event()  # the stream start
        docs = []
        while not isinstance(self.get_event(), yaml.StreamEndEvent):  # a document start
            docs.append(self._node(self.get_event()))
            self.get_event()  # the document end
        return docs

    def _node(self, event: Any) -> Any:
        kind = type(event)
        if kind is yaml.ScalarEvent:
            return self._plain(event)
        if kind is yaml.AliasEvent or event.anchor is not None or event.tag is not None:
            raise _Refused("anchor, alias or tag")
        get, node, scalar, plain = self.get_event, self._node, yaml.ScalarEvent, self._plain
        if kind is yaml.SequenceStartEvent:
            items = []
            while type(event := get()) is not yaml.SequenceEndEvent:
                items.append(node(event))
            return items
        out: dict[Any, Any] = {}
        while (kind := type(event := get())) is not yaml.MappingEndEvent:
            key = plain(event) if kind is scalar else node(event)
            if key in out:  # also raises TypeError for an unhashable key
                raise _Refused("duplicate key")
            event = get()
            out[key] = plain(event) if type(event) is scalar else node(event)
        return out

    def _plain(self, event: yaml.ScalarEvent) -> Any:
        """The value of a scalar event, as ``yaml.load`` builds it: quoted text is text, plain
        text goes through the implicit resolvers (:func:`_plain_value`)."""
        if event.anchor is not None or event.tag is not None:
            raise _Refused("anchor or tag")
        if not event.implicit[0]:
            return event.value
        return _plain_value(event.value, self)


def _plain_value(value: str, constructor: Any) -> Any:
    """A plain scalar's value as ``yaml.load`` builds it: its tag from the implicit resolvers
    for its first character, as ``resolve`` does (these loaders have no path resolvers), built
    by SafeConstructor's own method (of ``constructor``, a SafeConstructor)."""
    found = _PLAIN_VALUES.get(value, _PLAIN_VALUES)
    if found is not _PLAIN_VALUES:
        return found
    tag = _implicit_tag(_FastLoader.yaml_implicit_resolvers.get(value[:1], ()), value)
    if tag is None:
        found = value
    elif tag not in _SCALAR_TAGS:
        raise _Refused(tag)
    else:
        found = constructor.yaml_constructors[tag](constructor, yaml.ScalarNode(tag, value))
    if len(value) <= _PLAIN_CHARS and len(_PLAIN_VALUES) < _PLAIN_SIZE:
        _PLAIN_VALUES[value] = found
    return found


#: Plain scalars already read (keys, above all: a catalog repeats them), text → value: each
#: value is immutable (text, None, bool, int, float, date, datetime) and depends on the text
#: alone (the loader has no path resolvers), so a repeated text gives an equal value.
_PLAIN_VALUES: dict[str, Any] = {}
#: Most entries of :data:`_PLAIN_VALUES`, and the longest text it keeps [characters].
_PLAIN_SIZE, _PLAIN_CHARS = 4096, 40


def _implicit_tag(resolvers: list[tuple[str, re.Pattern[str]]], value: str) -> str | None:
    """The tag of the first resolver matching ``value``; None: text."""
    for tag, regexp in resolvers:
        if regexp.match(value):
            return tag
    return None


for _loader in (_StrictLoader, _FastLoader):
    _loader.add_implicit_resolver("tag:yaml.org,2002:float", EXPONENT_FLOAT, list("-+0123456789"))
# _FastLoader._plain resolves as Resolver.resolve does for loaders without these
assert None not in _FastLoader.yaml_implicit_resolvers and not _FastLoader.yaml_path_resolvers


#: The block-mapping subset :func:`_load_lines` reads: identifier keys; quoted text without
#: escapes, or plain text of a few characters with no indicator (``:``, ``#``, ``,``,
#: brackets …) and no leading ``- ``; flow mappings of those on one line.
_KEY = r"[A-Za-z_][A-Za-z0-9_]*"
_PLAIN = r"(?:[A-Za-z0-9_.+/()]|-(?=[^ ]))(?:[A-Za-z0-9_.+/() -]*[A-Za-z0-9_.+/()-])?"
_QUOTED = "\"[^\"\\\\\ufeff]*\"|'[^'\ufeff]*'"
_SCALAR = f"{_QUOTED}|{_PLAIN}"
#: Outside flow mappings, a plain value may hold commas (not start with one).
_BLOCK_SCALAR = f"{_QUOTED}|" + _PLAIN.replace("/() -]", "/() ,-]").replace("/()-]", "/(),-]")
_FLOW = rf"\{{ *(?:{_KEY}: +(?:{_SCALAR}) *(?:, *{_KEY}: +(?:{_SCALAR}) *)*,? *)?\}}"
#: A line: indentation, key, value (none: a nested mapping or null), blanks and a comment.
_LINE = re.compile(rf"( *)({_KEY}):(?: +({_FLOW}|{_BLOCK_SCALAR}))?(?: +(?:#.*)?)?")
#: A flow mapping's entries.
_ITEM = re.compile(rf"({_KEY}): +({_SCALAR})")
#: A blank or comment-only line.
_SKIP = re.compile(" *(?:#.*)?")
#: Line breaks other than ``\n`` (YAML has them; this reader does not).
_OTHER_BREAKS = ("\r", "\x85", "\u2028", "\u2029")


class _Lines:
    """The state of :func:`_load_lines`: the open mappings by indentation (the innermost one
    kept apart), and a key whose value (a nested mapping, or null) the next line decides."""

    def __init__(self) -> None:
        self.root: dict[Any, Any] = {}
        self.indent, self.mapping = 0, self.root
        self.outer: list[tuple[int, dict[Any, Any]]] = []
        self.open: Any = _Lines  # the key left open (the class itself: none)
        self.constructor = yaml.constructor.SafeConstructor()

    def add(self, indent: int, key: Any, raw: str | None) -> bool:
        """One ``key: value`` line; False where the subset ends (YAML decides)."""
        if self.open is not _Lines:
            if indent > self.indent:
                child: dict[Any, Any] = {}
                self.mapping[self.open] = child
                self.outer.append((self.indent, self.mapping))
                self.indent, self.mapping = indent, child
            self.open = _Lines
        while indent < self.indent and self.outer:
            self.indent, self.mapping = self.outer.pop()
        if indent != self.indent or key in self.mapping:
            return False
        if raw is None:
            self.mapping[key] = None
            self.open = key
        else:
            self.mapping[key] = self.value(raw)
        return True

    def value(self, raw: str) -> Any:
        """A value as ``yaml.load`` builds it."""
        if raw[0] in "\"'":
            return raw[1:-1]
        if raw[0] != "{":
            return _plain_value(raw, self.constructor)
        out: dict[Any, Any] = {}
        for m in _ITEM.finditer(raw):
            key = _plain_value(m[1], self.constructor)
            if key in out:
                raise _Refused("duplicate key")
            out[key] = self.value(m[2])
        return out


def _load_lines(text: str) -> list[Any] | None:
    """The documents of a text in a small subset of YAML (block mappings of the :data:`_LINE`
    lines, blank or comment lines, and ``---`` lines between documents), read line by line as
    ``yaml.load_all`` reads them; None for any other text (then libyaml reads it). Target files
    are mostly written in this subset, and libyaml's event objects cost most of the time reading
    them takes."""
    if any(c in text for c in _OTHER_BREAKS):
        return None
    docs: list[Any] = []
    doc, marked = _Lines(), False  # marked: a "---" opened the document
    match, skip = _LINE.fullmatch, _SKIP.fullmatch
    try:
        for line in text.split("\n"):
            m = match(line)
            if m is not None:
                if not doc.add(len(m[1]), _plain_value(m[2], doc.constructor), m[3]):
                    return None
            elif line == "---":
                if doc.root:
                    docs.append(doc.root)
                    doc = _Lines()
                elif docs or marked:
                    return None  # an empty document: YAML reads None
                marked = True
            elif not skip(line):
                return None
    except _Refused:
        return None
    return [*docs, doc.root] if doc.root else None


def _read_bytes(path: Path, limit: int, what: str) -> bytes:
    if "\x00" in str(path) or len(str(path)) > 4096:
        raise SchemaError(f"{shorten(str(path), 80)}: not a usable file name; check the path")
    try:
        st = path.stat()
        if not stat.S_ISREG(st.st_mode):
            raise SchemaError(f"{path}: not a regular file; give the path of a {what}")
        if (size := st.st_size) > limit:
            raise SchemaError(
                f"{path}: {size} bytes is larger than any {what} ({limit} bytes at most); "
                "check the path"
            )
        return path.read_bytes()
    except FileNotFoundError:
        raise SchemaError(f"{path}: file not found; check the path") from None
    except IsADirectoryError:
        raise SchemaError(f"{path}: is a folder; give the path of a {what}") from None
    except OSError as exc:
        raise SchemaError(f"{path}: cannot read ({exc.strerror}); check the path") from None


def _decode(data: bytes, path: Path) -> str:
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise SchemaError(
            f"{path}: not UTF-8 text (byte 0x{data[exc.start]:02x} at offset {exc.start}); "
            "save the file as UTF-8 (e.g. iconv -f latin1 -t utf-8)"
        ) from None


def read_text(path: Path, what: str = "text table", limit: int = MAX_TEXT_BYTES) -> str:
    """The file's text, UTF-8 with an optional byte-order mark.

    Raises
    ------
    SchemaError
        Missing, not a regular file, too large, or not UTF-8.
    """
    return _decode(_read_bytes(path, limit, what), path)


def blank_comments(text: str, path: Path) -> str:
    """``text`` with every ``#`` comment line emptied, in one linear pass (the line count is
    kept, so row and line numbers hold); the one comment reader of the CSV tables.

    A comment is a line whose first non-blank character is ``#``; a ``#`` later in a line is
    data. Emptying comments before a table parser matters: astropy's C reader is quadratic in a
    comment line's length (10⁶ characters took 7-29 s, issue 33).

    Raises
    ------
    SchemaError
        A comment line longer than :data:`MAX_COMMENT_CHARS`; one line naming its line.
    """

    def empty(match: re.Match[str]) -> str:
        size = match.end() - match.start()
        if size > MAX_COMMENT_CHARS:
            line = text.count("\n", 0, match.start()) + 1
            raise SchemaError(
                f"{path}: line {line}: a comment of {size} characters, longer than any note "
                f"({MAX_COMMENT_CHARS} at most); shorten or remove it"
            )
        return ""

    return _COMMENT_LINE.sub(empty, text)


def load_yaml(
    path: Path, what: str = "YAML file", text: str | None = None, *, documents: bool = False
) -> Any:
    """Parse a YAML file (or ``text`` read from it) strictly; see the module notes.

    ``documents``: return the list of every document of a multi-document file (``---``
    separated) instead of requiring exactly one.

    Raises
    ------
    SchemaError
        Unreadable file, YAML syntax error, duplicate key or alias bomb; one line with the
        position.
    """
    if text is None:
        text = _decode(_read_bytes(path, MAX_YAML_BYTES, what), path)
    elif len(text) > MAX_YAML_BYTES:
        raise SchemaError(f"{path}: larger than any {what} ({MAX_YAML_BYTES} bytes at most)")
    fast = _load_fast(text, documents)
    if fast is not None:
        return fast[0]
    try:
        loader = _StrictLoader(text)
    except yaml.YAMLError as exc:  # the reader checks characters on construction
        raise SchemaError(f"{path}: not valid YAML: {' '.join(str(exc).split())}") from None
    try:
        if not documents:
            return loader.get_single_data()
        docs = []
        while loader.check_data():
            docs.append(loader.get_data())
        return docs
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark
        where = f"line {mark.line + 1}, column {mark.column + 1}: " if mark else ""
        problem = " ".join(str(exc.problem or exc.context or "syntax error").split())
        raise SchemaError(f"{path}: not valid YAML: {where}{problem}") from None
    except yaml.YAMLError as exc:
        raise SchemaError(f"{path}: not valid YAML: {' '.join(str(exc).split())}") from None
    except RecursionError:
        raise SchemaError(f"{path}: nested too deeply to be a {what}; check the file") from None
    finally:
        loader.dispose()


def _load_fast(text: str, documents: bool) -> tuple[Any] | None:
    """``(document,)`` (or ``(documents,)``) read line by line (:func:`_load_lines`) or by
    libyaml, or None where the strict reader must read the text: :data:`_STRICT_ONLY`,
    characters it refuses, or any error (its messages are the ones users see)."""
    strict = any(c in text for c in _STRICT_CHARS)  # _STRICT_ONLY.search(text), faster
    if (
        not _FAST_LOADER
        or (strict and _STRICT_ONLY.search(_COMMENT.sub("", text)))
        or _non_printable(text)
    ):
        return None
    lines = None if strict else _load_lines(text)
    if lines is not None and (documents or len(lines) == 1):
        return (lines,) if documents else (lines[0],)
    loader = _FastLoader(text)
    try:
        docs = loader.documents()
    except Exception:  # every failure is reported by the strict reader
        return None
    finally:
        loader.dispose()
    if documents:
        return (docs,)
    if len(docs) > 1:
        return None  # the strict reader says "expected a single document"
    return (docs[0] if docs else None,)


def _non_printable(text: str) -> bool:
    """Whether ``text`` has a character the strict reader refuses (its ``NON_PRINTABLE``):
    ``str.isprintable`` clears most texts at once (a character Python prints, YAML allows)."""
    if text.replace("\n", "").isprintable():
        return False
    return yaml.reader.Reader.NON_PRINTABLE.search(text) is not None


def is_number(value: Any) -> TypeGuard[int | float | np.integer[Any] | np.floating[Any]]:
    """A real number (``int`` or ``float``, numpy scalars included), not a bool."""
    if isinstance(value, bool | np.bool_):
        return False
    return isinstance(value, int | float | np.integer | np.floating)


def _suffix(unit: str, why: str) -> str:
    return (f" {unit}" if unit else "") + (f" ({why})" if why else "")


def check_range(
    name: str,
    value: Any,
    low: float,
    high: float,
    unit: str = "",
    why: str = "",
    *,
    low_open: bool = False,
    error: type[InputError] = InputError,
) -> float:
    """``value`` as a float if it is a finite number with ``low <= value <= high``
    (``low < value`` with ``low_open``).

    Raises
    ------
    InputError
        (or ``error``) One line: ``NAME: expected a number in [LOW, HIGH] UNIT (WHY), got V``.
    """
    ok = is_number(value) and math.isfinite(float(value))
    ok = ok and (low < float(value) if low_open else low <= float(value)) and float(value) <= high
    if not ok:
        bracket = "(" if low_open else "["
        raise error(
            f"{name}: expected a number in {bracket}{low:g}, {high:g}]{_suffix(unit, why)}, "
            f"got {shorten(value, 40)}",
            parameter=name if name.isidentifier() else None,
        )
    return float(value)


def check_int(
    name: str,
    value: Any,
    low: int,
    high: int,
    why: str = "",
    *,
    error: type[InputError] = InputError,
) -> int:
    """``value`` as an int if it is a whole number with ``low <= value <= high``.

    Raises
    ------
    InputError
        (or ``error``) One line: ``NAME: expected a whole number in [LOW, HIGH] (WHY), got V``.
    """
    ok = is_number(value) and math.isfinite(float(value)) and float(value) == int(value)
    if not (ok and low <= int(value) <= high):
        raise error(
            f"{name}: expected a whole number in [{low}, {high}]{_suffix('', why)}, "
            f"got {shorten(value, 40)}",
            parameter=name if name.isidentifier() else None,
        )
    return int(value)


def check_number(
    name: str, value: float | None, low: float, high: float, unit: str = "", why: str = ""
) -> None:
    """Refuse an option value outside ``low < value <= high`` (``None`` passes).

    :func:`check_range` with an open lower bound, for values that must be strictly positive.

    Raises
    ------
    InputError
        One line naming the option, the allowed range with its unit, the value and ``why``.
    """
    if value is not None:
        check_range(name, value, low, high, unit, why, low_open=True)


#: Largest planning margin α (1 spends the whole phase tolerance; more is no longer a margin).
MAX_ALPHA = 10.0


def check_alpha(alpha: object) -> float:
    """``--alpha``, the planning margin on the phase tolerance, in (0, :data:`MAX_ALPHA`].

    Raises
    ------
    InputError
        Otherwise (one line naming the option, the range and the value).
    """
    why = "margin on the phase tolerance: 1 spends all of it"
    return check_range("alpha", alpha, 0.0, MAX_ALPHA, "", why, low_open=True)
