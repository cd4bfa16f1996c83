"""How the public functions' parameters are spelled on the command line: declared once, here.

Each public function of :mod:`ucbplan.api` declares its parameters in its signature (the
default, with its unit in the name or accepted as a Quantity) and documents them in its
numpydoc. The command line is a shell over those functions: it takes each option's default from
the function's signature (:func:`default_of`) and its flag and help text from the function's
:class:`Flag` table, so nothing the two doors share is written twice.

This module imports nothing heavy: the command line reads it at start-up.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True, slots=True)
class Flag:
    """One parameter of a public function as the command line spells it.

    Parameters
    ----------
    decls : tuple of str
        The flag and its aliases, as typer takes them (``("-o", "--output")``).
    help : str
        The ``--help`` text of the option.
    unit : str, optional
        The unit of the number typed on the command line, where the function also takes a
        Quantity (the function's default is then given in this unit).
    min, max : float, optional
        The range the command line checks and ``--help`` shows (``100<=x<=10000000``); the
        function checks the same bounds.
    """

    decls: tuple[str, ...]
    help: str
    unit: str | None = None
    min: float | None = None
    max: float | None = None

    @property
    def name(self) -> str:
        """The long flag (``--airmass-max``): the one error messages print."""
        longs = [d for d in self.decls if d.startswith("--")]
        return (longs or list(self.decls) or [""])[0].split("/")[0]  # "": an argument


def default_of(func: Callable[..., Any], parameter: str) -> Any:
    """The default of ``func``'s keyword ``parameter``, declared once in its signature.

    Raises
    ------
    KeyError
        When ``func`` has no such parameter or it has no default (a bug of the caller).
    """
    param = inspect.signature(func).parameters[parameter]
    if param.default is inspect.Parameter.empty:
        raise KeyError(f"{func.__name__}: parameter {parameter!r} has no default")
    return param.default


def flag_names(*tables: Mapping[str, Flag]) -> dict[str, str]:
    """Parameter name → the long flag printed for it, over the given flag tables."""
    out: dict[str, str] = {}
    for table in tables:
        for parameter, flag in table.items():
            if flag.decls:  # an argument has no flag
                out.setdefault(parameter, flag.name)
    return out
