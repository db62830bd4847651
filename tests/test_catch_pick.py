"""The approach keeps off the object it goes for, and lines up with it again when it is
off the side the hand must come from (actors/catch_approach.py)."""

from __future__ import annotations

import math

import pybullet as p
import pytest

from actors.catch import STANDOFF_CLEARANCE, target_marks
from categories import get as category

from tests.conftest import place_robot
from tests.localised_rig import localised_rig

#: a bottle lying on the floor, as perception reports it: axis from base to top
LYING = {
    "category": "bottle",
    "x": 8.84,
    "y": 7.28,
    "z": 0.0,
    "pose": "lying",
    "width": 0.07,
    "yaw": -0.507,
    "axis_base": [8.754, 7.327, 0.035],
    "axis_dir": [0.874, -0.486, 0.0],
}


def test_a_lying_target_is_marked_along_its_axis_leaving_the_standoff_room():
    strategy = category("bottle").strategy
    plan = strategy.plan_for("lying", 0.07)
    yaw = math.atan2(-0.486, 0.874)
    standoff = strategy.standoff_poses((8.0, 7.0), (LYING["x"], LYING["y"]), 0.0, yaw, plan)[0]
    marks = target_marks(LYING, strategy.length, standoff[:2])
    assert len(marks) >= 5
    for m in marks:  # none leaves the base less than its room at the standoff
        assert math.dist((m["x"], m["y"]), standoff[:2]) - m["radius"] >= STANDOFF_CLEARANCE - 1e-9
    # the far end (the neck) is marked: a way round to the standoff keeps off the body
    top = (8.754 + 0.874 * 0.305, 7.327 - 0.486 * 0.305)
    assert min(math.dist((m["x"], m["y"]), top) for m in marks) < 0.03
    # from a look pose 0.75 m aside, all of it is marked
    look = (LYING["x"] - 0.75 * math.cos(yaw + 0.8), LYING["y"] - 0.75 * math.sin(yaw + 0.8))
    far = target_marks(LYING, strategy.length, look)
    assert len(far) > len(marks)
    upright = target_marks({"x": 1.0, "y": 2.0, "width": 0.066}, 0.122, (0.6, 2.0))
    assert upright == [{"x": 1.0, "y": 2.0, "radius": pytest.approx(0.053)}]


def test_how_far_off_its_side_the_hand_may_come():
    bottle = category("bottle").strategy
    lying = bottle.plan_for("lying", 0.07)
    assert math.degrees(lying.tolerance) == pytest.approx(9.0)
    assert lying.off_sides(0.3 + math.radians(5), 0.3) == pytest.approx(math.radians(5))
    # one way: from its base end only
    assert lying.off_sides(0.3 + math.pi, 0.3) == pytest.approx(math.pi)
    assert bottle.upright.tolerance == math.pi  # round: any side
    assert bottle.upright.off_sides(1.0, None) == 0.0
    carton = category("carton").strategy
    assert carton.upright.off_sides(math.pi + 0.1, 0.0) == pytest.approx(0.1)  # either face
    assert math.degrees(carton.upright.tolerance) == pytest.approx(15.0)


def _lay(sim, name, x, y, axis_yaw, radius):
    body = sim.scene.objects[name]
    dyn = p.getDynamicsInfo(body, -1, physicsClientId=sim.cid)
    pos, orn = p.multiplyTransforms(
        [x, y, radius + 1e-4], p.getQuaternionFromEuler([0, math.pi / 2, axis_yaw]), dyn[3], dyn[4]
    )
    p.resetBasePositionAndOrientation(body, pos, orn, physicsClientId=sim.cid)
    p.resetBaseVelocity(body, [0, 0, 0], [0, 0, 0], physicsClientId=sim.cid)


def test_the_way_to_a_lying_bottle_does_not_push_it_and_the_pick_holds_it():
    """house_hard seed 2000: a bottle lies near the north-east wall, its base end to the
    west; the robot first sees it from the south-west. Its look pose is east of the bottle
    and the grasp's standoff west of it (from its base end): the way round used to drive
    the base over the bottle (too low for the lidar), pushing it 11 cm across its axis,
    and the hand then came 20 degrees off it and landed on it (or closed on nothing)."""
    start = (8.442, 6.031, 1.222)
    state = {}

    def setup(sim):
        name = [n for n in sim.object_names() if sim.object_category(n) == "bottle"][-1]
        state["name"] = name

        sim._on_hub_call(lambda: _lay(sim, name, 8.887, 7.253, -0.507, 0.035))
        place_robot(sim, start)

    with localised_rig("house_hard", 2000, start, setup) as (rt, sim):
        was = sim.object_pose(state["name"])[:2]
        found = rt.call("get_found", category="bottle")
        assert found and found["pose"] == "lying"
        close = rt.call("approach_object", target=found)
        moved = math.dist(sim.object_pose(state["name"])[:2], was)
        assert moved < 0.03, f"the way to the standoff pushed the bottle {moved * 100:.0f} cm"
        held = rt.call("pick", target=close)
        assert held["category"] == "bottle" and 0.058 <= held["width"] <= 0.078
        assert sim.object_pose(state["name"])[2] > 0.1  # lifted
