"""The reduce report as indented JSON text, byte for byte :func:`ucbplan.io.dumps_json`, faster.

The standard library writes indented JSON with its pure-Python encoder (the C one has no
indentation): one generator per nesting level that every token passes through, after
:func:`ucbplan.io.json_plain` has copied the whole document once. A report of 10⁶ spectra holds
~8,000 fixed-u pairs and ~2,000 sessions (~4·10⁵ values), and that cost 0.6 CPU s. Here one
recursive pass appends the text pieces to a list and applies json_plain's rule on the way (NaN and
infinities become ``null``; numpy scalars and arrays become numbers and lists).

Anything else (a value that :func:`ucbplan.io.json_default` would have to convert or refuse)
falls back to :func:`ucbplan.io.dumps_json` for the whole document, so its output or its error is
the reference's exactly.

A caller may also pass writers for the items of the lists under given keys (``items``): each
returns an item's text at its nesting level, or None to leave the item to this writer. The
report's ~8,000 fixed-u pairs are written that way, from one template
(:mod:`ucbplan.reduce.report`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from json.encoder import encode_basestring_ascii
from typing import Any

import numpy as np

_INDENT = "  "  # json.dumps(indent=2)


class _Unsupported(Exception):
    """A value this encoder leaves to the reference one."""


#: Writers of list items by the key of their list: an item's text at a nesting level, or None.
Items = Mapping[str, Callable[[Any, int], str | None]]


def dumps_report(doc: Any, items: Items | None = None) -> str:
    """``doc`` as JSON text indented by 2, identical to :func:`ucbplan.io.dumps_json` (no
    trailing newline); ``items``: writers of the items of the lists under these keys (module
    docstring), which must give the same text."""
    out: list[str] = []
    try:
        _value(doc, 0, out, {}, items or {})
    except _Unsupported:
        from ucbplan.io import dumps_json

        return dumps_json(doc)
    return "".join(out)


#: A mapping key's text before its value at one nesting level, after "{" and after ","
#: (built once per key and level of a document: ~8,000 pairs share a dozen keys).
_Heads = dict[tuple[str, int], tuple[str, str]]


def _value(obj: Any, level: int, out: list[str], heads: _Heads, items: Items) -> None:
    """Append the text of one value at nesting ``level`` (json.encoder's order of type tests)."""
    if isinstance(obj, str):
        out.append(encode_basestring_ascii(obj))
    elif obj is None:
        out.append("null")
    elif obj is True:
        out.append("true")
    elif obj is False:
        out.append("false")
    elif isinstance(obj, int):
        out.append(int.__repr__(obj))
    elif isinstance(obj, float):
        out.append(float.__repr__(obj) if math.isfinite(obj) else "null")
    elif isinstance(obj, Mapping):
        _mapping(obj, level, out, heads, items)
    elif isinstance(obj, list | tuple):
        _sequence(obj, level, out, heads, items, None)
    elif isinstance(obj, np.generic | np.ndarray):
        _value(obj.tolist(), level, out, heads, items)
    else:
        raise _Unsupported


def _mapping(
    obj: Mapping[Any, Any], level: int, out: list[str], heads: _Heads, items: Items
) -> None:
    if not obj:
        out.append("{}")
        return
    mark, first = len(out), 0
    for key, val in obj.items():
        if type(key) is not str:  # keys equal as text are one key (json_plain): start again
            del out[mark:]
            _mapping({str(k): v for k, v in obj.items()}, level, out, heads, items)
            return
        pair = heads.get((key, level))
        if pair is None:
            inner = "\n" + _INDENT * (level + 1) + encode_basestring_ascii(key) + ": "
            pair = heads[key, level] = ("{" + inner, "," + inner)
        head, first = pair[first], 1
        kind = type(val)
        if kind is float:  # the common leaves, without a call
            out.append(head + (float.__repr__(val) if math.isfinite(val) else "null"))
        elif kind is str:
            out.append(head + encode_basestring_ascii(val))
        elif kind is list and key in items:
            out.append(head)
            _sequence(val, level + 1, out, heads, items, items[key])
        else:
            out.append(head)
            _value(val, level + 1, out, heads, items)
    out.append("\n" + _INDENT * level + "}")


def _sequence(
    obj: list[Any] | tuple[Any, ...],
    level: int,
    out: list[str],
    heads: _Heads,
    items: Items,
    item: Callable[[Any, int], str | None] | None,
) -> None:
    if not obj:
        out.append("[]")
        return
    inner = "\n" + _INDENT * (level + 1)
    sep = "[" + inner
    for val in obj:
        text = None if item is None else item(val, level + 1)
        if text is None:
            out.append(sep)
            _value(val, level + 1, out, heads, items)
        else:
            out.append(sep + text)
        sep = "," + inner
    out.append("\n" + _INDENT * level + "]")
