"""/tf and /tf_static from the simulator: REP 105 frames from sim/frames.py, odom ->
base_footprint from the (noisy) odometry, the joints from the joint states, the static
tree latched for late subscribers, and never map -> odom."""

from __future__ import annotations

import numpy as np
import pybullet as p
import pytest
from geometry_msgs.msg import TwistStamped
from nav_msgs.msg import Odometry
from tf2_msgs.msg import TFMessage

from bt_engine import Runtime
from planning.tf_buffer import TransformBuffer, transform_matrix
from sim import SimWorld
from sim.frames import compose, odom_transform, static_transforms
from sim.topics import CMD_VEL


def _matrix(t) -> np.ndarray:
    return transform_matrix(t.translation, t.rotation)


def _chain(parent: str, child: str):
    """parent -> child through the URDF's fixed joints (sim/frames.py)."""
    edges = {t.child: t for t in static_transforms()}
    chain = []
    while child != parent:
        chain.append(edges[child])
        child = edges[child].parent
    out = chain.pop()
    while chain:
        out = compose(out, chain.pop())
    return out


@pytest.fixture(scope="module")
def driven():
    """A robot that drove a curve and moved its arm, with /tf, /tf_static and /odom heard."""
    rt = Runtime(clock="virtual")
    sim = SimWorld(rt, "open_floor", seed=3, camera=False, cmd_vel_timeout=0).start()
    heard = {"tf": [], "static": [], "odom": []}
    subs = [
        rt.bus.subscribe("/tf", TFMessage, heard["tf"].append),
        rt.bus.subscribe("/tf_static", TFMessage, heard["static"].append),
        rt.bus.subscribe("/odom", Odometry, heard["odom"].append),
    ]
    tw = TwistStamped()
    tw.twist.linear.x, tw.twist.angular.z = 0.2, 0.3
    rt.bus.publisher(CMD_VEL, TwistStamped).publish(tw)
    sim.set_arm_positions([0.5, 0.2, -0.1, 0.4], 1.0)
    rt.call("sleep", 3.0)
    rt.bus.publisher(CMD_VEL, TwistStamped).publish(TwistStamped())
    rt.call("sleep", 1.0)
    yield rt, sim, heard
    for s in subs:
        s.close()
    sim.close()
    rt.close()


def _buffer(heard) -> TransformBuffer:
    buf = TransformBuffer()
    for m in heard["static"]:
        buf.add_message(m, static=True)
    for m in heard["tf"]:
        buf.add_message(m)
    return buf


def test_tf_goes_out_at_the_odometry_rate_with_the_odometry_pose(driven):
    rt, sim, heard = driven
    assert len(heard["tf"]) == pytest.approx(len(heard["odom"]), abs=1)
    assert len(heard["tf"]) == pytest.approx(4.0 * 30, abs=3)
    tf, odom = heard["tf"][-1], heard["odom"][-1]
    edge = next(t for t in tf.transforms if t.child_frame_id == "base_footprint")
    assert edge.header.frame_id == "odom" and edge.header.stamp == odom.header.stamp
    pose = odom.pose.pose
    assert (edge.transform.translation.x, edge.transform.translation.y) == (pose.position.x, pose.position.y)
    assert edge.transform.rotation == pose.orientation
    # the odometry's, not the ground truth: the noisy odometry drifted from the true pose
    x, y, _ = sim.robot_pose()
    start = sim.spec.robot_start
    assert (x - start[0], y - start[1]) != pytest.approx((pose.position.x, pose.position.y), abs=1e-4)


def test_no_map_to_odom_from_the_simulator(driven):
    _, _, heard = driven
    edges = {(t.header.frame_id, t.child_frame_id) for m in heard["tf"] + heard["static"] for t in m.transforms}
    assert not any(child == "odom" for _, child in edges)
    assert "map" not in {parent for parent, _ in edges}


def test_static_tree_is_the_urdfs_fixed_joints(driven):
    _, _, heard = driven
    assert heard["static"], "/tf_static reached the first subscriber"
    got = {(t.header.frame_id, t.child_frame_id) for t in heard["static"][0].transforms}
    assert got == {(t.parent, t.child) for t in static_transforms()}
    assert {("base_footprint", "base_link"), ("base_link", "base_scan"), ("camera_link", "camera_optical_frame")} <= got
    assert len(heard["static"]) == 1, "sent once, not with every /tf"


def test_odom_to_sensor_frames_match_sim_frames(driven):
    _, sim, heard = driven
    buf = _buffer(heard)
    odom = heard["odom"][-1]
    stamp = odom.header.stamp.sec + odom.header.stamp.nanosec * 1e-9
    base = odom_transform(sim.odometry)  # the robot has stopped: the latest is the last
    for frame in ("base_scan", "camera_optical_frame", "camera_link"):
        want = _matrix(compose(base, _chain("base_footprint", frame)))
        got = buf.lookup("odom", frame, stamp)
        assert got == pytest.approx(want, abs=1e-6), frame


def test_arm_frames_follow_the_joint_states(driven):
    _, sim, heard = driven
    buf = _buffer(heard)
    got = buf.lookup("base_footprint", "end_effector_link")
    base_pos, base_orn = sim.link_pose("base_footprint")
    ee_pos, ee_orn = sim.link_pose("end_effector_link")
    inv = p.invertTransform(base_pos, base_orn)
    rel_pos, rel_orn = p.multiplyTransforms(inv[0], inv[1], ee_pos, ee_orn)
    assert got[:3, 3] == pytest.approx(rel_pos, abs=2e-3)
    assert got[:3, :3] == pytest.approx(transform_matrix((0, 0, 0), rel_orn)[:3, :3], abs=2e-3)
    moving = {t.child_frame_id for t in heard["tf"][-1].transforms}
    assert {
        "link2",
        "link3",
        "link4",
        "link5",
        "gripper_left_link",
        "gripper_right_link",
        "wheel_left_link",
        "wheel_right_link",
    } <= moving


def test_a_late_subscriber_still_gets_the_static_tree(driven):
    rt, _, heard = driven
    late = []
    sub = rt.bus.subscribe("/tf_static", TFMessage, late.append)
    try:
        rt.call("sleep", 0.1)
        assert len(late) == 1
        assert {t.child_frame_id for t in late[0].transforms} >= {"base_link", "base_scan"}
        rt.call("sleep", 0.5)
        assert len(late) == 1
    finally:
        sub.close()


def test_no_tf_without_subscribers():
    with Runtime(clock="virtual") as rt:
        sim = SimWorld(rt, "open_floor", seed=0, camera=False).start()
        try:
            built = []
            real = sim.topics.tf_msg
            sim.topics.tf_msg = lambda *a: built.append(1) or real(*a)
            rt.call("sleep", 0.5)
            assert not built
            sub = rt.bus.subscribe("/tf", TFMessage, lambda m: None)
            rt.call("sleep", 0.5)
            sub.close()
            assert len(built) == pytest.approx(15, abs=1)
        finally:
            sim.close()
