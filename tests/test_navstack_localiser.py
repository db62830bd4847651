"""navstack.localiser: the localiser as a SubSystem on the local bus, fed with the
synthetic house's /map, /odom and /scan messages."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from geometry_msgs.msg import PoseWithCovarianceStamped
from nav_msgs.msg import OccupancyGrid, Odometry
from sensor_msgs.msg import LaserScan
from tf2_msgs.msg import TFMessage

from navstack.localiser import LASER_POSE, TRANSFORM_TOLERANCE, Localiser
from navstack.map_io import read_map_yaml
from navstack.synthetic import LaserSpec, SyntheticWorld, world_boxes
from navstack.tf import planar_transform
from planning.tf_buffer import TransformBuffer, planar, pose2d

FIXTURES = Path(__file__).parent / "fixtures"


def stamp_of(msg, t):
    msg.header.stamp.sec = int(t)
    msg.header.stamp.nanosec = int(round((t - int(t)) * 1e9)) % 1_000_000_000


def odom_msg(s):
    m = Odometry()
    stamp_of(m, s.t)
    m.header.frame_id, m.child_frame_id = "odom", "base_footprint"
    m.pose.pose.position.x, m.pose.pose.position.y = s.odom[0], s.odom[1]
    m.pose.pose.orientation.z, m.pose.pose.orientation.w = math.sin(s.odom[2] / 2), math.cos(s.odom[2] / 2)
    return m


def scan_msg(s):
    m = LaserScan()
    stamp_of(m, s.t)
    m.header.frame_id = "base_scan"
    sc = s.scan
    m.angle_min, m.angle_increment = sc.angle_min, sc.angle_increment
    m.angle_max = sc.angle_min + sc.angle_increment * (len(sc.ranges) - 1)
    m.range_min, m.range_max = sc.range_min, sc.range_max
    m.ranges = sc.ranges
    return m


class Feed:
    def __init__(self, rt, world):
        bus = rt.bus
        self.rt, self.world = rt, world
        self.map = bus.publisher("/map", OccupancyGrid)
        self.odom = bus.publisher("/odom", Odometry)
        self.scan = bus.publisher("/scan", LaserScan)
        self.initial = bus.publisher("/initialpose", PoseWithCovarianceStamped)
        self.tf_static = bus.publisher("/tf_static", TFMessage)
        self.poses = []
        self.tf = []  # (receive time, map -> odom message)
        self.sub = bus.subscribe("/amcl_pose", PoseWithCovarianceStamped, self.poses.append)
        self.tf_sub = bus.subscribe("/tf", TFMessage, lambda m: self.tf.append((self.world.t, m)))

    def run(self, seconds):
        end = self.world.t + seconds
        while self.world.t < end - 1e-9:
            s = self.world.step()
            self.odom.publish(odom_msg(s))
            if s.scan is not None:
                self.scan.publish(scan_msg(s))
            self.rt.run_on_hub(lambda: None)  # let the hub deliver them
        return s


def test_localiser_subsystem_tracks_and_relocalises(rt):
    assert LASER_POSE == LaserSpec().pose
    occ = read_map_yaml(FIXTURES / "house.yaml")
    world = SyntheticWorld(occ, world_boxes(FIXTURES / "house_world.yaml"), seed=3)
    loc = rt.add_subsystem("localiser", Localiser, seed=1)
    feed = Feed(rt, world)
    assert rt.call("localisation_status")["state"] == "uninitialised"
    feed.map.publish(occ.to_msg())
    feed.run(0.2)
    # /initialpose, roughly right
    init = PoseWithCovarianceStamped()
    x, y, th = world.truth
    init.pose.pose.position.x, init.pose.pose.position.y = x + 0.1, y - 0.1
    init.pose.pose.orientation.z, init.pose.pose.orientation.w = math.sin(th / 2), math.cos(th / 2)
    cov = np.zeros((6, 6))
    cov[0, 0] = cov[1, 1] = 0.2**2
    cov[5, 5] = 0.1**2
    init.pose.covariance = cov.ravel().tolist()
    feed.initial.publish(init)
    feed.map.publish(occ.to_msg())  # republished: not rebuilt
    t0 = world.t
    s = feed.run(15)
    st = rt.call("localisation_status")
    assert st["state"] == "localised" and st["updates"] > 5
    assert math.hypot(st["pose"][0] - s.truth[0], st["pose"][1] - s.truth[1]) < 0.1
    # map -> odom on /tf at >= 10 Hz, future-dated; /amcl_pose after each filter update
    sent = [(t, m.transforms[0]) for t, m in feed.tf if t > t0 + 1]
    assert len(sent) >= 10 * 13
    assert all((ts.header.frame_id, ts.child_frame_id) == ("map", "odom") for _, ts in sent)
    t, ts = sent[-1]
    assert _seconds(ts.header.stamp) == pytest.approx(t + TRANSFORM_TOLERANCE, abs=0.06)
    stamps = [_seconds(ts.header.stamp) for _, ts in sent]
    assert stamps == sorted(stamps)
    buf = TransformBuffer()
    buf.add_message(ts)
    buf.set("odom", "base_footprint", planar(*s.odom), s.t)
    x, y, yaw = pose2d(buf.lookup("map", "base_footprint"))
    assert math.hypot(x - s.truth[0], y - s.truth[1]) < 0.1
    assert abs(math.remainder(yaw - s.truth[2], 2 * math.pi)) < 0.05
    assert 5 < len([p for p in feed.poses if _seconds(p.header.stamp) > t0 + 1]) < 100
    last = feed.poses[-1].pose.pose.position
    assert math.hypot(last.x - s.truth[0], last.y - s.truth[1]) < 0.1
    assert feed.poses[-1].header.frame_id == "map"
    assert np.asarray(feed.poses[-1].pose.covariance).reshape(6, 6)[0, 0] > 0
    mo = loc.map_to_odom
    assert mo != (0.0, 0.0, 0.0)
    # forget it: global localisation from the next scan
    st = rt.call("localise_globally")
    assert st["state"] == "uncertain" and st["pose"] is None
    unknown = np.asarray(feed.poses[-1].pose.covariance).reshape(6, 6)  # replaces the latched sure one
    assert unknown[0, 0] > 1 and unknown[5, 5] > 1
    s = feed.run(6)
    st = rt.call("localisation_status")
    assert st["state"] == "localised"
    assert math.hypot(st["pose"][0] - s.truth[0], st["pose"][1] - s.truth[1]) < 0.1


def _seconds(stamp):
    return stamp.sec + stamp.nanosec * 1e-9


def test_localiser_reads_the_laser_mounting_from_tf_static(rt):
    occ = read_map_yaml(FIXTURES / "house.yaml")
    world = SyntheticWorld(occ, world_boxes(FIXTURES / "house_world.yaml"), seed=3)
    loc = rt.add_subsystem("localiser", Localiser, seed=1, initial_pose=world.truth)
    feed = Feed(rt, world)
    feed.map.publish(occ.to_msg())
    feed.run(0.5)
    assert loc.amcl.params.laser_pose == LASER_POSE  # the URDF's, until /tf_static says
    mount = (-0.1, 0.02, 0.0)
    feed.tf_static.publish(
        TFMessage(
            transforms=[
                planar_transform("base_footprint", "base_link", (0.0, 0.0, 0.0), 0.0),
                planar_transform("base_link", "base_scan", mount, 0.0),
            ]
        )
    )
    feed.run(0.5)
    assert loc.amcl.params.laser_pose == pytest.approx(mount)
    assert feed.tf, "map -> odom went out from the initial pose on"


def test_without_an_initial_pose_the_localiser_localises_globally(rt):
    occ = read_map_yaml(FIXTURES / "house.yaml")
    world = SyntheticWorld(occ, world_boxes(FIXTURES / "house_world.yaml"), seed=5)
    rt.add_subsystem("localiser", Localiser, seed=2, global_after=1.0)
    feed = Feed(rt, world)
    feed.map.publish(occ.to_msg())
    feed.run(0.8)
    assert rt.call("localisation_status")["state"] == "uninitialised" and not feed.tf
    s = feed.run(10)
    st = rt.call("localisation_status")
    assert st["state"] == "localised"
    assert math.hypot(st["pose"][0] - s.truth[0], st["pose"][1] - s.truth[1]) < 0.1
    assert feed.tf, "map -> odom goes out once the global localisation converged"


def _transform_error(feed, s):
    """Position and heading error of map -> base_footprint from the newest map -> odom on
    /tf and the odometry of sample s."""
    buf = TransformBuffer()
    buf.add_message(feed.tf[-1][1].transforms[0])
    buf.set("odom", "base_footprint", planar(*s.odom), s.t)
    x, y, yaw = pose2d(buf.lookup("map", "base_footprint"))
    return math.hypot(x - s.truth[0], y - s.truth[1]), abs(math.remainder(yaw - s.truth[2], 2 * math.pi))


@pytest.mark.parametrize("start", [0, 6])
def test_a_robot_standing_away_from_the_origin_is_localised_where_it_stands(rt, start):
    """Rehearsal on the real robot, started with no /initialpose at (1, 1, 0): the
    localiser said "localised" (std 4 cm) at (0.00, 0.00, -0.15), the odometry's origin,
    and put that on /tf. The global localisation had converged to (1.04, 1.00), but the
    local hold (LocalHold: keep map -> odom while the robot stands still) kept the
    identity map -> odom it had before anything was known. Here the robot stands at a
    tour point of the house, its odometry at (0, 0, 0): every sample that says localised
    must be right, on localisation_status and on /tf, and it must say so in the end."""
    occ = read_map_yaml(FIXTURES / "house.yaml")
    world = SyntheticWorld(
        occ, world_boxes(FIXTURES / "house_world.yaml"), seed=start, start=start, reverse=False, speed=0.0, turn=0.0
    )
    assert math.hypot(*world.truth[:2]) > 1.0
    rt.add_subsystem("localiser", Localiser, seed=start, global_after=1.0)
    feed = Feed(rt, world)
    feed.map.publish(occ.to_msg())
    unknown = []  # (pose, /amcl_pose count) while not localised
    for _ in range(40):
        s = feed.run(0.2)
        st = rt.call("localisation_status")
        if st["state"] != "localised":
            assert not feed.tf
            unknown.append((st["pose"], len(feed.poses)))
            continue
        assert math.hypot(st["pose"][0] - s.truth[0], st["pose"][1] - s.truth[1]) < 0.1
        assert abs(math.remainder(st["pose"][2] - s.truth[2], 2 * math.pi)) < 0.1
        e, eyaw = _transform_error(feed, s)
        assert e < 0.1 and eyaw < 0.1
    assert st["state"] == "localised" and feed.poses
    assert unknown and all(u == (None, 0) for u in unknown)  # until then it said it did not know


def test_in_a_symmetric_room_the_localiser_says_it_does_not_know(rt):
    """An empty rectangular room: the robot's pose and the pose turned half round about
    the centre fit every scan alike. Not localised, nothing on /tf or /amcl_pose, and
    require_localised refuses."""
    from actors.navigation import Navigation
    from bt_engine import ActorError
    from tests.test_navstack_localisation import rectangular_room

    room, walls = rectangular_room()
    world = SyntheticWorld(room, walls, [(0.0, 0.0), (1.0, 0.0)], seed=1, unmapped=0, speed=0.0, turn=0.0)
    world.teleport((1.1, 0.6, 0.4))
    rt.add_subsystem("localiser", Localiser, seed=1, global_after=1.0)
    rt.add_subsystem("navigation", Navigation)
    feed = Feed(rt, world)
    feed.map.publish(room.to_msg())
    for _ in range(40):
        feed.run(0.2)
        assert rt.call("localisation_status")["state"] != "localised"
    st = rt.call("localisation_status")
    assert st["state"] == "uncertain" and st["ambiguous"] and st["pose"] is None
    assert not feed.tf and not feed.poses
    with pytest.raises(ActorError, match="delocalised: no /amcl_pose received"):
        rt.call("require_localised", wait=0.5)


def test_the_smoother_removes_the_estimates_jitter_and_follows_a_relocalisation():
    from navstack.smoothing import PoseSmoother

    rng = np.random.default_rng(0)
    sm = PoseSmoother()
    raw_jumps, smooth_jumps, errors = [], [], []
    last_raw = last = None
    for k in range(200):  # a straight drive, an update every 0.25 m
        truth = (0.25 * k, 1.0, 0.0)
        odom = (0.25 * k * 1.01, 0.0, 0.0)  # the odometry runs 1 % long
        est = (truth[0] + rng.normal(0, 0.015), truth[1] + rng.normal(0, 0.015), rng.normal(0, 0.005))
        out = sm.update(est, odom)
        if last is not None:
            raw_jumps.append(math.hypot(est[0] - last_raw[0] - 0.25, est[1] - last_raw[1]))
            smooth_jumps.append(math.hypot(out[0] - last[0] - 0.25, out[1] - last[1]))
        last_raw, last = est, out
        errors.append(math.hypot(out[0] - truth[0], out[1] - truth[1]))
    assert np.median(smooth_jumps) < 0.5 * np.median(raw_jumps)
    assert np.sqrt(np.mean(np.square(errors[20:]))) < 0.015  # and it follows the odometry's drift
    # a relocalisation (a correction drift cannot explain) is taken at once
    out = sm.update((truth[0] + 1.0, 1.0, 0.0), (0.25 * 200 * 1.01, 0.0, 0.0))
    assert out == pytest.approx((truth[0] + 1.0, 1.0, 0.0)) and sm.resets == 1


def test_the_local_hold_keeps_the_frame_until_the_robot_has_moved_away():
    from navstack.smoothing import LocalHold

    hold = LocalHold(radius=0.5)
    assert not hold.on_odometry(0.0, (0.0, 0.0, 0.0)) and not hold.holding
    assert not hold.on_odometry(0.1, (0.0, 0.0, 0.0)) and hold.holding  # it stands still
    for k in range(1, 6):  # manoeuvres near by
        assert not hold.on_odometry(0.1 + k, (0.09 * k, 0.0, 0.1 * k)) and hold.holding
    assert hold.on_odometry(7.0, (0.6, 0.0, 0.0)) and not hold.holding  # left: released once
    assert not hold.on_odometry(7.1, (0.62, 0.0, 0.0)) and not hold.holding  # driving on
    assert not hold.on_odometry(9.0, (0.62, 0.0, 0.0)) and hold.holding  # stopped again
    released = [hold.on_odometry(9.0 + 0.1 * k, (0.62, 0.0, 0.15 * k)) for k in range(1, 6)]
    assert released == [False] * 4 + [True]  # turned 0.75 rad
