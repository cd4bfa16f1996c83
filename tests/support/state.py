"""Snapshots of other libraries' module-level state, for the no-global-state checks."""

from __future__ import annotations

import warnings
from collections.abc import Iterator
from typing import Any

import astropy.io.misc.yaml as astropy_yaml
import yaml
from astropy import config
from astropy.utils import data, iers


def _namespaces() -> Iterator[config.ConfigNamespace]:
    import sys

    for module in list(sys.modules.values()):
        if not getattr(module, "__name__", "").startswith("astropy"):
            continue
        ns = getattr(module, "conf", None)
        if isinstance(ns, config.ConfigNamespace):
            yield ns


def _config_items() -> dict[str, Any]:
    """Every item of every astropy config namespace imported so far, by its full name."""
    items: dict[str, Any] = {}
    seen: set[int] = set()
    for ns in _namespaces():
        if id(ns) in seen:
            continue
        seen.add(id(ns))
        for name in ns:
            items[f"{type(ns).__module__}.{name}"] = repr(getattr(ns, name))
    return items


def _registries(cls: type) -> tuple[object, ...]:
    return tuple(
        tuple(sorted(((repr(k), v) for k, v in getattr(cls, name, {}).items()), key=str))
        for name in (
            "yaml_representers",
            "yaml_multi_representers",
            "yaml_constructors",
            "yaml_multi_constructors",
            "yaml_implicit_resolvers",
        )
    )


def astropy_state() -> tuple[object, ...]:
    """What the offline scope sets and must restore: astropy's IERS and data configuration,
    its ``IERS_Auto`` opener and default table, and the warning filters."""
    return (
        iers.conf.auto_download,
        iers.conf.auto_max_age,
        data.conf.allow_internet,
        iers.IERS_Auto.__dict__["open"],
        iers.earth_orientation_table._value,
        tuple(warnings.filters),
    )


def snapshot() -> dict[str, object]:
    """Everything a ucbplan call must leave as it was (see the module docstring)."""
    return {
        "offline scope": astropy_state(),
        "config": _config_items(),
        "AstropyDumper": astropy_yaml.AstropyDumper,
        "AstropyLoader": astropy_yaml.AstropyLoader,
        "astropy yaml registries": tuple(
            _registries(c) for c in (astropy_yaml.AstropyDumper, astropy_yaml.AstropyLoader)
        ),
        "pyyaml registries": tuple(
            _registries(c) for c in (yaml.SafeDumper, yaml.Dumper, yaml.SafeLoader, yaml.Loader)
        ),
        "warnings.filters": tuple(warnings.filters),
    }
