"""Mapping on the bus (slam_toolbox's stand-in): ``/scan`` and ``/odom`` in, ``/map`` and
map -> odom out.

Inputs: ``/scan`` (sensor QoS), ``/odom`` turned by the IMU's heading
(:mod:`navstack.gyro_odometry`), ``/tf_static`` (the laser's mounting), and
``/initialpose`` before the first scan (where the map frame puts the robot at the start;
slam_toolbox's ``map_start_pose``; default the origin).

Outputs: ``/map`` (``nav_msgs/OccupancyGrid``, transient local, every ``map_period``
seconds of scan time, map_server's trinary values) and map -> odom on ``/tf`` after each
scan, stamped ``transform_tolerance`` ahead as AMCL does.

The mapping itself is :class:`navstack.slam.Slam`; this node only feeds it and publishes.
:class:`navstack.stack.NavStack` makes it (``start_mapping``) and offers its actors.
"""

from __future__ import annotations

import math
import threading
from pathlib import Path

import numpy as np
from geometry_msgs.msg import PoseWithCovarianceStamped
from nav_msgs.msg import OccupancyGrid, Odometry
from sensor_msgs.msg import Imu, LaserScan
from tf2_msgs.msg import TFMessage

from bt_engine import ActorbtError, SubSystem

from .gyro_odometry import GyroOdometry
from .localiser import IMU_TOPIC
from .map_io import write_map_yaml, write_trajectory_tum
from .odometry import OdomHistory, seconds, yaw_of
from .slam import Slam, SlamParams
from .tf import TF, TfListener, TransformError, planar_transform

BASE_FRAME = "base_footprint"
MAP_PERIOD = 1.0  # [s] between /map messages
TRANSFORM_TOLERANCE = 0.2  # [s] map -> odom is stamped this far ahead


class MappingError(ActorbtError):
    """Nothing mapped yet, or the map could not be written."""


class Mapper(SubSystem):
    """Builds the map from /scan and /odom and publishes it; see the module docstring.

    Args:
        start_pose: (x, y, yaw) of the robot in the map frame at the first scan (an
            /initialpose before it overrides this)
        map_period: [s] of scan time between /map messages
        slam: overrides of :class:`navstack.slam.SlamParams` by name
        imu_topic: the IMU whose heading turns the odometry; None: the wheels' alone
    """

    def __init__(
        self,
        start_pose: tuple = (0.0, 0.0, 0.0),
        map_period: float = MAP_PERIOD,
        slam: dict | None = None,
        imu_topic: str | None = IMU_TOPIC,
    ) -> None:
        super().__init__()
        self._start = tuple(float(v) for v in start_pose)
        self._period = float(map_period)
        self._slam_args = dict(slam or {})
        self._lock = threading.RLock()
        self.slam: Slam | None = None
        self._odom = OdomHistory()  # fused poses (see GyroOdometry)
        self.odometry = GyroOdometry()
        self._map_sent = -math.inf
        self._frozen = False
        self.scans = 0
        bus = self.runtime.bus
        self._map_pub = bus.publisher("/map", OccupancyGrid, "latched")
        self._tf_pub = bus.publisher(TF, TFMessage, 100)
        self.tf = TfListener(bus, children=())  # /tf_static only: the laser's mounting
        self._subs = [
            bus.subscribe("/odom", Odometry, self._on_odom, 50),
            bus.subscribe("/scan", LaserScan, self._on_scan, "sensor"),
            bus.subscribe("/initialpose", PoseWithCovarianceStamped, self._on_initial_pose, 10),
        ]
        if imu_topic:
            self._subs.append(bus.subscribe(imu_topic, Imu, self._on_imu, 100))

    def close(self) -> None:
        for s in self._subs:
            s.close()
        self._subs = []
        self.tf.close()

    # -- bus callbacks --------------------------------------------------------------------
    def _on_imu(self, msg: Imu) -> None:
        with self._lock:
            self.odometry.on_imu(seconds(msg.header.stamp), yaw_of(msg.orientation))

    def _on_odom(self, msg: Odometry) -> None:
        p = msg.pose.pose
        t = seconds(msg.header.stamp)
        with self._lock:
            self._odom.add(t, self.odometry.fuse(t, (p.position.x, p.position.y, yaw_of(p.orientation))))

    def _on_initial_pose(self, msg: PoseWithCovarianceStamped) -> None:
        p = msg.pose.pose
        with self._lock:
            if self.slam is None:  # the map frame is fixed by the first scan
                self._start = (p.position.x, p.position.y, yaw_of(p.orientation))

    def _on_scan(self, msg: LaserScan) -> None:
        with self._lock:
            if self._frozen:
                return
            t = seconds(msg.header.stamp)
            odom = self._odom.at(t)
            if odom is None:
                return
            if self.slam is None:
                try:
                    laser = self.tf.pose(BASE_FRAME, msg.header.frame_id)
                except TransformError:
                    return  # wait for /tf_static
                self.slam = Slam(SlamParams(**{**self._slam_args, "sensor_offset": laser, "initial_pose": self._start}))
                self._map_sent = t  # the first map after a period of scans: one scan
                #                        alone leaves the floor unknown (a free cell needs a few)
            ranges = np.asarray(msg.ranges, dtype=float)
            angles = msg.angle_min + msg.angle_increment * np.arange(ranges.size)
            self.slam.add(
                odom, ranges, angles, msg.range_max, t, range_min=msg.range_min, gyro=self.odometry.gyro_heading
            )
            self.scans += 1
            self._send_tf(t)
            if t - self._map_sent >= self._period:
                self.publish_map(t)

    def _send_tf(self, t: float) -> None:
        assert self.slam is not None  # sent after a scan went into it
        self._tf_pub.publish(
            TFMessage(
                transforms=[
                    planar_transform(
                        "map", "odom", self.odometry.map_to_wheel_odom(self.slam.map_to_odom()), t + TRANSFORM_TOLERANCE
                    )
                ]
            )
        )

    def map_msg(self) -> OccupancyGrid | None:
        """The map so far as a nav_msgs/OccupancyGrid (None before the first scan)."""
        with self._lock:
            return None if self.slam is None else self.slam.map().to_msg("map")

    def publish_map(self, t: float | None = None) -> None:
        with self._lock:
            if self.slam is None:
                return
            msg = self.slam.map(fresh=t is None).to_msg("map")  # while mapping: rebuilt now and then
            if t is not None:
                sec, nsec = divmod(int(round(t * 1e9)), 1_000_000_000)
                msg.header.stamp.sec, msg.header.stamp.nanosec = sec, nsec
                self._map_sent = t
            self._map_pub.publish(msg)

    # -- what navstack's actors do (NavStack.save_map, mapping_status, localise_on_map) ----
    def save(self, path: str) -> dict:
        """Write the map as map_server YAML + PGM (nav2's map_saver) and, beside them, the
        keyframe trajectory (``<name>.tum``, TUM format), and return the files, the map's
        size and the trajectory's length.

        Args:
            path: the YAML file to write; the PGM goes beside it
        """
        with self._lock:
            if self.slam is None:
                raise MappingError("nothing mapped yet: no scan has arrived")
            occ = self.slam.map()
            traj = self.slam.trajectory()
        out = Path(path)
        if out.suffix not in (".yaml", ".yml"):
            out = out / "map.yaml"
        try:
            out.parent.mkdir(parents=True, exist_ok=True)
            yaml_path, pgm_path = write_map_yaml(occ, out)
            tum_path = write_trajectory_tum(traj, yaml_path.with_suffix(".tum"))
        except OSError as e:
            raise MappingError(f"cannot write the map to {out}: {e}") from None
        length = sum(math.dist(a[1:3], b[1:3]) for a, b in zip(traj, traj[1:]))
        return {
            "yaml": str(yaml_path),
            "pgm": str(pgm_path),
            "trajectory": str(tum_path),
            "width": occ.width,
            "height": occ.height,
            "resolution": occ.resolution,
            "keyframes": len(traj),
            "travelled": round(length, 2),
        }

    def status(self) -> dict:
        """How the mapping is doing: scans taken, keyframes, loop closures, the pose
        [x m, y m, yaw rad] in the map frame, and whether it is frozen."""
        with self._lock:
            if self.slam is None:
                return {"scans": self.scans, "keyframes": 0, "loop_closures": 0, "pose": None, "frozen": self._frozen}
            return {
                "scans": self.scans,
                "keyframes": len(self.slam.trajectory()),
                "loop_closures": int(self.slam.loop_closures),
                "pose": [round(float(v), 4) for v in self.slam.pose()],
                "frozen": self._frozen,
            }

    def stop(self) -> list[float]:
        """Freeze the map: no more scans go in, /map keeps the last one (as map_server
        would serve it) and map -> odom is no longer sent. Returns the robot's map pose
        [x m, y m, yaw rad] at that moment, for a localiser to start from."""
        with self._lock:
            if self.slam is None:
                raise MappingError("nothing mapped yet: no scan has arrived")
            self._frozen = True
            pose = self.slam.pose()
        self.publish_map(None)
        return [float(v) for v in pose]
