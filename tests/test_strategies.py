"""The per-category strategy registry."""
from __future__ import annotations

import math

import pytest

from actors.strategies import (Approach, Grasp, Strategy, UnknownCategoryError, categories,
                               register_strategy, strategy_for)
from bt_engine import ActorbtError
from planning import ArmKinematics


def test_can_and_bottle_are_registered():
    assert {"can", "bottle"} <= set(categories())
    assert strategy_for("can").grasp.height == pytest.approx(0.061)  # middle of a 122 mm can
    assert strategy_for("bottle").grasp.height < 0.1                 # low on the body


def test_unknown_category_lists_the_known_ones():
    with pytest.raises(UnknownCategoryError) as e:
        strategy_for("cna")
    assert "did you mean can" in str(e.value) and "bottle" in str(e.value)


@pytest.mark.parametrize("category", ["can", "bottle"])
def test_every_grasp_pose_is_reachable_by_the_arm(category):
    s = strategy_for(category)
    kin = ArmKinematics.from_urdf()
    g, a = s.grasp, s.approach
    for z in (g.height, g.height + g.lift):
        assert kin.ik(a.reach, 0.0, z, g.pitch).ok, f"{category}: z={z} unreachable"
    assert g.open_width <= 0.09  # the gripper's stroke


def test_standoff_poses_face_the_object_from_the_robot_first():
    s = strategy_for("can")
    poses = s.standoff_poses((0.0, 0.0), (2.0, 0.0))
    x, y, yaw = poses[0]
    assert (x, y, yaw) == pytest.approx((2.0 - s.approach.reach - s.approach.standoff, 0.0, 0.0))
    assert len({round(p[2], 6) for p in poses}) == len(poses) == 12  # every 30 degrees once
    for px, py, pyaw in poses:
        assert math.hypot(2.0 - px, -py) == pytest.approx(s.approach.reach + s.approach.standoff)
        assert math.atan2(-py, 2.0 - px) == pytest.approx(pyaw)     # each faces the object


def test_holding_is_judged_by_the_finger_opening():
    s = strategy_for("can")
    assert s.holding(0.065)
    assert not s.holding(0.0)     # closed on nothing
    assert not s.holding(0.085)   # still open


def test_registering_a_category_and_replacing_it(monkeypatch):
    import actors.strategies as registry
    monkeypatch.setattr(registry, "_REGISTRY", dict(registry._REGISTRY))  # leave no trace
    mug = Strategy("mug_test", Approach(), Grasp(height=0.05, open_width=0.088))
    register_strategy(mug)
    assert strategy_for("mug_test") is mug
    with pytest.raises(ActorbtError):
        register_strategy(mug)
    register_strategy(mug, replace=True)
