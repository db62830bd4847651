"""The simulated robot's own senses: the LDS-01 scan, wheel odometry with a real robot's
errors, the ground-truth topic behind its debug flag, and the frames /tf will carry."""

from __future__ import annotations

import math

import numpy as np
import pytest
from geometry_msgs.msg import PoseStamped, TwistStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import LaserScan

from bt_engine import Runtime
from sim import SimWorld
from sim.description import parse_world
from sim.frames import compose, joint_transforms, odom_transform, static_transforms
from sim.lidar import Lidar, LidarModel
from sim.odometry import OdomNoise, WheelOdometry
from sim.odometry import episode_rng as odometry_rng
from sim.topics import CMD_VEL

SCAN_X = -0.150  # base_scan in base_footprint (URDF: scan_joint)
SCAN_Z = 0.132

# one wall 2 m ahead of the robot: its face at x = 1.95, from y = -1.05 to 1.05
WALL = parse_world("""
name: wall
bounds: [-1, -2, 3, 2]
wall: {height: 0.5, thickness: 0.1}
walls:
  - [2, -1, 2, 1]
robot: {start: [0, 0, 0]}
""")
WALL_RANGE = 1.95 - SCAN_X

# a large empty floor to drive 10 m on
FLOOR = parse_world("""
name: big_floor
bounds: [-2, -2, 8, 8]
robot: {start: [0, 0, 0]}
""")


def _beam(deg):
    return int(round(deg)) % 360


# ------------------------------------------------------------------------------ lidar
def test_scan_geometry_against_a_known_wall():
    sim = SimWorld(None, WALL, seed=0, camera=False, lidar_noise=False, cmd_vel_timeout=0)
    try:
        r = sim.scan()
        assert r.dtype == np.float32 and r.shape == (360,)
        # the arm's shoulder stands in the scan plane 0.11 m ahead of base_scan: the beams
        # pass through the robot's own body and read the wall
        for deg in list(range(0, 21)) + list(range(340, 360)):
            expected = WALL_RANGE / math.cos(math.radians(deg))
            assert r[deg] == pytest.approx(expected, abs=0.002), deg
        assert np.all(np.isposinf(r[35:326])), "nothing else within 3.5 m"
        # rays that may hit the robot stop at the shoulder, closer than range_min
        selfish = Lidar(sim.cid, LidarModel(), np.random.default_rng(0), ray_mask=-1, noise=False)
        assert np.isneginf(selfish.scan(*sim.link_pose("base_scan"))[0])
    finally:
        sim.close()


def test_scan_noise_is_a_few_centimetres_and_seeded():
    def scans(seed, n=40):
        sim = SimWorld(None, WALL, seed=seed, camera=False, cmd_vel_timeout=0)
        try:
            return np.array([sim.scan() for _ in range(n)])
        finally:
            sim.close()

    a = scans(0)
    beam0 = a[:, 0]
    sigma = 0.03 * WALL_RANGE  # 3 % of the range (> 1 cm)
    assert beam0.mean() == pytest.approx(WALL_RANGE, abs=3 * sigma / math.sqrt(len(beam0)))
    assert beam0.std() == pytest.approx(sigma, rel=0.35)
    assert np.array_equal(a, scans(0)), "same seed, same noise"
    assert not np.array_equal(a[:, :21], scans(1)[:, :21]), "another seed, other noise"


def test_scan_respects_range_min():
    sim = SimWorld(None, WALL, seed=0, camera=False, cmd_vel_timeout=0)
    try:
        # a bottle right behind the robot, 0.075 m from base_scan (the chassis is under
        # the scan plane, the bottle reaches above it)
        sim.add_object("bottle", -0.26, 0.0)
        for _ in range(20):
            r = sim.scan()
            finite = r[np.isfinite(r)]
            assert np.all(finite >= 0.12)
            assert np.isneginf(r[180]), r[180]  # REP 117: too close -> -inf
            assert np.all(finite <= 3.5)
    finally:
        sim.close()


def test_scan_sees_a_bottle_that_the_grid_does_not_have_and_not_a_can():
    sim = SimWorld(None, FLOOR, seed=0, camera=False, lidar_noise=False, cmd_vel_timeout=0)
    try:
        sim.add_object("bottle", 1.0, 0.0)
        sim.add_object("can", 1.0, 1.0)  # 41 deg to the left of base_scan
        sim.advance(0.5)  # let them settle
        assert sim.grid.value_at(1.0, 0.0) != 100, "objects are not in the occupancy grid"
        r = sim.scan()
        assert r[0] == pytest.approx(1.0 - 0.035 - SCAN_X, abs=0.003)  # the bottle's body
        # a can is 0.122 m tall, under the 0.132 m scan plane: the real LDS-01 misses it too
        can_deg = math.degrees(math.atan2(1.0, 1.0 - SCAN_X))
        assert np.all(np.isposinf(r[_beam(can_deg) - 3 : _beam(can_deg) + 4]))
    finally:
        sim.close()


def test_scan_model_is_the_lds01():
    m = LidarModel()
    assert (m.beams, m.range_min, m.range_max, m.scan_time) == (360, 0.12, 3.5, 0.2)
    assert m.angle_min == 0.0
    assert m.angle_increment == pytest.approx(2 * math.pi / 360)
    assert m.angle_max == pytest.approx(2 * math.pi * 359 / 360)


# ------------------------------------------------------------------------------ on the bus
def test_scan_and_odom_topics_and_rates_on_the_runtime_clock():
    rt = Runtime(clock="virtual")
    sim = SimWorld(rt, WALL, seed=0, camera=False).start()
    try:
        rt.call("sleep", 1.0)
        assert sim.lidar.scans == 0, "no subscriber, no ray cast"
        scans, odoms = [], []
        subs = [
            rt.bus.subscribe("/scan", LaserScan, scans.append, "sensor"),
            rt.bus.subscribe("/odom", Odometry, odoms.append),
        ]
        rt.call("sleep", 3.0)
        for s in subs:
            s.close()
        t_scan = np.array([m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec for m in scans])
        t_odom = np.array([m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec for m in odoms])
        assert len(scans) == pytest.approx(15, abs=1)
        assert np.allclose(np.diff(t_scan), 0.2, atol=1e-6)  # 5 Hz
        assert len(odoms) == pytest.approx(90, abs=2)
        assert np.allclose(np.diff(t_odom), 1 / 30, atol=1e-6)  # 30 Hz
        m = scans[-1]
        assert m.header.frame_id == "base_scan"
        assert (m.angle_min, m.range_min, m.range_max, m.scan_time) == pytest.approx((0.0, 0.12, 3.5, 0.2))
        assert m.angle_max == pytest.approx(2 * math.pi * 359 / 360, abs=1e-6)
        assert m.angle_increment == pytest.approx(2 * math.pi / 360, abs=1e-7)
        assert len(m.ranges) == 360
        assert m.ranges[0] == pytest.approx(WALL_RANGE, abs=0.3)
        o = odoms[-1]
        assert (o.header.frame_id, o.child_frame_id) == ("odom", "base_footprint")
        assert o.pose.covariance[0] > 0 and o.pose.covariance[35] > 0 and o.twist.covariance[0] > 0
    finally:
        sim.close()
        rt.close()


@pytest.mark.parametrize("flag", [True, False])
def test_ground_truth_topic_only_with_the_debug_flag(flag):
    rt = Runtime(clock="virtual")
    sim = SimWorld(rt, WALL, seed=0, camera=False, debug_ground_truth=flag).start()
    try:
        got = {"gt": [], "odom": []}
        subs = [
            rt.bus.subscribe("/ground_truth/pose", PoseStamped, got["gt"].append),
            rt.bus.subscribe("/odom", Odometry, got["odom"].append),
        ]
        rt.call("sleep", 0.5)
        for s in subs:
            s.close()
        assert len(got["odom"]) > 10
        assert (len(got["gt"]) > 10) if flag else (got["gt"] == [])
        assert sim.robot_pose() == pytest.approx((0.0, 0.0, 0.0), abs=1e-3)  # still inside the sim
    finally:
        sim.close()
        rt.close()


# ------------------------------------------------------------------------------ odometry
# The physics does not depend on the seed on an empty floor: drive once, record what the
# encoders and the gyro see every tick, and replay it through the odometry of many seeds.
@pytest.fixture(scope="module")
def l_drive():
    """East 5 m, turn left, north 5 m (10 m, open loop), seed 0: the per-tick trace of
    (left wheel, right wheel, true yaw), the true poses, and the world's own odometry.
    Physics at 120 Hz (half the default) keeps it quick; the odometry does not mind."""
    sim = SimWorld(None, FLOOR, seed=0, camera=False, physics_hz=120, cmd_vel_timeout=0)
    try:
        trace, truth = [], []

        def record():
            q = sim.robot.joint_states()[0]
            pose = sim.robot_pose()
            trace.append((q[0], q[1], pose[2]))
            truth.append(pose)

        record()
        for v, w, seconds in ((0.25, 0.0, 20.0), (0.0, 1.0, math.pi / 2), (0.25, 0.0, 20.0), (0.0, 0.0, 1.0)):
            sim.apply_cmd_vel(v, w)
            for _ in range(int(round(seconds / sim.dt))):
                sim.advance(sim.dt)
                record()
        return dict(
            trace=trace, truth=np.array(truth), dt=sim.dt, odom=sim.odom_pose(), cov=sim.odometry.pose_covariance()
        )
    finally:
        sim.close()


def _replay(drive, seed, noise=None):
    odo = WheelOdometry(noise or OdomNoise(), odometry_rng(seed))
    (l0, r0, y0), *rest = drive["trace"]
    odo.reset(l0, r0, y0)
    for left, right, yaw in rest:
        odo.update(left, right, drive["dt"], yaw)
    return odo


def _error(drive, odo):
    end = drive["truth"][-1]
    return math.hypot(odo.x - end[0], odo.y - end[1])


def _distance(drive):
    xy = drive["truth"][:, :2]
    return float(np.sum(np.hypot(*np.diff(xy, axis=0).T)))


def test_odometry_replay_is_the_worlds_odometry(l_drive):
    odo = _replay(l_drive, 0)
    assert (odo.x, odo.y, odo.yaw) == l_drive["odom"], "same seed, same wheels: same odometry"
    assert odo.pose_covariance() == l_drive["cov"]


def test_odometry_drifts_like_a_real_robot_and_is_seeded(l_drive):
    dist = _distance(l_drive)
    assert dist == pytest.approx(10.0, abs=0.5)
    errors = []
    for seed in range(8):
        odo = _replay(l_drive, seed)
        err = _error(l_drive, odo)
        errors.append(err / dist)
        # the reported uncertainty covers the error (x/y standard deviation, 3 sigma)
        assert err < 3 * math.sqrt(2 * odo.pose_covariance()[0])
    assert np.mean(errors) > 0.01, errors  # > 1 % of the distance, on average
    assert max(errors) < 0.08, errors  # ... but a plausible few per cent
    assert len(set(round(e, 9) for e in errors)) == len(errors), "each seed its own errors"
    assert _error(l_drive, _replay(l_drive, 5)) / dist == errors[5], "same seed, same errors"


def test_exact_odometry_follows_the_wheels(l_drive):
    assert _error(l_drive, _replay(l_drive, 0, OdomNoise.exact())) < 0.002 * _distance(l_drive)


def test_heading_from_the_wheels_bends_with_the_wheels_mismatch(l_drive):
    scale_only = dict(
        wheel_noise=0.0, wheel_scale=0.0, gyro_bias=0.0, gyro_bias_walk=0.0, gyro_noise=0.0, gyro_scale=0.0
    )
    for seed in range(3):
        imu = _replay(l_drive, seed, OdomNoise(heading="imu", **scale_only))
        wheels = _replay(l_drive, seed, OdomNoise(**scale_only))
        assert _error(l_drive, wheels) > _error(l_drive, imu)


# ------------------------------------------------------------------------------ frames
def test_static_frames_come_from_the_urdf():
    tf = {(t.parent, t.child): t for t in static_transforms()}
    assert tf[("base_footprint", "base_link")].translation == pytest.approx((0, 0, 0.01))
    scan = tf[("base_link", "base_scan")]
    assert scan.translation == pytest.approx((SCAN_X, 0, SCAN_Z - 0.01))
    assert scan.rotation == pytest.approx((0, 0, 0, 1))
    assert ("camera_link", "camera_optical_frame") in tf


def test_joint_frames_match_pybullet():
    sim = SimWorld(None, WALL, seed=0, camera=False, cmd_vel_timeout=0)
    try:
        sim.set_arm_positions([0.4, 0.3, -0.2, 0.5], 0.5)
        sim.advance(1.5)
        q, _, _ = sim.robot.joint_states()
        from sim.robot import JOINT_STATE_NAMES

        edges = {t.child: t for t in static_transforms() + joint_transforms(dict(zip(JOINT_STATE_NAMES, q)))}
        chain, link = [], "end_effector_link"
        while link != "base_footprint":
            chain.append(edges[link])
            link = edges[link].parent
        t = chain.pop()
        while chain:
            t = compose(t, chain.pop())
        base_pos, base_orn = sim.link_pose("base_footprint")
        ee_pos, ee_orn = sim.link_pose("end_effector_link")
        import pybullet as p

        inv = p.invertTransform(base_pos, base_orn)
        rel_pos, rel_orn = p.multiplyTransforms(inv[0], inv[1], ee_pos, ee_orn)
        assert t.translation == pytest.approx(rel_pos, abs=1e-4)
        assert abs(np.dot(t.rotation, rel_orn)) == pytest.approx(1.0, abs=1e-6)
    finally:
        sim.close()


def test_odom_message_and_odom_transform_agree():
    rt = Runtime(clock="virtual")
    # one command, held: no controller timeout
    sim = SimWorld(rt, FLOOR, seed=2, camera=False, cmd_vel_timeout=0).start()
    try:
        got = []
        sub = rt.bus.subscribe("/odom", Odometry, got.append)
        tw = TwistStamped()
        tw.twist.linear.x, tw.twist.angular.z = 0.2, 0.4
        rt.bus.publisher(CMD_VEL, TwistStamped).publish(tw)
        rt.call("sleep", 2.0)
        sub.close()
        msg = got[-1]
        tf = odom_transform(sim.odometry)
        p = msg.pose.pose
        # the last message is at most one publish period old
        assert (p.position.x, p.position.y) == pytest.approx(tf.translation[:2], abs=0.2 * 2 / 30)
        assert (tf.parent, tf.child) == (msg.header.frame_id, msg.child_frame_id)
    finally:
        sim.close()
        rt.close()
