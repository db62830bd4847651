"""The referee's measure of a grasp: how far the held object tilts in the fingers.

After a pick, and at every later step of the carry (``verify_grasp``, ``carry_pose``,
the start of ``place``), the object nearest the hand is compared with the end effector:
its axis (a body's z: a can's or a bottle's axis, a box's height) against the gripper's
z axis, the axis it is held along whichever way the hand came. An object held as it was
grasped keeps 0 degrees; one that pivots about the fingers' line tilts. The episode keeps
the largest tilt seen while the object was held.

It also notes which object each pick went for: the category object nearest the pick's
target as the pick starts (the robot may stand 1.8 m from an object on a table).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from bt_engine.trees import TreeObserver
from sim import SimWorld

#: the end effector is at most this far from the held object's frame [m] (a bottle held
#: low on its body has its frame ~10 cm above the fingers)
HELD_DISTANCE = 0.15
#: the actors after which (or, for the place actors, before which) the grip is measured
AFTER = ("pick", "verify_grasp", "carry_pose")
BEFORE = ("place", "place_on")
HAND = "end_effector_link"
#: a pick's object is at most this far from its target (or the base) as the pick starts [m]
PICKED_DISTANCE = 0.8


def _axis_z(quat) -> np.ndarray:
    x, y, z, w = quat
    return np.array([2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)])


def held_tilt(sim: SimWorld) -> float | None:
    """Tilt [deg] of the object nearest the hand relative to the gripper's z axis, or None
    when no object is within HELD_DISTANCE. Reads the simulator's truth."""
    hand_pos, hand_quat = sim.link_pose(HAND)
    best = None
    for pose in sim.object_poses().values():
        d = math.dist(pose[:3], hand_pos)
        if d <= HELD_DISTANCE and (best is None or d < best[0]):
            best = (d, pose[3:])
    if best is None:
        return None
    c = abs(float(np.dot(_axis_z(best[1]), _axis_z(hand_quat))))  # either way up
    return math.degrees(math.acos(min(1.0, c)))


class GraspProbe(TreeObserver):
    """Keeps ``worst``: the largest held-object tilt [deg] seen in an episode (NaN: never
    held), and ``picked``: the objects the picks went for, in order (see
    :func:`nearest_object`)."""

    def __init__(self, sim: SimWorld, categories: tuple[str, ...] = ()) -> None:
        self.sim = sim
        self.categories = categories
        self.worst = float("nan")
        self.samples: list[float] = []
        self.picked: list[str] = []

    def _sample(self) -> None:
        tilt = held_tilt(self.sim)
        if tilt is not None:
            self.samples.append(tilt)
            self.worst = max(self.samples)

    def actor_started(self, run: Any, leaf: Any, args: tuple, kwargs: dict, txn: Any) -> None:
        if leaf.node.actor in BEFORE:
            self._sample()
        if leaf.node.actor == "pick":
            target = kwargs.get("target", args[0] if args else None)
            at = (target["x"], target["y"]) if isinstance(target, dict) and "x" in target else None
            name = nearest_object(self.sim, self.categories, at)
            if name is not None:
                self.picked.append(name)

    def actor_finished(self, run: Any, leaf: Any, txn: Any) -> None:
        if leaf.node.actor in AFTER and txn.state.value != "failed":
            self._sample()


def nearest_object(
    sim: SimWorld, categories: tuple[str, ...] = (), at: tuple[float, float] | None = None
) -> str | None:
    """The object (of one of ``categories``; () any) nearest ``at`` (x, y) [m], the pick's
    target (default: base_footprint), within PICKED_DISTANCE, or None. Reads the
    simulator's truth."""
    x, y = at if at is not None else sim.robot_pose()[:2]
    best = None
    for name, pose in sim.object_poses().items():
        if categories and sim.object_category(name) not in categories:
            continue
        d = math.hypot(pose[0] - x, pose[1] - y)
        if d <= PICKED_DISTANCE and (best is None or d < best[0]):
            best = (d, name)
    return None if best is None else best[1]
