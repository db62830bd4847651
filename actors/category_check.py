"""The object categories against this robot's arm: every grasp a category declares must be
within the reach of the arm's kinematics (planning.ArmKinematics, from the robot's URDF).

The rules are categories/check.py's; this side supplies what the plain library does not
know, the arm. The catch subsystem checks every registered category when the robot
starts, so a category that cannot work fails before the robot crosses the house.
"""

from __future__ import annotations

import functools

import categories
from categories import Category, CategoryError
from categories.check import category_problems
from planning import ArmKinematics


@functools.lru_cache(maxsize=1)
def _arm() -> ArmKinematics:
    return ArmKinematics.from_urdf()


def reachable(reach: float, z: float, pitch: float) -> bool:
    """Whether the hand gets to ``z`` [m] above the floor, ``reach`` [m] ahead of the
    base, its pitch ``pitch`` [rad] below the horizontal."""
    return _arm().ik(reach, 0.0, z, pitch).ok


def problems_of(category: Category) -> list[str]:
    """What stops ``category`` working on this robot, each with what to change."""
    return category_problems(category, reachable)


def check_registered() -> None:
    """Raises CategoryError naming each registered category that cannot work on this robot
    (where it is declared, and what to change); nothing when all can."""
    bad = []
    for cat in categories.all_categories():
        problems = problems_of(cat)
        if problems:
            where = categories.declared_at(cat.name) or "?"
            bad.append(f"{where}: category {cat.name!r} cannot work on this robot: {'; '.join(problems)}")
    if bad:
        raise CategoryError("\n".join(bad))
