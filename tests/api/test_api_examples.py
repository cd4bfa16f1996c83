"""The Examples sections of the public API (``ucbplan.api``'s modules) run as written.

Each module's docstrings go through :mod:`doctest` from the repository root, where the examples'
bundled ``catalogs/`` files are; the examples are offline (bundled tables only) and short (under
a second per module).
"""

from __future__ import annotations

import doctest
import importlib
import warnings
from pathlib import Path

import pytest

from ucbplan.errors import UcbplanWarning

ROOT = next(p for p in Path(__file__).resolve().parents if (p / "pyproject.toml").is_file())
FLAGS = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE

#: The modules of ``ucbplan.api.__all__``'s functions, whose examples run here.
MODULES = [
    "targets",
    "ephemeris",
    "validity",
    "planning",
    "replanning",
    "exporting",
    "signal_sizes",
    "lisa_analysis",
    "reduction",
    "timing",
    "populations",
]


def _run(name: str) -> doctest.TestResults:
    module = importlib.import_module(f"ucbplan.api.{name}")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UcbplanWarning)  # the bundled IERS tables end in 2027
        return doctest.testmod(module, optionflags=FLAGS, verbose=False, report=True)


@pytest.mark.parametrize("name", MODULES)
def test_examples_run(name: str, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(ROOT)
    result = _run(name)
    assert result.attempted > 0, f"ucbplan.api.{name} has no examples"
    assert result.failed == 0, f"ucbplan.api.{name}: {result.failed} example(s) failed (above)"


def test_every_public_function_has_an_example() -> None:
    """Each function of ``ucbplan.api.__all__`` has an Examples section with a doctest."""
    import inspect

    import ucbplan.api

    missing = [
        n
        for n in ucbplan.api.__all__
        if inspect.isfunction(obj := getattr(ucbplan.api, n))
        and "\n>>> "
        not in "\n" + "\n".join(line.strip() for line in (inspect.getdoc(obj) or "").splitlines())
    ]
    assert not missing, f"public functions without an example: {missing}"
    homes = {
        getattr(ucbplan.api, n).__module__.rsplit(".", 1)[1]
        for n in ucbplan.api.__all__
        if inspect.isfunction(getattr(ucbplan.api, n))
    }
    assert homes <= set(MODULES), sorted(homes - set(MODULES))
