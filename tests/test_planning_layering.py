"""planning is a plain library: it imports neither bt_engine, sim nor actors,
and every name it exports exists."""

from __future__ import annotations

import ast
import importlib
from pathlib import Path

import planning

FORBIDDEN = {"bt_engine", "sim", "actors"}
PACKAGE = Path(planning.__file__).resolve().parent


def _imported_roots(path: Path) -> set[str]:
    roots = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            roots |= {alias.name.split(".")[0] for alias in node.names}
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            roots.add(node.module.split(".")[0])
        elif isinstance(node, ast.Call) and getattr(node.func, "attr", getattr(node.func, "id", "")) in (
            "import_module",
            "__import__",
        ):
            roots.add("<dynamic import>")
    return roots


def test_planning_imports_nothing_from_the_layers_above():
    files = sorted(PACKAGE.glob("**/*.py"))
    assert files
    for path in files:
        bad = _imported_roots(path) & (FORBIDDEN | {"<dynamic import>"})
        assert not bad, f"{path.relative_to(PACKAGE.parent)} imports {sorted(bad)}"


def test_every_exported_name_exists():
    for name in planning.__all__:
        assert hasattr(planning, name), name
    for path in PACKAGE.glob("*.py"):
        if path.stem.startswith("_"):
            continue
        module = importlib.import_module(f"planning.{path.stem}")
        for name in getattr(module, "__all__", ()):
            assert hasattr(module, name), f"planning.{path.stem}.{name}"


def test_results_are_frozen_dataclasses():
    import dataclasses

    for cls in (
        planning.MotionPlan,
        planning.BasePath,
        planning.IKResult,
        planning.IKSolution,
        planning.ArmPose,
        planning.TimedTrajectory,
        planning.JointLimits,
        planning.CollisionReport,
        planning.Obstacle,
    ):
        assert dataclasses.is_dataclass(cls) and cls.__dataclass_params__.frozen, cls.__name__
    assert all(
        issubclass(e, planning.PlanningError)
        for e in (
            planning.ModelError,
            planning.InvalidInputError,
            planning.UnreachableError,
            planning.InvalidStateError,
            planning.NoPathError,
            planning.TrajectoryError,
            planning.SceneError,
        )
    )
