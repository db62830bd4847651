"""The public surface of bt_engine.trees: every exported name exists, and the layer
imports nothing above the engine."""

from __future__ import annotations

import ast
from pathlib import Path

import bt_engine.trees as trees

PACKAGE = Path(trees.__file__).parent


def test_every_exported_name_exists() -> None:
    missing = [name for name in trees.__all__ if not hasattr(trees, name)]
    assert missing == []
    assert len(set(trees.__all__)) == len(trees.__all__)


def test_the_tree_layer_imports_no_robot_code() -> None:
    for path in PACKAGE.glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0:
                names = [node.module or ""]
            else:
                continue
            for name in names:
                assert name.split(".")[0] not in ("actors", "planning", "sim"), f"{path.name} imports {name}"
