"""What a category's strategy supplies: how to approach an object and how to grasp it.

The arm of the reference robot reaches the floor only in a narrow band in front of the
base, so every strategy here grasps the same way: the base stops at a standoff facing the
object, the arm extends the open gripper to the grasp pose, and the base drives the
fingers around the object before they close. What differs per category is the numbers:
the standoff, which part is held (height, tool pitch), the opening, the lift, and what a
successful grasp looks like.
"""
from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Approach:
    """How the base approaches an object.

    Attributes:
        reach: distance from base_footprint to the object's axis when grasping [m].
        standoff: extra distance kept before the final straight approach [m]; the arm
            unfolds there, clear of the object.
        max_bearing: largest bearing error accepted before the final approach [rad]; the
            base turns until the object is this close to straight ahead.
        look_distance: where the base stops to take a closer look first [m], or 0.
    """

    reach: float = 0.27
    standoff: float = 0.12
    max_bearing: float = math.radians(0.6)
    look_distance: float = 0.75


@dataclass(frozen=True)
class Grasp:
    """How the gripper holds an object.

    Attributes:
        height: height of the held part above the floor [m] ("which part to hold").
        pitch: tool angle below the horizontal [rad] while grasping.
        open_width: finger opening before closing [m].
        closed_min, closed_max: finger opening that means "holding it" [m]; less is a
            miss (the fingers closed on nothing), more is a jam.
        lift: how far to lift after closing [m].
    """

    height: float
    pitch: float = 0.0
    open_width: float = 0.085
    closed_min: float = 0.050
    closed_max: float = 0.080
    lift: float = 0.12


@dataclass(frozen=True)
class Strategy:
    """A category's approach and grasp."""

    category: str
    approach: Approach
    grasp: Grasp
    description: str = ""

    def standoff_poses(self, robot_xy: tuple[float, float], obj_xy: tuple[float, float],
                       extra: float = 0.0) -> list[tuple[float, float, float]]:
        """Where the base may stop, facing the object (x, y, yaw), best first: straight
        from the robot's side, then turning around the object in 30 degree steps."""
        (rx, ry), (ox, oy) = robot_xy, obj_xy
        direct = math.atan2(oy - ry, ox - rx)
        d = self.approach.reach + self.approach.standoff + extra
        poses = []
        for k in (0, 1, -1, 2, -2, 3, -3, 4, -4, 5, -5, 6):
            h = direct + k * math.radians(30)
            h = math.atan2(math.sin(h), math.cos(h))
            poses.append((ox - d * math.cos(h), oy - d * math.sin(h), h))
        return poses

    def holding(self, closed_width: float) -> bool:
        """True when the fingers stopped at a width that means the object is held."""
        return self.grasp.closed_min <= closed_width <= self.grasp.closed_max
