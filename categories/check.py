"""Can a category work on a robot? The rules, each problem with what to change.

The gripper's rules need nothing else: the stall window must bracket the width the
fingers close on at the grasp height, and the opening must fit the gripper; they are
checked when a category registers. The arm's rules need its kinematics, which this
plain library does not know: ``reachable(reach, z, pitch) -> bool`` is given by the
robot's side (actors/category_check.py, with planning's ArmKinematics), which checks
every registered category when the robot starts and in ``actorbt category check FILE``.
Every grasp the category declares is put to it: upright, its test lift and its full
lift at ``approach.reach``; lying, from above at ``top_grasp.reach``.
"""

from __future__ import annotations

import math
from typing import Callable

from .category import Category
from .strategy import CLOSED_BELOW_OPEN, GraspPlan

#: whether the hand gets to z [m] above the floor, reach [m] ahead of the base, its
#: pitch [rad] below the horizontal: ``reachable(reach, z, pitch)``
Reachable = Callable[[float, float, float], bool]

#: the first, short lift that checks the grip [m] (the pick does it: actors/catch.py)
TEST_LIFT = 0.02
#: the gripper's largest opening (OpenManipulator-X) [m]
GRIPPER_MAX_OPENING = 0.09
#: the heights scanned for the arm's reachable band [m]
_BAND = [i / 1000 for i in range(0, 601)]


def reach_band(reachable: Reachable, reach: float, pitch: float) -> tuple[float, float] | None:
    """(lowest, highest) z [m] the hand reaches at ``reach`` and ``pitch``, None if none."""
    ok = [z for z in _BAND if reachable(reach, z, pitch)]
    return (ok[0], ok[-1]) if ok else None


def _band_text(reachable: Reachable, reach: float, pitch: float) -> str:
    band = reach_band(reachable, reach, pitch)
    where = f"at reach {reach:.3f} m and pitch {math.degrees(pitch):.0f} deg"
    if band is None:
        return f"{where} the hand reaches no height"
    return f"{where} the hand reaches {band[0]:.3f}..{band[1]:.3f} m above the floor"


def _upright(category: Category, reachable: Reachable) -> list[str]:
    g, a = category.grasp, category.approach
    problems = []
    for what, z, fix in (
        ("grasp.height", g.height, "grasp.height or approach.reach"),
        ("the test lift (grasp.height + 0.02)", g.height + TEST_LIFT, "grasp.height"),
        ("the lift (grasp.height + grasp.lift)", g.height + g.lift, "grasp.lift"),
    ):
        if not reachable(a.reach, z, g.pitch):
            problems.append(
                f"{what} {z:.3f} m is out of the arm's reach: {_band_text(reachable, a.reach, g.pitch)}; change {fix}"
            )
    return problems


def _window(category: Category) -> list[str]:
    g = category.grasp
    # the window is filled in by Category.__post_init__ when the description leaves it out
    assert g.closed_min is not None and g.closed_max is not None
    problems = []
    if g.open_width > GRIPPER_MAX_OPENING:
        problems.append(
            f"grasp.open_width {g.open_width * 1000:.0f} mm is wider than the gripper opens "
            f"({GRIPPER_MAX_OPENING * 1000:.0f} mm)"
        )
    if g.closed_max > g.open_width - CLOSED_BELOW_OPEN + 1e-9:
        problems.append(
            f"grasp.closed_max {g.closed_max * 1000:.0f} mm reaches the opening "
            f"({g.open_width * 1000:.0f} mm): a jammed hand would count as holding"
        )
    # a box's other side has the window moved by its width (GraspPlan.side_plans)
    w = category.held_width()
    if not g.closed_min <= w <= g.closed_max:
        problems.append(
            f"at grasp.height {g.height:.3f} m the fingers close on {w * 1000:.0f} mm, outside "
            f"closed_min..closed_max {g.closed_min * 1000:.0f}..{g.closed_max * 1000:.0f} mm; "
            "leave both out to have them derived from the shape"
        )
    return problems


def _lying(category: Category, reachable: Reachable) -> list[str]:
    problems = []
    t = category.top_grasp
    for plan in category.lying_plans():
        for what, z in (("lying, the grasp", plan.height), ("lying, the lift", plan.height + plan.lift)):
            if not reachable(plan.reach, z, plan.pitch):
                problems.append(
                    f"{what} at {z:.3f} m is out of the arm's reach: "
                    f"{_band_text(reachable, plan.reach, plan.pitch)}; change top_grasp (reach "
                    f"{t.reach:.3f} m, above_axis {t.above_axis:.3f} m, lift {t.lift:.3f} m)"
                )
    return problems


def gripper_problems(category: Category) -> list[str]:
    """What stops ``category`` fitting the gripper, each with what to change; empty: it fits."""
    return _window(category)


def category_problems(category: Category, reachable: Reachable) -> list[str]:
    """What stops ``category`` working on a robot whose arm reaches what ``reachable``
    says, each with what to change; empty: it can."""
    return _upright(category, reachable) + _window(category) + _lying(category, reachable)


def plan_text(plan: GraspPlan) -> str:
    return (
        f"reach {plan.reach:.3f} m, height {plan.height:.3f} m, pitch {math.degrees(plan.pitch):.0f} deg, "
        f"held at {plan.closed_min * 1000:.0f}..{plan.closed_max * 1000:.0f} mm"
    )
