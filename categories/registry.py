"""The registry of categories: built-ins plus what a configuration or a program adds.

A category file declares ``CATEGORY = register(Category(...))``. ``load`` imports such a
file by path (``my_robot/juice.py``) or module (``my_robot.juice``); importing it registers it.
"""

from __future__ import annotations

import difflib
import importlib
import pathlib
import sys
import threading

from bt_engine.errors import ActorbtError
from bt_engine.modules import import_file, is_file_reference

from .category import Category

_REGISTRY: dict[str, Category] = {}
_WHERE: dict[str, str] = {}  # name -> "file:line" of its register() call
#: the categories that come with actorbt (categories/__init__.py loads them)
BUILT_IN = ("categories.can", "categories.bottle", "categories.carton")
_LOCK = threading.Lock()


class UnknownCategoryError(ActorbtError, LookupError):
    """No category of that name is registered."""


class CategoryError(ActorbtError):
    """A category could not be registered or loaded."""


def register(category: Category, replace: bool = False) -> Category:
    """Make ``category`` known by its name; returns it. Registering an equal declaration
    again is harmless; a different one under a taken name needs ``replace=True``.

    Raises:
        CategoryError: the category cannot fit the gripper (a stall window that misses
            the object, an opening wider than the gripper's: :mod:`categories.check`),
            named with the file and line of this call and what to change. The arm's reach
            is checked by the robot's side when it starts (actors/category_check.py).
    """
    if not isinstance(category, Category):
        raise CategoryError(f"register() takes a Category, got {type(category).__name__}")
    caller = sys._getframe(1)
    where = f"{caller.f_code.co_filename}:{caller.f_lineno}"
    from .check import gripper_problems

    problems = gripper_problems(category)
    if problems:
        raise CategoryError(f"{where}: category {category.name!r} cannot work: {'; '.join(problems)}")
    with _LOCK:
        old = _REGISTRY.get(category.name)
        if old is not None and old != category and not replace:
            raise CategoryError(
                f"a different category {category.name!r} is registered already; pick another name or pass replace=True"
            )
        _REGISTRY[category.name] = category
        _WHERE.setdefault(category.name, where)
    return category


def declared_at(name: str) -> str:
    """``file:line`` where category ``name`` was registered ("" if unknown)."""
    return _WHERE.get(name, "")


def unregister(name: str) -> None:
    with _LOCK:
        _REGISTRY.pop(name, None)
        _WHERE.pop(name, None)


def get(name: str) -> Category:
    """The category ``name``; the error lists close matches and the known ones."""
    try:
        return _REGISTRY[name]
    except (KeyError, TypeError):
        close = difflib.get_close_matches(str(name), list(_REGISTRY), n=3)
        hint = f" (did you mean {', '.join(close)}?)" if close else ""
        raise UnknownCategoryError(f"unknown category {name!r}{hint}; known: {', '.join(names())}") from None


def names() -> list[str]:
    return sorted(_REGISTRY)


def all_categories() -> list[Category]:
    return [_REGISTRY[n] for n in names()]


def load(ref: str | pathlib.Path, base: pathlib.Path | None = None) -> list[Category]:
    """Import a category file (``path/to/juice.py``, relative to ``base``) or module
    (``my_robot.juice``); returns the categories it registered."""
    before = dict(_REGISTRY)
    text = str(ref)
    if is_file_reference(text):
        path = pathlib.Path(text).expanduser()
        if not path.is_absolute() and base is not None:
            path = base / path
        if not path.is_file():
            raise CategoryError(f"category file {text!r} not found (looked at {path.resolve()})")
        try:
            import_file(path)
        except (ValueError, TypeError) as e:  # a Category's own checks: where it is declared
            raise CategoryError(f"{_where(e, path)}: {e}") from e
    else:
        try:
            importlib.import_module(text)
        except ImportError as e:
            raise CategoryError(f"cannot import category module {text!r}: {e}") from None
    return [c for n, c in _REGISTRY.items() if before.get(n) is not c]


def _where(exc: BaseException, path: pathlib.Path) -> str:
    """``file:line`` of the deepest frame of ``exc``'s traceback in ``path`` (else the file)."""
    where, tb = str(path), exc.__traceback__
    target = str(path.resolve())
    while tb is not None:
        if tb.tb_frame.f_code.co_filename == target:
            where = f"{path}:{tb.tb_lineno}"
        tb = tb.tb_next
    return where
