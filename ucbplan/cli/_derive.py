"""typer options derived from the public API's declarations (:mod:`ucbplan.api.flagspec`).

A command writes ``airmass_max: float = option(api.plan, PLAN_FLAGS, "airmass_max")``: the
default comes from the API function's signature and the flag and help text from its flag table,
so the command line declares neither again.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import typer

from ucbplan.api.flagspec import Flag, default_of


def option(func: Callable[..., Any], flags: Mapping[str, Flag], parameter: str) -> Any:
    """``typer.Option`` for ``func``'s ``parameter``: its default, flag and help, declared once."""
    spec = flags[parameter]
    return typer.Option(
        default_of(func, parameter), *spec.decls, help=spec.help, min=spec.min, max=spec.max
    )


def argument(flags: Mapping[str, Flag], parameter: str) -> Any:
    """``typer.Argument`` (required) with the help text declared for ``parameter``."""
    return typer.Argument(..., help=flags[parameter].help)


def flag(flags: Mapping[str, Flag], parameter: str, default: Any = None) -> Any:
    """``typer.Option`` with the flag and help declared for ``parameter`` and a default of the
    command line's own: None (the API takes the value in another form or has no default), or
    ``...`` (required)."""
    spec = flags[parameter]
    return typer.Option(default, *spec.decls, help=spec.help)
