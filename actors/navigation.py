"""The mobile base as actors: plan on /map, follow the path on /cmd_vel.

Localisation is the ``/ground_truth/pose`` topic (map frame); on a real robot, remap it
to AMCL's pose. Cancelling any motion stops the base.
"""
from __future__ import annotations

import math

from geometry_msgs.msg import PoseStamped, Twist
from nav_msgs.msg import OccupancyGrid as OccupancyGridMsg
from nav_msgs.msg import Odometry

from bt_engine import ActorbtError, Cancelled, SubSystem, actor
from planning import BasePath, FailureReason, GridPlanner, OccupancyGrid, inflate, with_obstacles

from .ros_conv import pose2d, wrap

MAX_SPEED = 0.22        # [m/s]   (TurtleBot3 Waffle: 0.26)
MAX_TURN = 1.2          # [rad/s] (TurtleBot3 Waffle: 1.82)
LOOKAHEAD = 0.25        # pure-pursuit look-ahead distance [m]
ROBOT_RADIUS = 0.20     # footprint radius used to inflate the map [m]
INFLATION = 0.45        # distance over which the map cost decays [m]
XY_TOLERANCE = 0.04     # goal position tolerance [m]
YAW_TOLERANCE = math.radians(0.5)
RECOVERY_BACKUP = 0.15  # how far to back away when the start is too close to something [m]


class NavigationError(ActorbtError):
    """A base motion could not be planned, was blocked, or timed out."""


def _twist(v: float = 0.0, w: float = 0.0) -> Twist:
    msg = Twist()
    msg.linear.x = float(v)
    msg.angular.z = float(w)
    return msg


class Navigation(SubSystem):
    """Differential-drive base: planning on the occupancy grid and a path follower."""

    def __init__(self) -> None:
        super().__init__()
        self.register_publisher("cmd_vel", Twist, "/cmd_vel")
        self.register_subscriber("pose", PoseStamped, "/ground_truth/pose", 1)
        self.register_subscriber("odom", Odometry, "/odom", 1)
        self.register_subscriber("map", OccupancyGridMsg, "/map", 1)
        self.set_value("grid", None)        # the static map, once received
        self.set_value("obstacles", {})     # perceived objects marked on it
        self.set_value("planner", None)     # built from both
        self.set_value("last_path", None)

    # -- queries -----------------------------------------------------------------------
    @actor
    def get_pose(self) -> tuple[float, float, float]:
        """The base pose (x [m], y [m], yaw [rad]) in the map frame."""
        return pose2d(self.run_actor("pose"))

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
        """Put perceived objects on the planner's map, replacing those marked before.
        Returns how many are marked.

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
        return len(marked)

    @actor
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

    def _plan_from_here(self, x: float, y: float) -> BasePath:
        sx, sy, _ = self.get_pose()
        path = self._planner().plan((sx, sy), (x, y))
        self.set_value("last_path", path)
        return path

    @actor
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
        return [tuple(p) for p in path.waypoints]

    # -- motions -----------------------------------------------------------------------
    @actor
    def goto(self, x: float, y: float, theta: float, timeout: float | None = None) -> tuple[float, float, float]:
        """Drive to (x, y) [m] in the map frame and turn to ``theta`` [rad].

        Fails with NavigationError when no path exists or the goal is not reached in time.

        Args:
            x: goal x in the map frame [m]
            y: goal y in the map frame [m]
            theta: heading to turn to at the goal, counter-clockwise from the map's x axis [rad]
            timeout: give up after this long [s]; None: from the path length

        Returns:
            the pose reached: x [m], y [m], yaw [rad] in the map frame
        """
        plan = self._plan_from_here(x, y)
        if plan.failure is FailureReason.START_INVALID:
            # Recovery: the robot stands too close to something (a newly marked object, a
            # wall after a pick); back away and plan again.
            self.run_actor("mini_walk", -RECOVERY_BACKUP)
            plan = self._plan_from_here(x, y)
        if not plan.ok:
            raise NavigationError(f"no path to ({x:.2f}, {y:.2f}): {plan.message}")
        path = [tuple(p) for p in plan.waypoints]
        length = sum(math.dist(a, b) for a, b in zip(path, path[1:]))
        budget = timeout if timeout is not None else 20.0 + 3.0 * length / MAX_SPEED
        deadline = self.runtime.now() + budget
        with self._stopping():
            self._follow(path, deadline)
            self._turn_to(theta, deadline)
        return self.get_pose()

    @actor
    def migrate(self, dx: float, dy: float, dtheta: float) -> tuple[float, float, float]:
        """Move by (dx, dy) [m] in the robot's frame and turn by ``dtheta`` [rad].

        Args:
            dx: distance forward (negative: backward) [m]
            dy: distance to the left (negative: right) [m]
            dtheta: turn, counter-clockwise positive [rad]

        Returns:
            the pose reached: x [m], y [m], yaw [rad] in the map frame
        """
        x, y, yaw = self.get_pose()
        gx = x + dx * math.cos(yaw) - dy * math.sin(yaw)
        gy = y + dx * math.sin(yaw) + dy * math.cos(yaw)
        return self.run_actor("goto", gx, gy, wrap(yaw + dtheta))

    @actor
    def mini_walk(self, distance: float, speed: float = 0.1, tolerance: float = 0.005) -> float:
        """Drive straight by ``distance`` [m] (negative: backwards) without planning, to
        within ``tolerance`` [m]; returns the distance driven [m].

        Args:
            distance: how far to drive, negative backwards [m]
            speed: top speed [m/s]
            tolerance: how close to ``distance`` to stop [m]
        """
        x0, y0, yaw0 = self.get_pose()
        sign = 1.0 if distance >= 0 else -1.0
        deadline = self.runtime.now() + 5.0 + abs(distance) / max(speed, 1e-3) * 2
        with self._stopping():
            with self.run_actor_mode("pose", "iterator") as poses:
                for msg in poses:
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
        x, y, _ = self.get_pose()
        return (x - x0) * math.cos(yaw0) + (y - y0) * math.sin(yaw0)

    @actor
    def mini_turn(self, angle: float) -> float:
        """Turn in place by ``angle`` [rad]; returns the yaw reached [rad].

        Args:
            angle: turn, counter-clockwise positive [rad]
        """
        _, _, yaw = self.get_pose()
        with self._stopping():
            self._turn_to(wrap(yaw + angle), self.runtime.now() + 10.0 + abs(angle) / 0.3)
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

    def _follow(self, path: list[tuple[float, float]], deadline: float) -> None:
        """Pure pursuit along ``path`` until within XY_TOLERANCE of its end."""
        gx, gy = path[-1]
        seg = 0
        with self.run_actor_mode("pose", "iterator") as poses:
            for msg in poses:
                x, y, yaw = pose2d(msg)
                if math.hypot(gx - x, gy - y) < XY_TOLERANCE:
                    return
                if self.runtime.now() > deadline:
                    raise NavigationError(
                        f"goto timed out {math.hypot(gx - x, gy - y):.2f} m from ({gx:.2f}, {gy:.2f})")
                seg, (tx, ty) = _lookahead_point(path, seg, (x, y))
                heading = wrap(math.atan2(ty - y, tx - x) - yaw)
                dist_goal = math.hypot(gx - x, gy - y)
                if abs(heading) > math.radians(50):
                    v = 0.0  # face the path first
                else:
                    v = min(MAX_SPEED, 0.8 * dist_goal + 0.03) * math.cos(heading)
                w = max(-MAX_TURN, min(MAX_TURN, 2.5 * heading))
                self.run_actor("cmd_vel", _twist(v, w))

    def _turn_to(self, theta: float, deadline: float) -> None:
        with self.run_actor_mode("pose", "iterator") as poses:
            for msg in poses:
                err = wrap(theta - pose2d(msg)[2])
                if abs(err) < YAW_TOLERANCE:
                    return
                if self.runtime.now() > deadline:
                    raise NavigationError(f"turn timed out {math.degrees(err):.1f} deg short")
                w = math.copysign(min(MAX_TURN, max(0.05, 2.0 * abs(err))), err)
                self.run_actor("cmd_vel", _twist(0.0, w))


def _lookahead_point(path: list[tuple[float, float]], seg: int,
                     here: tuple[float, float]) -> tuple[int, tuple[float, float]]:
    """The point LOOKAHEAD ahead of the robot's projection on the path (segment index kept
    monotonic so the robot never skips back)."""
    px, py = here
    best, best_d = seg, math.inf
    for i in range(seg, len(path) - 1):
        (ax, ay), (bx, by) = path[i], path[i + 1]
        dx, dy = bx - ax, by - ay
        L2 = dx * dx + dy * dy or 1e-12
        t = max(0.0, min(1.0, ((px - ax) * dx + (py - ay) * dy) / L2))
        d = math.hypot(ax + t * dx - px, ay + t * dy - py)
        if d < best_d - 1e-9:
            best, best_d = i, d
        if d > best_d + 0.5:
            break
    remaining = LOOKAHEAD
    (ax, ay), (bx, by) = path[best], path[best + 1]
    dx, dy = bx - ax, by - ay
    L = math.hypot(dx, dy) or 1e-12
    t = max(0.0, min(1.0, ((px - ax) * dx + (py - ay) * dy) / (L * L)))
    cx, cy = ax + t * dx, ay + t * dy
    i = best
    while True:
        bx, by = path[i + 1]
        d = math.hypot(bx - cx, by - cy)
        if d >= remaining or i + 2 >= len(path):
            if d >= remaining and d > 0:
                f = remaining / d
                return best, (cx + f * (bx - cx), cy + f * (by - cy))
            return best, (bx, by)
        remaining -= d
        cx, cy = bx, by
        i += 1
