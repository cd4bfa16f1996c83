"""The ECSV header of the blocks table, as astropy writes it, made faster.

astropy writes the header (column declarations and the table ``meta``: a plan's provenance and
its ``visits``) through PyYAML's pure-Python emitter. :func:`ecsv_header` writes the same bytes
with a dumper of its own (astropy's representation, libyaml's emitter in C) when the header's
strings are ones both emitters write alike (:func:`header_safe`), and a plan's ``visits`` list
apart, line by line as libyaml would (:func:`yaml_flow_items`); astropy's dumper, its registry
and the caller's table are never changed. The tests compare every path with PyYAML's own.
"""

from __future__ import annotations

import contextlib
import functools
import itertools
import math
import operator
import os
import re
from collections import OrderedDict
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
import yaml
from astropy.table import Table

from ucbplan.observing.blocks.schema import META_SCALARS

#: Characters every string of an ECSV header must be made of for libyaml to write it: libyaml
#: and PyYAML's pure-Python emitter write such headers byte for byte alike (tested on random
#: headers), not strings that need double quotes (other characters) nor empty mapping keys.
_LIBYAML_SAFE = frozenset(map(chr, range(0x20, 0x7F)))


def _libyaml_safe(value: Any) -> bool:
    """Whether every string in ``value`` (mapping keys, non-empty, and values, recursively) is
    printable ASCII; other values (numbers, booleans, None) are always safe."""
    if isinstance(value, str):
        return _LIBYAML_SAFE.issuperset(value)
    if isinstance(value, Mapping):
        return all(
            isinstance(k, str) and k != "" and _libyaml_safe(k) and _libyaml_safe(v)
            for k, v in value.items()
        )
    if isinstance(value, list | tuple):
        flat = flat_records_safe(value)
        return flat if flat is not None else all(_libyaml_safe(v) for v in value)
    return isinstance(value, int | float | np.number | np.bool_ | type(None))


def flat_records_safe(records: list[Any] | tuple[Any, ...]) -> bool | None:
    """:func:`_libyaml_safe` of a list of plain dicts of plain scalars (a plan's ``visits``),
    their keys and texts checked joined, or None for any other list."""
    if not records or any(type(r) is not dict for r in records):
        return None
    values = list(itertools.chain.from_iterable(map(dict.values, records)))
    if not META_SCALARS.issuperset(map(type, values)):
        return None
    keys = set(itertools.chain.from_iterable(records))
    if not all(type(k) is str and k != "" for k in keys):
        return False
    texts = itertools.chain(keys, filter(str.__instancecheck__, values))
    return _LIBYAML_SAFE.issuperset("".join(texts))


def header_safe(table: Table, meta: Mapping[str, Any] | None = None) -> bool:
    """Whether the whole ECSV header of ``table`` (meta, column names, units, descriptions,
    formats and column meta) is :func:`_libyaml_safe`; with ``meta`` in place of the table's."""
    if not _libyaml_safe(dict(table.meta if meta is None else meta)):
        return False
    for col in table.itercols():
        info = col.info
        unit = getattr(col, "unit", None)
        attrs = [info.name, info.description, info.format, None if unit is None else str(unit)]
        if not _libyaml_safe(attrs) or not _libyaml_safe(dict(info.meta or {})):
            return False
    return True


def _represent_data(dumper: Any, data: Any) -> Any:
    """``represent_data`` of the libyaml dumper: a ``str`` becomes the node PyYAML's
    ``represent_str`` makes (no alias, default style) without the generic dispatch; the
    header of a long plan holds tens of thousands of strings."""
    if type(data) is str and dumper.yaml_representers.get(str) is _REPRESENT_STR:
        dumper.alias_key = None
        return yaml.ScalarNode("tag:yaml.org,2002:str", data, style=dumper.default_style)
    return yaml.representer.BaseRepresenter.represent_data(dumper, data)


def _resolve(dumper: Any, kind: Any, value: Any, implicit: Any) -> Any:
    """``resolve`` of the libyaml dumper, remembered per scalar text (the tag of a plain
    scalar depends on its text alone; a header repeats the same texts)."""
    if kind is not yaml.ScalarNode:
        return yaml.resolver.BaseResolver.resolve(dumper, kind, value, implicit)
    cache = dumper.__dict__.setdefault("_ucbplan_resolved", {})
    key = (value, implicit)
    if key not in cache:
        cache[key] = yaml.resolver.BaseResolver.resolve(dumper, kind, value, implicit)
    return cache[key]


#: PyYAML's representer of ``str`` (the one :func:`_represent_data` stands in for).
_REPRESENT_STR = yaml.representer.SafeRepresenter.represent_str


def _represent_mapping(dumper: Any, tag: str, mapping: Any, flow_style: Any = None) -> Any:
    """astropy's ECSV ``TableDumper.represent_mapping`` (``astropy.table.meta``): the keys in
    the mapping's own order, flow style when every key and value is a plain scalar."""
    value: list[tuple[Any, Any]] = []
    node = yaml.MappingNode(tag, value, flow_style=flow_style)
    if dumper.alias_key is not None:
        dumper.represented_objects[dumper.alias_key] = node
    best_style = True
    if hasattr(mapping, "items"):
        mapping = mapping.items()
        if hasattr(mapping, "sort"):  # astropy's ColumnOrderList: its own order
            mapping.sort()
        else:
            mapping = list(mapping)
            with contextlib.suppress(TypeError):
                mapping = sorted(mapping)
    for item_key, item_value in mapping:
        node_key, node_value = dumper.represent_data(item_key), dumper.represent_data(item_value)
        for node_ in (node_key, node_value):
            best_style &= isinstance(node_, yaml.ScalarNode) and not node_.style
        value.append((node_key, node_value))
    if flow_style is None:
        default = dumper.default_flow_style
        node.flow_style = best_style if default is None else default
    return node


@functools.cache
def _table_dumper(libyaml: bool) -> type:
    """A dumper of ECSV headers like astropy's ``TableDumper`` (a subclass of astropy's
    ``AstropyDumper`` with its own representers), emitting with libyaml (C) when ``libyaml``:
    ~20x faster on a semester's header. Made beside astropy's classes, never in place of them:
    astropy's dumper and its registry stay as they are."""
    from astropy.io.misc.yaml import AstropyDumper
    from astropy.table.meta import ColumnDict, _repr_column_dict, _repr_odict

    methods: dict[str, Any] = {"represent_mapping": _represent_mapping}
    bases: tuple[type, ...] = (AstropyDumper,)
    if libyaml:
        from yaml._yaml import CEmitter
        from yaml.cyaml import CSafeDumper

        bases = (CEmitter, AstropyDumper)
        methods |= {"__init__": CSafeDumper.__init__, "represent_data": _represent_data}
        methods |= {"resolve": _resolve}
    dumper: Any = type("UcbplanTableDumper", bases, methods)
    dumper.add_representer(OrderedDict, _repr_odict)  # copies the registry into the subclass
    dumper.add_representer(ColumnDict, _repr_column_dict)
    return dumper


def _header_text(table: Table, meta: Mapping[str, Any], libyaml: bool) -> str:
    """The ECSV header of ``table``'s columns with ``meta``, as astropy's ECSV writer writes it
    for a table of plain columns (``astropy.io.ascii.ecsv.EcsvHeader.write``)."""
    from astropy.io.ascii.ecsv import ECSV_VERSION
    from astropy.table.meta import _get_col_attributes

    header: dict[str, Any] = {"schema": "astropy-2.0"}
    header["datatype"] = [_get_col_attributes(col) for col in table.itercols()]
    if meta:
        header["meta"] = OrderedDict(meta)
    dumper = _table_dumper(libyaml and yaml.__with_libyaml__)
    text = yaml.dump(header, default_flow_style=None, Dumper=dumper, width=130)
    lines = [f"%ECSV {ECSV_VERSION}", "---", *text.splitlines()]
    return "".join(f"# {line}{os.linesep}" for line in lines) + _names_line(table)


def _names_line(table: Table) -> str:
    """The line of column names ending astropy's ECSV header (every name quoted when the first
    looks like a comment or one has surrounding spaces)."""
    from astropy.io.ascii.ecsv import ECSVHeaderSplitter, ECSVHeaderSplitterQuoteAll

    names = table.colnames
    quote_all = (names and re.match(r"\s*#", names[0])) or any(n.strip() != n for n in names)
    splitter = ECSVHeaderSplitterQuoteAll() if quote_all else ECSVHeaderSplitter()
    splitter.delimiter = " "
    return splitter.join(names) + os.linesep


def _apart(meta: Mapping[str, Any]) -> dict[str, tuple[Any, list[str]]]:
    """The entries of a plan's meta written apart (``visits``, ``not_planned``): for each,
    (the empty value that stands in for it, its lines), where this module's paths write it."""
    out: dict[str, tuple[Any, list[str]]] = {}
    visits = meta.get("visits")
    if isinstance(visits, list) and visits and all(isinstance(v, dict) for v in visits):
        items = yaml_flow_items(visits, _yaml_tag)
        if items is not None:
            out["visits"] = ([], items)
    reasons = meta.get("not_planned")
    if isinstance(reasons, dict) and reasons:
        lines = yaml_nested_flow(reasons, _yaml_tag)
        if lines is not None:
            out["not_planned"] = ({}, lines)
    return out


def ecsv_header(table: Table) -> str:
    """The ECSV header of ``table`` (plain columns), as astropy writes it: with libyaml's
    emitter when the header is :func:`header_safe`, a plan's ``visits`` and ``not_planned``
    written apart (their paths write only strings that are, so these are not checked twice);
    else with PyYAML's. Neither ``table`` nor astropy's YAML dumper is changed."""
    apart = _apart(table.meta)
    stand_in = {key: empty for key, (empty, _) in apart.items()}
    meta = {**table.meta, **stand_in}  # written apart below
    if not header_safe(table, meta):
        return _header_text(table, table.meta, False)
    text = _header_text(table, meta, True)
    for key, (empty, lines) in apart.items():
        blank = f"{os.linesep}# - {key}: {'[]' if empty == [] else '{}'}{os.linesep}"
        if text.count(blank) != 1:  # never: meta keys are unique
            return _header_text(table, table.meta, True)
        listed = "# " + f"{os.linesep}# ".join(lines) + os.linesep
        text = text.replace(blank, f"{os.linesep}# - {key}:{os.linesep}{listed}")
    return text


def yaml_nested_flow(
    mapping: dict[Any, Any], tags: Callable[[str], str], indent: int = 4
) -> list[str] | None:
    """Lines of a block mapping (at ``indent``) of block mappings … whose innermost values are
    flow mappings of scalars (a plan's ``not_planned``: target → night → reason → count), as
    astropy's ECSV header writer emits it through libyaml, keys sorted; None where this path
    does not know (a key or value of another kind, a line that libyaml might break)."""
    return _nested_flow(mapping, _ScalarTexts(tags), indent)


def _nested_flow(mapping: dict[Any, Any], texts: _ScalarTexts, indent: int) -> list[str] | None:
    """:func:`yaml_nested_flow`, each scalar's text found once in ``texts``."""
    if not all(type(k) is str for k in mapping):
        return None
    lines: list[str] = []
    pad = " " * indent
    for key in sorted(mapping):
        head = texts.text(key)
        value = mapping[key]
        if head is None or not isinstance(value, dict):
            return None
        flat = all(not isinstance(v, dict | list | tuple) for v in value.values())
        if flat:
            inner = _flow_mapping(value, texts, len(pad) + len(head) + 2)
            if inner is None:
                return None
            lines.append(f"{pad}{head}: {inner}")
            continue
        nested = _nested_flow(value, texts, indent + 2)
        if nested is None:
            return None
        lines += [f"{pad}{head}:", *nested]
    return lines


class _ScalarTexts(dict[tuple[type, Any], str | None]):
    """:func:`_flow_scalar` of each string and integer met, found once: a plan's
    ``not_planned`` repeats its nights, reasons and counts over targets and nights. Keyed by
    exact type and value (``True`` is not ``1``); other kinds are not kept (``-0.0 == 0.0``)."""

    def __init__(self, tags: Callable[[str], str]) -> None:
        super().__init__()
        self.tags = tags

    def __missing__(self, key: tuple[type, Any]) -> str | None:
        got = self[key] = _flow_scalar(key[1], self.tags)
        return got

    def text(self, value: Any) -> str | None:
        """:func:`_flow_scalar` of ``value``."""
        kind = type(value)
        if kind is str or kind is int:
            return self[kind, value]
        return _flow_scalar(value, self.tags)


def _flow_scalar(value: Any, tags: Callable[[str], str]) -> str | None:
    """A key or value of :func:`yaml_nested_flow` as libyaml writes it, unbroken (no space in
    a value, a key short enough to be a simple key), or None."""
    if isinstance(value, str) and (not value or value.strip() != value or len(value) > 128):
        return None
    got = _yaml_scalar(value, tags)
    return None if got is None else got[0]


def _flow_mapping(mapping: dict[Any, Any], texts: _ScalarTexts, col: int) -> str | None:
    """``{k: v, …}`` (keys sorted) starting at column ``col``, on one line: None where libyaml
    would break it (a key starting past the width, a value with a space) or for other kinds."""
    if not all(type(k) is str for k in mapping):
        return None
    parts: list[str] = []
    col += 1  # "{"
    for key in sorted(mapping):
        k, v = texts.text(key), texts.text(mapping[key])
        col += 1 if parts else 0  # the "," before it: libyaml breaks there past the width
        if k is None or v is None or " " in v or col > _YAML_WIDTH:
            return None
        part = f"{k}: {v}"
        col += len(part) + (1 if parts else 0)  # and the " " after the ","
        parts.append(part)
    return "{" + ", ".join(parts) + "}"


@functools.lru_cache(maxsize=4096)
def _yaml_tag(text: str) -> str:
    """PyYAML's implicit tag of a plain scalar: ``str``, ``int``, ``float``, ``bool`` ..."""
    return str(yaml.SafeDumper.resolve(_RESOLVER, yaml.ScalarNode, text, (True, False))).rsplit(
        ":", 1
    )[-1]


_RESOLVER = yaml.resolver.Resolver()


#: Characters of a text value the fast ECSV header path writes itself (others: PyYAML's path).
_YAML_TEXT = frozenset("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_.()/+- :")
#: The column after which libyaml breaks a line (astropy writes ECSV headers at width 130).
_YAML_WIDTH = 130
#: Indentation of a flow mapping's continuation lines in the ``visits`` list: before a key,
#: and inside a scalar (libyaml indents a scalar one step, 2, deeper).
_YAML_INDENT, _YAML_SCALAR_INDENT = 4, 6


def _yaml_scalar(value: Any, tags: Callable[[str], str]) -> tuple[str, bool] | None:
    """(text, breakable at spaces) of one scalar of a flow mapping as libyaml emits PyYAML's
    node for it, or None where this path does not know (the caller takes PyYAML's)."""
    if isinstance(value, bool) or value is None:
        return None
    if isinstance(value, int):
        text = str(value)
        return (text, False) if tags(text) == "int" else None
    if isinstance(value, float):
        if not math.isfinite(value):
            return None
        text = repr(value).lower()
        if "." not in text and "e" in text:
            text = text.replace("e", ".0e", 1)
        return (text, False) if tags(text) == "float" else None
    if not isinstance(value, str) or not value or not _YAML_TEXT.issuperset(value):
        return None
    if not (value[0].isalnum() or value[0] in "_(") or value[-1] == " " or "  " in value:
        return None
    if tags(value) != "str":  # a date, a number, true/null ...: single-quoted, if unbroken
        return None if " " in value else (f"'{value}'", False)
    if ":" in value:  # a plain ':' is a flow indicator for libyaml
        return None
    return value, True


def yaml_flow_items(items: list[dict[str, Any]], tags: Callable[[str], str]) -> list[str] | None:
    """Lines of a block sequence (indent 2) of flow mappings with sorted keys, as astropy's ECSV
    header writer emits them through libyaml (:func:`libyaml_header`); None if
    any key or value is of a kind this path does not write (the caller then takes PyYAML's).
    ``tags(text)``: PyYAML's implicit tag of a plain scalar (``str``, ``int``, ``float``, ...).

    libyaml breaks a flow mapping before a key once the column passes the width, and a plain
    value at a space once the column passes it; the tests compare with libyaml's own output.
    Items of the same keys are written key by key: each distinct value's text found once, and
    each mapping made from a ``%`` template of its texts' lengths (where the lines break)."""
    if items and not all(type(key) is str for key in items[0]):
        return None  # keys of other kinds (which need not sort): PyYAML's path
    keys = sorted(items[0]) if items else []
    if (
        not keys
        or any(map(items[0].keys().__ne__, map(dict.keys, items)))
        or not all(
            isinstance(key, str) and " " not in key and _yaml_scalar(key, tags) == (key, True)
            for key in keys
        )
    ):
        return _flow_items_one_by_one(items, tags)
    columns = []
    for key in keys:
        texts = _column_texts([item[key] for item in items], tags)
        if texts is None:
            return None
        columns.append(texts)
    rows = list(zip(*columns, strict=True))
    widths = list(zip(*(list(map(len, col)) for col in columns), strict=True))
    templates = {w: _template(keys, w) for w in set(widths)}
    if not any(type(col) is _MayBreak for col in columns):  # no value breaks: templates
        return "\n".join(map(operator.mod, map(templates.__getitem__, widths), rows)).split("\n")
    lines: list[str] = []
    for item, row, width in zip(items, rows, widths, strict=True):
        if _Words in map(type, row):  # a value that may break at its spaces
            lines += _flow_item(item, tags) or []
        else:
            lines += (templates[width] % row).split("\n")
    return lines


class _Words(str):
    """A value's text that libyaml may break at its spaces (a plain string with spaces)."""


class _MayBreak(list[str]):
    """The texts of a column that may hold a :class:`_Words` (the others hold none)."""


def _column_texts(values: list[Any], tags: Callable[[str], str]) -> list[str] | None:
    """Each value's text (a :class:`_Words` where it may break, in a :class:`_MayBreak`): in a
    column of one kind, each distinct number's text (a function of its ``repr``) found once and
    each string's style once per :func:`_shapes`; None if a value is of a kind this path does
    not write."""
    kinds = set(map(type, values))
    if kinds == {str}:
        return _text_column(values, _shapes(values), tags)
    if kinds != {int} and kinds != {float}:
        # one by one: a string's text (its own shape), a number's (never breakable)
        each = [
            _text_column([v], [v], tags) if type(v) is str else _yaml_scalar(v, tags)
            for v in values
        ]
        if None in each:
            return None
        texts = [got[0] for got in each if got is not None]
        return _MayBreak(texts) if _Words in map(type, texts) else texts
    reprs = list(map(repr, values))
    known = {}
    for text, v in dict(zip(reprs, values, strict=True)).items():
        got = _yaml_scalar(v, tags)
        if got is None:
            return None
        known[text] = got[0]
    return list(map(known.__getitem__, reprs))


def _text_column(
    values: list[str], shapes: list[str], tags: Callable[[str], str]
) -> list[str] | None:
    """The texts of strings (see :func:`_column_texts`), each style found once per shape."""
    styles = {}
    for shape, v in dict(zip(shapes, values, strict=True)).items():
        style = styles[shape] = _style(v, tags)
        if style is None:
            return None
    if len(set(styles.values())) == 1 and style != "words":  # one style: the column at once
        return list(values) if style == "plain" else list(map("'{}'".format, values))
    return _MayBreak(
        v if s == "plain" else f"'{v}'" if s == "quoted" else _Words(v)
        for v, s in zip(values, map(styles.__getitem__, shapes), strict=True)
    )


#: Every character of PyYAML's implicit ``int`` and ``float`` patterns (digits, signs, ``_.:``,
#: hexadecimal letters, ``0b``/``0x``, ``inf``/``nan`` in their cases).
_NUMBER_CHARS = frozenset("0123456789_+-.:xXbBaAcCdDeEfFiInN")
#: Every ASCII digit as ``0`` (in UTF-8, whose other characters hold no ASCII byte).
_DIGITS_AS_0 = bytes.maketrans(b"123456789", b"000000000")


def _shapes(values: list[str]) -> list[str]:
    """Per string, the text whose :func:`_style` is its own: itself if it might be a number,
    else with every digit as ``0``. A text with a character outside :data:`_NUMBER_CHARS`
    cannot be an ``int`` or a ``float``, and PyYAML's other patterns (timestamps) take any
    digit alike, as every digit starts the same resolvers: a header's times and visit ids share
    a handful of shapes."""
    joined = "\x00".join(values)
    if joined.count("\x00") != len(values) - 1:  # a NUL inside a value
        return list(values)
    coarse_bytes = joined.encode("utf-8", "surrogatepass").translate(_DIGITS_AS_0)
    coarse = coarse_bytes.decode("utf-8", "surrogatepass").split("\x00")
    # digits map to digits: a text and its shape are alike made of :data:`_NUMBER_CHARS` or not
    numeric = {c for c in set(coarse) if _NUMBER_CHARS.issuperset(c)}
    if not numeric:
        return coarse
    return [v if c in numeric else c for v, c in zip(values, coarse, strict=True)]


def _style(text: str, tags: Callable[[str], str]) -> str | None:
    """How :func:`_yaml_scalar` writes the string ``text``: ``plain``, ``quoted`` (in single
    quotes), ``words`` (plain, breakable at its spaces), or None (not by this path)."""
    got = _yaml_scalar(text, tags)
    if got is None:
        return None
    if got[0] != text:
        return "quoted"
    return "words" if got[1] and " " in text else "plain"


def _template(keys: list[str], widths: tuple[int, ...]) -> str:
    """The ``%`` template of a flow mapping of ``keys`` whose value texts have ``widths`` (none
    breakable), its lines joined by newlines: a line breaks before a key past the width."""
    parts, col = ["  - {"], 5
    for k, (key, width) in enumerate(zip(keys, widths, strict=True)):
        if k:
            col += 1
            if col > _YAML_WIDTH:
                parts.append(",\n" + " " * _YAML_INDENT)
                col = _YAML_INDENT
            else:
                parts.append(", ")
                col += 1
        parts.append(f"{key}: %s")
        col += len(key) + 2 + width
    return "".join(parts) + "}"


def _flow_items_one_by_one(
    items: list[dict[str, Any]], tags: Callable[[str], str]
) -> list[str] | None:
    """:func:`yaml_flow_items` of mappings of differing keys, one mapping at a time."""
    lines: list[str] = []
    for item in items:
        got = _flow_item(item, tags)
        if got is None:
            return None
        lines += got
    return lines


def _flow_item(item: dict[str, Any], tags: Callable[[str], str]) -> list[str] | None:
    """The lines of one flow mapping (see :func:`yaml_flow_items`), or None."""
    if not all(type(key) is str for key in item):
        return None
    lines: list[str] = []
    line, col = "  - {", 5
    for k, key in enumerate(sorted(item)):
        if not isinstance(key, str) or _yaml_scalar(key, tags) != (key, True) or " " in key:
            return None
        got = _yaml_scalar(item[key], tags)
        if got is None:
            return None
        text, breakable = got
        if k:
            line += ","
            col += 1
            if col > _YAML_WIDTH:
                lines.append(line)
                line, col = " " * _YAML_INDENT, _YAML_INDENT
            else:
                line += " "
                col += 1
        line += f"{key}: "
        col += len(key) + 2
        words = text.split(" ") if breakable else [text]
        for w, word in enumerate(words):
            if w:
                if col > _YAML_WIDTH:
                    lines.append(line)
                    line, col = " " * _YAML_SCALAR_INDENT, _YAML_SCALAR_INDENT
                else:
                    line += " "
                    col += 1
            line += word
            col += len(word)
    lines.append(line + "}")
    return lines
