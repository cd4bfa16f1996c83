"""The plan's provenance as the exports read it: its meta, creation time, site, version."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from astropy.table import Table

# Provenance
# --------------------------------------------------------------------------------------------


def meta(table: Table) -> dict[str, Any]:
    """The table's ``meta`` as a dict (empty when absent or not a mapping)."""
    return dict(table.meta) if isinstance(table.meta, Mapping) else {}


def _meta_text(value: Any, default: str) -> str:
    """A provenance value as one short line of text (``default`` unless it is a plain value)."""
    if isinstance(value, str | int | float) and not isinstance(value, bool):
        text = " ".join(_utf8(str(value)).split())
        return text[:200] if text else default
    return default


def _utf8(text: str) -> str:
    """``text`` without lone surrogates (a YAML ``"\\ud800"`` escape cannot be written)."""
    return text.encode("utf-8", "replace").decode("utf-8")


def clean_meta(value: Any, budget: list[int] | None = None, depth: int = 0) -> Any:
    """A copy of provenance metadata that can be written again: plain dicts, lists, numbers and
    UTF-8 strings, at most 8 levels deep and 10 000 values in all (shared references, as a YAML
    alias makes them, cannot expand without limit). A table's own metadata comes back equal."""
    budget = [10_000] if budget is None else budget
    budget[0] -= 1
    if depth > 8 or budget[0] < 0:
        return "..."
    if isinstance(value, Mapping):
        return {_utf8(str(k)): clean_meta(v, budget, depth + 1) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [clean_meta(v, budget, depth + 1) for v in value]
    if isinstance(value, str):
        return _utf8(value)
    if value is None or isinstance(value, bool | int | float):
        return value
    return _utf8(str(value))


def created_utc(table: Table) -> str:
    """The table's ``meta['created_utc']`` ('' when absent)."""
    return _meta_text(meta(table).get("created_utc"), "")


def site_name(table: Table) -> str:
    """The observing site's name from the table ``meta`` ('unknown site' when absent)."""
    site = meta(table).get("site")
    if isinstance(site, Mapping):
        return _meta_text(site.get("name"), "unknown site")
    return _meta_text(site, "unknown site")


def version() -> str:
    """The ucbplan version written into every export."""
    from ucbplan._version import __version__

    return __version__


# --------------------------------------------------------------------------------------------
