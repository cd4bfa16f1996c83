"""The package layout is the pipeline: imports point one way and never in a circle.

Layers, bottom to top (a module may import its own package and any lower layer):

0. ``ucbplan._version``, ``ucbplan.errors``
1. ``ucbplan.core`` (physics), ``ucbplan.io``/``ucbplan.inputs`` (files), ``ucbplan.offline``
2. ``ucbplan.target`` (target files)
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

PACKAGE = Path(__file__).resolve().parents[1] / "ucbplan"

LAYER = {
    "_version": 0,
    "errors": 0,
    "core": 1,
    "io": 1,
    "offline": 1,
    "inputs": 1,
    "target": 2,
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
