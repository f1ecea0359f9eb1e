"""The package's layers point one way (issue 29, DESIGN §2): a module imports only from its own
layer or lower ones — lazy imports inside functions included — and the import graph has no cycle.

The layers are written here once, top to bottom; ``docs/architecture.md`` draws the same list.
Every import statement of every module under ``src/g1patch`` is read from its syntax tree, so an
import hidden in a function body counts as much as one at the top.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "g1patch"

#: top to bottom; names in one row are one layer (they may import each other, never a cycle)
LAYERS: tuple[tuple[str, ...], ...] = (
    ("cli",),
    ("batch",),
    ("demo",),
    ("api",),
    ("viewer",),
    ("render",),
    ("io",),
    ("fitting",),
    ("build", "adaptive", "compare", "fidelity"),
    ("construct",),
    ("targets",),
    ("subdivision", "sharpen", "shapes"),
    ("continuity", "tessellate", "geometry"),
    ("network",),
    ("mesh",),
    ("gregory",),
    ("patches",),
    ("_grid", "curves", "frame", "projective"),
    ("basis",),
    ("display", "kernels", "memory", "errors"),
)
#: the shells: only they (and the root) may import the package root or api
SHELLS = {"cli", "batch"}
LEVEL = {name: depth for depth, row in enumerate(LAYERS) for name in row}


def _module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports_of(name: str, source: str, is_package: bool) -> set[str]:
    """The g1patch modules and packages ``source`` (module ``name``) imports, anywhere in it."""
    found: set[str] = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names if alias.name.startswith("g1patch"))
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = name.split(".") if is_package else name.split(".")[:-1]
                base = base[: len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if not target.startswith("g1patch"):
                continue
            for alias in node.names:  # ``from pkg import sub`` imports the module pkg.sub
                module = f"{target}.{alias.name}"
                relative = Path(*module.split(".")[1:])
                is_module = (PACKAGE / relative).is_dir() or (PACKAGE / f"{relative}.py").exists()
                found.add(module if is_module else target)
    return found


def _graph() -> dict[str, set[str]]:
    graph = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        name = _module_name(path)
        graph[name] = imports_of(name, path.read_text(), path.name == "__init__.py")
    return graph


def _top(name: str) -> str:
    """The top-level part of ``g1patch.a.b`` (``a``), or ``""`` for the root."""
    parts = name.split(".")
    return parts[1] if len(parts) > 1 else ""


def violations(graph: dict[str, set[str]]) -> list[str]:
    """Every import that climbs a layer, or reaches the root or api from below the shells."""
    found = []
    for module, targets in graph.items():
        source = _top(module)
        if source == "":
            continue  # the package root is a shell: it registers the painters, loads names lazily
        for target in targets:
            upper = _top(target)
            if upper == source:
                continue
            if upper in ("", "api"):
                if source not in SHELLS:
                    found.append(f"{module} imports the package root or api")
            elif LEVEL.get(upper, -1) < LEVEL.get(source, -1):
                found.append(f"{module} imports {target}, a higher layer")
    return sorted(found)


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan), package ``__init__``
    modules standing for themselves only."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def resolve(target: str) -> str | None:
        while target and target not in graph:
            target = target.rpartition(".")[0]
        return target or None

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for raw in graph[node]:
            target = resolve(raw)
            if target is None or target == node:
                continue
            if target not in index:
                visit(target)
                low[node] = min(low[node], low[target])
            elif target in on_stack:
                low[node] = min(low[node], index[target])
        if low[node] == index[node]:
            component = []
            while True:
                member = stack.pop()
                on_stack.discard(member)
                component.append(member)
                if member == node:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for node in graph:
        if node not in index:
            visit(node)
    return found


def test_every_module_has_a_layer() -> None:
    tops = {_top(name) for name in _graph()} - {""}
    assert tops <= set(LEVEL), f"modules with no layer: {sorted(tops - set(LEVEL))}"


def test_layers_point_one_way() -> None:
    assert violations(_graph()) == []


def test_no_import_cycles() -> None:
    assert cycles(_graph()) == []


@pytest.mark.parametrize(
    ("module", "source", "expected"),
    [
        ("g1patch.mesh.topology", "def f():\n    from ..render import render\n", "higher layer"),
        (
            "g1patch.mesh.topology",
            "def f():\n    from ..api import smooth\n",
            "package root or api",
        ),
        ("g1patch.network", "import g1patch.render\n", "higher layer"),
        ("g1patch.continuity.report", "from .. import read\n", "package root"),
        ("g1patch.viewer", "from ..api import Surface\n", "package root or api"),
    ],
)
def test_the_contract_fails_on_a_forbidden_import(module: str, source: str, expected: str) -> None:
    """The checks are live: a forbidden import, even a lazy one, is caught."""
    graph = _graph()
    is_package = (PACKAGE / Path(*module.split(".")[1:])).is_dir()
    graph[module] = graph.get(module, set()) | imports_of(module, source, is_package)
    assert any(expected in line for line in violations(graph))


def test_the_contract_finds_a_cycle() -> None:
    graph = _graph()
    graph["g1patch.basis"] = graph["g1patch.basis"] | {"g1patch.patches"}
    assert any("g1patch.basis" in component for component in cycles(graph))
