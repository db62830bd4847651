"""Per-category strategies: a registry from category name to :class:`Strategy`.

Adding a category is one new :class:`Strategy` (approach and grasp numbers) registered
here or with :func:`register_strategy`; see docs/strategies.md.
"""
from __future__ import annotations

import difflib

from bt_engine import ActorbtError

from .base import Approach, Grasp, Strategy
from .bottle import BOTTLE
from .can import CAN

_REGISTRY: dict[str, Strategy] = {}


class UnknownCategoryError(ActorbtError, LookupError):
    """No strategy is registered for a category."""


def register_strategy(strategy: Strategy, replace: bool = False) -> None:
    """Make ``strategy`` the one used for its category."""
    if strategy.category in _REGISTRY and not replace:
        raise ActorbtError(f"a strategy for {strategy.category!r} exists; pass replace=True")
    _REGISTRY[strategy.category] = strategy


def strategy_for(category: str) -> Strategy:
    """The strategy of ``category``; the error lists the known ones."""
    try:
        return _REGISTRY[category]
    except KeyError:
        close = difflib.get_close_matches(str(category), list(_REGISTRY), n=3)
        hint = f" (did you mean {', '.join(close)}?)" if close else ""
        raise UnknownCategoryError(
            f"no strategy for category {category!r}{hint}; known: {', '.join(sorted(_REGISTRY))}"
        ) from None


def categories() -> list[str]:
    return sorted(_REGISTRY)


register_strategy(CAN)
register_strategy(BOTTLE)

__all__ = ["Approach", "Grasp", "Strategy", "UnknownCategoryError", "categories",
           "register_strategy", "strategy_for"]
