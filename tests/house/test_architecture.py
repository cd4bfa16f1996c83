"""The package layout is the pipeline: imports point one way and never in a circle.

Layers, bottom to top (a module may import its own package and any lower layer):

0. ``ucbplan._version``, ``ucbplan.errors``
1. ``ucbplan.core`` (physics), ``ucbplan.io``/``ucbplan.inputs`` (files), ``ucbplan.offline``
2. ``ucbplan.targets`` (target files)
3. ``ucbplan.plotting`` (backend, atomic figures, horizon plot)
4. ``ucbplan.observing``, ``ucbplan.reduce``, ``ucbplan.lisa``, ``ucbplan.feasibility``,
   ``ucbplan.population``
5. ``ucbplan.api`` (the public functions), then ``ucbplan.cli`` (thin shells over them)
6. ``ucbplan`` itself (its lazy public names come from the API), then ``ucbplan.__main__``

Between packages of one layer only the edges in ``SIBLING_EDGES`` are allowed. Imports inside
``if TYPE_CHECKING:`` are annotations only and are not counted; imports inside functions are.
"""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[2] / "ucbplan"

LAYER = {
    "_version": 0,
    "errors": 0,
    "core": 1,
    "io": 1,
    "offline": 1,
    "inputs": 1,
    "targets": 2,
    "plotting": 3,
    "observing": 4,
    "reduce": 4,
    "lisa": 4,
    "feasibility": 4,
    "population": 4,
    "timing": 4,
    "api": 5,
    "cli": 6,
    "": 7,
    "__main__": 8,
}
#: reduce converts site-UTC spectrum times to barycentric TDB with the observing time conversion;
#: population runs the LISA Fisher forecast and the observing visibility per source.
SIBLING_EDGES = {("reduce", "observing"), ("population", "lisa"), ("population", "observing")}


def _module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _is_type_checking(node: ast.If) -> bool:
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _imports(tree: ast.AST, modules: set[str], this: str, is_pkg: bool) -> set[str]:
    """Every ucbplan module imported by ``tree`` outside ``if TYPE_CHECKING`` blocks."""
    found: set[str] = set()
    stack: list[ast.AST] = [tree]
    while stack:
        node = stack.pop()
        if isinstance(node, ast.If) and _is_type_checking(node):
            stack.extend(node.orelse)
            continue
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names if a.name.startswith("ucbplan"))
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = this.split(".")
                anchor = anchor[: len(anchor) - node.level + (1 if is_pkg else 0)]
                base = ".".join([*anchor, base] if base else anchor)
            if base.startswith("ucbplan"):
                for alias in node.names:
                    sub = f"{base}.{alias.name}"
                    found.add(sub if sub in modules else base)
        stack.extend(ast.iter_child_nodes(node))
    return found


def _graph() -> dict[str, set[str]]:
    files = {_module_name(p): p for p in PACKAGE.rglob("*.py")}
    modules = set(files)
    graph = {}
    for name, path in files.items():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        deps = _imports(tree, modules, name, path.name == "__init__.py")
        graph[name] = {d for d in deps if d != name}
    return graph


def _area(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def test_layers_point_one_way() -> None:
    bad = []
    for module, deps in _graph().items():
        area = _area(module)
        assert area in LAYER, f"{module}: package {area!r} has no layer in this test; add it"
        for dep in deps:
            dep_area = _area(dep)
            if dep_area == area or (area, dep_area) in SIBLING_EDGES:
                continue
            if LAYER[dep_area] >= LAYER[area]:
                bad.append(f"{module} -> {dep}")
    assert not bad, "imports against the layering:\n" + "\n".join(sorted(bad))


def test_nothing_below_the_cli_imports_it() -> None:
    bad = [
        f"{m} -> {d}"
        for m, deps in _graph().items()
        if _area(m) not in ("cli", "__main__")
        for d in deps
        if _area(d) == "cli"
    ]
    assert not bad, bad


def _find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    colour: dict[str, int] = {}
    path: list[str] = []

    def visit(node: str) -> list[str] | None:
        colour[node] = 1
        path.append(node)
        for dep in sorted(graph.get(node, ())):
            if colour.get(dep) == 1:
                return [*path[path.index(dep) :], dep]
            if dep not in colour and (cycle := visit(dep)):
                return cycle
        colour[node] = 2
        path.pop()
        return None

    for start in sorted(graph):
        if start not in colour and (cycle := visit(start)):
            return cycle
    return None


def test_no_import_cycles() -> None:
    cycle = _find_cycle(_graph())
    assert cycle is None, "import cycle: " + " -> ".join(cycle or [])


def test_cycle_finder_finds_a_planted_cycle() -> None:
    # the checker itself must be able to fail
    assert _find_cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert _find_cycle({"a": {"b"}, "b": set()}) is None


def test_relative_and_lazy_imports_are_seen() -> None:
    code = "def f():\n    from ucbplan.cli import app\nif TYPE_CHECKING:\n    import ucbplan.x\n"
    found = _imports(ast.parse(code), {"ucbplan.cli", "ucbplan.cli.app"}, "ucbplan.core.a", False)
    assert found == {"ucbplan.cli.app"}


# --- the house rules of issue 25: no cycle even in annotations, short functions and modules,
# --- one owner per concern, no twins, ERFA's warnings silenced at the edges only


def _graph_with_annotations() -> dict[str, set[str]]:
    """The import graph counting ``if TYPE_CHECKING:`` imports too (a cycle of types is a cycle)."""
    files = {_module_name(p): p for p in PACKAGE.rglob("*.py")}
    modules = set(files)
    graph: dict[str, set[str]] = {}
    for name, path in files.items():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        is_pkg = path.name == "__init__.py"
        deps = _imports(_without_type_checking_guards(tree), modules, name, is_pkg)
        graph[name] = {d for d in deps if d != name}
    return graph


def _without_type_checking_guards(tree: ast.Module) -> ast.Module:
    """``tree`` with each ``if TYPE_CHECKING:`` block's body lifted out of its guard."""

    class Lift(ast.NodeTransformer):
        def visit_If(self, node: ast.If) -> ast.AST | list[ast.stmt]:
            self.generic_visit(node)
            return [*node.body, *node.orelse] if _is_type_checking(node) else node

    return ast.fix_missing_locations(Lift().visit(tree))


def test_no_import_cycles_even_between_annotations() -> None:
    cycle = _find_cycle(_graph_with_annotations())
    assert cycle is None, "import cycle (annotations counted): " + " -> ".join(cycle or [])


def test_annotation_imports_are_counted_by_the_cycle_check() -> None:
    code = "if TYPE_CHECKING:\n    from ucbplan.b import X\n"
    tree = _without_type_checking_guards(ast.parse(code))
    assert _imports(tree, {"ucbplan.b"}, "ucbplan.a", False) == {"ucbplan.b"}


#: The longest a function may be (``def`` to its last line, decorators aside, signature counted),
#: and how many may be longer. A long function is read as a whole before it can be changed.
MAX_FUNCTION_LINES = 60
MAX_LONG_FUNCTIONS = 5


def _code_lines(node: ast.FunctionDef | ast.AsyncFunctionDef) -> int:
    """Lines from ``def`` to the end, less the docstring (the reference, not code to read)."""
    n = (node.end_lineno or node.lineno) - node.lineno + 1
    first = node.body[0]
    if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant):
        if isinstance(first.value.value, str):
            n -= (first.end_lineno or first.lineno) - first.lineno + 1
    return n


def _long_functions(root: Path = PACKAGE) -> list[tuple[int, str]]:
    found = []
    for path in sorted(root.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                n = _code_lines(node)
                if n > MAX_FUNCTION_LINES:
                    found.append((n, f"{path.relative_to(root.parent)}:{node.name}"))
    return sorted(found, reverse=True)


def test_at_most_five_functions_are_long() -> None:
    long = _long_functions()
    listing = "\n".join(f"{n} lines  {name}" for n, name in long)
    assert len(long) <= MAX_LONG_FUNCTIONS, f"functions over {MAX_FUNCTION_LINES} lines:\n{listing}"


def test_the_length_check_finds_a_planted_long_function(tmp_path: Path) -> None:
    """61 lines of code are long; a 70-line docstring over 5 lines of code is not."""
    doc = "    " + '"""' + "\n    line\n" * 35 + '    """\n'
    code = "".join(f"    x{i} = {i}\n" for i in range(60))
    (tmp_path / "planted.py").write_text(
        f"def documented():\n{doc}    return 0\n\n\ndef long():\n{code}    return x0\n"
    )
    assert _long_functions(tmp_path) == [(62, f"{tmp_path.name}/planted.py:long")]


#: The longest a module may be, and the modules allowed past it because each is one cohesive
#: declaration (docs/architecture.md names them and says why).
MAX_MODULE_LINES = 600
COHESIVE_DECLARATIONS: dict[str, str] = {}


def test_modules_are_short_or_declared_cohesive() -> None:
    long = {
        str(p.relative_to(PACKAGE.parent)): n
        for p in sorted(PACKAGE.rglob("*.py"))
        if (n := len(p.read_text(encoding="utf-8").splitlines())) > MAX_MODULE_LINES
    }
    undeclared = {m: n for m, n in long.items() if m not in COHESIVE_DECLARATIONS}
    assert not undeclared, f"modules over {MAX_MODULE_LINES} lines: {undeclared}"
    doc = (PACKAGE.parent / "docs" / "architecture.md").read_text(encoding="utf-8")
    missing = [m for m in COHESIVE_DECLARATIONS if m not in doc]
    assert not missing, f"docs/architecture.md does not name the long modules {missing}"


#: Module names that stand twice in one top-level package on purpose (none today: the package
#: a module sits in says its concern, so ``observing/blocks/write.py`` and ``targets/write.py`` are
#: two owners of two names, "blocks write" and "targets write").
SHARED_MODULE_NAMES = {"__init__"}


def _name_twins(paths: list[Path]) -> dict[str, list[str]]:
    """Module names that stand more than once inside one top-level package of ``ucbplan``
    (the one-owner rule is keyed on that package, so names inside it can stay short)."""
    owners: dict[tuple[str, str], list[str]] = {}
    for path in paths:
        parts = path.relative_to(PACKAGE).parts
        area = parts[0] if len(parts) > 1 else ""
        owners.setdefault((area, path.stem), []).append(str(path.relative_to(PACKAGE.parent)))
    return {
        f"{area}/…/{stem}": sorted(v)
        for (area, stem), v in owners.items()
        if len(v) > 1 and stem not in SHARED_MODULE_NAMES
    }


def test_each_module_name_has_one_owner() -> None:
    twins = _name_twins(list(PACKAGE.rglob("*.py")))
    assert not twins, f"one module name, two modules of one package (rename by concern): {twins}"


def test_the_owner_check_finds_a_planted_twin() -> None:
    planted = [
        PACKAGE / "observing" / "blocks" / "write.py",
        PACKAGE / "observing" / "night" / "write.py",
    ]
    assert _name_twins([*planted, PACKAGE / "targets" / "write.py"]) == {
        "observing/…/write": [
            "ucbplan/observing/blocks/write.py",
            "ucbplan/observing/night/write.py",
        ]
    }


#: Lines of the same logic two places may share; the next one makes them twins.
MAX_SHARED_LINES = 10


def _logic_lines(path: Path) -> list[tuple[int, str]]:
    """(line, text) of the lines that carry logic: no blanks, comments, imports, docstrings."""
    text = path.read_text(encoding="utf-8")
    skip: set[int] = set()
    for node in ast.walk(ast.parse(text)):
        body = getattr(node, "body", None)
        if isinstance(body, list) and body and isinstance(body[0], ast.Expr):
            value = body[0].value
            if isinstance(value, ast.Constant) and isinstance(value.value, str):
                skip.update(range(body[0].lineno, (body[0].end_lineno or body[0].lineno) + 1))
    out = []
    for i, raw in enumerate(text.splitlines(), start=1):
        line = " ".join(raw.split())
        if i in skip or not line or line.startswith(("#", "import ", "from ", "@")):
            continue
        if line in {")", "]", "}", "),", "],", "},", "else:", "try:", "finally:", '"""'}:
            continue
        out.append((i, line))
    return out


def _twins(files: dict[str, list[tuple[int, str]]], run: int) -> list[str]:
    """Places where ``run`` consecutive logic lines stand again elsewhere (or in the same file)."""
    seen: dict[tuple[str, ...], tuple[str, int]] = {}
    found = []
    for name, lines in sorted(files.items()):
        texts = [t for _, t in lines]
        last_hit = -run
        for k in range(len(texts) - run + 1):
            key = tuple(texts[k : k + run])
            here = (name, lines[k][0])
            first = seen.setdefault(key, here)
            if first != here and k >= last_hit + run:
                found.append(f"{first[0]}:{first[1]} ~ {name}:{here[1]}")
                last_hit = k
    return found


def test_no_two_places_share_more_than_ten_lines() -> None:
    files = {
        str(p.relative_to(PACKAGE.parent)): _logic_lines(p) for p in sorted(PACKAGE.rglob("*.py"))
    }
    twins = _twins(files, MAX_SHARED_LINES + 1)
    assert not twins, "the same logic in two places (make it one function):\n" + "\n".join(twins)


def test_the_twin_finder_finds_a_planted_twin() -> None:
    block = [(i, f"x{i} = f(x{i - 1})") for i in range(1, 13)]
    assert _twins({"a.py": block, "b.py": block}, 11) == ["a.py:1 ~ b.py:1"]
    assert _twins({"a.py": block, "b.py": block[:10]}, 11) == []


#: Where ERFA's "dubious year" warnings may be silenced: the edges (the offline scope every API
#: function, the CLI entry and each population task enter), and the module that declares the filter.
ERFA_EDGES = {"ucbplan/offline.py"}


def test_erfa_warnings_are_silenced_at_the_edges_only() -> None:
    users = sorted(
        str(p.relative_to(PACKAGE.parent))
        for p in PACKAGE.rglob("*.py")
        if "ErfaWarning" in p.read_text(encoding="utf-8") or "quiet_erfa" in p.read_text("utf-8")
    )
    assert set(users) <= ERFA_EDGES, f"ERFA warnings handled away from the edges: {users}"


# --------------------------------------------------------------- the CLI is a shell (issue 30)

#: What ``ucbplan.cli`` may import: the public API, the errors, the version and itself.
CLI_MAY_IMPORT = ("ucbplan.api", "ucbplan.errors", "ucbplan._version", "ucbplan.cli")


def _cli_imports_outside_the_api(graph: dict[str, set[str]]) -> list[str]:
    """``module -> import`` for each import of a CLI module that is not the API's."""
    return sorted(
        f"{m} -> {d}"
        for m, deps in graph.items()
        if _area(m) == "cli"
        for d in deps
        if not any(d == ok or d.startswith(f"{ok}.") for ok in CLI_MAY_IMPORT)
    )


def test_the_cli_imports_only_the_api() -> None:
    bad = _cli_imports_outside_the_api(_graph())
    assert not bad, "the command line reaches past ucbplan.api:\n" + "\n".join(bad)


def test_the_cli_import_check_finds_a_planted_import() -> None:
    code = "def f():\n    from ucbplan.observing.night.countdown import what_next\n"
    deps = _imports(ast.parse(code), {"ucbplan.observing.night.countdown"}, "ucbplan.cli.x", False)
    graph = {"ucbplan.cli.x": deps, "ucbplan.cli.y": {"ucbplan.api.exporting", "ucbplan.errors"}}
    assert _cli_imports_outside_the_api(graph) == [
        "ucbplan.cli.x -> ucbplan.observing.night.countdown"
    ]


#: Defaults a command may write itself: "not given" (None, False, an empty list) and "required".
_NEUTRAL_DEFAULTS = (None, False, Ellipsis)


def _is_typer_call(node: ast.AST) -> bool:
    """``typer.Option(…)`` or ``typer.Argument(…)`` (the default is their first argument)."""
    return (
        isinstance(node, ast.Call)
        and isinstance(node.func, ast.Attribute)
        and node.func.attr in ("Option", "Argument")
    )


def _literal_defaults(tree: ast.AST, where: str, declared: set[str]) -> list[str]:
    """``where:function:parameter = value`` for each parameter of ``declared`` (a parameter the
    API declares) whose default is a literal (``3.0``, ``"auto"``, ``True``), also inside
    ``typer.Option(3.0, …)``: a default the command line declares beside the API's."""
    found = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            continue
        a = node.args
        pairs = list(zip(a.args[len(a.args) - len(a.defaults) :], a.defaults, strict=True))
        pairs += [(k, d) for k, d in zip(a.kwonlyargs, a.kw_defaults, strict=True) if d]
        for arg, default in pairs:
            if arg.arg not in declared:
                continue
            value = default.args[0] if _is_typer_call(default) and default.args else default
            if isinstance(value, ast.Constant) and value.value not in _NEUTRAL_DEFAULTS:
                found.append(f"{where}:{node.name}:{arg.arg} = {value.value!r}")
            elif isinstance(value, ast.List | ast.Tuple) and value.elts:
                found.append(f"{where}:{node.name}:{arg.arg} = {ast.unparse(value)}")
    return found


def _api_parameters() -> set[str]:
    """Every parameter a flag table of ``ucbplan.api`` declares (``PLAN_FLAGS`` …)."""
    import importlib
    import pkgutil

    import ucbplan.api
    from ucbplan.api.flagspec import Flag

    names: set[str] = set()
    for info in pkgutil.iter_modules(ucbplan.api.__path__):
        module = importlib.import_module(f"ucbplan.api.{info.name}")
        for value in vars(module).values():
            if (
                isinstance(value, dict)
                and value
                and all(isinstance(v, Flag) for v in value.values())
            ):
                names |= set(value)
    return names


def test_no_default_is_declared_twice() -> None:
    # a command's option takes its default from the API signature (ucbplan.cli._derive.option);
    # a literal default in ucbplan/cli for a parameter the API declares is a second declaration
    declared = _api_parameters()
    assert {"airmass_max", "samples", "alpha"} <= declared
    found = []
    for path in sorted((PACKAGE / "cli").glob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        found += _literal_defaults(tree, _module_name(path), declared)
    assert not found, "defaults written in the command line, not taken from the API:\n" + "\n".join(
        found
    )


def test_the_default_check_finds_planted_defaults() -> None:
    code = (
        "def cmd(a: int = 3, b: _Opt = None, *, c: str = typer.Option('auto', '--c'),\n"
        "        d: bool = False, e: list[str] = [], f: list[str] = ['x'],\n"
        "        g: float = option(api.plan, FLAGS, 'g'), h: str = typer.Option(..., '--h')):\n"
        "    pass\n"
    )
    declared = set("abcdefgh")
    assert sorted(_literal_defaults(ast.parse(code), "m", declared)) == [
        "m:cmd:a = 3",
        "m:cmd:c = 'auto'",
        "m:cmd:f = ['x']",
    ]
    assert _literal_defaults(ast.parse(code), "m", {"b", "d"}) == []  # CLI-only options
