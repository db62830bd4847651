"""The layering of ``bus`` and ``ros``, read from the source: ``bus`` knows nothing of
ROS, ``ros`` never imports the ``cli`` above it, and the modules of ``ros`` import
each other without a cycle. Every import counts: in functions and under
``TYPE_CHECKING`` too."""
from __future__ import annotations

import ast
import pathlib

ROOT = pathlib.Path(__file__).resolve().parents[1]
ENGINE = ROOT / "bt_engine"


def imports(path: pathlib.Path) -> set[str]:
    """Absolute names of every module ``path`` imports (``from a import b`` gives both
    ``a`` and ``a.b``; it may be a module)."""
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    package = parts[:-1]  # a package's __init__ and its modules resolve alike
    found = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            base = package[:len(package) - node.level + 1] if node.level else []
            mod = ".".join(base + ([node.module] if node.module else []))
            found.add(mod)
            found |= {f"{mod}.{a.name}" for a in node.names}
    return found


def test_bus_knows_nothing_of_ros():
    bad = {f"{f.name}: {name}" for f in (ENGINE / "bus").glob("*.py") for name in imports(f)
           if name.startswith(("bt_engine.ros", "rclpy"))}
    assert not bad, bad


def test_ros_does_not_import_the_cli():
    bad = {f"{f.name}: {name}" for f in (ENGINE / "ros").glob("*.py") for name in imports(f)
           if name.startswith("bt_engine.cli")}
    assert not bad, bad


def test_ros_modules_import_each_other_without_a_cycle():
    modules = {f"bt_engine.ros.{f.stem}": f for f in (ENGINE / "ros").glob("*.py")
               if f.stem != "__init__"}
    edges = {m: {n for n in imports(f) if n in modules and n != m} for m, f in modules.items()}
    done: set[str] = set()

    def visit(m: str, path: list[str]) -> None:
        assert m not in path, "import cycle: " + " -> ".join(path[path.index(m):] + [m])
        if m in done:
            return
        for n in sorted(edges[m]):
            visit(n, path + [m])
        done.add(m)
    for m in sorted(modules):
        visit(m, [])
