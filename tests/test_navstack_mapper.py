"""navstack.mapper through NavStack on the simulated open floor: with no map server, the
robot starts mapping, drives a metre and turns on the spot; the mapper publishes /map and map -> odom,
saves the map, and hands over to the localiser on it."""

from __future__ import annotations

import math

import numpy as np
import pytest
from nav_msgs.msg import OccupancyGrid

from bt_engine import Runtime
from sim.initial_pose import initial_pose_msg
from navstack.map_io import read_map_yaml, read_trajectory_tum

sim_mod = pytest.importorskip("sim")


@pytest.fixture(scope="module")
def mapping():
    from actors.navigation import Navigation
    from navstack import NavStack
    from geometry_msgs.msg import PoseWithCovarianceStamped

    rt = Runtime(clock="virtual")
    world = sim_mod.SimWorld(rt, "open_floor", seed=0, camera=False)
    world.serve_map = False
    world.start()
    rt.add_subsystem("navigation", Navigation)
    rt.add_subsystem("navstack", NavStack)
    rt.bus.publisher("/initialpose", PoseWithCovarianceStamped).publish(initial_pose_msg(world.spec.robot_start))
    rt.call("sleep", 0.5)
    assert rt.call("start_mapping") == pytest.approx(list(world.spec.robot_start), abs=1e-3)
    # turn where walls are within the scan matcher's 3 m: from the floor's centre every
    # wall is 3-4.2 m away, and a match on the few returns left slides along them
    rt.call("mini_walk", 1.0)
    rt.call("mini_turn", math.pi)
    rt.call("mini_turn", math.pi)
    yield rt, world
    world.close()
    rt.close()


def test_the_map_comes_from_the_scans(mapping):
    rt, _ = mapping
    msg = rt.call("map")  # latched: the newest at once
    assert isinstance(msg, OccupancyGrid)
    data = np.asarray(msg.data).reshape(msg.info.height, msg.info.width)
    res, ox, oy = msg.info.resolution, msg.info.origin.position.x, msg.info.origin.position.y

    def value(x, y):
        return data[int((y - oy) / res), int((x - ox) / res)]

    assert res == pytest.approx(0.05)
    assert value(0.5, 0.5) == 0  # free around the robot
    for x, y in ((3.0, 0.0), (-3.0, 0.5), (0.5, 3.0), (0.0, -3.0)):  # the walls, 3 m away
        near = [value(x + dx, y + dy) for dx in np.arange(-0.2, 0.21, 0.05) for dy in (-0.1, 0, 0.1)]
        assert 100 in near, (x, y)
    assert value(4.0, 0.0) == -1  # behind the wall: never seen


def test_the_mapper_localises_the_robot(mapping):
    rt, world = mapping
    x, y, yaw = rt.call("get_pose")  # map -> base_footprint on /tf
    tx, ty, tyaw = world.robot_pose()
    assert math.hypot(x - tx, y - ty) < 0.08
    assert abs(math.remainder(yaw - tyaw, 2 * math.pi)) < math.radians(3)
    st = rt.call("mapping_status")
    assert st["keyframes"] >= 2 and not st["frozen"]


def test_save_map_then_localise_on_it(mapping, tmp_path):
    rt, _ = mapping
    saved = rt.call("save_map", str(tmp_path / "built.yaml"))
    m = read_map_yaml(saved["yaml"])
    assert (m.data == 100).sum() > 100 and m.resolution == pytest.approx(0.05)
    traj = read_trajectory_tum(saved["trajectory"])  # the keyframes, beside the map
    assert len(traj) == saved["keyframes"] and saved["trajectory"].endswith("built.tum")
    pose = rt.call("localise_on_map")
    assert rt.call("mapping_status")["frozen"]
    rt.call("sleep", 1.0)
    st = rt.call("localisation_status")
    assert st["map"] and math.dist(st["pose"][:2], pose[:2]) < 0.1
