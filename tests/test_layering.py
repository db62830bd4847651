"""The layering of docs/architecture.md ("The layers"), read from the imports of every module.

Every import counts: absolute and relative, at module level, inside functions and under
``if TYPE_CHECKING:``. Four rules hold for every package of the repository:

- it imports only the packages its row of the table allows (the table lists them all);
- no import cycle between its modules, nor between its sub-packages taken as wholes;
- no module imports a private module (a ``_name``) of a package it is not part of;
- inside ``bt_engine`` the parts import only downwards (ENGINE_FORBIDDEN).
"""

from __future__ import annotations

import ast
import functools
import pathlib
import re

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
ENGINE = ROOT / "bt_engine"

#: the "may import" column of docs/architecture.md's table: the repository's packages each
#: package may import (any other one is forbidden)
MAY_IMPORT = {
    "common": set(),
    "bt_engine": set(),
    "bt_tools": {"bt_engine"},
    "bt_xml": {"bt_engine", "bt_tools"},
    "bt_ros": {"bt_engine", "bt_tools"},
    "bt_cli": {"bt_engine", "bt_tools", "bt_ros"},
    "bt_mcp": {"bt_engine", "bt_tools", "bt_cli"},
    "planning": {"common"},
    "categories": {"bt_engine"},
    "actors": {"bt_engine", "bt_ros", "planning", "categories"},
    "navstack": {"bt_engine", "planning", "common"},
    "sim": {"bt_engine", "categories", "common"},
}
MAY_IMPORT["demo"] = set(MAY_IMPORT)  # the reference application: everything; imported by nothing
FORBIDDEN = {package: set(MAY_IMPORT) - allowed - {package} for package, allowed in MAY_IMPORT.items()}


def packages() -> list[str]:
    """The repository's top-level packages (a folder with an ``__init__.py``)."""
    return sorted(p.parent.name for p in ROOT.glob("*/__init__.py"))


def imported_packages(path: pathlib.Path) -> set[str]:
    tree = ast.parse(path.read_text(), str(path))
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found |= {a.name.split(".")[0] for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            found.add(node.module.split(".")[0])
    return found


def test_no_circle_between_packages():
    """The table itself goes downwards, so the packages' imports cannot close a circle."""
    assert cycles({p: set(deps) for p, deps in MAY_IMPORT.items()}) == []


def test_the_engine_imports_no_front_end():
    assert not MAY_IMPORT["bt_engine"] & {"bt_tools", "bt_xml", "bt_ros", "bt_cli", "bt_mcp"}


def test_every_package_has_a_row():
    assert packages() == sorted(MAY_IMPORT)


def documented_layers() -> dict[str, set[str]]:
    """docs/architecture.md's table: package -> the packages its "may import" cell names."""
    text = (ROOT / "docs" / "architecture.md").read_text()
    table = text.split("## The layers", 1)[1].split("\n## ", 1)[0]
    rows = {}
    for line in table.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        match = re.fullmatch(r"`(\w+)`", cells[0]) if len(cells) == 3 else None
        if match:
            named = {n.split(".")[0] for n in re.findall(r"`([\w.]+)`", cells[2])}
            rows[match.group(1)] = set(MAY_IMPORT) if cells[2].startswith("everything") else named
    return rows


def test_the_documented_table_is_the_one_enforced():
    documented = documented_layers()
    assert sorted(documented) == sorted(MAY_IMPORT)
    assert {p: documented[p] - {p} for p in documented} == MAY_IMPORT


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
                if not any(mod == a or mod.startswith(a + ".") for a in allowed - {"bt_engine"}) and mod != "bt_engine":
                    bad.append(f"{f.relative_to(ROOT)}: {mod}")
    assert not bad, bad


def test_categories_use_only_the_engines_errors_and_file_imports():
    bad = []
    for f in sorted((ROOT / "categories").rglob("*.py")):
        for node in ast.walk(ast.parse(f.read_text())):
            if (
                isinstance(node, ast.ImportFrom)
                and node.module
                and node.module.startswith("bt_engine")
                and node.module not in ("bt_engine.errors", "bt_engine.modules")
            ):
                bad.append(f"{f.relative_to(ROOT)}: {node.module}")
    assert not bad, bad


def test_public_names_exist():
    import bt_engine

    for name in bt_engine.__all__:
        assert hasattr(bt_engine, name), name


# -- the module graph -----------------------------------------------------------------------
def module_name(path: pathlib.Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def module_imports(path: pathlib.Path, modules: set[str]) -> set[str]:
    """The repository's modules ``path`` imports: each imported name as the module that
    holds it (``from a import b`` names module ``a.b`` when it is one, else ``a``;
    ``from a.b import C`` names ``a.b``)."""
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    package = parts[:-1]  # a package's __init__ and its modules resolve alike
    found = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = package[: len(package) - node.level + 1] if node.level else []
            mod = ".".join(base + ([node.module] if node.module else []))
            names = [f"{mod}.{a.name}" if f"{mod}.{a.name}" in modules else mod for a in node.names]
        else:
            continue
        for name in names:
            while name and name not in modules:  # an attribute of a module: the module
                name = name.rpartition(".")[0]
            if name:
                found.add(name)
    return found


@functools.cache
def repo_graph() -> dict[str, frozenset[str]]:
    """Each module of the repository's packages -> the modules of the repository it imports."""
    files = {module_name(f): f for p in packages() for f in (ROOT / p).rglob("*.py")}
    modules = set(files)
    return {m: frozenset(n for n in module_imports(f, modules) if n != m) for m, f in files.items()}


def module_graph(package: str) -> dict[str, set[str]]:
    """Each module of ``package`` -> the modules of the repository it imports."""
    return {m: set(deps) for m, deps in repo_graph().items() if m.split(".")[0] == package}


def engine_graph() -> dict[str, set[str]]:
    graph = module_graph("bt_engine")
    return {m: {n for n in deps if n.startswith("bt_engine")} for m, deps in graph.items()}


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


def within(graph: dict[str, set[str]], package: str) -> dict[str, set[str]]:
    """The edges of ``graph`` between modules of ``package``."""
    return {m: {n for n in deps if n.split(".")[0] == package} for m, deps in graph.items()}


def sub_packages_as_wholes(graph: dict[str, set[str]]) -> dict[str, set[str]]:
    """``graph`` with each sub-package (``bt_engine.trees``, ``sim.models``...) as one node;
    the package's own top-level modules stay nodes of their own."""
    inits = {module_name(f) for f in ROOT.glob("*/*/__init__.py")}

    def node(module: str) -> str:
        two = ".".join(module.split(".")[:2])
        return two if two in inits else module

    wholes: dict[str, set[str]] = {}
    for m, deps in graph.items():
        wholes.setdefault(node(m), set()).update(node(n) for n in deps)
    return {m: deps - {m} for m, deps in wholes.items()}


@pytest.mark.parametrize("package", sorted(MAY_IMPORT))
def test_no_import_cycle_inside_a_package(package):
    assert cycles(within(module_graph(package), package)) == []


@pytest.mark.parametrize("package", sorted(MAY_IMPORT))
def test_no_import_cycle_between_sub_packages(package):
    """A circle such as trees <-> btxml passes module by module, yet neither package can
    be taken without the other."""
    assert cycles(sub_packages_as_wholes(within(module_graph(package), package))) == []


def test_the_cycle_finder_finds_a_cycle():
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_sub_packages_as_wholes_show_a_circle_between_packages():
    graph = {
        "bt_engine.trees._run": {"bt_engine.bus.messages"},
        "bt_engine.bus.messages": {"bt_engine.trees._model"},
        "bt_engine.trees._model": set(),
    }
    assert cycles(within(graph, "bt_engine")) == []
    assert cycles(sub_packages_as_wholes(graph)) == [["bt_engine.bus", "bt_engine.trees"]]


# -- private modules ----------------------------------------------------------------------
def private_owner(module: str) -> str | None:
    """The package a private module belongs to (the folder holding its first ``_name``
    part; ``__init__`` and ``__main__`` are not private), or None for a public module."""
    parts = module.split(".")
    for i, part in enumerate(parts):
        if part.startswith("_") and not part.startswith("__"):
            return ".".join(parts[:i])
    return None


def test_private_owner():
    assert private_owner("bt_engine.trees._model") == "bt_engine.trees"
    assert private_owner("sim._pybullet") == "sim"
    assert private_owner("bt_engine.trees.__main__") is None
    assert private_owner("bt_xml.cli") is None


@pytest.mark.parametrize("package", sorted(MAY_IMPORT))
def test_no_private_module_of_another_package(package):
    """What another package needs is public: exported by the package's ``__init__`` (or a
    public module of it). ``bt_engine``'s sub-packages are packages of their own here."""
    bad = []
    for module, deps in sorted(module_graph(package).items()):
        for dep in sorted(deps):
            owner = private_owner(dep)
            if owner is not None and not (module == owner or module.startswith(owner + ".")):
                bad.append(f"{module} imports {dep}")
    assert not bad, "private modules used from outside their package:\n" + "\n".join(bad)


# -- inside bt_engine ---------------------------------------------------------------------
#: which parts of the engine a part may not import (the core is the top-level modules)
FRONT_ENDS = ("bt_ros", "bt_cli", "bt_xml", "bt_mcp")
ENGINE_FORBIDDEN = {
    "bt_engine.bus": FRONT_ENDS + ("bt_engine.trees", "bt_engine.runtime", "bt_engine.subsystem", "bt_engine.default"),
    "core": FRONT_ENDS + ("bt_engine.trees",),
    "bt_engine.trees": FRONT_ENDS + ("bt_engine.default",),
    "bt_xml": ("bt_ros", "bt_cli", "bt_mcp", "bt_engine.default"),
    "bt_ros": ("bt_cli", "bt_xml", "bt_mcp", "bt_engine.default"),
    "bt_cli": ("bt_mcp",),
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
        bad += [
            f"{module} imports {d}" for d in sorted(deps) if any(d == f or d.startswith(f + ".") for f in forbidden)
        ]
    assert not bad, "layering broken:\n" + "\n".join(bad)
