"""Importing a Python file by its path, once: what ``imports`` in actorbt.yaml and a
category file loaded by path both need."""

from __future__ import annotations

import hashlib
import importlib.util
import pathlib
import sys
from types import ModuleType


def import_file(path: str | pathlib.Path) -> ModuleType:
    """The module of the .py file at ``path``, imported on the first call; later calls with
    the same file return it without running it again. An error in the file propagates and
    leaves no half-imported module behind."""
    path = pathlib.Path(path).expanduser().resolve()
    name = f"_actorbt_file_{path.stem}_{hashlib.sha1(str(path).encode()).hexdigest()[:10]}"
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, path)
    if spec is None or spec.loader is None:
        raise ImportError(f"{path} is not an importable Python file")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    try:
        spec.loader.exec_module(module)
    except BaseException:
        del sys.modules[name]
        raise
    return module


def is_file_reference(ref: str) -> bool:
    """Does ``ref`` name a file (``my_robot/juice.py``) rather than a module (``my_robot.juice``)?"""
    return ref.endswith(".py") or "/" in ref or "\\" in ref
