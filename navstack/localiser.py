"""The localiser on the runtime's bus: AMCL's topics and two actors.

Subscribed: ``/map`` (nav_msgs/OccupancyGrid), ``/odom`` (nav_msgs/Odometry), the IMU
(``/imu_broadcaster/imu``, sensor_msgs/Imu: the heading between odometry poses, see
:mod:`navstack.gyro_odometry`), ``/scan`` (sensor_msgs/LaserScan, sensor-data QoS),
``/initialpose`` (geometry_msgs/PoseWithCovarianceStamped), ``/tf_static`` (the laser's
mounting). The filter runs on the wheel odometry turned by the gyro; what goes on /tf is
map -> the wheels' odom frame.

Published:

* ``/tf`` (tf2_msgs/TFMessage): **map -> odom**, as AMCL: the estimate composed with the
  inverse of the odometry pose at the last filter update. It goes out after every filter
  update and, in between, on the odometry's messages at most ``tf_rate`` (20 Hz) times a
  second (15 Hz on the simulator's 30 Hz odometry: every second message), each time
  stamped ``transform_tolerance`` (0.2 s) into the future, as AMCL future-dates it: a
  lookup of map -> base_footprint "now" (the odometry's newest stamp) then never has to
  wait for the localiser, and a lookup at a past stamp (a camera image's) uses the
  correction that was current ``transform_tolerance`` before it. AMCL's default is 1 s;
  0.2 s covers three republication periods on one machine and keeps that lag short, so a
  correction reaches the camera's poses a fifth of a second after the base's pose. The
  stamps only grow (a filter update never goes out stamped before the last republication).
* ``/amcl_pose`` (PoseWithCovarianceStamped, map frame, transient local): after every
  filter update, as AMCL (``pose_rate`` > 0 adds the odometry-predicted pose in between).

Both carry the filter's estimate smoothed (``smoothing``, :mod:`navstack.smoothing`): a
Kalman filter with the odometry as motion and each estimate as a measurement, so that
map-frame poses do not jump by the estimate's update-to-update jitter (~1 cm) while the
robot measures an object and drives up to it. While the filter converges or relocalises,
and on any correction larger than drift explains, the estimate goes out as it is. And
map -> odom is held while the robot manoeuvres within ``hold_radius`` of where it last
stood still (:class:`navstack.smoothing.LocalHold`): a look, an approach and a grasp
then see one rigid map frame, moving with the odometry alone; the corrections made
meanwhile are applied once the robot has left (this is not AMCL's behaviour; on a robot
with AMCL, the mission has to cope with such jumps by measuring the object again).

Nothing is on /tf or /amcl_pose before the localiser knows where the robot is (AMCL
publishes no pose before it has an initial one): from an ``/initialpose`` (RViz's "2D
Pose Estimate"; or ``initial_pose``, AMCL's ``set_initial_pose``) at once, or from a
global localisation once it has converged. Without either, ``global_after`` seconds
(odometry time) after the first scan with a map the localiser localises globally from
the scan (None: wait for /initialpose for ever, as AMCL does), and runs a filter update
on every scan (AMCL's no-motion update) until it has converged, since nothing moves the
robot before it knows where it is. Such a global localisation converges only where the
scan fits no other place nearly as well (:meth:`navstack.amcl.Amcl._confirm_unique`):
in a symmetric room the localiser stays uncertain, and says so, rather than pick one of
the look-alike poses. Its pose is taken at once, neither smoothed nor held. A
``localise_globally`` forgets the pose the same way until the search has converged.

The laser's pose on the base (``laser_pose``) is read from /tf_static (base_footprint ->
the scan's frame) once it is there, and is the URDF's base_footprint -> base_scan
(:data:`LASER_POSE`) until then. Each scan is paired with the odometry pose interpolated
at its stamp. All the work runs in the bus callbacks (a few ms a filter update; a global
relocalisation's search about 0.2 s).
"""

from __future__ import annotations

import math
import threading
import zlib
from dataclasses import fields

import numpy as np
from builtin_interfaces.msg import Time
from geometry_msgs.msg import PoseWithCovarianceStamped
from nav_msgs.msg import OccupancyGrid, Odometry
from sensor_msgs.msg import Imu, LaserScan
from tf2_msgs.msg import TFMessage

from bt_engine import SubSystem, actor
from bt_engine.bus import close_publishers

from .amcl import LOCALISED, UNINITIALISED, Amcl, AmclParams, Scan, compose
from .likelihood_field import LaserModelParams
from .map_io import OccupancyMap
from .particle_filter import FilterParams
from .smoothing import LocalHold, PoseSmoother, SmootherParams
from .gyro_odometry import GyroOdometry
from .odometry import OdomHistory, Pose
from .odometry import seconds as _seconds
from .odometry import yaw_of as _yaw
from .tf import TF, TfListener, TransformError, planar_transform, to_stamp

#: base_footprint -> base_scan in sim/models/mobile_manipulator.urdf (x, y, yaw)
LASER_POSE = (-0.15, 0.0, 0.0)
#: the pose handed over by the mapper: as sure as its scan matching
RESUME_COV = np.diag([0.05**2, 0.05**2, 0.03**2])
#: AMCL's default initial covariance (0.5 m, 0.5 m, pi/12 rad standard deviations)
INITIAL_COV = np.diag([0.5**2, 0.5**2, (math.pi / 12) ** 2])
#: the covariance /amcl_pose carries when the pose is forgotten (10 m, pi rad)
UNKNOWN_COV = np.diag([10.0**2, 10.0**2, math.pi**2])
#: [s] how far map -> odom is stamped into the future (AMCL's transform_tolerance)
TRANSFORM_TOLERANCE = 0.2
#: [Hz] at most this often map -> odom goes out between filter updates
TF_RATE = 20.0
GLOBAL_FRAME, ODOM_FRAME, BASE_FRAME = "map", "odom", "base_footprint"
#: the OpenCR's IMU as ROBOTIS' ros2_control bring-up publishes it (imu_broadcaster's ~/imu)
IMU_TOPIC = "/imu_broadcaster/imu"


def split_params(params: dict | None) -> tuple[AmclParams, FilterParams, LaserModelParams]:
    """AmclParams, FilterParams and LaserModelParams from one flat dict of overrides."""
    parts = (AmclParams(laser_pose=LASER_POSE), FilterParams(), LaserModelParams())
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
        tf_rate: [Hz] republish map -> odom on /tf at most this often between filter updates
        transform_tolerance: [s] map -> odom is stamped this far into the future
        global_after: [s] of odometry time after the first scan with a map, with no
            initial pose yet: localise globally from the scan (None: never by itself)
        smoothing: smooth the published pose (:mod:`navstack.smoothing`; a dict overrides
            SmootherParams); False: publish each filter update's estimate as it is (AMCL)
        hold_radius: [m] keep map -> odom while the robot manoeuvres this near where it
            last stood still (:class:`navstack.smoothing.LocalHold`); 0: never
        imu_topic: the IMU whose heading turns the odometry; None: the wheels' alone
    """

    def __init__(
        self,
        params: dict | None = None,
        seed: int = 0,
        initial_pose: tuple | None = None,
        pose_rate: float = 0.0,
        tf_rate: float = TF_RATE,
        transform_tolerance: float = TRANSFORM_TOLERANCE,
        global_after: float | None = None,
        smoothing: bool | dict = True,
        hold_radius: float = 0.75,
        imu_topic: str | None = IMU_TOPIC,
    ) -> None:
        super().__init__()
        self.hold = LocalHold(hold_radius) if hold_radius > 0 else None
        self._target: Pose | None = None  # the newest map -> odom, held or not
        self.smoother = (
            None
            if smoothing is False
            else PoseSmoother(SmootherParams(**smoothing) if isinstance(smoothing, dict) else None)
        )
        self._params = split_params(params)
        self._seed = seed
        self._initial_pose = initial_pose
        self._pose_period = 1.0 / pose_rate if pose_rate > 0 else math.inf
        self._tf_period = 1.0 / tf_rate if tf_rate > 0 else math.inf
        self._tolerance = float(transform_tolerance)
        self._global_after = global_after
        self._lock = threading.RLock()
        self.amcl: Amcl | None = None
        self._map_key: tuple[int, int, float, float, float, int] | None = None  # size, resolution, origin, data
        self._now = 0.0
        self._odom = OdomHistory()  # (t, fused (x, y, yaw)), by stamp
        self.odometry = GyroOdometry()  # the wheels' poses turned by the gyro
        self._last_pub = -math.inf
        self._pending_initial: tuple[Pose, np.ndarray] | None = None  # an /initialpose before the map
        self._first_scan: float | None = None  # odometry time of the first scan with a map
        self._tf_valid = False  # map -> odom may go out
        self._tf_sent = -math.inf  # odometry time of the last map -> odom
        self._tf_stamp = -math.inf  # the stamp it carried
        self._laser_from_tf = False
        self.map_to_odom: Pose = (0.0, 0.0, 0.0)
        self._paused = False  # another node (the mapper) owns map -> odom
        bus = self.runtime.bus
        self._pub = bus.publisher("/amcl_pose", PoseWithCovarianceStamped, "latched")
        self._tf_pub = bus.publisher(TF, TFMessage, 100)
        self.tf = TfListener(bus, children=())  # /tf_static only: the laser's mounting
        self._subs = [
            bus.subscribe("/map", OccupancyGrid, self._on_map, "latched"),
            bus.subscribe("/odom", Odometry, self._on_odom, 50),
            bus.subscribe("/scan", LaserScan, self._on_scan, "sensor"),
            bus.subscribe("/initialpose", PoseWithCovarianceStamped, self._on_initial_pose, 10),
        ]
        if imu_topic:
            self._subs.append(bus.subscribe(imu_topic, Imu, self._on_imu, 100))

    def close(self) -> None:
        """Unsubscribe and stop publishing (the runtime's bus closes them too)."""
        for s in self._subs:
            s.close()
        self._subs = []
        self.tf.close()
        close_publishers(self._pub, self._tf_pub)

    # -- bus callbacks --------------------------------------------------------------------
    def _on_map(self, msg: OccupancyGrid) -> None:
        info = msg.info
        key = (
            info.width,
            info.height,
            info.resolution,
            info.origin.position.x,
            info.origin.position.y,
            zlib.crc32(np.asarray(msg.data, dtype=np.int8).tobytes()),
        )
        with self._lock:
            if self._paused or key == self._map_key:
                return  # mapping, or the same map republished
            self._map_key = key
            occ = OccupancyMap.from_msg(msg)
            if self.amcl is None:
                ap, fp, lp = self._params
                self.amcl = Amcl(occ, ap, fp, lp, seed=self._seed, clock=lambda: self._now)
                if len(self._odom):
                    self.amcl.on_odometry(self._odom.latest())
                start = self._pending_initial or (
                    (tuple(self._initial_pose), INITIAL_COV) if self._initial_pose is not None else None
                )
                if start is not None:
                    self._initialise(*start)
            else:
                self.amcl.set_map(occ)

    def _initialise(self, pose, cov) -> None:
        """Start from a pose the user gave: map -> odom is known at once."""
        assert self.amcl is not None  # called once the map has made the filter
        self.amcl.initialise(pose, cov)
        self.map_to_odom = self._target = self.amcl.map_to_odom
        if self.hold is not None:
            self.hold.release()
        if self.smoother is not None:
            self.smoother.reset(pose, self._odom.latest() or (0.0, 0.0, 0.0))
        self._tf_valid = True
        self._send_tf()

    def _estimate(self, odom) -> None:
        """map -> odom from the filter's new estimate at odometry pose ``odom``: smoothed
        while localised, as it is otherwise (converging, relocalising); held while the
        robot manoeuvres near where it stood still, unless the correction is one that
        drift cannot explain. Until map -> odom is known (a global localisation before it
        first converges), the estimate is taken as it is: the transform there is nothing
        the robot has used, so there is nothing to hold or to smooth towards."""
        assert self.amcl is not None  # called on a scan the filter took
        localised = self.amcl.status.state == LOCALISED
        big = not localised or not self._tf_valid
        if self.smoother is None:
            target = self.amcl.map_to_odom
        else:
            resets = self.smoother.resets
            if localised and self._tf_valid:
                self.smoother.update(self.amcl.pose(odom), odom)
            else:
                self.smoother.reset(self.amcl.pose(odom), odom)
            big = big or self.smoother.resets != resets
            target = self.smoother.map_to_odom()
        self._target = target
        if self.hold is not None and self.hold.holding and not big:
            return  # kept until the robot moves away
        if big and self.hold is not None:
            self.hold.release()
        self.map_to_odom = target

    def pose(self, odom=None):
        """The robot's map pose as published (at the newest odometry pose when None)."""
        if odom is None:
            odom = self._odom.latest() or (0.0, 0.0, 0.0)
        return compose(self.map_to_odom, tuple(odom))

    def _on_imu(self, msg: Imu) -> None:
        with self._lock:
            self.odometry.on_imu(_seconds(msg.header.stamp), _yaw(msg.orientation))

    def _on_odom(self, msg: Odometry) -> None:
        p = msg.pose.pose
        t = _seconds(msg.header.stamp)
        with self._lock:
            pose = self.odometry.fuse(t, (p.position.x, p.position.y, _yaw(p.orientation)))
            if self._odom.add(t, pose):  # time went backwards (a new episode)
                self._tf_sent = self._tf_stamp = -math.inf
            self._now = max(self._now, t)
            if self.amcl is None or self._paused:
                return
            self.amcl.on_odometry(pose)
            if (
                self.hold is not None
                and self.hold.on_odometry(t, pose)
                and self._target is not None
                and self._target != self.map_to_odom
            ):
                self.map_to_odom = self._target  # the hold ended: apply what was kept
                if self._tf_valid:
                    self._send_tf()
            if self._tf_valid and t - self._tf_sent >= self._tf_period - 1e-9:
                self._send_tf()
            if self._tf_valid:
                if t - self._last_pub >= self._pose_period - 1e-9:
                    self._publish(msg.header.stamp, self.pose(pose))

    def odom_at(self, t: float):
        """The odometry pose interpolated at time t (the newest one outside the history)."""
        return self._odom.at(t)

    def _laser_pose(self, frame: str) -> None:
        """The laser's mounting from /tf_static, once it is there."""
        if self._laser_from_tf or not frame:
            return
        try:
            pose = self.tf.pose(BASE_FRAME, frame)
        except TransformError:
            return
        self._laser_from_tf = True
        self._params[0].laser_pose = pose
        if self.amcl is not None:
            self.amcl.params.laser_pose = pose

    def _on_scan(self, msg: LaserScan) -> None:
        with self._lock:
            if self.amcl is None or self._paused:
                return
            t = _seconds(msg.header.stamp)
            odom = self.odom_at(t)
            if odom is None:
                return
            self._now = max(self._now, t)
            self._laser_pose(msg.header.frame_id)
            if self._first_scan is None:
                self._first_scan = t
            if not self._tf_valid:
                if self.amcl.status.state != UNINITIALISED:
                    # converge while standing still: the robot waits for its pose
                    self.amcl.request_nomotion_update()
                elif self._global_after is not None and t - self._first_scan >= self._global_after:
                    self.amcl.global_localisation()  # nobody said where the robot is
            if self.amcl.on_scan(Scan.from_msg(msg), odom, self.odometry.gyro_heading):
                self._estimate(odom)
                if not self._tf_valid and self.amcl.status.state == LOCALISED:
                    self._tf_valid = True  # a global localisation converged
                if self._tf_valid:  # else the pose is unknown: nothing to say
                    self._send_tf()
                    self._publish(msg.header.stamp, self.pose(odom))

    def _on_initial_pose(self, msg: PoseWithCovarianceStamped) -> None:
        p = msg.pose.pose
        pose = (p.position.x, p.position.y, _yaw(p.orientation))
        c = np.asarray(msg.pose.covariance, float).reshape(6, 6)
        cov = c[np.ix_([0, 1, 5], [0, 1, 5])]
        if not np.any(cov):
            cov = INITIAL_COV
        with self._lock:
            if self._paused:
                return
            if self.amcl is None:
                self._pending_initial = (pose, cov)
            else:
                self._initialise(pose, cov)

    def _send_tf(self) -> None:
        """map -> odom on /tf, stamped transform_tolerance ahead of the odometry's time
        (and after the last one sent)."""
        stamp = max(self._now + self._tolerance, self._tf_stamp + 1e-3)
        self._tf_pub.publish(
            TFMessage(
                transforms=[
                    planar_transform(GLOBAL_FRAME, ODOM_FRAME, self.odometry.map_to_wheel_odom(self.map_to_odom), stamp)
                ]
            )
        )
        self._tf_sent, self._tf_stamp = self._now, stamp

    def _publish(self, stamp, pose, cov3=None) -> None:
        msg = PoseWithCovarianceStamped()
        msg.header.stamp = stamp
        msg.header.frame_id = GLOBAL_FRAME
        msg.pose.pose.position.x, msg.pose.pose.position.y = float(pose[0]), float(pose[1])
        msg.pose.pose.orientation.z = math.sin(pose[2] / 2)
        msg.pose.pose.orientation.w = math.cos(pose[2] / 2)
        cov = np.zeros((6, 6))
        if cov3 is None:
            assert self.amcl is not None  # a pose is published only once the filter runs
            cov3 = self.amcl.covariance()
        cov[np.ix_([0, 1, 5], [0, 1, 5])] = cov3
        msg.pose.covariance = cov.ravel().tolist()
        self._pub.publish(msg)
        self._last_pub = _seconds(stamp)

    # -- handing map -> odom to the mapper and back -----------------------------------------
    def pause(self):
        """Stop localising while another node (the mapper) owns map -> odom and /map: maps,
        scans and initial poses are ignored and nothing is published. Returns the best pose
        known now (x, y, yaw), for the mapper to start from: the user's initial pose, else
        the estimate, else None."""
        with self._lock:
            self._paused = True
            if self._pending_initial is not None:
                return tuple(self._pending_initial[0])
            if self.amcl is not None and self._tf_valid:
                return tuple(self.pose())
            return tuple(self._initial_pose) if self._initial_pose is not None else None

    def resume(self, pose, map_msg: OccupancyGrid) -> None:
        """Localise again, on ``map_msg`` (the map just made), from ``pose`` (x, y, yaw)."""
        with self._lock:
            self._paused = False
            self.amcl, self._map_key, self._tf_valid = None, None, False
            self._pending_initial = (tuple(pose), RESUME_COV)
        self._on_map(map_msg)

    # -- actors -------------------------------------------------------------------------------
    @actor
    def localise_globally(self, wait: float = 0.0) -> dict:
        """Forget the pose and find the robot on the whole map from the next scan (the
        reinitialize_global_localization service): until that has converged, map -> odom
        is off /tf and /amcl_pose says the pose is unknown (AMCL goes on publishing its
        estimate as it converges). Returns the localisation status.

        Args:
            wait: wait up to this long for the robot to be localised [s]; 0: return at once
        """
        with self._lock:
            if self.amcl is None:
                raise RuntimeError("no map received on /map yet")
            self.amcl.global_localisation()
            if self._tf_valid:
                # the pose is forgotten: no map -> odom until the search has converged, and
                # the latched /amcl_pose, sure of the old pose, is replaced by one that is not
                self._tf_valid = False
                self._publish(to_stamp(self._now, Time()), self.pose(), UNKNOWN_COV)
        if wait > 0:
            end = self.runtime.now() + wait
            while self.runtime.now() < end:
                self.run_actor("sleep", 0.2)
                with self._lock:
                    if self.amcl.status.state == LOCALISED and self.amcl.status.updates:
                        break
        return self.localisation_status()

    @actor(read_only=True)
    def localisation_status(self) -> dict:
        """How the localisation is doing.

        Returns:
            state (uninitialised, uncertain, localised or lost), pose [x m, y m, yaw rad]
            in the map frame now (None while the localiser does not know it: no initial
            pose yet, or a global localisation that has not converged), score (share of
            beams that fit the map, smoothed), ambiguous and rival_score (a global
            localisation whose estimate the scan fits no better than another place, whose
            fit is rival_score: it stays uncertain until the robot has moved),
            std_xy [m] and std_yaw [rad] of the estimate, particles, clusters, updates,
            recoveries (times lost was declared), kept_count (relocalisations after a
            lost that found no better pose than the one held: false alarms),
            last_update_ms
        """
        with self._lock:
            if self.amcl is None:
                return {"state": "uninitialised", "pose": None, "map": False}
            st = self.amcl.status.as_dict()
            st.pop("last_lost", None)
            st["pose"] = [round(float(v), 4) for v in self.pose()] if self._tf_valid else None
            st["map"] = True
            return {k: (float(v) if isinstance(v, (np.floating,)) else v) for k, v in st.items()}
