"""The navigation actors (actors/navigation.py) driving the simulated robot as a client of
the robot's navigation: goto through /navigate_to_pose, get_pose from tf, the short moves
on /odom. navstack stands in for Nav2 and AMCL, localised from /initialpose."""

from __future__ import annotations

import math

import pytest
from geometry_msgs.msg import PoseWithCovarianceStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import PointCloud2

from bt_engine import ActorError, Runtime
from sim.initial_pose import initial_pose_msg
from tests.conftest import run_in_actor

sim_mod = pytest.importorskip("sim")


def robot_in(world: str, seed: int = 0):
    from actors.navigation import Navigation
    from navstack import NavStack

    rt = Runtime()
    sim = sim_mod.SimWorld(rt, world=world, seed=seed, camera=False).start()
    rt.add_subsystem("navigation", Navigation)
    rt.add_subsystem("navstack", NavStack)
    rt.bus.publisher("/initialpose", PoseWithCovarianceStamped).publish(initial_pose_msg(sim.spec.robot_start))
    return rt, sim


@pytest.fixture(scope="module")
def open_floor():
    rt, world = robot_in("open_floor")
    yield rt, world
    world.close()
    rt.close()


def _error(pose, truth) -> float:
    return math.hypot(pose[0] - truth[0], pose[1] - truth[1])


def test_get_pose_is_the_localised_pose_from_tf(open_floor):
    rt, world = open_floor
    pose = rt.call("get_pose")
    assert _error(pose, world.robot_pose()) < 0.05
    assert abs(math.remainder(pose[2] - world.robot_pose()[2], 2 * math.pi)) < 0.05


def test_mini_walk_and_turn_on_the_odometry(open_floor):
    rt, world = open_floor
    x0, y0, _ = world.robot_pose()
    driven = rt.call("mini_walk", 0.3)
    assert driven == pytest.approx(0.3, abs=0.01)
    x1, y1, _ = world.robot_pose()
    assert math.hypot(x1 - x0, y1 - y0) == pytest.approx(0.3, abs=0.02)  # the odometry's few per cent
    _, _, yaw0 = world.robot_pose()
    yaw = rt.call("mini_turn", math.pi / 2)
    _, _, true_yaw = world.robot_pose()
    assert abs(math.remainder(true_yaw - yaw0 - math.pi / 2, 2 * math.pi)) < 0.03
    assert abs(math.remainder(yaw - true_yaw, 2 * math.pi)) < 0.05  # the localised yaw
    rt.call("migrate", 0.0, 0.0, -math.pi / 2)


def test_cancelling_goto_stops_the_base(open_floor):
    rt, world = open_floor
    x, y, _ = world.robot_pose()

    def body():
        txn = rt.start("goto", x + 2.0, y, 0.0)
        rt.sleep(3.0)
        txn.cancel("operator stop")
        rt.sleep(1.0)
        return txn

    txn = run_in_actor(rt, body)
    odom = rt.call("odom")
    assert txn.cancelled
    assert abs(odom.twist.twist.linear.x) < 0.01 and abs(odom.twist.twist.angular.z) < 0.02
    assert rt.call("navigator_status")["goal"] is None


def test_goto_into_a_wall_fails_cleanly(open_floor):
    rt, _ = open_floor
    with pytest.raises(ActorError) as e:
        rt.call("goto", 100.0, 100.0, 0.0)
    assert "NavigationError" in str(e.value) and "outside the map" in str(e.value)


def test_marked_obstacles_reach_the_navigation_and_the_queries(open_floor):
    rt, world = open_floor
    got = []
    sub = rt.bus.subscribe("/perceived_obstacles", PointCloud2, got.append)
    x, y, _ = rt.call("goto", -1.5, 0.0, 0.0)
    free = rt.call("clearance", x + 1.0, y)
    assert rt.call("mark_obstacles", [{"x": x + 1.0, "y": y, "radius": 0.06}]) == 1
    assert rt.call("clearance", x + 1.0, y) == 0.0 < free
    # the navigation plans around it: the straight line through it is not the path
    path = rt.call("plan_path", x + 2.0, y)
    assert len(path) > 2
    rt.call("sleep", 0.1)
    assert got and got[-1].width > 10 and got[-1].header.frame_id == "map"
    from navstack.navigator import cloud_points

    pts = cloud_points(got[-1])
    assert max(math.hypot(px - x - 1.0, py - y) for px, py in pts) <= 0.06 + 1e-6
    # the navigation server has them too: the robot drives round the marked disc
    trail = []

    def body():
        txn = rt.start("goto", x + 2.0, y, 0.0)
        while not txn.done:
            trail.append(world.robot_pose()[:2])
            rt.sleep(0.2)
        return txn

    assert run_in_actor(rt, body).error is None
    assert min(math.hypot(px - x - 1.0, py - y) for px, py in trail) > 0.2
    rt.call("mark_obstacles", [])
    sub.close()
    assert rt.call("clearance", x + 1.0, y) == free


def test_goto_across_two_rooms_of_the_house():
    rt, world = robot_in("house")
    try:
        goal = (2.6, 5.4, math.pi / 2)  # living room -> bedroom, through a doorway
        pose = rt.call("goto", *goal)
        x, y, yaw = world.robot_pose()
        odom = []
        sub = rt.bus.subscribe("/odom", Odometry, odom.append)
        rt.call("sleep", 0.1)
        sub.close()
    finally:
        world.close()
        rt.close()
    assert math.hypot(x - goal[0], y - goal[1]) < 0.10
    assert abs(math.degrees(math.remainder(yaw - goal[2], 2 * math.pi))) < 5.0
    assert _error(pose, (x, y)) < 0.06


def test_require_localised_reads_the_localisers_covariance():
    """No sim: /amcl_pose is published by hand, as an uncertain then a sure estimate."""
    from actors.navigation import Navigation

    with Runtime(clock="virtual") as rt:
        rt.add_subsystem("navigation", Navigation)
        pub = rt.bus.publisher("/amcl_pose", PoseWithCovarianceStamped, "latched")
        with pytest.raises(ActorError, match="delocalised: no /amcl_pose received after 1 s"):
            rt.call("require_localised", wait=1.0)
        unsure = initial_pose_msg((1.0, 2.0, 0.0))
        unsure.pose.covariance[0] = unsure.pose.covariance[7] = 0.5**2
        pub.publish(unsure)
        with pytest.raises(ActorError, match=r"delocalised: the localisation is uncertain: std 50\.0 cm"):
            rt.call("require_localised", wait=1.0)
        pub.publish(initial_pose_msg((1.0, 2.0, 0.0)))  # 5 cm, 1.7 degrees
        assert rt.call("require_localised") == {"std_xy": 0.05, "std_yaw": 0.03}
