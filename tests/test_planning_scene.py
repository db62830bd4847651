"""planning.scene: the collision model (self, world, run-time and attached obstacles)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from planning import InvalidInputError, PlanningScene, SceneError

HOME = (0.0, -1.0, 0.3, 0.7)
FOLDED_INTO_BASE = (0.0, 1.2, 1.0, 1.0)


@pytest.fixture(scope="module")
def scene():
    s = PlanningScene()
    yield s
    s.close()


@pytest.fixture(autouse=True)
def _clean(scene):
    yield
    for name in scene.obstacles:
        if scene.obstacles[name].attached_to is not None:
            scene.detach(name)
    scene.clear()


def test_home_is_valid_and_self_collision_is_detected(scene):
    assert scene.is_valid(HOME)
    report = scene.check(FOLDED_INTO_BASE)
    assert not report.valid and report.within_limits
    names = {c.a for c in report.contacts} | {c.b for c in report.contacts}
    assert "base_link" in names and "link5" in names
    assert all(c.distance < 0 for c in report.contacts)


def test_adjacent_and_rigid_pairs_are_not_reported(scene):
    # At home the closed fingers touch each other and the arm rests on its base
    # plate; none of these pairs can change while the arm moves.
    assert scene.check(HOME).contacts == ()


def test_floor_and_joint_limits(scene):
    k = scene.kinematics
    low = k.ik(0.2, 0.0, -0.02, math.pi / 2).best  # tool 2 cm below the floor
    report = scene.check(low)
    assert not report.valid and any("floor" in (c.a, c.b) for c in report.contacts)
    outside = np.array(HOME)
    outside[1] = k.upper[1] + 0.1
    assert not scene.is_valid(outside)
    assert not scene.check(outside).within_limits


def test_obstacles_are_added_and_removed_by_name(scene):
    k = scene.kinematics
    q = k.ik(0.25, 0.0, 0.10, 0.0).best
    assert scene.is_valid(q)
    scene.add_box("table", (0.2, 0.3, 0.02), (0.3, 0.0, 0.10))
    report = scene.check(q)
    assert not report.valid and any("table" in (c.a, c.b) for c in report.contacts)
    scene.remove("table")
    assert scene.is_valid(q)
    scene.add_cylinder("can", 0.033, 0.12, (0.25, 0.0, 0.06))
    assert not scene.is_valid(q)
    scene.add_cylinder("can", 0.033, 0.12, (0.25, 0.3, 0.06))  # replaced, moved away
    assert scene.is_valid(q)
    assert set(scene.obstacles) == {"floor", "can"}
    scene.add_sphere("ball", 0.03, (0.25, 0.0, 0.10))
    assert not scene.is_valid(q)


def _finger_tip_x(k, q) -> float:
    """x of the finger tips [m] for a horizontal tool, from the URDF geometry."""
    import xml.etree.ElementTree as ET

    root = ET.parse(k.urdf.path).getroot()
    link = next(el for el in root.findall("link") if el.get("name") == "gripper_left_link")
    col = link.find("collision")
    cx = float(col.find("origin").get("xyz").split()[0])
    sx = float(col.find("geometry/box").get("size").split()[0])
    finger = k.urdf.joint("gripper_left_joint")
    wrist = k.urdf.joint("end_effector_joint")
    # end_effector_link and the finger joint both hang off link5 along its x axis
    return float(k.fk(q)[0, 3]) - wrist.xyz[0] + finger.xyz[0] + cx + sx / 2


def test_padding_keeps_a_margin(scene):
    k = scene.kinematics
    q = k.ik(0.25, 0.0, 0.15, 0.0).best
    finger_tip = _finger_tip_x(k, q)
    # a wall whose face is 5 mm beyond the finger tips: inside the 10 mm padding
    scene.add_box("wall", (0.02, 0.3, 0.3), (finger_tip + 0.005 + 0.01, 0.0, 0.15))
    assert not scene.is_valid(q)
    exact = PlanningScene(padding=0.0, acm_samples=0)
    try:
        exact.add(scene.obstacles["wall"])
        assert exact.is_valid(q)
    finally:
        exact.close()


def test_detach_leaves_the_object_where_it_is(scene):
    k = scene.kinematics
    grasp = k.ik(0.25, 0.0, 0.20, 0.0).best
    tip = k.fk(grasp)[:3, 3]
    scene.add_cylinder("can", 0.033, 0.12, tuple(tip))
    scene.attach("can", grasp)
    lifted = k.ik(0.2, 0.1, 0.25, 0.0).best
    assert scene.is_valid(lifted)
    moved = scene.detach("can")
    assert moved.attached_to is None
    new_tip = k.fk(lifted)[:3, 3]
    assert np.allclose(moved.position, new_tip, atol=1e-6)
    assert not scene.is_valid(lifted)  # now a world object inside the gripper


def test_attached_object_moves_with_the_gripper(scene):
    k = scene.kinematics
    grasp = k.ik(0.25, 0.0, 0.20, 0.0).best
    tip = k.fk(grasp)[:3, 3]
    scene.add_cylinder("bottle", 0.035, 0.20, tuple(tip))
    assert not scene.is_valid(grasp)  # as a world object it is in the gripper
    scene.attach("bottle", grasp)
    assert scene.obstacles["bottle"].attached_to == "end_effector_link"
    assert scene.is_valid(grasp)  # attached: the gripper may hold it
    # lowering the arm drives the held bottle into the floor
    low = k.ik(0.25, 0.0, 0.08, 0.0).best
    report = scene.check(low)
    assert any({c.a, c.b} == {"bottle", "floor"} for c in report.contacts)
    # and it hits a world obstacle that the bare gripper would pass
    top = tip[2] + 0.10  # top of the held bottle
    scene.add_box("shelf", (0.14, 0.3, 0.02), (0.25, 0.0, top + 0.01 + 0.005))  # 5 mm into the padding
    assert not scene.is_valid(grasp)
    scene.detach("bottle")
    scene.remove("bottle")
    assert scene.is_valid(grasp)  # without the bottle the gripper passes under the shelf


def test_scene_errors_name_the_choices(scene):
    with pytest.raises(SceneError, match="no obstacle 'nope'.*floor"):
        scene.remove("nope")
    with pytest.raises(SceneError, match="no settable joint"):
        scene.set_fixed_joint("joint1", 0.0)
    with pytest.raises(InvalidInputError):
        scene.add_box("bad", (0.1, -0.1, 0.1), (0, 0, 0))
    with pytest.raises(InvalidInputError):
        scene.add_box("bad", (0.1, 0.1), (0, 0, 0))
    with pytest.raises(SceneError, match="not attached"):
        scene.detach("floor")


def test_open_gripper_is_checked(scene):
    k = scene.kinematics
    q = k.ik(0.25, 0.0, 0.15, 0.0).best
    # a thin post beside the fingers: clear of closed fingers (outer faces at
    # y = +-1 cm), in the way of open ones (45 mm stroke)
    scene.add_box("post", (0.01, 0.01, 0.18), (_finger_tip_x(k, q) - 0.02, 0.045, 0.09))
    assert scene.is_valid(q)
    scene.set_fixed_joint("gripper_left_joint", 0.045)
    scene.set_fixed_joint("gripper_right_joint", 0.045)
    try:
        assert not scene.is_valid(q)
    finally:
        scene.set_fixed_joint("gripper_left_joint", 0.0)
        scene.set_fixed_joint("gripper_right_joint", 0.0)


def test_segment_check_samples_by_joint_and_cartesian_step(scene):
    a, b = np.array(HOME), np.array([1.0, -1.0, 0.3, 0.7])
    bound = scene.displacement_bound(a, b)
    assert 0.3 < bound < 0.6  # 1 rad of joint1 moves points at most ~0.46 m
    assert scene.segment_valid(a, b)
