"""The layering of DESIGN.md, read from the imports of every module."""
from __future__ import annotations

import ast
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
FORBIDDEN = {
    "bt_engine": {"actors", "planning", "sim"},
    "planning": {"bt_engine", "sim", "actors"},
    "actors": {"sim"},
    "sim": {"actors", "planning"},
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


def test_sim_uses_only_the_engines_bus_and_clock():
    allowed = {"bt_engine", "bt_engine.bus", "bt_engine.clock", "bt_engine.errors"}
    bad = []
    for f in sorted((ROOT / "sim").rglob("*.py")):
        for node in ast.walk(ast.parse(f.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("bt_engine"):
                mod = node.module
                if not any(mod == a or mod.startswith(a + ".") for a in allowed - {"bt_engine"}) \
                        and mod != "bt_engine":
                    bad.append(f"{f.relative_to(ROOT)}: {mod}")
    assert not bad, bad


def test_public_names_exist():
    import bt_engine
    for name in bt_engine.__all__:
        assert hasattr(bt_engine, name), name
