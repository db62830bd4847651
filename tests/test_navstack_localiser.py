"""navstack.localiser: the localiser as a SubSystem on the local bus, fed with the
synthetic house's /map, /odom and /scan messages."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from geometry_msgs.msg import PoseWithCovarianceStamped
from nav_msgs.msg import OccupancyGrid, Odometry
from sensor_msgs.msg import LaserScan

from navstack.localiser import LASER_POSE, Localiser
from navstack.map_io import read_map_yaml
from navstack.synthetic import LaserSpec, SyntheticWorld, world_boxes

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
        self.poses = []
        self.sub = bus.subscribe("/amcl_pose", PoseWithCovarianceStamped, self.poses.append)

    def run(self, seconds):
        end = self.world.t + seconds
        while self.world.t < end - 1e-9:
            s = self.world.step()
            self.odom.publish(odom_msg(s))
            if s.scan is not None:
                self.scan.publish(scan_msg(s))
            self.rt.run_on_hub(lambda: None)     # let the hub deliver them
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
    cov[0, 0] = cov[1, 1] = 0.2 ** 2
    cov[5, 5] = 0.1 ** 2
    init.pose.covariance = cov.ravel().tolist()
    feed.initial.publish(init)
    feed.map.publish(occ.to_msg())                # republished: not rebuilt
    t0 = world.t
    s = feed.run(15)
    st = rt.call("localisation_status")
    assert st["state"] == "localised" and st["updates"] > 5
    assert math.hypot(st["pose"][0] - s.truth[0], st["pose"][1] - s.truth[1]) < 0.1
    # /amcl_pose at >= 10 Hz, the last one right
    stamps = [p.header.stamp.sec + p.header.stamp.nanosec * 1e-9 for p in feed.poses]
    assert len([t for t in stamps if t > t0 + 1]) >= 10 * 13
    last = feed.poses[-1].pose.pose.position
    assert math.hypot(last.x - s.truth[0], last.y - s.truth[1]) < 0.1
    assert feed.poses[-1].header.frame_id == "map"
    assert np.asarray(feed.poses[-1].pose.covariance).reshape(6, 6)[0, 0] > 0
    mo = loc.map_to_odom
    assert mo != (0.0, 0.0, 0.0)
    # forget it: global localisation from the next scan
    st = rt.call("localise_globally")
    assert st["state"] == "uncertain"
    s = feed.run(6)
    st = rt.call("localisation_status")
    assert st["state"] == "localised"
    assert math.hypot(st["pose"][0] - s.truth[0], st["pose"][1] - s.truth[1]) < 0.1
