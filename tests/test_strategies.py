"""Strategies as the robot reads them from the category files."""

from __future__ import annotations

import math

import pytest

from actors.strategies import UnknownCategoryError, known_categories, strategy_for
from categories import Box, Category, Grasp
from planning import ArmKinematics


def test_the_built_in_categories_have_strategies():
    assert {"can", "bottle", "carton"} <= set(known_categories())
    assert strategy_for("can").grasp.height == pytest.approx(0.061)  # middle of a 122 mm can
    assert strategy_for("bottle").grasp.height < 0.1  # low on the body


def test_unknown_category_lists_the_known_ones():
    with pytest.raises(UnknownCategoryError) as e:
        strategy_for("cna")
    assert "did you mean can" in str(e.value) and "bottle" in str(e.value)


@pytest.mark.parametrize("category", ["can", "bottle", "carton"])
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
        assert math.atan2(-py, 2.0 - px) == pytest.approx(pyaw)  # each faces the object


def test_holding_is_judged_by_the_finger_opening():
    s = strategy_for("can")
    assert s.holding(0.065)
    assert not s.holding(0.0)  # closed on nothing
    assert not s.holding(0.085)  # still open


def test_a_box_is_approached_square_to_its_faces_narrow_side_first():
    s = strategy_for("carton")
    yaw = math.radians(20)
    poses = s.standoff_poses((0.0, 0.0), (2.0, 0.0), object_yaw=yaw)
    assert len(poses) == 4
    rel = [math.degrees(math.remainder(p[2] - yaw, 2 * math.pi)) for p in poses]
    assert rel[0] == pytest.approx(0.0, abs=1e-6)  # along x: the fingers close on 45 mm
    assert abs(rel[1]) == pytest.approx(180.0)  # the far face of the same side next
    assert sorted(abs(r) for r in rel[2:]) == pytest.approx([90.0, 90.0])
    # without a measured yaw it is approached like a round object
    assert len(s.standoff_poses((0.0, 0.0), (2.0, 0.0))) == 12


@pytest.mark.parametrize("category", ["can", "bottle"])
def test_a_lying_body_is_held_from_above_within_the_arms_reach(category):
    s = strategy_for(category)
    plan = s.plan_for("lying")
    assert plan.pitch == pytest.approx(math.pi / 2)
    assert plan.closed_min < 2 * 0.034 < plan.closed_max  # across the body
    kin = ArmKinematics.from_urdf()
    for z in (plan.height, plan.height + plan.lift):
        assert kin.ik(plan.reach, 0.0, z, plan.pitch).ok, f"{category}: z={z} unreachable"
    # the base faces along the axis: the fingers close across the body; a bottle only
    # from its base end (object_yaw: base to top), nearly square to it
    poses = s.standoff_poses((0.0, 0.0), (2.0, 0.0), object_yaw=math.radians(40), plan=plan)
    headings = sorted(round(math.degrees(p[2])) for p in poses)
    assert headings == ([32, 40, 48] if category == "bottle" else [-140, 40])


def test_a_lying_box_is_held_from_above_across_the_face_it_shows():
    s = strategy_for("carton")  # 70 x 45 x 120 mm
    assert s.plan_for("upright").sides == (0.0, math.pi / 2)
    kin = ArmKinematics.from_urdf()
    for width, height in ((0.070, 0.045), (0.045, 0.070)):  # lying on either long face
        plan = s.plan_for("lying", width)
        assert plan.closed_min < width < plan.closed_max
        assert plan.pitch == pytest.approx(math.pi / 2) and plan.sides == (0.0,)
        assert height / 2 < plan.height < height  # the pads span its upper half
        for z in (plan.height, plan.height + plan.lift):
            assert kin.ik(plan.reach, 0.0, z, plan.pitch).ok


def test_a_box_lying_on_a_face_too_wide_for_the_hand_has_no_grasp():
    box = Category(
        name="crate",
        shape=Box(0.090, 0.050, 0.12),
        mass=0.05,
        rgba=(0.2, 0.3, 0.9, 1),
        grasp=Grasp(height=0.06, open_width=0.085, closed_min=0.04, closed_max=0.06),
    )
    assert box.strategy.plan_for("lying", 0.090) is None  # 90 mm across: too wide
    assert box.strategy.plan_for("lying", 0.050).closed_min < 0.050


def test_a_lying_bottle_is_approached_from_its_base_end_and_a_can_from_either():
    assert strategy_for("bottle").plan_for("lying").one_way  # the neck end is long
    assert not strategy_for("can").plan_for("lying").one_way


def test_a_leaning_box_is_held_across_the_side_measured_across_its_lean():
    carton = strategy_for("carton")
    upright = carton.plan_for("upright")
    narrow = carton.plan_for("tilted", 0.045)  # its 45 mm side across: as upright
    assert (narrow.closed_min, narrow.closed_max) == (upright.closed_min, upright.closed_max)
    assert narrow.sides == (0.0,) and narrow.one_way
    wide = carton.plan_for("tilted", 0.070)  # its 70 mm side across (house_hard 2015)
    assert wide.holding(0.073) and wide.holding(0.070) and not wide.holding(0.045)
    assert wide.closed_max < wide.open_width
    # a round body keeps its own grip whatever width is passed
    can = strategy_for("can")
    assert can.plan_for("tilted", 0.05).closed_min == can.plan_for("upright").closed_min


def test_an_upright_box_is_held_across_either_side_that_fits_the_hand():
    upright = strategy_for("carton").plan_for("upright")
    narrow, wide = upright.side_plans()
    assert narrow == upright  # the range as declared: 45 mm
    assert narrow.holding(0.045) and not narrow.holding(0.072)
    assert wide.holding(0.072) and wide.holding(0.078) and not wide.holding(0.045)
    assert wide.closed_max < wide.open_width
    # a round body has one grip; so has a box lying or leaning (its plan names the side)
    assert strategy_for("can").plan_for("upright").side_plans() == (strategy_for("can").plan_for("upright"),)
    assert len(strategy_for("carton").plan_for("tilted", 0.045).side_plans()) == 1
