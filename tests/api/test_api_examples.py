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


#: Further modules of ``ucbplan.__all__``'s classes whose docstrings hold examples.
OTHER_MODULES = ["ucbplan.observing.constraints"]


def _run(name: str) -> doctest.TestResults:
    module = importlib.import_module(name if "." in name else f"ucbplan.api.{name}")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UcbplanWarning)  # the bundled IERS tables end in 2027
        return doctest.testmod(module, optionflags=FLAGS, verbose=False, report=True)


@pytest.mark.parametrize("name", MODULES + OTHER_MODULES)
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


#: The numpydoc sections that document a method's call (one is enough: ``plot(ax)`` may return
#: what it was given, ``to_dict()`` takes nothing).
CALL_SECTIONS = ("Parameters\n---", "Returns\n---")


def _undocumented_methods(cls: type) -> list[str]:
    """The public methods of ``cls`` (inherited ones too) whose docstring has no call section."""
    import inspect

    names = []
    for name in dir(cls):
        static = inspect.getattr_static(cls, name)
        func = getattr(static, "__func__", static)  # classmethod, staticmethod
        if name.startswith("_") or not inspect.isfunction(func):
            continue
        doc = inspect.getdoc(getattr(cls, name)) or ""
        if not any(section in doc for section in CALL_SECTIONS):
            names.append(f"{cls.__name__}.{name}")
    return names


def test_every_public_method_has_numpydoc_sections() -> None:
    """Each public class of ``ucbplan`` and ``ucbplan.api`` documents its fields (Parameters or
    Attributes, unless it takes none) and each public method its call (Parameters or Returns)."""
    import inspect

    import ucbplan
    import ucbplan.api

    public = {getattr(m, n) for m in (ucbplan, ucbplan.api) for n in m.__all__}
    classes = sorted(
        (c for c in public if inspect.isclass(c) and not issubclass(c, Warning | Exception)),
        key=lambda c: c.__name__,
    )
    assert len(classes) > 10, [c.__name__ for c in classes]
    bare = [
        c.__name__
        for c in classes
        if len(inspect.signature(c).parameters) > 0
        and not any(s in (inspect.getdoc(c) or "") for s in ("Parameters\n---", "Attributes\n---"))
    ]
    assert not bare, f"public classes without Parameters/Attributes: {bare}"
    missing = [m for c in classes for m in _undocumented_methods(c)]
    assert not missing, f"public methods without Parameters/Returns: {missing}"


def test_the_method_check_finds_a_planted_bare_method() -> None:
    class Planted:
        def documented(self, x: int) -> int:
            """Twice ``x``.

            Parameters
            ----------
            x : int
                A number.
            """
            return 2 * x

        def bare(self) -> int:
            """A number."""
            return 1

    assert _undocumented_methods(Planted) == ["Planted.bare"]
