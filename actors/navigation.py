"""The mobile base as actors: a client of the robot's navigation, and short precise moves.

What the robot offers, as a TurtleBot3 running Nav2 and AMCL does (in the simulator,
navstack stands in for both):

* where it is: the transform map -> base_footprint on ``/tf`` (the localiser's map -> odom
  composed with the odometry's odom -> base_footprint, the robot's fixed frames on
  ``/tf_static``): ``get_pose``; where it starts, for the localiser: ``/initialpose``
  (geometry_msgs/PoseWithCovarianceStamped, as RViz's "2D Pose Estimate" sends it):
  ``set_initial_pose``;
* getting somewhere: the ``/navigate_to_pose`` action (nav2_msgs/NavigateToPose), which
  plans on the map, drives around what the laser sees and turns to the goal's heading:
  ``goto`` sends a goal and waits for its end; cancelling the call cancels the goal, which
  stops the base;
* what else is in the way: perceived objects (``mark_obstacles``) go to the navigation on
  ``/perceived_obstacles`` (sensor_msgs/PointCloud2, map frame, transient local: a
  costmap observation source) and onto this SubSystem's own copy of the map, which
  answers ``clearance`` and ``plan_path``;
* short relative moves for grasping (``mini_walk``, ``mini_turn``, ``migrate``) on
  ``/odom`` and the base's velocity command directly (``/diff_drive_controller/cmd_vel``,
  geometry_msgs/TwistStamped, as ROS 2 Jazzy's diff_drive_controller takes it): over a
  few decimetres the odometry is precise and never jumps, as a localiser's correction may.

Cancelling any motion stops the base.
"""

from __future__ import annotations

import array
import math

import numpy as np
from geometry_msgs.msg import PoseWithCovarianceStamped, TwistStamped
from nav2_msgs.action import NavigateToPose
from nav_msgs.msg import OccupancyGrid as OccupancyGridMsg
from nav_msgs.msg import Odometry
from sensor_msgs.msg import Imu, PointCloud2, PointField

from bt_engine import ActorbtError, ActorError, ActorTimeout, SubSystem, actor
from bt_engine.bus.actions import ActionGoalError
from bt_ros.pose_cli import initial_pose_msg
from planning import BasePath, GridPlanner, OccupancyGrid, inflate, with_obstacles
from planning.viewpoints import viewpoints

from .ros_conv import pose2d, wrap, yaw_of
from .tf_listener import BASE, MAP, TransformError, tf_listener

MAX_TURN = 1.2  # [rad/s] (TurtleBot3 Waffle: 1.82)
MAX_SPEED = 0.26  # [m/s] the TurtleBot3 Waffle Pi's top speed: mini_walk's limit
ROBOT_RADIUS = 0.20  # footprint radius used to inflate the map [m] (the navigation's)
INFLATION = 0.45  # distance over which the map cost decays [m]
YAW_TOLERANCE = math.radians(0.5)  # mini_turn's
POSE_WAIT = 5.0  # [s] how long get_pose waits for map -> base_footprint
LOCALISED_STD_XY = 0.10  # [m] position std of /amcl_pose above which the robot is delocalised
LOCALISED_STD_YAW = 0.10  # [rad] heading std likewise
INITIAL_STD_XY = 0.5  # [m] set_initial_pose's position std: RViz's "2D Pose Estimate" default
INITIAL_STD_YAW = 0.2618  # [rad] its heading std: RViz's, pi/12
ACTION = "/navigate_to_pose"
#: the base's velocity command: diff_drive_controller's ~/cmd_vel (ROS 2 Jazzy takes only
#: TwistStamped there; ROBOTIS' bring-up leaves it unremapped)
BASE_COMMAND = "/diff_drive_controller/cmd_vel"
#: the OpenCR's IMU (imu_broadcaster's ~/imu): turns are measured on its heading, which a
#: wheel radius off by a few per cent does not scale as it scales the wheels'
IMU = "/imu_broadcaster/imu"
PERCEIVED = "/perceived_obstacles"
MARK_SPACING = 0.025  # [m] between the points that mark a perceived object's disc


class NavigationError(ActorbtError):
    """A base motion could not be planned, was blocked, or timed out."""


def _twist(v: float = 0.0, w: float = 0.0) -> TwistStamped:
    """A base command, stamped 0: diff_drive_controller takes a zero stamp as "now", so
    the command does not depend on this process's clock agreeing with the robot's."""
    msg = TwistStamped()
    msg.twist.linear.x = float(v)
    msg.twist.angular.z = float(w)
    return msg


def disc_points(circles) -> np.ndarray:
    """(N, 2) points covering each circle (x, y, radius) every MARK_SPACING."""
    out = []
    for x, y, r in circles:
        k = int(math.ceil(r / MARK_SPACING))
        g = np.arange(-k, k + 1) * MARK_SPACING
        dx, dy = np.meshgrid(g, g)
        inside = dx**2 + dy**2 <= r * r + 1e-12
        out.append(np.column_stack([x + dx[inside], y + dy[inside]]))
    return np.vstack(out) if out else np.zeros((0, 2))


def cloud_msg(points: np.ndarray, frame: str = MAP) -> PointCloud2:
    """A PointCloud2 of (N, 2) points on the floor (float32 x, y, z)."""
    msg = PointCloud2()
    msg.header.frame_id = frame
    msg.height, msg.width = 1, len(points)
    msg.fields = [PointField(name=n, offset=4 * i, datatype=PointField.FLOAT32, count=1) for i, n in enumerate("xyz")]
    msg.is_bigendian = False
    msg.point_step, msg.row_step = 12, 12 * len(points)
    xyz = np.zeros((len(points), 3), "<f4")
    xyz[:, :2] = points
    msg.data = array.array("B", xyz.tobytes())
    msg.is_dense = True
    return msg


def _goal_msg(x: float, y: float, theta: float) -> NavigateToPose.Goal:
    goal = NavigateToPose.Goal()
    goal.pose.header.frame_id = MAP
    goal.pose.pose.position.x, goal.pose.pose.position.y = float(x), float(y)
    goal.pose.pose.orientation.z = math.sin(theta / 2)
    goal.pose.pose.orientation.w = math.cos(theta / 2)
    return goal


class Navigation(SubSystem):
    """Differential-drive base: the robot's navigation as a client, a copy of the map for
    queries, and odometry-driven short moves."""

    def __init__(self) -> None:
        super().__init__()
        self.register_publisher("cmd_vel", TwistStamped, BASE_COMMAND, moves=True)
        self.register_subscriber("odom", Odometry, "/odom", 1)
        self.register_subscriber("imu", Imu, IMU, 1)
        self.register_subscriber("map", OccupancyGridMsg, "/map", "latched")  # map_server latches it
        self.register_action("navigate_to_pose", NavigateToPose, ACTION, moves=True)
        # the localiser's estimate and its covariance (AMCL latches it)
        self.register_subscriber("amcl_pose", PoseWithCovarianceStamped, "/amcl_pose", "latched")
        # where the robot starts, for the localiser (RViz's "2D Pose Estimate"; reliable, volatile)
        self.register_publisher("initialpose", PoseWithCovarianceStamped, "/initialpose", "reliable")
        self._perceived = self.runtime.bus.publisher(PERCEIVED, PointCloud2, "latched")
        self.tf = tf_listener(self)
        self.set_value("grid", None)  # the static map, once received
        self.set_value("obstacles", {})  # perceived objects marked on it
        self.set_value("planner", None)  # built from both
        self.set_value("last_path", None)

    # -- queries -----------------------------------------------------------------------
    @actor(read_only=True)
    def get_pose(self) -> tuple[float, float, float]:
        """The base pose (x [m], y [m], yaw [rad]) in the map frame, as the robot's
        localisation has it (tf: map -> base_footprint)."""
        end = self.runtime.now() + POSE_WAIT
        while True:
            try:
                return self.tf.pose(MAP, BASE)
            except TransformError as e:
                if self.runtime.now() >= end:
                    raise NavigationError(
                        f"the robot is not localised: no {MAP} -> {BASE} transform "
                        f"on /tf after {POSE_WAIT:g} s (give /initialpose): {e}"
                    ) from None
            self.run_actor("sleep", 0.05)

    @actor(limits={"std_xy": (0.0, None), "std_yaw": (0.0, None)})
    def set_initial_pose(
        self, x: float, y: float, yaw: float, std_xy: float = INITIAL_STD_XY, std_yaw: float = INITIAL_STD_YAW
    ) -> tuple[float, float, float]:
        """Tell the localiser where the robot is, as RViz's "2D Pose Estimate" does: one
        /initialpose in the map frame, which the localiser (AMCL) starts from. The robot
        does not move. Returns the pose given.

        Args:
            x: the robot's x in the map frame [m]
            y: the robot's y in the map frame [m]
            yaw: the robot's heading, counter-clockwise from the map's x axis [rad]
            std_xy: the standard deviation of x and of y [m] (RViz's default 0.5)
            std_yaw: the standard deviation of the heading [rad] (RViz's default pi/12)

        Returns:
            the pose given: x [m], y [m], yaw [rad] in the map frame
        """
        self.run_actor("initialpose", initial_pose_msg(x, y, yaw, std_xy, std_yaw, MAP))
        return float(x), float(y), float(yaw)

    @actor(read_only=True)
    def require_localised(
        self, max_std_xy: float = LOCALISED_STD_XY, max_std_yaw: float = LOCALISED_STD_YAW, wait: float = 10.0
    ) -> dict:
        """Wait until the localiser is sure of the pose (the covariance of its latest
        /amcl_pose within the limits), and fail with NavigationError if it is not within
        ``wait``: a robot that does not know where it is must not grasp. Returns the
        estimate's std_xy [m] and std_yaw [rad].

        Args:
            max_std_xy: the largest position standard deviation accepted [m]
            max_std_yaw: the largest heading standard deviation accepted [rad]
            wait: how long to wait for a good estimate [s]
        """
        end = self.runtime.now() + wait
        last = "no /amcl_pose received"
        while True:
            try:
                msg = self.run_actor_mode("amcl_pose", "timed", 0.5)  # latched: the latest at once
            except ActorbtError:
                msg = None
            if msg is not None:
                cov = msg.pose.covariance
                std_xy = math.sqrt(max(cov[0], cov[7], 0.0))
                std_yaw = math.sqrt(max(cov[35], 0.0))
                if std_xy <= max_std_xy and std_yaw <= max_std_yaw:
                    return {"std_xy": round(std_xy, 4), "std_yaw": round(std_yaw, 4)}
                last = (
                    f"the localisation is uncertain: std {std_xy * 100:.1f} cm, "
                    f"{math.degrees(std_yaw):.1f} deg (limits {max_std_xy * 100:.0f} cm, "
                    f"{math.degrees(max_std_yaw):.0f} deg)"
                )
            if self.runtime.now() >= end:
                raise NavigationError(f"the robot is delocalised: {last} after {wait:g} s")
            self.run_actor("sleep", 0.2)

    def _odometry(self) -> tuple[float, float, float]:
        return pose2d(self.run_actor_mode("odom", "timed", 5.0))

    def _heading_source(self):
        """(stream actor, heading of its message): the IMU when something publishes it."""
        if self.runtime.bus.publisher_count(IMU):
            return "imu", lambda msg: yaw_of(msg.orientation)
        return "odom", lambda msg: pose2d(msg)[2]

    def _planner(self) -> GridPlanner:
        planner = self.get_value("planner")
        if planner is None:
            grid = self.get_value("grid")
            if grid is None:
                grid = OccupancyGrid.from_msg(self.run_actor_mode("map", "timed", 5.0))
                self.set_value("grid", grid)
            marked = with_obstacles(grid, list(self.get_value("obstacles").values()))
            planner = GridPlanner(inflate(marked, ROBOT_RADIUS, inflation_radius=INFLATION))
            self.set_value("planner", planner)
        return planner

    @actor
    def mark_obstacles(self, obstacles: list) -> int:
        """Put perceived objects on the map, replacing those marked before: the
        navigation plans around them, and clearance and plan_path see them. Returns how
        many are marked.

        Args:
            obstacles: the objects, each a dict with x, y (map frame) and radius [m];
                an empty list clears the marks
        """
        marked = {}
        for i, o in enumerate(obstacles):
            try:
                marked[i] = (float(o["x"]), float(o["y"]), float(o["radius"]))
            except (TypeError, KeyError, ValueError):
                raise NavigationError(f"obstacle {i} needs numeric x, y and radius, got {o!r}") from None
        if marked != self.get_value("obstacles"):
            self.set_value("obstacles", marked)
            self.set_value("planner", None)  # rebuilt with them on the next query
            self._perceived.publish(cloud_msg(disc_points(marked.values())))
        return len(marked)

    @actor(read_only=True)
    def clearance(self, x: float, y: float) -> float:
        """Distance from (x, y) [m] to the nearest obstacle on the map [m] (0 outside it).

        Args:
            x: the point's x in the map frame [m]
            y: the point's y in the map frame [m]
        """
        costmap = self._planner().costmap
        row, col = costmap.grid.cell_of(x, y)
        if not costmap.grid.contains(row, col):
            return 0.0
        return float(costmap.clearance[row, col])

    @actor(read_only=True)
    def search_views(self, view_range: float = 2.5, seen_from: list | None = None) -> list[list[float]]:
        """Places [x, y] [m] from which the camera sees all the floor the base can reach
        from where it is, in a visiting order from here (for a search given no
        locations: a map the robot built, a user's map).

        Args:
            view_range: how far the camera is trusted to see an object [m]
            seen_from: places [x, y] [m] already looked around from: only places for
                the floor they do not see are returned
        """
        try:
            seen = [(float(p[0]), float(p[1])) for p in seen_from or ()]
        except (TypeError, ValueError, IndexError):
            raise NavigationError(f"seen_from must be a list of [x, y], got {seen_from!r}") from None
        x, y, _ = self.get_pose()
        return [
            [round(px, 2), round(py, 2)]
            for px, py in viewpoints(self._planner().costmap, (x, y), view_range=view_range, seen_from=seen)
        ]

    def _plan_from_here(self, x: float, y: float) -> BasePath:
        sx, sy, _ = self.get_pose()
        path = self._planner().plan((sx, sy), (x, y))
        self.set_value("last_path", path)
        return path

    @actor(read_only=True)
    def plan_path(self, x: float, y: float) -> list[tuple[float, float]]:
        """A collision-free path from the robot to (x, y) [m] on the inflated map.

        Args:
            x: goal x in the map frame [m]
            y: goal y in the map frame [m]

        Returns:
            the waypoints [x, y] in the map frame [m], from the robot to the goal
        """
        path = self._plan_from_here(x, y)
        if not path.ok:
            raise NavigationError(f"no path to ({x:.2f}, {y:.2f}): {path.message}")
        return list(path.waypoints)

    # -- motions -----------------------------------------------------------------------
    @actor(moves=True, limits={"timeout": (0.0, None)})
    def goto(self, x: float, y: float, theta: float, timeout: float | None = None) -> tuple[float, float, float]:
        """Drive to (x, y) [m] in the map frame and turn to ``theta`` [rad].

        Fails with NavigationError when no path exists, the way stays blocked or the goal
        is not reached in time.

        Args:
            x: goal x in the map frame [m]
            y: goal y in the map frame [m]
            theta: heading to turn to at the goal, counter-clockwise from the map's x axis [rad]
            timeout: give up after this long [s]; None: when the navigation gives up

        Returns:
            the pose reached: x [m], y [m], yaw [rad] in the map frame
        """
        goal = _goal_msg(x, y, theta)
        try:
            if timeout is None:
                self.run_actor("navigate_to_pose", goal)
            else:
                self.run_actor_mode("navigate_to_pose", "timed", timeout, goal)
        except (ActorError, ActorTimeout) as e:
            root = e.root_cause if isinstance(e, ActorError) else e
            if isinstance(root, ActionGoalError):
                detail = getattr(root.result, "error_msg", "") or str(root)
                raise NavigationError(f"goto ({x:.2f}, {y:.2f}) failed: {detail}") from None
            if isinstance(root, ActorTimeout):
                raise NavigationError(f"goto ({x:.2f}, {y:.2f}) timed out after {timeout:g} s") from None
            raise
        return self.get_pose()

    @actor(moves=True, limits={"dx": (-1.0, 1.0), "dy": (-1.0, 1.0), "dtheta": (-math.pi, math.pi)})
    def migrate(self, dx: float, dy: float, dtheta: float) -> tuple[float, float, float]:
        """Move by (dx, dy) [m] in the robot's frame and turn by ``dtheta`` [rad], on the
        odometry and without planning (a short move: nothing may be in the way).

        Args:
            dx: distance forward (negative: backward) [m]
            dy: distance to the left (negative: right) [m]
            dtheta: turn, counter-clockwise positive [rad]

        Returns:
            the pose reached: x [m], y [m], yaw [rad] in the map frame
        """
        dist = math.hypot(dx, dy)
        if dist > 1e-3:
            bearing = math.atan2(dy, dx)
            if abs(bearing) > math.pi / 2:  # behind: back up instead of turning round
                bearing = wrap(bearing + math.pi)
                dist = -dist
            if abs(bearing) > 1e-3:
                self.run_actor("mini_turn", bearing)
            self.run_actor("mini_walk", dist)
            dtheta -= bearing
        if abs(wrap(dtheta)) > 1e-3:
            self.run_actor("mini_turn", wrap(dtheta))
        return self.get_pose()

    @actor(moves=True, limits={"distance": (-1.0, 1.0), "speed": (0.01, MAX_SPEED), "tolerance": (0.001, 0.1)})
    def mini_walk(self, distance: float, speed: float = 0.1, tolerance: float = 0.005) -> float:
        """Drive straight by ``distance`` [m] (negative: backwards) on the odometry,
        without planning, to within ``tolerance`` [m]; returns the distance driven [m].

        Args:
            distance: how far to drive, negative backwards [m]
            speed: top speed [m/s]
            tolerance: how close to ``distance`` to stop [m]
        """
        x0, y0, yaw0 = self._odometry()
        sign = 1.0 if distance >= 0 else -1.0
        deadline = self.runtime.now() + 5.0 + abs(distance) / max(speed, 1e-3) * 2
        along = 0.0
        with self._stopping():
            with self.run_actor_mode("odom", "iterator") as odoms:
                for msg in odoms:
                    x, y, yaw = pose2d(msg)
                    along = (x - x0) * math.cos(yaw0) + (y - y0) * math.sin(yaw0)
                    remaining = distance - along
                    if abs(remaining) < tolerance:
                        break
                    if self.runtime.now() > deadline:
                        raise NavigationError(f"mini_walk timed out {remaining:+.3f} m short")
                    v = sign * min(speed, max(0.02, 1.5 * abs(remaining)))
                    if sign * remaining < 0:
                        v = -v * 0.5
                    self.run_actor("cmd_vel", _twist(v, 2.0 * wrap(yaw0 - yaw)))
        return along

    @actor(moves=True, limits={"angle": (-2 * math.pi, 2 * math.pi)})
    def mini_turn(self, angle: float) -> float:
        """Turn in place by ``angle`` [rad] on the IMU's heading (the odometry's where no
        IMU publishes); returns the yaw reached in the map frame [rad].

        Args:
            angle: turn, counter-clockwise positive [rad]
        """
        source, heading = self._heading_source()
        yaw0 = heading(self.run_actor_mode(source, "timed", 5.0))
        target = wrap(yaw0 + angle)
        deadline = self.runtime.now() + 10.0 + abs(angle) / 0.3
        with self._stopping():
            with self.run_actor_mode(source, "iterator") as messages:
                for msg in messages:
                    err = wrap(target - heading(msg))
                    if abs(err) < YAW_TOLERANCE:
                        break
                    if self.runtime.now() > deadline:
                        raise NavigationError(f"turn timed out {math.degrees(err):.1f} deg short")
                    w = math.copysign(min(MAX_TURN, max(0.05, 2.0 * abs(err))), err)
                    self.run_actor("cmd_vel", _twist(0.0, w))
        return self.get_pose()[2]

    @actor
    def stop(self) -> None:
        """Stop the base."""
        self.run_actor("cmd_vel", _twist())

    # -- control -----------------------------------------------------------------------
    def _stopping(self):
        """Context manager: the base stops however the block ends, cancellation included."""
        nav = self

        class _Stop:
            def __enter__(self):
                return self

            def __exit__(self, *exc):
                nav.run_actor("cmd_vel", _twist())
                return False

        return _Stop()
