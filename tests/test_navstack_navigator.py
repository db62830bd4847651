"""navstack.navigator: /navigate_to_pose served on the local bus, driving the simulated
robot (open_floor, no camera) localised by navstack's localiser from /initialpose."""

from __future__ import annotations

import math

import pytest
from geometry_msgs.msg import PoseWithCovarianceStamped
from nav2_msgs.action import NavigateToPose
from nav_msgs.msg import Odometry

from bt_engine import ActorError, Runtime
from bt_engine.bus.actions import STATUS_ABORTED, ActionGoalError
from navstack import NavStack
from navstack.navigator import GOAL_OCCUPIED, GOAL_OUTSIDE_MAP, NO_VALID_PATH, lookahead_point
from sim.initial_pose import initial_pose_msg
from tests.conftest import run_in_actor

sim_mod = pytest.importorskip("sim")


def goal_msg(x, y, yaw=0.0, frame="map"):
    g = NavigateToPose.Goal()
    g.pose.header.frame_id = frame
    g.pose.pose.position.x, g.pose.pose.position.y = float(x), float(y)
    g.pose.pose.orientation.z, g.pose.pose.orientation.w = math.sin(yaw / 2), math.cos(yaw / 2)
    return g


def _open_floor(camera: bool):
    """open_floor with the navstack, localised from /initialpose; a client actor ``nav``."""
    rt = Runtime(clock="virtual")
    world = sim_mod.SimWorld(rt, "open_floor", seed=0, camera=camera).start()
    rt.add_subsystem("navstack", NavStack)
    rt.root.register_action("nav", NavigateToPose, "/navigate_to_pose")
    rt.bus.publisher("/initialpose", PoseWithCovarianceStamped).publish(initial_pose_msg(world.spec.robot_start))
    rt.call("sleep", 0.5)
    yield rt, world
    world.close()
    rt.close()


@pytest.fixture(scope="module")
def floor():
    """_open_floor without the camera."""
    yield from _open_floor(camera=False)


def test_lookahead_point_walks_along_the_path():
    path = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0)]
    assert lookahead_point(path, 0, (0.5, 0.1), 0.25) == (0, pytest.approx((0.75, 0.0)))
    assert lookahead_point(path, 0, (0.9, 0.0), 0.25) == (0, pytest.approx((1.0, 0.15)))
    assert lookahead_point(path, 1, (1.0, 0.95), 0.25)[1] == (1.0, 1.0)


def test_a_goal_on_the_map_succeeds_within_the_tolerances(floor):
    rt, world = floor
    before = rt.call("navigator_status")
    result = rt.call("nav", goal_msg(1.5, -0.8, math.pi / 2), timeout=120)
    assert result.error_code == 0 and result.error_msg == ""
    x, y, yaw = world.robot_pose()
    assert math.hypot(x - 1.5, y + 0.8) < 0.12  # the goal checker's 4 cm + the localisation's error
    assert abs(math.remainder(yaw - math.pi / 2, 2 * math.pi)) < 0.08
    st = rt.call("navigator_status")
    assert st["succeeded"] == before["succeeded"] + 1 and st["goal"] is None
    # the localisation followed: map -> base_footprint on tf is where the robot is
    est = rt.call("localisation_status")["pose"]
    assert math.hypot(est[0] - x, est[1] - y) < 0.1


def test_no_path_aborts_with_the_reason(floor):
    rt, _ = floor
    with pytest.raises(ActorError) as e:
        rt.call("nav", goal_msg(100.0, 100.0), timeout=30)
    err = e.value.root_cause
    assert isinstance(err, ActionGoalError) and err.status == STATUS_ABORTED
    assert err.result.error_code == GOAL_OUTSIDE_MAP and "outside the map" in err.result.error_msg
    with pytest.raises(ActorError) as e:
        rt.call("nav", goal_msg(3.0, 0.0), timeout=30)  # in the east wall
    err = e.value.root_cause
    assert err.result.error_code == GOAL_OCCUPIED and "blocked" in err.result.error_msg
    with pytest.raises(ActorError) as e:
        rt.call("nav", goal_msg(3.2, 0.0), timeout=30)  # outside the walls: unknown space
    assert e.value.root_cause.result.error_code in (GOAL_OCCUPIED, NO_VALID_PATH)


def test_cancel_stops_the_base_and_ends_canceled(floor):
    rt, world = floor
    before = rt.call("navigator_status")
    x, y, _ = world.robot_pose()

    def body():
        txn = rt.start("nav", goal_msg(-2.0, -2.0, 0.0))
        rt.sleep(4.0)
        moving = rt.call("navigator_status")["phase"]
        txn.cancel("operator stop")
        rt.sleep(1.0)
        return txn, moving

    txn, moving = run_in_actor(rt, body)
    assert moving == "follow"
    assert txn.cancelled
    st = rt.call("navigator_status")
    assert st["canceled"] == before["canceled"] + 1 and st["goal"] is None
    odom = []
    sub = rt.bus.subscribe("/odom", Odometry, odom.append)
    rt.call("sleep", 0.2)
    sub.close()
    assert abs(odom[-1].twist.twist.linear.x) < 0.01 and abs(odom[-1].twist.twist.angular.z) < 0.02
    assert math.hypot(world.robot_pose()[0] - x, world.robot_pose()[1] - y) > 0.2  # it had moved


def test_an_obstacle_on_the_scan_but_not_on_the_map_is_driven_around(floor):
    rt, world = floor
    rt.call("nav", goal_msg(-1.5, 0.0, 0.0), timeout=120)
    # a bottle (taller than the scan plane, not on /map) right on the straight line ahead
    name = world.add_object("bottle", 0.0, 0.05)
    before = world.object_pose(name)
    stats0 = rt.call("navigator_status")
    path = []

    def body():
        txn = rt.start("nav", goal_msg(1.5, 0.0, 0.0))
        while not txn.done:
            path.append(world.robot_pose()[:2])
            rt.sleep(0.2)
        return txn

    txn = run_in_actor(rt, body)
    assert txn.error is None, txn.error
    st = rt.call("navigator_status")
    assert st["obstacle_stops"] > stats0["obstacle_stops"] and st["recoveries"] > stats0["recoveries"]
    after = world.object_pose(name)
    assert math.hypot(after[0] - before[0], after[1] - before[1]) < 0.005, "the bottle was not touched"
    assert min(math.hypot(px - before[0], py - before[1]) for px, py in path) > 0.15
    world.set_object_pose(name, 2.5, 2.5)  # out of the way of the next tests


@pytest.fixture(scope="module")
def floor_with_camera():
    """_open_floor with the robot's depth camera."""
    yield from _open_floor(camera=True)


def test_an_obstacle_below_the_scan_is_seen_by_the_depth_camera_and_driven_around(floor_with_camera):
    rt, world = floor_with_camera
    rt.call("nav", goal_msg(-1.5, 0.0, 0.0), timeout=120)
    # a flat box, 4 cm tall: under the scan plane, only the depth camera sees it
    name = world.add_object("flat_box", 0.0, 0.03)
    before = world.object_pose(name)
    stats0 = rt.call("navigator_status")
    rt.call("nav", goal_msg(1.5, 0.0, 0.0), timeout=120)
    st = rt.call("navigator_status")
    assert st["succeeded"] > stats0["succeeded"], st
    assert st["obstacle_stops"] > stats0["obstacle_stops"] and st["recoveries"] > stats0["recoveries"]
    after = world.object_pose(name)
    assert math.hypot(after[0] - before[0], after[1] - before[1]) < 0.005, "the box was not touched"
    assert rt.bus.subscription_count("/camera/depth/image_raw") == 0  # only while driving


def test_a_goal_that_makes_no_progress_backs_up_once_before_it_aborts():
    import pybullet as pb
    from geometry_msgs.msg import TwistStamped

    from navstack.navigator import BASE_COMMAND

    rt = Runtime(clock="virtual")
    world = sim_mod.SimWorld(rt, "open_floor", seed=0, camera=False).start()
    # (the localiser follows the spinning wheels part of the way: a wide progress radius)
    rt.add_subsystem("navstack", NavStack, navigator={"progress_radius": 0.5, "progress_time": 4.0})
    rt.root.register_action("nav", NavigateToPose, "/navigate_to_pose")
    rt.bus.publisher("/initialpose", PoseWithCovarianceStamped).publish(initial_pose_msg(world.spec.robot_start))
    rt.call("sleep", 0.5)
    try:
        # the wheels spin on ice: the base stays where it is, whatever it is told
        for j in world.robot.wheel_idx:
            pb.changeDynamics(world.robot.body, j, lateralFriction=0.0, physicsClientId=world.scene.cid)
        commands = []
        sub = rt.bus.subscribe(BASE_COMMAND, TwistStamped, commands.append)
        x, y, _ = world.robot_pose()
        with pytest.raises(ActorError) as e:
            rt.call("nav", goal_msg(x + 1.5, y, 0.0), timeout=120)
        sub.close()
        assert "no progress for 4 s" in str(e.value)
        assert rt.call("navigator_status")["recoveries"] == 1  # the back-up, once
        assert min(c.twist.linear.x for c in commands) < -0.05
    finally:
        world.close()
        rt.close()


def test_a_turn_does_not_sweep_the_base_into_a_can_it_passed():
    # the base's rear reaches 0.21 m behind the axle: a can standing two centimetres off the
    # robot's side once it stops swings into the rear's way as the base turns away from it
    rt_world = _open_floor(camera=True)
    rt, world = next(rt_world)
    try:
        # a can under the scan plane, beside the straight line to the first goal, seen
        # by the depth camera on the way there and then out of its view
        can = world.add_object("can", 1.0, 0.21)
        before = world.object_pose(can)
        rt.call("nav", goal_msg(1.2, 0.0, 0.0), timeout=120)
        x, y, _ = world.robot_pose()
        assert math.hypot(x - 1.2, y) < 0.06
        assert math.dist(world.object_pose(can)[:2], before[:2]) < 0.005, "passing it did not touch the can"
        # away from the can: turning right in place swings the rear left, into it
        rt.call("nav", goal_msg(1.3, -1.0, -math.pi / 2), timeout=120)
        moved = math.dist(world.object_pose(can)[:2], before[:2])
        assert moved < 0.01, f"the turn pushed the can {moved * 100:.1f} cm"
        x, y, yaw = world.robot_pose()
        assert math.hypot(x - 1.3, y + 1.0) < 0.06 and abs(math.remainder(yaw + math.pi / 2, 2 * math.pi)) < 0.1
    finally:
        next(rt_world, None)
