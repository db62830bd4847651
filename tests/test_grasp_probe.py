"""The referee's grasp measure (demo/grasp_probe.py): the held object's tilt in the hand."""

from __future__ import annotations

import math

import pybullet as p
import pytest

import sim as sim_mod
from bt_engine import Runtime
from demo.grasp_probe import HAND, held_tilt, nearest_object


@pytest.fixture(scope="module")
def world():
    rt = Runtime()
    w = sim_mod.SimWorld(rt, world="open_floor", seed=0, camera=False)
    yield w
    rt.run_on_hub(w.close)
    rt.close()


def _put_in_hand(world, name: str, tilt_deg: float) -> None:
    """The object's frame at the hand, its axis tilted about the hand's y axis."""

    def put():
        pos, quat = world.robot.link_pose(HAND)
        tilt = p.getQuaternionFromEuler([0.0, math.radians(tilt_deg), 0.0])
        _, orn = p.multiplyTransforms([0, 0, 0], quat, [0, 0, 0], tilt)
        p.resetBasePositionAndOrientation(world.scene.objects[name], pos, orn, physicsClientId=world.cid)

    world.runtime.run_on_hub(put)


@pytest.mark.parametrize("tilt", [0.0, 7.0, 20.0])
def test_the_tilt_is_measured_against_the_hand(world, tilt):
    can = next(n for n in world.object_names() if world.object_category(n) == "can")
    _put_in_hand(world, can, tilt)
    assert held_tilt(world) == pytest.approx(tilt, abs=0.05)
    _put_in_hand(world, can, 180.0 - tilt)  # upside down is held the same way
    assert held_tilt(world) == pytest.approx(tilt, abs=0.05)


def test_nothing_near_the_hand_is_none(world):
    for i, name in enumerate(world.object_names()):
        world.set_object_pose(name, 2.5, -2.5 + 0.3 * i)
    assert held_tilt(world) is None


def test_the_picked_object_is_the_category_object_nearest_the_base(world):
    x, y, _ = world.robot_pose()
    names = world.object_names()
    for i, name in enumerate(names):
        world.set_object_pose(name, 2.5, -2.5 + 0.3 * i)
    assert nearest_object(world) is None  # nothing within reach
    can = next(n for n in names if world.object_category(n) == "can")
    other = next(n for n in names if world.object_category(n) != "can")
    world.set_object_pose(can, x + 0.6, y)
    world.set_object_pose(other, x + 0.4, y)
    assert nearest_object(world) == other
    assert nearest_object(world, ("can",)) == can
    assert nearest_object(world, at=(x + 0.62, y)) == can  # nearest the pick's target
