"""The localiser on the runtime's bus: AMCL's topics and two actors.

Subscribed: ``/map`` (nav_msgs/OccupancyGrid), ``/odom`` (nav_msgs/Odometry), ``/scan``
(sensor_msgs/LaserScan, sensor-data QoS), ``/initialpose``
(geometry_msgs/PoseWithCovarianceStamped). Published: ``/amcl_pose``
(PoseWithCovarianceStamped, map frame, latched): after every filter update, as AMCL, and
(``pose_rate``, 10 Hz by default) the odometry-predicted pose between updates, since the
map -> odom transform is not on /tf yet.

NEXT STEP: publish map -> odom on /tf once tf2_msgs is available; :attr:`Localiser.map_to_odom`
already holds it (``(x, y, yaw)``, valid at the last filter update's odometry), computed
as AMCL does: the estimate composed with the inverse of the odometry pose.

The laser's pose on the base (``laser_pose``) is the URDF's base_footprint -> base_scan
until /tf_static carries it. Each scan is paired with the odometry pose interpolated at
its stamp. All the work runs in the bus callbacks (a few ms a filter update; a global
relocalisation's search about 0.2 s).
"""
from __future__ import annotations

import bisect
import math
import threading
import zlib
from collections import deque
from dataclasses import fields

import numpy as np
from geometry_msgs.msg import PoseWithCovarianceStamped
from nav_msgs.msg import OccupancyGrid, Odometry
from sensor_msgs.msg import LaserScan

from bt_engine import SubSystem, actor

from .amcl import LOCALISED, Amcl, AmclParams, Scan
from .likelihood_field import LaserModelParams
from .map_io import OccupancyMap
from .particle_filter import FilterParams

#: base_footprint -> base_scan in sim/models/mobile_manipulator.urdf (x, y, yaw)
LASER_POSE = (-0.15, 0.0, 0.0)
#: AMCL's default initial covariance (0.5 m, 0.5 m, pi/12 rad standard deviations)
INITIAL_COV = np.diag([0.5 ** 2, 0.5 ** 2, (math.pi / 12) ** 2])


def _yaw(q) -> float:
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def _seconds(stamp) -> float:
    return stamp.sec + stamp.nanosec * 1e-9


def _interpolate(a, b, f: float):
    dyaw = math.remainder(b[2] - a[2], 2 * math.pi)
    return (a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]), math.remainder(a[2] + f * dyaw, 2 * math.pi))


def split_params(params: dict | None):
    """AmclParams, FilterParams and LaserModelParams from one flat dict of overrides."""
    parts = [AmclParams(laser_pose=LASER_POSE), FilterParams(), LaserModelParams()]
    for key, value in (params or {}).items():
        for p in parts:
            if key in {f.name for f in fields(p)}:
                setattr(p, key, value)
                break
        else:
            raise ValueError(f"unknown localiser parameter {key!r}")
    return parts


class Localiser(SubSystem):
    """Adaptive Monte Carlo localisation on /map from /scan and /odom (AMCL's stand-in).

    Args:
        params: overrides of AmclParams, FilterParams and LaserModelParams by name
        seed: the filter's random seed
        initial_pose: (x, y, yaw) to start from (nav2's set_initial_pose); None: wait for
            /initialpose or localise_globally
        pose_rate: [Hz] publish the odometry-predicted pose on /amcl_pose this often
            between filter updates (0: only after updates, as AMCL)
    """

    def __init__(self, params: dict | None = None, seed: int = 0,
                 initial_pose: tuple | None = None, pose_rate: float = 10.0) -> None:
        super().__init__()
        self._params = split_params(params)
        self._seed = seed
        self._initial_pose = initial_pose
        self._pose_period = 1.0 / pose_rate if pose_rate > 0 else math.inf
        self._lock = threading.RLock()
        self.amcl: Amcl | None = None
        self._map_key = None
        self._now = 0.0
        self._odom = deque(maxlen=200)          # (t, (x, y, yaw)), by stamp
        self._last_pub = -math.inf
        self._pending_initial = None            # an /initialpose before the map
        self.map_to_odom = (0.0, 0.0, 0.0)
        bus = self.runtime.bus
        self._pub = bus.publisher("/amcl_pose", PoseWithCovarianceStamped, "latched")
        self._subs = [
            bus.subscribe("/map", OccupancyGrid, self._on_map, "latched"),
            bus.subscribe("/odom", Odometry, self._on_odom, 50),
            bus.subscribe("/scan", LaserScan, self._on_scan, "sensor"),
            bus.subscribe("/initialpose", PoseWithCovarianceStamped, self._on_initial_pose, 10),
        ]

    def close(self) -> None:
        """Unsubscribe (the runtime's bus closes them too)."""
        for s in self._subs:
            s.close()
        self._subs = []

    # -- bus callbacks --------------------------------------------------------------------
    def _on_map(self, msg: OccupancyGrid) -> None:
        info = msg.info
        key = (info.width, info.height, info.resolution, info.origin.position.x, info.origin.position.y,
               zlib.crc32(np.asarray(msg.data, dtype=np.int8).tobytes()))
        with self._lock:
            if key == self._map_key:
                return                     # the same map, republished
            self._map_key = key
            occ = OccupancyMap.from_msg(msg)
            if self.amcl is None:
                ap, fp, lp = self._params
                self.amcl = Amcl(occ, ap, fp, lp, seed=self._seed, clock=lambda: self._now)
                if self._odom:
                    self.amcl.on_odometry(self._odom[-1][1])
                start = self._pending_initial or (
                    (tuple(self._initial_pose), INITIAL_COV) if self._initial_pose is not None else None)
                if start is not None:
                    self.amcl.initialise(*start)
            else:
                self.amcl.set_map(occ)

    def _on_odom(self, msg: Odometry) -> None:
        p = msg.pose.pose
        pose = (p.position.x, p.position.y, _yaw(p.orientation))
        t = _seconds(msg.header.stamp)
        with self._lock:
            if self._odom and t < self._odom[-1][0]:
                self._odom.clear()         # time went backwards (a new episode)
            self._odom.append((t, pose))
            self._now = max(self._now, t)
            if self.amcl is None:
                return
            self.amcl.on_odometry(pose)
            if self.amcl.status.state == LOCALISED or self.amcl.status.updates:
                if t - self._last_pub >= self._pose_period - 1e-9:
                    self._publish(msg.header.stamp, self.amcl.pose(pose))

    def odom_at(self, t: float):
        """The odometry pose interpolated at time t (the newest one outside the history)."""
        if not self._odom:
            return None
        times = [s for s, _ in self._odom]
        i = bisect.bisect_left(times, t)
        if i <= 0:
            return self._odom[0][1]
        if i >= len(times):
            return self._odom[-1][1]
        (t0, a), (t1, b) = self._odom[i - 1], self._odom[i]
        return _interpolate(a, b, (t - t0) / (t1 - t0) if t1 > t0 else 1.0)

    def _on_scan(self, msg: LaserScan) -> None:
        with self._lock:
            if self.amcl is None:
                return
            t = _seconds(msg.header.stamp)
            odom = self.odom_at(t)
            if odom is None:
                return
            self._now = max(self._now, t)
            if self.amcl.on_scan(Scan.from_msg(msg), odom):
                self.map_to_odom = self.amcl.map_to_odom   # NEXT STEP: on /tf
                self._publish(msg.header.stamp, self.amcl.pose(odom))

    def _on_initial_pose(self, msg: PoseWithCovarianceStamped) -> None:
        p = msg.pose.pose
        pose = (p.position.x, p.position.y, _yaw(p.orientation))
        c = np.asarray(msg.pose.covariance, float).reshape(6, 6)
        cov = c[np.ix_([0, 1, 5], [0, 1, 5])]
        if not np.any(cov):
            cov = INITIAL_COV
        with self._lock:
            if self.amcl is None:
                self._pending_initial = (pose, cov)
            else:
                self.amcl.initialise(pose, cov)

    def _publish(self, stamp, pose) -> None:
        msg = PoseWithCovarianceStamped()
        msg.header.stamp = stamp
        msg.header.frame_id = "map"
        msg.pose.pose.position.x, msg.pose.pose.position.y = float(pose[0]), float(pose[1])
        msg.pose.pose.orientation.z = math.sin(pose[2] / 2)
        msg.pose.pose.orientation.w = math.cos(pose[2] / 2)
        cov = np.zeros((6, 6))
        cov[np.ix_([0, 1, 5], [0, 1, 5])] = self.amcl.covariance()
        msg.pose.covariance = cov.ravel().tolist()
        self._pub.publish(msg)
        self._last_pub = _seconds(stamp)

    # -- actors -------------------------------------------------------------------------------
    @actor
    def localise_globally(self, wait: float = 0.0) -> dict:
        """Forget the pose and find the robot on the whole map from the next scan (the
        reinitialize_global_localization service). Returns the localisation status.

        Args:
            wait: wait up to this long for the robot to be localised [s]; 0: return at once
        """
        with self._lock:
            if self.amcl is None:
                raise RuntimeError("no map received on /map yet")
            self.amcl.global_localisation()
        if wait > 0:
            end = self.runtime.now() + wait
            while self.runtime.now() < end:
                self.run_actor("sleep", 0.2)
                with self._lock:
                    if self.amcl.status.state == LOCALISED and self.amcl.status.updates:
                        break
        return self.localisation_status()

    @actor
    def localisation_status(self) -> dict:
        """How the localisation is doing.

        Returns:
            state (uninitialised, uncertain, localised or lost), pose [x m, y m, yaw rad]
            in the map frame now, score (share of beams that fit the map, smoothed),
            std_xy [m] and std_yaw [rad] of the estimate, particles, clusters, updates,
            recoveries (times lost was declared), last_update_ms
        """
        with self._lock:
            if self.amcl is None:
                return {"state": "uninitialised", "pose": None, "map": False}
            st = self.amcl.status.as_dict()
            st.pop("last_lost", None)
            st["pose"] = [round(float(v), 4) for v in self.amcl.pose()]
            st["map"] = True
            return {k: (float(v) if isinstance(v, (np.floating,)) else v) for k, v in st.items()}
