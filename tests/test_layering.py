"""The layering of docs/architecture.md ("The layers"), read from the imports of every module.

Every import counts: absolute and relative, at module level, inside functions and under
``if TYPE_CHECKING:``.
"""
from __future__ import annotations

import ast
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
ENGINE = ROOT / "bt_engine"
FORBIDDEN = {
    "bt_engine": {"actors", "categories", "planning", "sim", "navstack"},
    "categories": {"actors", "planning", "sim", "navstack", "demo"},
    "planning": {"bt_engine", "sim", "actors", "navstack"},
    "actors": {"sim", "navstack"},
    "sim": {"actors", "planning", "navstack"},
    "navstack": {"sim", "actors"},
}


def imported_packages(path: pathlib.Path) -> set[str]:
    tree = ast.parse(path.read_text(), str(path))
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found |= {a.name.split(".")[0] for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            found.add(node.module.split(".")[0])
    return found


@pytest.mark.parametrize("package", sorted(FORBIDDEN))
def test_imports_only_go_downwards(package):
    bad = []
    for f in sorted((ROOT / package).rglob("*.py")):
        wrong = imported_packages(f) & FORBIDDEN[package]
        if wrong:
            bad.append(f"{f.relative_to(ROOT)} imports {sorted(wrong)}")
    assert not bad, "layering broken:\n" + "\n".join(bad)


def test_sim_uses_only_the_engines_bus_clock_and_errors():
    allowed = {"bt_engine", "bt_engine.bus", "bt_engine.clock", "bt_engine.errors", "bt_engine.yaml_hints"}
    bad = []
    for f in sorted((ROOT / "sim").rglob("*.py")):
        for node in ast.walk(ast.parse(f.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("bt_engine"):
                mod = node.module
                if not any(mod == a or mod.startswith(a + ".") for a in allowed - {"bt_engine"}) \
                        and mod != "bt_engine":
                    bad.append(f"{f.relative_to(ROOT)}: {mod}")
    assert not bad, bad


def test_categories_use_only_the_engines_errors_and_file_imports():
    bad = []
    for f in sorted((ROOT / "categories").rglob("*.py")):
        for node in ast.walk(ast.parse(f.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("bt_engine") \
                    and node.module not in ("bt_engine.errors", "bt_engine.modules"):
                bad.append(f"{f.relative_to(ROOT)}: {node.module}")
    assert not bad, bad


def test_public_names_exist():
    import bt_engine
    for name in bt_engine.__all__:
        assert hasattr(bt_engine, name), name


# -- inside bt_engine ---------------------------------------------------------------------
def module_name(path: pathlib.Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def engine_imports(path: pathlib.Path, modules: set[str]) -> set[str]:
    """The bt_engine modules ``path`` imports (``from a import b`` names module ``a.b``
    when it is one, else ``a``)."""
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    package = parts[:-1]  # a package's __init__ and its modules resolve alike
    found = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = package[:len(package) - node.level + 1] if node.level else []
            mod = ".".join(base + ([node.module] if node.module else []))
            names = [f"{mod}.{a.name}" if f"{mod}.{a.name}" in modules else mod for a in node.names]
        else:
            continue
        found |= {n for n in names if n.startswith("bt_engine")}
    return found


def engine_graph() -> dict[str, set[str]]:
    files = {module_name(f): f for f in ENGINE.rglob("*.py")}
    modules = set(files)
    return {m: {n for n in engine_imports(f, modules) if n != m and n in modules}
            for m, f in files.items()}


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))
    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def test_no_import_cycle_inside_the_engine():
    assert cycles(engine_graph()) == []


def test_the_cycle_finder_finds_a_cycle():
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


#: which parts of the engine a part may not import (the core is the top-level modules)
ENGINE_FORBIDDEN = {
    "bt_engine.bus": ("bt_engine.ros", "bt_engine.trees", "bt_engine.cli", "bt_engine.runtime",
                      "bt_engine.subsystem", "bt_engine.default"),
    "core": ("bt_engine.ros", "bt_engine.trees", "bt_engine.cli"),
    "bt_engine.trees": ("bt_engine.ros", "bt_engine.cli", "bt_engine.default"),
    "bt_engine.ros": ("bt_engine.cli", "bt_engine.default"),
}


def part_of(module: str) -> str:
    parts = module.split(".")
    if len(parts) > 2 or (module + ".__init__").replace(".", "/") + ".py" in _package_inits():
        return ".".join(parts[:2])
    return "core" if module != "bt_engine" else "bt_engine"


def _package_inits() -> set[str]:
    return {str(f.relative_to(ROOT)) for f in ENGINE.rglob("__init__.py")}


def test_engine_parts_import_only_downwards():
    bad = []
    for module, deps in engine_graph().items():
        forbidden = ENGINE_FORBIDDEN.get(part_of(module), ())
        bad += [f"{module} imports {d}" for d in sorted(deps)
                if any(d == f or d.startswith(f + ".") for f in forbidden)]
    assert not bad, "layering broken:\n" + "\n".join(bad)
