"""The RGB-D camera and the map on the bus: rendered only while subscribed, a can in front
of the robot is seen where the intrinsics say and at the right depth."""

from __future__ import annotations

import numpy as np
import pybullet as p
import pytest
from nav_msgs.msg import OccupancyGrid
from sensor_msgs.msg import CameraInfo, Image

from bt_engine import Runtime
from sim import SimWorld

CAN_X = 0.6


@pytest.fixture(scope="module")
def world():
    """One camera world for the module (loading EGL is the expensive part)."""
    rt = Runtime(clock="virtual")
    sim = SimWorld(rt, "open_floor", seed=0, camera_size=(320, 240), camera_hz=5.0).start()
    sim.set_object_pose("can_1", CAN_X, 0.0)
    yield rt, sim
    sim.close()
    rt.close()


def _collect(rt, topics, seconds):
    got = {t: [] for t, _ in topics}
    subs = [rt.bus.subscribe(t, ty, got[t].append) for t, ty in topics]
    rt.call("sleep", seconds)
    for s in subs:
        s.close()
    return got


def test_camera_renders_only_while_subscribed(world):
    rt, sim = world
    before = sim.frames_rendered
    rt.call("sleep", 2.0)
    assert sim.frames_rendered == before
    got = _collect(rt, [("/camera/color/image_raw", Image)], 1.0)
    n = len(got["/camera/color/image_raw"])
    assert 4 <= n <= 5  # 5 Hz
    assert sim.frames_rendered - before in (n, n + 1)  # the last frame may land after the close
    assert sim.renderer_name in ("gl", "egl", "tiny")


def test_can_in_front_is_seen_at_the_right_place_and_depth(world):
    rt, sim = world
    got = _collect(
        rt,
        [("/camera/color/image_raw", Image), ("/camera/depth/image_raw", Image), ("/camera/camera_info", CameraInfo)],
        0.4,
    )
    rgb_msg = got["/camera/color/image_raw"][-1]
    depth_msg = got["/camera/depth/image_raw"][-1]
    info = got["/camera/camera_info"][-1]
    assert (rgb_msg.encoding, depth_msg.encoding) == ("rgb8", "32FC1")
    assert rgb_msg.header.frame_id == depth_msg.header.frame_id == info.header.frame_id == "camera_optical_frame"
    h, w = rgb_msg.height, rgb_msg.width
    assert (w, h) == (info.width, info.height) == (320, 240)
    rgb = np.frombuffer(bytes(rgb_msg.data), np.uint8).reshape(h, w, 3).astype(int)
    depth = np.frombuffer(bytes(depth_msg.data), np.float32).reshape(h, w)

    red = (rgb[:, :, 0] > 120) & (rgb[:, :, 1] < 60) & (rgb[:, :, 2] < 60)
    assert red.sum() > 300, "the red can is visible"
    rows, cols = np.nonzero(red)

    # where the can's centre should project, from the camera's pose and CameraInfo.K
    pos, orn = sim.link_pose("camera_optical_frame")
    R = np.array(p.getMatrixFromQuaternion(orn)).reshape(3, 3)
    can = np.array(sim.object_pose("can_1")[:3])
    pc = R.T @ (can - np.array(pos))  # can centre in the optical frame
    K = np.array(info.k).reshape(3, 3)
    u, v = (K @ (pc / pc[2]))[:2]
    assert abs(np.median(cols) - u) < 4 and abs(np.median(rows) - v) < 8, ((u, v), np.median(cols), np.median(rows))

    # depth on the can: its front face, about CAN_X - radius ahead of base_footprint
    front = R.T @ (can - np.array([0.033, 0, 0]) - np.array(pos))
    d = np.nanmedian(depth[red])
    assert d == pytest.approx(front[2], abs=0.02)
    assert d < pc[2]


def test_the_map_is_published_once_and_latched(world):
    rt, sim = world
    maps = []
    sub = rt.bus.subscribe("/map", OccupancyGrid, maps.append, "latched")  # as map_server's are
    rt.call("sleep", 0.5)
    sub.close()
    assert len(maps) == 1
    m = maps[0]
    assert m.info.resolution == pytest.approx(0.05)
    assert (m.info.width, m.info.height) == (sim.grid.width, sim.grid.height)
    data = np.array(m.data, dtype=np.int8).reshape(m.info.height, m.info.width)
    assert np.array_equal(data, sim.grid.data)
    # published once, as map_server does: a late subscriber asking for transient local
    # durability ("latched") gets it from the bus at once; it is not sent again
    rt.call("sleep", 0.1)
    late = []
    sub = rt.bus.subscribe("/map", OccupancyGrid, late.append, "latched")
    rt.call("sleep", 0.1)
    assert len(late) == 1 and np.array_equal(np.array(late[0].data, dtype=np.int8), np.array(m.data, dtype=np.int8))
    rt.call("sleep", 3.0)
    assert len(late) == 1
    sub.close()
