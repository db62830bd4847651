"""The simulator's ROS interfaces on the runtime's bus (real ROS 2 message classes): what
a TurtleBot3 Waffle Pi with an OpenManipulator-X offers under ROBOTIS' Jazzy ros2_control
bring-up (turtlebot3_manipulation_bringup: diff_drive_controller, imu_broadcaster,
arm_controller, gripper_controller, joint_state_broadcaster, robot_state_publisher), the
LDS-01 driver and an RGB-D camera driver. docs/real-robot.md has the table with sources.

Subscribed (actuators):
  /diff_drive_controller/cmd_vel    geometry_msgs/TwistStamped  linear.x, angular.z; TB3 limits;
                                    a zero stamp means now, a command older than
                                    cmd_vel_timeout is ignored, and the base brakes when
                                    none came for cmd_vel_timeout (diff_drive_controller)
  /arm_controller/joint_trajectory  trajectory_msgs/JointTrajectory  joint1..joint4
Actions served (sim/controllers.py, ros2_control's controllers):
  /arm_controller/follow_joint_trajectory  control_msgs/FollowJointTrajectory  joint1..joint4
  /gripper_controller/gripper_cmd          control_msgs/GripperCommand  position -0.010
                                            (closed) .. 0.019 (open) [m], stalled / reached_goal
Published (sensors):
  /scan                             sensor_msgs/LaserScan     LDS-01, base_scan, 360 beams, 5 Hz;
                                                              sensor-data QoS (best effort)
  /odom                             nav_msgs/Odometry         wheel-only odometry with a real
                                                              robot's errors, odom -> base_footprint
  /imu_broadcaster/imu              sensor_msgs/Imu           the OpenCR's IMU, frame imu_link
  /tf                               tf2_msgs/TFMessage        odom -> base_footprint (the same
                                                              odometry) and the movable joints
                                                              (wheels, arm, fingers), with /odom
  /tf_static                        tf2_msgs/TFMessage        the URDF's fixed joints; latched:
                                                              sent again whenever the subscriber
                                                              count grows
  /ground_truth/pose                geometry_msgs/PoseStamped map -> base_footprint, exact; only
                                                              with SimWorld(debug_ground_truth=True)
  /joint_states                     sensor_msgs/JointState    wheels, arm, fingers
  /camera/color/image_raw           sensor_msgs/Image         rgb8
  /camera/depth/image_raw           sensor_msgs/Image         32FC1, metres, NaN = no return
  /camera/camera_info               sensor_msgs/CameraInfo    (colour and depth share it)
  /map                              nav_msgs/OccupancyGrid    5 cm; published once, latched
                                                              (map_server's); not while the
                                                              robot maps (SimWorld.serve_map)
State topics go out only while subscribed; the lidar casts and the camera renders only
while subscribed. map -> odom is never published here: that is the localiser's.

As a user would (not the robot): ``/initialpose`` (geometry_msgs/PoseWithCovarianceStamped,
RViz's "2D Pose Estimate") with the pose the robot stands at once it has come to rest
(``SETTLED`` s), to each new subscriber while it has not driven yet
(``SimWorld(initial_pose=False)``: never).
"""

from __future__ import annotations

import array
import logging
import math
import random

from builtin_interfaces.msg import Time
from geometry_msgs.msg import PoseStamped, PoseWithCovarianceStamped, TransformStamped, TwistStamped
from nav_msgs.msg import OccupancyGrid, Odometry
from sensor_msgs.msg import CameraInfo, Image, Imu, JointState, LaserScan
from tf2_msgs.msg import TFMessage

from bt_engine.bus import close_publishers

from .controllers import ArmController, GripperController
from .faults import faulty
from .frames import joint_transforms, odom_transform, static_transforms
from .gridmap import occupancy_grid_msg
from .imu import GRAVITY, IMU_FRAME
from .initial_pose import initial_pose_msg
from .lidar import SCAN_FRAME
from .robot import JOINT_STATE_NAMES

CMD_VEL = "/diff_drive_controller/cmd_vel"
ODOM = "/odom"
IMU = "/imu_broadcaster/imu"
INITIAL_POSE = "/initialpose"
#: topics the simulator publishes as the user, not as the robot (left out of its interfaces)
USER_TOPICS = (INITIAL_POSE,)
TF = "/tf"
TF_STATIC = "/tf_static"
LATCHED_QOS = "latched"  # reliable, transient local, keep last 1 (robot_state_publisher's /tf_static)
SCAN = "/scan"
SENSOR_QOS = "sensor"  # best effort, keep last 5 (rclpy's qos_profile_sensor_data), as the LDS driver
GROUND_TRUTH = "/ground_truth/pose"
JOINT_STATES = "/joint_states"
COLOR = "/camera/color/image_raw"
DEPTH = "/camera/depth/image_raw"
CAMERA_INFO = "/camera/camera_info"
MAP = "/map"
#: [m, rad] a robot that moved this far has left its start: no initial pose any more
MOVED = 0.01
#: [s] the user gives the pose of a robot that has come to rest after it was put down
SETTLED = 0.5

CAMERA_FRAME = "camera_optical_frame"

log = logging.getLogger("sim")


def stamp(t: float) -> Time:
    sec, nsec = divmod(int(round(t * 1e9)), 1_000_000_000)
    return Time(sec=sec, nanosec=nsec)


def transform_stamped(tf, t: Time) -> TransformStamped:
    """A geometry_msgs/TransformStamped of a :class:`sim.frames.Transform`."""
    msg = TransformStamped()
    msg.header.stamp = t
    msg.header.frame_id = tf.parent
    msg.child_frame_id = tf.child
    tr, q = msg.transform.translation, msg.transform.rotation
    tr.x, tr.y, tr.z = (float(x) for x in tf.translation)
    q.x, q.y, q.z, q.w = (float(x) for x in tf.rotation)
    return msg


class SimTopics:
    def __init__(self, sim, rt):
        self.sim = sim
        self.bus = bus = rt.bus
        self.pub_odom = bus.publisher(ODOM, Odometry)
        self.pub_imu = bus.publisher(IMU, Imu)
        self.pub_scan = bus.publisher(SCAN, LaserScan, SENSOR_QOS)
        # the exact pose only on request (SimWorld(debug_ground_truth=True))
        self.pub_gt = bus.publisher(GROUND_TRUTH, PoseStamped) if sim.debug_ground_truth else None
        self.pub_js = bus.publisher(JOINT_STATES, JointState)
        self.pub_rgb = bus.publisher(COLOR, Image)
        self.pub_depth = bus.publisher(DEPTH, Image)
        self.pub_info = bus.publisher(CAMERA_INFO, CameraInfo)
        self.pub_map = bus.publisher(MAP, OccupancyGrid, LATCHED_QOS)  # map_server latches it
        self.pub_tf = bus.publisher(TF, TFMessage)
        self.pub_tf_static = bus.publisher(TF_STATIC, TFMessage, LATCHED_QOS)
        faults = sim.faults
        if faults is not None:  # actorbt robot --fault: a real robot's losses
            rng = random.Random(sim.seed * 1009 + 17)
            self.pub_scan = faulty(self.pub_scan, rt, faults.scan_drop, faults.scan_delay, rng)
            self.pub_rgb, self.pub_depth, self.pub_info = (
                faulty(p, rt, faults.camera_drop, faults.camera_delay, rng)
                for p in (self.pub_rgb, self.pub_depth, self.pub_info)
            )
        self.pub_initial = bus.publisher(INITIAL_POSE, PoseWithCovarianceStamped) if sim.give_initial_pose else None
        self.subs = [bus.subscribe(CMD_VEL, TwistStamped, self._on_cmd_vel)]
        self.arm = ArmController(sim, bus)
        self.gripper = GripperController(sim, bus)
        if faults is not None:
            self.arm.abort_goals = set(faults.arm_abort)
        self._static_subs = 0
        self._initial_subs = 0
        self._map_sent = False
        self._ticks = 0

    def close(self):
        """Off the bus: subscriptions, actions and publishers (a driver that stopped)."""
        for s in self.subs:
            s.close()
        self.subs = []
        self.arm.close()
        self.gripper.close()
        close_publishers(
            self.pub_odom,
            self.pub_imu,
            self.pub_scan,
            self.pub_gt,
            self.pub_js,
            self.pub_rgb,
            self.pub_depth,
            self.pub_info,
            self.pub_map,
            self.pub_tf,
            self.pub_tf_static,
            self.pub_initial,
        )

    # ---------------- actuators ----------------
    def _on_cmd_vel(self, msg: TwistStamped):
        """diff_drive_controller's rules: a zero stamp means now; a command older than
        cmd_vel_timeout is ignored."""
        sent = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
        timeout = self.sim.cmd_vel_timeout
        if sent and timeout > 0 and self.sim.ros_time() - sent > timeout:
            log.warning(
                "ignored %s stamped %.3f s ago (cmd_vel_timeout %g s)", CMD_VEL, self.sim.ros_time() - sent, timeout
            )
            return
        self.sim.apply_cmd_vel(msg.twist.linear.x, msg.twist.angular.z)

    # ---------------- sensors ----------------
    def after_step(self):
        sim, count = self.sim, self.bus.subscription_count
        self._ticks += 1
        now = sim.now()
        st = None
        if self.arm.active is not None or self.gripper.active is not None:
            st = sim.robot.joint_states()
            self.arm.update(now, st)
            self.gripper.update(now, st)
        if self._ticks % sim.publish_every == 0:
            if count(ODOM):
                self.pub_odom.publish(self.odom_msg(now))
            if count(IMU):
                self.pub_imu.publish(self.imu_msg(now))
            if self.pub_gt is not None and count(GROUND_TRUTH):
                self.pub_gt.publish(self.ground_truth_msg(now))
            if count(JOINT_STATES):
                st = st or sim.robot.joint_states()
                self.pub_js.publish(self.joint_state_msg(now, st))
            if count(TF):
                st = st or sim.robot.joint_states()
                self.pub_tf.publish(self.tf_msg(now, st))
        n = count(TF_STATIC)
        if n > self._static_subs:  # latched: a new subscriber gets the tree at once
            self.pub_tf_static.publish(self.tf_static_msg(now))
        self._static_subs = n
        if self._ticks % sim.scan_every == 0 and count(SCAN):
            self.pub_scan.publish(self.scan_msg(now, sim.scan_now()))
        if sim.serve_map and not self._map_sent:
            self.publish_map(now)
        if self.pub_initial is not None:
            self._give_initial_pose(now)

    def publish_map(self, now):
        """The map, once: the bus keeps it for later subscribers (transient local)."""
        msg = occupancy_grid_msg(self.sim.grid)
        msg.header.stamp = stamp(self.sim.ros_time(now))
        msg.info.map_load_time = msg.header.stamp
        self.pub_map.publish(msg)
        self._map_sent = True

    def _give_initial_pose(self, now):
        """The start pose on /initialpose for each new subscriber (a localiser that came
        up), as its user would give it, until the robot has moved."""
        if self.sim.t < SETTLED:
            return
        assert self.pub_initial is not None  # called by tick only when there is the publisher
        n = self.bus.subscription_count(INITIAL_POSE)
        if n > self._initial_subs:
            o = self.sim.odometry
            if o.distance < MOVED and o.turned < MOVED:
                msg = initial_pose_msg(self.sim.robot_pose())  # where it stands, seen by the user
                msg.header.stamp = stamp(self.sim.ros_time(now))
                self.pub_initial.publish(msg)
        self._initial_subs = n

    def odom_msg(self, now) -> Odometry:
        o = self.sim.odometry
        tf = odom_transform(o)  # the same edge /tf will carry
        msg = Odometry()
        msg.header.stamp = stamp(self.sim.ros_time(now))
        msg.header.frame_id = tf.parent
        msg.child_frame_id = tf.child
        pos, q = msg.pose.pose.position, msg.pose.pose.orientation
        pos.x, pos.y, pos.z = tf.translation
        q.x, q.y, q.z, q.w = tf.rotation
        msg.twist.twist.linear.x = o.v
        msg.twist.twist.angular.z = o.w
        msg.pose.covariance = o.pose_covariance()
        msg.twist.covariance = o.twist_covariance()
        return msg

    def imu_msg(self, now) -> Imu:
        """imu_broadcaster's message: the board's orientation (flat floor: its heading),
        yaw rate and acceleration (gravity and the base's forward acceleration)."""
        g = self.sim.gyro
        msg = Imu()
        msg.header.stamp = stamp(self.sim.ros_time(now))
        msg.header.frame_id = IMU_FRAME
        msg.orientation.z, msg.orientation.w = math.sin(g.yaw / 2), math.cos(g.yaw / 2)
        msg.angular_velocity.z = g.rate
        msg.linear_acceleration.x = g.accel
        msg.linear_acceleration.z = GRAVITY
        msg.angular_velocity_covariance = [0.0] * 8 + [g.rate_variance()]
        return msg

    def tf_msg(self, now, st) -> TFMessage:
        """odom -> base_footprint from the odometry (as /odom), and the movable joints at
        their positions in ``st`` (robot_state_publisher's share of /tf)."""
        t = stamp(self.sim.ros_time(now))
        edges = [odom_transform(self.sim.odometry)]
        edges += joint_transforms(dict(zip(JOINT_STATE_NAMES, st[0])))
        return TFMessage(transforms=[transform_stamped(e, t) for e in edges])

    def tf_static_msg(self, now) -> TFMessage:
        """Every fixed joint of the URDF (robot_state_publisher's /tf_static)."""
        t = stamp(self.sim.ros_time(now))
        return TFMessage(transforms=[transform_stamped(e, t) for e in static_transforms()])

    def scan_msg(self, now, ranges) -> LaserScan:
        m = self.sim.lidar_model
        msg = LaserScan()
        msg.header.stamp = stamp(self.sim.ros_time(now))
        msg.header.frame_id = SCAN_FRAME
        msg.angle_min, msg.angle_max, msg.angle_increment = m.angle_min, m.angle_max, m.angle_increment
        msg.time_increment = 0.0  # every beam at the same instant (one ray cast)
        msg.scan_time = m.scan_time
        msg.range_min, msg.range_max = m.range_min, m.range_max
        msg.ranges = ranges  # float32 array
        return msg

    def ground_truth_msg(self, now) -> PoseStamped:
        _, pos, orn = self.sim.robot.base_pose()
        msg = PoseStamped()
        msg.header.stamp = stamp(self.sim.ros_time(now))
        msg.header.frame_id = "map"
        msg.pose.position.x, msg.pose.position.y, msg.pose.position.z = pos
        q = msg.pose.orientation
        q.x, q.y, q.z, q.w = orn
        return msg

    def joint_state_msg(self, now, st) -> JointState:
        q, v, e = st
        msg = JointState()
        msg.header.stamp = stamp(self.sim.ros_time(now))
        msg.name = list(JOINT_STATE_NAMES)
        msg.position = [float(x) for x in q]
        msg.velocity = [float(x) for x in v]
        msg.effort = [float(x) for x in e]
        return msg

    def camera_info_msg(self, st: Time) -> CameraInfo:
        cam = self.sim.camera
        msg = CameraInfo()
        msg.header.stamp = st
        msg.header.frame_id = CAMERA_FRAME
        msg.width, msg.height = cam.width, cam.height
        msg.distortion_model = "plumb_bob"
        msg.d = [0.0] * 5
        k = cam.K()
        msg.k = k
        msg.r = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
        msg.p = [k[0], 0.0, k[2], 0.0, 0.0, k[4], k[5], 0.0, 0.0, 0.0, 1.0, 0.0]
        return msg

    def camera_tick(self):
        count = self.bus.subscription_count
        want_rgb, want_depth, want_info = count(COLOR) > 0, count(DEPTH) > 0, count(CAMERA_INFO) > 0
        if not (want_rgb or want_depth or want_info):
            return
        st = stamp(self.sim.ros_time())
        if want_rgb or want_depth:
            rgb, depth = self.sim.render_camera()
            h, w = depth.shape
            if want_rgb:
                im = Image()
                im.header.stamp = st
                im.header.frame_id = CAMERA_FRAME
                im.height, im.width = h, w
                im.encoding = "rgb8"
                im.is_bigendian = 0
                im.step = w * 3
                im.data = array.array("B", rgb.tobytes())
                self.pub_rgb.publish(im)
            if want_depth:
                im = Image()
                im.header.stamp = st
                im.header.frame_id = CAMERA_FRAME
                im.height, im.width = h, w
                im.encoding = "32FC1"
                im.is_bigendian = 0
                im.step = w * 4
                im.data = array.array("B", depth.astype("<f4").tobytes())
                self.pub_depth.publish(im)
        if want_info:
            self.pub_info.publish(self.camera_info_msg(st))
