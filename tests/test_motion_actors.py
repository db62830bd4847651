"""Manipulator and navigation actors driving the simulated robot through its topics and
its controllers' actions."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bt_engine import Runtime
from tests.conftest import run_in_actor

sim_mod = pytest.importorskip("sim")


def robot_on(rt, world):
    """The robot's actors and the navigation stack (as actorbt.yaml starts them), told
    where the robot starts (/initialpose, as a user does)."""
    from actors.robot import Robot
    from sim.initial_pose import initial_pose_msg
    from geometry_msgs.msg import PoseWithCovarianceStamped
    from navstack import NavStack

    rt.add_subsystem("robot", Robot)
    rt.add_subsystem("navstack", NavStack)
    rt.bus.publisher("/initialpose", PoseWithCovarianceStamped).publish(initial_pose_msg(tuple(world.spec.robot_start)))


@pytest.fixture(scope="module")
def open_floor():
    rt = Runtime()
    world = sim_mod.SimWorld(rt, world="open_floor", seed=0)
    world.start()
    robot_on(rt, world)
    yield rt, world
    rt.run_on_hub(world.close)
    rt.close()


def tool_in_base_frame(world) -> np.ndarray:
    """Ground truth: end_effector_link position in base_footprint [m]."""
    (x, y, yaw) = world.robot_pose()
    pos, _ = world.link_pose("end_effector_link")
    dx, dy = pos[0] - x, pos[1] - y
    return np.array([math.cos(yaw) * dx + math.sin(yaw) * dy, -math.sin(yaw) * dx + math.cos(yaw) * dy, pos[2]])


@pytest.mark.parametrize("target", [(0.24, 0.0, 0.07, 0.0), (0.20, 0.08, 0.12, 0.5), (0.15, -0.10, 0.05, 1.2)])
def test_move_to_pose_ends_within_one_centimetre(open_floor, target):
    rt, world = open_floor
    rt.call("home")
    rt.call("move_to_pose", *target)
    err = np.linalg.norm(tool_in_base_frame(world) - np.array(target[:3]))
    assert err < 0.01, f"tool {err * 1000:.1f} mm from {target}"


def test_joint_moves_and_status(open_floor):
    rt, _ = open_floor
    q = rt.call("move_joint_degree", 20, -30, 20, 10)
    assert np.allclose(q, np.radians([20, -30, 20, 10]), atol=0.01)
    q2 = rt.call("adjust_joint", -20, 0, 0, 0)
    assert q2[0] == pytest.approx(0.0, abs=0.01)
    status = rt.call("get_status")
    assert set(status) == {"joints", "velocities", "gripper", "pose"}


def test_unreachable_pose_is_a_clean_failure(open_floor):
    from bt_engine import ActorError

    rt, _ = open_floor
    with pytest.raises(ActorError) as e:
        rt.call("move_to_pose", 1.5, 0.0, 0.1, 0.0)
    assert "unreachable" in str(e.value)


def test_an_arm_that_arrives_but_does_not_settle_in_time_counts_as_arrived(open_floor, monkeypatch):
    """The controller gives up on a goal the arm has not settled on in time
    (GOAL_TOLERANCE_VIOLATED), as it does when a loaded arm sags or rocks a little: near
    enough, the motion is done; farther, it fails with the controller's reason."""
    import actors.manipulator as manipulator

    rt, _ = open_floor
    rt.call("home")
    # a tolerance no arm settles within, and little time to settle
    monkeypatch.setattr(manipulator, "CONVERGED", 1e-6)
    monkeypatch.setattr(manipulator, "SETTLE_TIME", 0.05)
    q = rt.call("move_joint", 0.3, -0.5, 0.3, 0.4)
    assert max(abs(a - b) for a, b in zip(q, (0.3, -0.5, 0.3, 0.4))) <= manipulator.ARRIVED
    monkeypatch.setattr(manipulator, "ARRIVED", 0.0)
    with pytest.raises(Exception, match="did not reach its goal.*goal_time_tolerance"):
        rt.call("move_joint", *manipulator.HOME)


def test_gripper_opens_and_closes(open_floor):
    rt, _ = open_floor
    opened = rt.call("open")
    assert opened["width"] == pytest.approx(0.085, abs=0.003) and opened["reached_goal"]
    closed = rt.call("close")  # on nothing: reaches the closed end
    assert closed["width"] == pytest.approx(0.0, abs=0.003)
    assert closed["reached_goal"] and not closed["stalled"]
    assert closed["position"] == pytest.approx(-0.010, abs=0.001)
    assert rt.call("get_status")["gripper"] == closed


def test_cancelling_a_trajectory_stops_the_arm_smoothly(open_floor):
    rt, world = open_floor
    rt.call("home")

    def body():
        txn = rt.start("move_joint", 1.5, 0.3, -0.2, 0.4)
        rt.sleep(0.6)  # mid-way
        txn.cancel("operator stop")
        t_cancel = rt.now()
        speeds = []
        while rt.now() - t_cancel < 1.0:
            rt.sleep(0.05)
            speeds.append(max(abs(v) for v in rt.call("get_status")["velocities"]))
        return txn, speeds

    txn, speeds = run_in_actor(rt, body)
    assert txn.cancelled
    assert max(speeds[:2]) > 0.02, "the stop is a ramp, not a freeze"
    assert speeds[-1] < 0.02, f"joint speeds after 1 s: {speeds[-1]:.3f} rad/s"


def test_goto_across_two_rooms_of_the_house():
    with Runtime() as rt:
        world = sim_mod.SimWorld(rt, world="house", seed=0)
        world.start()
        robot_on(rt, world)
        goal = (2.6, 5.4, math.pi / 2)  # living room -> bedroom, through a doorway
        rt.call("goto", *goal)
        x, y, yaw = world.robot_pose()
        rt.run_on_hub(world.close)
    assert math.hypot(x - goal[0], y - goal[1]) < 0.10
    assert abs(math.degrees(math.remainder(yaw - goal[2], 2 * math.pi))) < 5.0


def test_goto_into_a_wall_fails_cleanly(open_floor):
    from bt_engine import ActorError

    rt, _ = open_floor
    with pytest.raises(ActorError) as e:
        rt.call("goto", 100.0, 100.0, 0.0)
    assert "no path" in str(e.value)
