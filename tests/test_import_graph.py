"""The library's import graph runs one way: no circles between modules, and no import of the CLI.

The graph is read from the source with :mod:`ast`, never by importing, so lazy imports count too. Its rules:

* Every ``import`` and ``from ... import`` statement counts wherever it sits: module level, inside a function, under
  ``if TYPE_CHECKING:``. A circle closed by an import inside a function is still a circle; it only fails later.
* ``import a.b.c`` is an edge to ``a.b.c`` only, not to ``a`` and ``a.b``. Python does run the parent packages'
  ``__init__`` first, but counting that would make every submodule of a package whose ``__init__`` re-exports its
  submodules sit in a circle with it, which says nothing about how the modules depend on one another.
* ``from a.b import c`` is an edge to the module ``a.b.c`` when that file exists, else to ``a.b`` (a name defined or
  re-exported there, so the package ``__init__`` and whatever it imports are really needed).
* Relative imports (``from . import x``, ``from ..y import z``) are resolved against the importing module's package.
* ``importlib.import_module`` with a computed name (the packages' lazy ``__getattr__`` re-exports) is not followed.
"""

from __future__ import annotations

import ast
from pathlib import Path

LIBRARY = "rgbt_toolkit"
CLI_PACKAGES = ("rgbt_cli", "cli")
PACKAGE_DIR = Path(__file__).resolve().parents[1] / LIBRARY


def module_names(package_dir: Path) -> dict[str, Path]:
    """Dotted module name -> source file for every ``.py`` file under the package folder."""
    modules = {}
    for path in sorted(package_dir.rglob("*.py")):
        parts = list(path.relative_to(package_dir.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        modules[".".join(parts)] = path
    return modules


def _package_of(module: str, path: Path) -> str:
    """The package a relative import in ``module`` starts from."""
    return module if path.name == "__init__.py" else module.rpartition(".")[0]


def imported_names(module: str, path: Path) -> list[tuple[str, ...]]:
    """One entry per imported name: the dotted names it may be, most specific first, relative imports made absolute.

    ``import a.b`` gives ``("a.b",)``; ``from a import b`` gives ``("a.b", "a")``: the module ``a.b`` if it exists,
    else the name ``b`` defined in ``a``.
    """
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    names = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.extend((alias.name,) for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = _package_of(module, path).split(".")
                anchor = anchor[: len(anchor) - (node.level - 1)]
                base = ".".join([*anchor, base] if base else anchor)
            names.extend((f"{base}.{alias.name}", base) for alias in node.names)
    return names


def import_graph(package_dir: Path = PACKAGE_DIR) -> dict[str, set[str]]:
    """Module -> the library modules it imports (see the module docstring for what counts as an edge)."""
    modules = module_names(package_dir)
    graph = {}
    for module, path in modules.items():
        targets = (next((name for name in candidates if name in modules), None)
                   for candidates in imported_names(module, path))
        graph[module] = {target for target in targets if target is not None}
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module, and modules importing themselves (Tarjan)."""
    index: dict[str, int] = {}
    lowlink: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def visit(node: str) -> None:
        index[node] = lowlink[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for target in sorted(graph.get(node, ())):
            if target not in index:
                visit(target)
                lowlink[node] = min(lowlink[node], lowlink[target])
            elif target in on_stack:
                lowlink[node] = min(lowlink[node], index[target])
        if lowlink[node] == index[node]:
            component = []
            while True:
                member = stack.pop()
                on_stack.discard(member)
                component.append(member)
                if member == node:
                    break
            if len(component) > 1 or node in graph.get(node, ()):
                found.append(sorted(component))

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return sorted(found)


def cli_imports(package_dir: Path = PACKAGE_DIR) -> dict[str, set[str]]:
    """Module -> the CLI modules it imports (there should be none)."""
    found = {}
    for module, path in module_names(package_dir).items():
        names = {candidates[-1] for candidates in imported_names(module, path)
                 if candidates[-1].split(".")[0] in CLI_PACKAGES}
        if names:
            found[module] = names
    return found


def _describe(component: list[str], graph: dict[str, set[str]]) -> str:
    members = set(component)
    edges = [f"{a} -> {b}" for a in component for b in sorted(graph[a] & members)]
    return "circle of " + ", ".join(component) + ":\n    " + "\n    ".join(edges)


def test_the_library_modules_import_one_another_without_circles():
    graph = import_graph()
    found = cycles(graph)
    assert not found, "import circles (move the shared name to a lower module, or pass the part in):\n" + "\n".join(
        _describe(component, graph) for component in found)


def test_the_library_never_imports_the_cli():
    assert cli_imports() == {}


def test_the_library_graph_holds_known_edges():
    """Guards the checker itself: a graph with no edges would pass the circle test for the wrong reason."""
    graph = import_graph()
    assert len(graph) > 150
    assert "rgbt_toolkit.jmmac.pipeline" in graph["rgbt_toolkit.jmmac"]  # a package __init__ re-exporting
    assert "rgbt_toolkit.api" in graph["rgbt_toolkit"]
    assert "rgbt_toolkit.jmmac.run" in graph["rgbt_toolkit.jmmac.api"]  # imported inside a function


def test_cycles_finds_circles_and_self_loops_and_nothing_else():
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a", "d"}, "d": set(), "e": {"e"}, "f": {"d"}}
    assert cycles(graph) == [["a", "b", "c"], ["e"]]


def test_the_graph_follows_relative_lazy_and_submodule_imports(tmp_path):
    """Edge rules of the module docstring, on a small package written for the test."""
    package = tmp_path / "pkg"
    (package / "sub").mkdir(parents=True)
    sources = {
        "__init__.py": "from pkg.sub import deep\n",
        "a.py": "def later():\n    from . import b\n",
        "b.py": "import pkg.sub.deep\nfrom .sub import NAME\n",
        "sub/__init__.py": "NAME = 1\n",
        "sub/deep.py": "from ..a import later\nimport numpy\nfrom cli.cmd import run\n",
    }
    for name, text in sources.items():
        (package / name).write_text(text, encoding="utf-8")
    assert import_graph(package) == {
        "pkg": {"pkg.sub.deep"},
        "pkg.a": {"pkg.b"},
        "pkg.b": {"pkg.sub.deep", "pkg.sub"},
        "pkg.sub": set(),
        "pkg.sub.deep": {"pkg.a"},
    }
    assert cycles(import_graph(package)) == [["pkg.a", "pkg.b", "pkg.sub.deep"]]
    assert cli_imports(package) == {"pkg.sub.deep": {"cli.cmd"}}
