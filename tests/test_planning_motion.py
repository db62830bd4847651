"""planning.motion: joint and pose planning (straight line, OMPL, simplification, re-check)."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

from planning import (
    FailureReason,
    InvalidStateError,
    NoPathError,
    PlanningScene,
    UnreachableError,
    plan_joint_motion,
    plan_pose_motion,
    seed_planners,
)

HOME = (0.0, -1.0, 0.3, 0.7)


@pytest.fixture(scope="module")
def scene():
    seed_planners(5)
    s = PlanningScene()
    yield s
    s.close()


@pytest.fixture(scope="module")
def exact():
    """The same robot without padding: what 'collision-free' means physically."""
    s = PlanningScene(padding=0.0, acm_samples=0)
    yield s
    s.close()


@pytest.fixture(autouse=True)
def _clean(scene, exact):
    yield
    scene.clear()
    exact.clear()


def _mirror(scene: PlanningScene, exact: PlanningScene) -> None:
    for ob in scene.obstacles.values():
        if ob.name != "floor":
            exact.add(ob)


def test_free_motion_takes_the_straight_line(scene):
    goal = scene.kinematics.ik(0.22, 0.1, 0.15, 0.6).best
    plan = plan_joint_motion(HOME, goal, scene)
    assert plan.ok, plan.message
    assert plan.planner == "straight"
    assert plan.path == (HOME, tuple(goal))
    assert plan.length == pytest.approx(float(np.linalg.norm(np.subtract(goal, HOME))))
    assert plan.length_raw == plan.length


def test_planning_around_an_obstacle(scene, exact):
    k = scene.kinematics
    start = k.ik(0.2, -0.15, 0.12, 0.6).best
    goal = k.ik(0.2, 0.15, 0.12, 0.6).best
    scene.add_box("wall", (0.04, 0.1, 0.22), (0.25, 0.0, 0.11))
    _mirror(scene, exact)
    assert scene.is_valid(start) and scene.is_valid(goal)
    assert not scene.segment_valid(start, goal), "the straight joint motion must collide"

    plan = plan_joint_motion(start, goal, scene, timeout=2.0)
    assert plan.ok, plan.message
    assert plan.planner == "RRTConnect"
    assert plan.failure is None and plan.message == ""
    assert np.allclose(plan.path[0], start) and np.allclose(plan.path[-1], goal)
    assert len(plan.path) >= 3
    assert 0 < plan.length <= plan.length_raw + 1e-9
    assert 0 < plan.planning_time < 2.0
    # dense re-check, finer than the planner's own: every 2.5 mrad and 2 mm of
    # travel of any robot point, against padded and real obstacles
    assert scene.path_valid(plan.path, 0.0025, max_step=0.002)
    assert exact.path_valid(plan.path, 0.0025, max_step=0.002)


@pytest.mark.parametrize("planner", ["RRT", "KPIECE1", "PRM"])
def test_other_ompl_planners(scene, planner):
    k = scene.kinematics
    start = k.ik(0.2, -0.15, 0.12, 0.6).best
    goal = k.ik(0.2, 0.15, 0.12, 0.6).best
    scene.add_box("wall", (0.04, 0.1, 0.22), (0.25, 0.0, 0.11))
    plan = plan_joint_motion(start, goal, scene, planner=planner, timeout=3.0)
    assert plan.ok, plan.message
    assert plan.planner == planner
    assert scene.path_valid(plan.path, 0.005)


def test_pose_motion_picks_a_collision_free_ik_solution(scene, exact):
    k = scene.kinematics
    scene.add_cylinder("bottle", 0.035, 0.25, (0.2, 0.0, 0.125))
    _mirror(scene, exact)
    pose = (0.2, 0.12, 0.10, 0.8)
    plan = plan_pose_motion(HOME, pose, scene, timeout=2.0)
    assert plan.ok, plan.message
    got = k.fk_pose(plan.goal)
    assert math.dist((got.x, got.y, got.z), pose[:3]) < 1e-3
    assert got.pitch == pytest.approx(pose[3], abs=1e-6)
    assert exact.path_valid(plan.path, 0.0025, max_step=0.002)


def test_unreachable_pose_fails_cleanly(scene):
    plan = plan_pose_motion(HOME, (0.9, 0.0, 0.2, 0.0), scene)
    assert not plan.ok and plan.path == ()
    assert plan.failure is FailureReason.UNREACHABLE
    assert "unreachable" in plan.message
    with pytest.raises(UnreachableError):
        plan.raise_for_failure()


def test_goal_in_collision_fails_cleanly(scene):
    scene.add_box("block", (0.1, 0.1, 0.1), (0.25, 0.0, 0.10))
    plan = plan_pose_motion(HOME, (0.25, 0.0, 0.10, 0.0), scene)
    assert plan.failure is FailureReason.GOAL_INVALID
    assert "block" in plan.message
    with pytest.raises(InvalidStateError):
        plan.raise_for_failure()


def test_start_in_collision_fails_cleanly(scene):
    plan = plan_joint_motion((0.0, 1.2, 1.0, 1.0), HOME, scene)
    assert plan.failure is FailureReason.START_INVALID
    assert "base_link" in plan.message


def test_start_a_hair_outside_the_limits_is_clipped(scene):
    k = scene.kinematics
    start = np.array(HOME)
    start[3] = k.upper[3] + 0.01
    goal = (0.3, -1.0, 0.3, 0.7)
    plan = plan_joint_motion(start, goal, scene)
    assert plan.ok, plan.message
    assert plan.start[3] == pytest.approx(k.upper[3])


def test_unsolvable_plan_fails_within_the_timeout(scene):
    """Start and goal on either side of a wall that the arm cannot get around:
    a ceiling stops it rising over, and the wall runs through the arm's axis
    front and back."""
    k = scene.kinematics
    scene.add_box("ceiling", (2.0, 2.0, 0.02), (0.0, 0.0, 0.31))
    scene.add_box("wall_front", (0.95, 0.01, 0.30), (0.05 + 0.475, 0.0, 0.15))
    scene.add_box("wall_back", (0.92, 0.01, 0.30), (-0.08 - 0.46, 0.0, 0.15))
    start = k.ik(0.25, 0.15, 0.1, 0.5).best
    goal = k.ik(0.25, -0.15, 0.1, 0.5).best
    assert scene.is_valid(start) and scene.is_valid(goal)
    t0 = time.perf_counter()
    plan = plan_joint_motion(start, goal, scene, timeout=0.3)
    elapsed = time.perf_counter() - t0
    assert not plan.ok and plan.path == ()
    assert plan.failure is FailureReason.TIMEOUT
    assert "no collision-free path" in plan.message
    assert elapsed < 1.0
    with pytest.raises(NoPathError):
        plan.raise_for_failure()


def test_bad_arguments_are_reported_not_raised(scene):
    assert plan_joint_motion((0, 0), HOME, scene).failure is FailureReason.INVALID_INPUT
    assert plan_joint_motion(HOME, (0, 0, math.nan, 0), scene).failure is FailureReason.INVALID_INPUT
    bad = plan_joint_motion(HOME, HOME, scene, planner="Dijkstra")
    assert bad.failure is FailureReason.INVALID_INPUT and "RRTConnect" in bad.message
    assert plan_joint_motion(HOME, HOME, scene, timeout=0).failure is FailureReason.INVALID_INPUT
    assert plan_pose_motion(HOME, "up", scene).failure is FailureReason.INVALID_INPUT  # type: ignore[arg-type]
