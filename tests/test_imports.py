"""No import circles: the project's modules import only downward.

Every import statement counts, those inside functions and under ``TYPE_CHECKING`` included: a
lazy import still ties the two modules together, it only hides the circle until a call. Read
with :mod:`ast`, nothing is imported, so the test takes a fraction of a second.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("envs", "optim", "cli")  # pyproject.toml's packages, bottom to top


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def project_modules() -> dict[str, Path]:
    """Every module of the project's packages, by dotted name."""
    return {_module_name(p): p for pkg in PACKAGES for p in sorted((ROOT / pkg).rglob("*.py"))}


def _resolve(name: str, modules: dict[str, Path]) -> str | None:
    """The project module ``name`` loads: itself, or the package holding the imported name
    (``envs.check`` for ``from envs import check``, ``envs`` for ``from envs import Scene``)."""
    while name and name not in modules:
        name = name.rpartition(".")[0]
    return name or None


def imports_of(module: str, path: Path, modules: dict[str, Path]) -> set[str]:
    """The project modules that ``module`` imports anywhere in its file."""
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                source = ".".join(base + ([node.module] if node.module else []))
            else:
                source = node.module or ""
            targets = [f"{source}.{alias.name}" for alias in node.names]
        else:
            continue
        found.update(t for t in (_resolve(name, modules) for name in targets) if t)
    found.discard(module)
    return found


def import_graph() -> dict[str, set[str]]:
    """Module -> the project modules it imports."""
    modules = project_modules()
    return {name: imports_of(name, path, modules) for name, path in modules.items()}


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One import circle as ``[a, b, ..., a]``, or None (depth-first search)."""
    state: dict[str, int] = {}  # 1: on the current path, 2: finished
    path: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = 1
        path.append(node)
        for dep in sorted(graph[node]):
            if state.get(dep) == 1:
                return path[path.index(dep):] + [dep]
            if dep not in state and (found := visit(dep)):
                return found
        path.pop()
        state[node] = 2
        return None

    for node in sorted(graph):
        if node not in state and (found := visit(node)):
            return found
    return None


def test_the_finder_sees_a_circle_through_a_lazy_import():
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}
    assert find_cycle(graph) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"b"}, "b": set()}) is None
    modules = {"envs": ROOT, "envs.scene": ROOT, "envs.model.geometry": ROOT}
    assert _resolve("envs.scene.Gripper", modules) == "envs.scene"
    assert _resolve("envs.Scene", modules) == "envs"
    assert _resolve("numpy.linalg", modules) is None


def test_the_graph_holds_imports_inside_functions():
    graph = import_graph()
    # cli/main.py imports the command modules at its top; cli/simulate.py imports envs inside
    # its functions only
    assert {"cli.optimize", "cli.simulate"} <= graph["cli.main"]
    assert "envs.solver" in graph["cli.simulate"]


def test_no_import_circles():
    cycle = find_cycle(import_graph())
    assert cycle is None, "import circle: " + " -> ".join(cycle)


def test_layers_import_only_downward():
    """``envs`` imports neither ``optim`` nor ``cli``; ``optim`` does not import ``cli``."""
    graph = import_graph()
    for lower, upper in (("envs", ("optim", "cli")), ("optim", ("cli",))):
        wrong = sorted(f"{m} -> {d}" for m, deps in graph.items()
                       if m.split(".")[0] == lower for d in deps if d.split(".")[0] in upper)
        assert not wrong, f"{lower} imports a layer above it: {wrong}"
