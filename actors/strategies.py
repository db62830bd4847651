"""Per-category strategies, read from the category files (``categories``): how the base
approaches an object and how the gripper holds it. A new category brings its own; see
docs/categories.md."""

from __future__ import annotations

import categories
from categories import Approach, Grasp, GraspPlan, Strategy, UnknownCategoryError


def strategy_for(category: str) -> Strategy:
    """The strategy of ``category``; the error lists close matches and the known ones."""
    return categories.get(category).strategy


def known_categories() -> list[str]:
    return categories.names()


__all__ = ["Approach", "Grasp", "GraspPlan", "Strategy", "UnknownCategoryError", "known_categories", "strategy_for"]
