"""The navigation server: ``/navigate_to_pose`` (nav2_msgs/action/NavigateToPose), Nav2's
stand-in.

A goal is a pose in the map frame (or any frame tf can put into it). The server

1. **localises** through tf: map -> base_footprint from ``/tf`` (the localiser's map ->
   odom, the odometry's odom -> base_footprint) and ``/tf_static``;
2. **plans** on ``/map``, inflated for a round footprint (:class:`planning.GridPlanner`:
   Dijkstra on the costmap, smoothed), with the cells of ``/perceived_obstacles`` marked
   occupied (a PointCloud2 in the map frame, transient local: what the robot's other
   senses found that the map and the laser do not show, such as cans lower than the scan
   plane; in Nav2 an obstacle-layer observation source);
3. **follows** the path on the base's velocity command (:data:`BASE_COMMAND`) with pure pursuit, a control step on the
   odom -> base_footprint transforms on /tf at most ``controller_frequency`` (20 Hz: 15 Hz
   on the simulator's 30 Hz odometry), then turns in place to the goal's yaw; it succeeds
   within ``xy_goal_tolerance`` and ``yaw_goal_tolerance``. No command is sent that would
   sweep the base's box (``footprint``, :mod:`navstack.footprint`) into a point of the scan
   or of the depth camera (the newest image's, and for ``depth_memory`` s those of earlier
   images that are out of its view, :mod:`navstack.obstacle_memory`): a turn in place goes
   the other way round if that is clear, else the base drives straight ahead or back a
   little until the turn is clear;
4. **watches** ``/scan``, and while it drives the depth camera (``depth_topic``, with
   its ``camera_info_topic``) for what stands out of the floor below the scan's plane
   (:mod:`navstack.depth_obstacles`; and the points remembered): points in the corridor
   of the path ahead (closer than ``collision_radius`` to it, over
   ``collision_lookahead``) where the map has nothing stop the robot; if the obstacle is
   still there after ``obstacle_wait`` s, the path is planned again with the unmapped
   points marked, up to ``max_recoveries`` times;
5. **recovers** from a start inside the inflated obstacles (the robot stands close to
   something, after a pick or a place): it plans out of it (:mod:`navstack.escape`:
   straight to a free cell within ``escape_distance``, else the way it came, through
   cells about as clear as the start, up to ``escape_winding``), or else backs up
   ``backup_distance`` (when the scan shows room behind) and plans again; it backs up
   so too, once a goal, when it has made no progress for ``progress_time``.

It sends feedback (current pose, times, distance remaining, recoveries) five times a
second, and ends each goal once:

* succeeded, within the tolerances;
* aborted with an ``error_msg`` and, as Jazzy's bt_navigator passes its nodes' codes on,
  an ``error_code`` of ComputePathToPose (start/goal outside the map or occupied, no
  valid path) or FollowPath (tf error, blocked: patience exceeded, no progress, timed out);
* canceled on a client's request, after stopping the base (a zero velocity command).

A newer goal preempts the running one, which is aborted. Only ``/scan``, ``/map``,
``/perceived_obstacles``, the depth camera (during a goal: a simulated camera renders only
while someone subscribes) and tf are read; only the base's velocity command (:data:`BASE_COMMAND`) is commanded.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field, fields
from typing import TypedDict

import numpy as np
from builtin_interfaces.msg import Duration
from geometry_msgs.msg import TwistStamped
from nav2_msgs.action import NavigateToPose
from nav_msgs.msg import OccupancyGrid as OccupancyGridMsg
from sensor_msgs.msg import CameraInfo, Image, LaserScan, PointCloud2

from bt_engine import SubSystem, actor
from bt_engine.bus import close_publishers
from planning.base_planner import BasePath, GridPlanner
from planning.failure import FailureReason
from planning.grid import OccupancyGrid, inflate
from planning.tf_buffer import planar

from .depth_obstacles import DepthObstacleParams, depth_obstacle_points
from .escape import plan_out_of
from .footprint import sweep_hits, turn_hits
from .obstacle_memory import ObstacleMemory
from .odometry import Pose
from .tf import TfListener, TransformError, to_stamp

log = logging.getLogger("navstack.navigator")

GLOBAL_FRAME, ODOM_FRAME, BASE_FRAME = "map", "odom", "base_footprint"
ACTION = "/navigate_to_pose"
#: the base's velocity command: diff_drive_controller's ~/cmd_vel, TwistStamped (Jazzy).
#: Nav2 publishes cmd_vel, remapped there by the robot's launch file; this stand-in
#: publishes straight to the controller.
BASE_COMMAND = "/diff_drive_controller/cmd_vel"
PERCEIVED = "/perceived_obstacles"

# error codes: Jazzy's NavigateToPose defines only NONE; bt_navigator reports the code of
# the node that failed, from ComputePathToPose (2xx) and FollowPath (1xx)
NONE = 0
FOLLOW_UNKNOWN, FOLLOW_TF_ERROR, PATIENCE_EXCEEDED, FAILED_TO_MAKE_PROGRESS, CONTROLLER_TIMED_OUT = (
    100,
    102,
    104,
    105,
    107,
)
PLAN_UNKNOWN, PLAN_TF_ERROR, START_OUTSIDE_MAP, GOAL_OUTSIDE_MAP, START_OCCUPIED, GOAL_OCCUPIED, NO_VALID_PATH = (
    200,
    202,
    203,
    204,
    205,
    206,
    208,
)


@dataclass
class NavigatorParams:
    """The navigator's parameters (units: m, rad, s)."""

    robot_radius: float = 0.20  # footprint radius the map is inflated by
    inflation_radius: float = 0.45  # where the inflation cost falls to 0
    cost_weight: float = 3.0  # how much the planner avoids the inflated band
    max_speed: float = 0.22  # [m/s] (TurtleBot3 Waffle: 0.26)
    max_turn: float = 1.2  # [rad/s] (TurtleBot3 Waffle: 1.82)
    lookahead: float = 0.25  # pure-pursuit look-ahead distance
    controller_frequency: float = 20.0  # [Hz] at most (Nav2's default); a control step runs on
    #                                     the odometry's transform on /tf: 15 Hz on a 30 Hz one
    # The goal checker. Nav2's defaults are 0.25 m / 0.25 rad; the mission's goals are
    # standoffs in front of objects, from which the last metre is driven on odometry
    # (mini_walk, mini_turn), so the pose only needs to be good enough for the object to
    # be straight ahead and in reach of that straight drive: 4 cm, 2 degrees.
    xy_goal_tolerance: float = 0.04
    yaw_goal_tolerance: float = 0.035
    # obstacles on /scan
    collision_radius: float = 0.17  # a beam this close to the path ahead is in the way
    collision_lookahead: float = 0.45  # [m] of path ahead that is checked
    collision_min_points: int = 2  # beams needed to call it an obstacle
    mapped_distance: float = 0.08  # a beam ending this close to a mapped obstacle is it
    obstacle_wait: float = 1.0  # [s] stand still before planning around it
    max_recoveries: int = 3  # replans around obstacles and back-ups per goal
    self_box: tuple = (-0.23, 0.10, 0.18)  # x_min, x_max, |y| max in base_footprint:
    #                                     beams ending there hit the robot or what it holds
    # obstacles the depth camera sees below the scan (empty topic: none)
    depth_topic: str = "/camera/depth/image_raw"
    camera_info_topic: str = "/camera/camera_info"
    depth_period: float = 0.5  # [s] between the depth images taken (0: every one)
    depth: DepthObstacleParams = field(default_factory=DepthObstacleParams)
    depth_memory: float = 60.0  # [s] depth obstacle points are remembered this long once out of
    #                             the camera's view: the base's rear swings into them as it turns
    footprint: tuple = (-0.21, 0.08, 0.155)  # the base's box, as self_box: its rear corners
    #                         are 0.26 m from the axle's middle, beyond robot_radius
    sweep_pad: float = 0.02  # a command that brings an obstacle this near the footprint
    #                         within sweep_horizon s is not sent as it is
    sweep_horizon: float = 0.4
    creep_speed: float = 0.06  # [m/s] ... the base drives straight instead, while a turn would
    creep_limit: float = 0.15  # sweep into something, at most this far a goal [m]
    backup_distance: float = 0.15  # start inside the inflation: back up this far
    escape_distance: float = 0.3  # or else leave it through a free cell this near [m]
    escape_winding: float = 1.5  # or else the way it came, about as clear as the start, this long [m]
    backup_speed: float = 0.08
    # patience
    tf_timeout: float = 5.0  # [s] without map -> base_footprint: abort
    progress_radius: float = 0.1  # move this far ...
    progress_time: float = 12.0  # ... within this long, or abort
    time_allowance: float = 20.0  # [s] plus 3 x the path's length at max_speed
    feedback_period: float = 0.2


def _twist(v: float = 0.0, w: float = 0.0) -> TwistStamped:
    """A base command, stamped 0: diff_drive_controller takes a zero stamp as "now", so
    the command does not depend on this process's clock agreeing with the robot's."""
    msg = TwistStamped()
    msg.twist.linear.x = float(v)
    msg.twist.angular.z = float(w)
    return msg


def _wrap(a: float) -> float:
    return math.remainder(a, 2 * math.pi)


def _duration(seconds: float) -> Duration:
    seconds = max(0.0, seconds)
    sec = int(seconds)
    return Duration(sec=sec, nanosec=min(int((seconds - sec) * 1e9), 999_999_999))


def cloud_points(msg: PointCloud2) -> np.ndarray:
    """(N, 2) x, y of a PointCloud2 with float32 x and y fields."""
    offs = {f.name: f.offset for f in msg.fields}
    if "x" not in offs or "y" not in offs or msg.point_step <= 0:
        return np.zeros((0, 2))
    n = msg.width * msg.height
    raw = np.frombuffer(bytes(msg.data), np.uint8)[: n * msg.point_step].reshape(n, msg.point_step)
    dt = np.dtype(">f4" if msg.is_bigendian else "<f4")
    x = raw[:, offs["x"] : offs["x"] + 4].copy().view(dt).ravel()
    y = raw[:, offs["y"] : offs["y"] + 4].copy().view(dt).ravel()
    return np.column_stack([x, y]).astype(float)


def lookahead_point(path, seg: int, here, lookahead: float):
    """The point ``lookahead`` ahead of the robot's projection on ``path`` (the segment
    index is kept monotonic so the robot never skips back); returns (segment, point)."""
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
    remaining = lookahead
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


def path_ahead(path, seg: int, here, length: float) -> list:
    """The path from the robot's projection on segment ``seg`` on, ``length`` long."""
    (ax, ay), (bx, by) = path[seg], path[seg + 1]
    dx, dy = bx - ax, by - ay
    L2 = dx * dx + dy * dy or 1e-12
    t = max(0.0, min(1.0, ((here[0] - ax) * dx + (here[1] - ay) * dy) / L2))
    out = [tuple(here), (ax + t * dx, ay + t * dy)]
    left = length
    for p in path[seg + 1 :]:
        d = math.dist(out[-1], p)
        if d >= left:
            f = left / d if d > 0 else 0.0
            out.append((out[-1][0] + f * (p[0] - out[-1][0]), out[-1][1] + f * (p[1] - out[-1][1])))
            break
        out.append(tuple(p))
        left -= d
    return out


def distance_to_polyline(pts: np.ndarray, line: list) -> np.ndarray:
    """(N,) distance of each point (N, 2) to the polyline."""
    best = np.full(len(pts), np.inf)
    for (ax, ay), (bx, by) in zip(line[:-1], line[1:]):
        dx, dy = bx - ax, by - ay
        L2 = dx * dx + dy * dy
        if L2 < 1e-12:
            d = np.hypot(pts[:, 0] - ax, pts[:, 1] - ay)
        else:
            t = np.clip(((pts[:, 0] - ax) * dx + (pts[:, 1] - ay) * dy) / L2, 0.0, 1.0)
            d = np.hypot(ax + t * dx - pts[:, 0], ay + t * dy - pts[:, 1])
        best = np.minimum(best, d)
    return best


class _Goal:
    """One goal's state."""

    def __init__(self, handle, pose, now: float) -> None:
        self.handle = handle
        self.goal = pose  # (x, y, yaw), map frame
        self.started = now
        self.phase = "plan"  # plan, follow, turn, backup
        self.path: list = []
        self.seg = 0
        self.deadline = math.inf
        self.recoveries = 0
        self.backups = 0
        self.marks = np.zeros((0, 2))  # unmapped scan points planned around
        self.pose: Pose | None = None  # the newest map -> base_footprint
        self.progress: tuple[Pose, float] | None = None  # (pose, time) the progress is measured from
        self.blocked_since: float | None = None
        self.blocked_at: tuple[float, float] | None = None
        self.checked: tuple[int, int] | None = None  # (scan, path) the obstacle check last ran on
        self.obstacle = np.zeros((0, 2))  # ... and what it found
        self.backup_from: Pose | None = None
        self.crept = 0.0  # [m] driven straight because a turn would have swept into something
        self.swept = False  # whether that, or a turn the other way, has happened (logged once)
        self.turn_way = 0.0  # the way round a turn in place goes: +1 counter-clockwise, -1, 0: none yet
        self.commanded_at = -math.inf  # when the last velocity command was sent
        self.feedback_at = -math.inf
        self.ticked = -math.inf  # when the last control step ran


class _Stats(TypedDict):
    """The goals' counts and the last abort's reason (navigator_status)."""

    goals: int
    succeeded: int
    aborted: int
    canceled: int
    recoveries: int
    obstacle_stops: int
    last_error: str


class Navigator(SubSystem):
    """``/navigate_to_pose`` on the runtime's bus (Nav2's stand-in); see the module
    docstring. ``params``: overrides of :class:`NavigatorParams` by name."""

    def __init__(self, params: dict | None = None) -> None:
        super().__init__()
        self.params = p = NavigatorParams()
        for key, value in (params or {}).items():
            if key not in {f.name for f in fields(p)}:
                raise ValueError(f"unknown navigator parameter {key!r}")
            if key == "depth" and isinstance(value, dict):  # from a configuration file
                value = DepthObstacleParams(**value)
            setattr(p, key, value)
        bus = self.runtime.bus
        self.tf = TfListener(bus, on_tf=self._on_tf)
        self._cmd = bus.publisher(BASE_COMMAND, TwistStamped)
        self._grid: OccupancyGrid | None = None
        self._map_key: tuple[int, int, float, float, float, int] | None = None  # size, resolution, origin, data
        self._perceived = np.zeros((0, 2))
        self._planners: dict = {}  # marks key -> GridPlanner
        self._goal: _Goal | None = None
        self._scan_pts: np.ndarray | None = None  # the newest scan's beams, map frame
        self._scan_seq = 0  # scans (and depth images) received
        self._depth_pts = np.zeros((0, 2))  # the newest depth image's obstacles, map frame
        depth = self.params.depth
        self._depth_memory = ObstacleMemory(p.depth_memory, depth.min_range, depth.max_range)  # odom frame
        self._depth_subs: list = []  # the depth camera's, while a goal runs
        self._camera_info: CameraInfo | None = None
        self.last_path: BasePath | None = None
        self.stats: _Stats = {
            "goals": 0,
            "succeeded": 0,
            "aborted": 0,
            "canceled": 0,
            "recoveries": 0,
            "obstacle_stops": 0,
            "last_error": "",
        }
        self._subs = [
            bus.subscribe("/map", OccupancyGridMsg, self._on_map, "latched"),
            bus.subscribe("/scan", LaserScan, self._on_scan, "sensor"),
            bus.subscribe(PERCEIVED, PointCloud2, self._on_perceived, "latched"),
        ]
        self._server = bus.action_server(ACTION, NavigateToPose, self._on_goal)

    def close(self) -> None:
        """Stop serving and unsubscribe (the runtime's bus closes them too)."""
        self._server.close()
        for s in self._subs:
            s.close()
        self._subs = []
        close_publishers(self._cmd)
        self._goal = None
        self._watch_depth(False)
        self.tf.close()

    @actor(read_only=True)
    def navigator_status(self) -> dict:
        """What the navigation server has done: goals received, succeeded, aborted and
        canceled, recoveries (replans around obstacles, back-ups), stops for obstacles
        on the scan, the last abort's reason, and the running goal [x, y, yaw] (or None)."""
        g = self._goal
        return {
            **self.stats,
            "goal": list(g.goal) if g is not None else None,
            "phase": g.phase if g is not None else None,
        }

    # -- inputs ------------------------------------------------------------------------
    def _on_map(self, msg: OccupancyGridMsg) -> None:
        info = msg.info
        data = np.asarray(msg.data, dtype=np.int8)
        key = (
            info.width,
            info.height,
            info.resolution,
            info.origin.position.x,
            info.origin.position.y,
            hash(data.tobytes()),
        )
        if key != self._map_key:
            self._map_key = key
            self._grid = OccupancyGrid.from_msg(msg)
            self._planners.clear()

    def _on_perceived(self, msg: PointCloud2) -> None:
        pts = cloud_points(msg)
        if msg.header.frame_id not in ("", GLOBAL_FRAME) and len(pts):
            try:
                T = self.tf.buffer.lookup(GLOBAL_FRAME, msg.header.frame_id)
            except TransformError:
                return
            pts = pts @ T[:2, :2].T + T[:2, 3]
        self._perceived = pts
        self._planners.clear()

    def _on_scan(self, msg: LaserScan) -> None:
        r = np.asarray(msg.ranges, dtype=float)
        a = msg.angle_min + msg.angle_increment * np.arange(len(r))
        ok = np.isfinite(r) & (r >= msg.range_min) & (r < msg.range_max)
        if not ok.any():
            self._scan_pts = np.zeros((0, 2))
            return
        poses = self._sensor_poses(msg.header, msg.header.frame_id)
        if poses is None:
            return
        T_bl, T_mb = poses
        r, a = r[ok], a[ok]
        pl = np.column_stack([r * np.cos(a), r * np.sin(a)])
        pb = pl @ T_bl[:2, :2].T + T_bl[:2, 3]
        x0, x1, ymax = self.params.self_box
        robot = (pb[:, 0] >= x0) & (pb[:, 0] <= x1) & (np.abs(pb[:, 1]) <= ymax)
        pb = pb[~robot]
        self._scan_pts = pb @ T_mb[:2, :2].T + T_mb[:2, 3]
        self._scan_seq += 1

    def _sensor_poses(self, header, frame: str) -> tuple[np.ndarray, np.ndarray] | None:
        """(sensor ``frame`` in base_footprint, base_footprint in the map at the header's
        stamp, or the newest) from tf; None when tf cannot tell."""
        try:
            return self.tf.buffer.lookup(BASE_FRAME, frame), self._base_in(GLOBAL_FRAME, header.stamp)
        except TransformError:
            return None

    def _base_in(self, frame: str, stamp) -> np.ndarray:
        """base_footprint in ``frame`` at ``stamp`` or, when tf has none then (a camera's
        stamp is often ahead of the odometry's), the newest; TransformError without."""
        try:
            return self.tf.buffer.lookup(frame, BASE_FRAME, stamp.sec + stamp.nanosec * 1e-9)
        except TransformError:
            return self.tf.buffer.lookup(frame, BASE_FRAME)

    def _watch_depth(self, on: bool) -> None:
        """Take depth images while a goal runs, one each depth_period: between them the
        subscription is closed, as a simulated camera renders only for subscribers (a
        frame costs it ~40 ms; at its 5 Hz a drive would take twice as long)."""
        if on and not self._depth_subs and self.params.depth_topic:
            bus = self.runtime.bus
            self._depth_subs = [
                bus.subscribe(self.params.camera_info_topic, CameraInfo, self._on_camera_info, "sensor"),
                bus.subscribe(self.params.depth_topic, Image, self._on_depth, "sensor"),
            ]
        elif not on and self._depth_subs:
            for sub in self._depth_subs:
                sub.close()
            self._depth_subs = []
        if not on and self._goal is None:
            self._depth_pts = np.zeros((0, 2))

    def _next_depth(self, g: _Goal) -> None:
        if self._goal is g:
            self._watch_depth(True)

    def _on_camera_info(self, msg: CameraInfo) -> None:
        self._camera_info = msg

    def _on_depth(self, msg: Image) -> None:
        info = self._camera_info
        if info is None or msg.encoding != "32FC1" or self._goal is None:
            return
        dt = np.dtype(">f4" if msg.is_bigendian else "<f4")
        raw = np.frombuffer(bytes(msg.data), np.uint8).reshape(msg.height, msg.step)[:, : msg.width * 4]
        depth = raw.copy().view(dt).reshape(msg.height, msg.width)
        poses = self._sensor_poses(msg.header, msg.header.frame_id or info.header.frame_id)
        if poses is None:
            return
        T_bc, T_mb = poses
        k = info.k
        pb = depth_obstacle_points(depth, k[0], k[4], k[2], k[5], T_bc, self.params.depth)
        self._depth_pts = pb @ T_mb[:2, :2].T + T_mb[:2, 3]
        try:  # remembered in the odometry's frame, which does not jump when the localiser corrects
            T_ob = self._base_in(ODOM_FRAME, msg.header.stamp)
        except TransformError:
            pass
        else:
            pts = pb @ T_ob[:2, :2].T + T_ob[:2, 3]
            self._depth_memory.update(pts, T_ob @ T_bc, k, info.width, info.height, self.runtime.now())
        self._scan_seq += 1
        if self.params.depth_period > 0:
            self._watch_depth(False)
            self.runtime.call_later(self.params.depth_period, self._next_depth, self._goal)

    def _on_tf(self, msg) -> None:
        g = self._goal
        if g is not None and any(ts.child_frame_id == BASE_FRAME for ts in msg.transforms):
            now = self.runtime.now()
            if now - g.ticked >= 1.0 / self.params.controller_frequency - 1e-6:
                g.ticked = now
                self._tick()

    # -- planning ----------------------------------------------------------------------
    def _planner(self, extra: np.ndarray | None = None) -> GridPlanner:
        """The planner on the map with the perceived obstacles (and ``extra`` points)
        marked; one per set of marks."""
        key = None if extra is None or not len(extra) else hash(np.round(extra, 3).tobytes())
        planner = self._planners.get(key)
        if planner is None:
            grid = self._grid
            assert grid is not None  # callers plan only once a map has come
            pts = self._perceived if extra is None else np.vstack([self._perceived, extra])
            if len(pts):
                data = grid.data.copy()
                cols = np.floor((pts[:, 0] - grid.origin[0]) / grid.resolution).astype(int)
                rows = np.floor((pts[:, 1] - grid.origin[1]) / grid.resolution).astype(int)
                inside = (rows >= 0) & (rows < data.shape[0]) & (cols >= 0) & (cols < data.shape[1])
                data[rows[inside], cols[inside]] = 100
                grid = OccupancyGrid(data, grid.resolution, grid.origin)
            p = self.params
            planner = GridPlanner(
                inflate(grid, p.robot_radius, inflation_radius=p.inflation_radius), cost_weight=p.cost_weight
            )
            if len(self._planners) > 8:
                self._planners.clear()
            self._planners[key] = planner
        return planner

    def plan(self, start, goal) -> BasePath:
        """A path from ``start`` (x, y) to ``goal`` (x, y) on the map as the navigator
        sees it (the map and the perceived obstacles)."""
        if self._grid is None:
            raise RuntimeError("no map received on /map yet")
        return self._planner().plan(start, goal)

    def _plan(self, g: _Goal) -> None:
        p = self.params
        assert g.pose is not None  # _tick has set it
        planner = self._planner(g.marks)
        path = planner.plan(g.pose[:2], g.goal[:2])
        if path.failure is FailureReason.START_INVALID and "outside" not in path.message:
            path = plan_out_of(planner, g.pose[:2], g.goal[:2], p.escape_distance, p.escape_winding) or path
        self.last_path = path
        now = self.runtime.now()
        if path.ok:
            g.path = [tuple(w) for w in path.waypoints]
            if len(g.path) < 2:
                g.path = [tuple(g.pose[:2]), tuple(g.goal[:2])]
            g.seg = 0
            g.checked = None
            g.phase = "follow"
            g.deadline = now + p.time_allowance + 3.0 * path.length / p.max_speed
            g.progress = (g.pose, now)
            g.blocked_since = None
            return
        why = path.message
        if path.failure is FailureReason.START_INVALID and "outside" not in why:
            if self._back_up(g, now, "stands too close to something"):
                return
            self._abort(g, START_OCCUPIED, f"cannot leave the start: {why}")
        elif path.failure is FailureReason.START_INVALID:
            self._abort(g, START_OUTSIDE_MAP, why)
        elif path.failure is FailureReason.GOAL_INVALID:
            self._abort(g, GOAL_OUTSIDE_MAP if "outside" in why else GOAL_OCCUPIED, f"no path: {why}")
        elif len(g.marks):
            assert g.blocked_at is not None  # marks are made where the robot was blocked
            self._abort(
                g,
                NO_VALID_PATH,
                f"no path around an obstacle that is not on the map, "
                f"near ({g.blocked_at[0]:.2f}, {g.blocked_at[1]:.2f}): {why}",
            )
        elif path.failure is FailureReason.NO_PATH:
            self._abort(g, NO_VALID_PATH, why)
        else:
            self._abort(g, PLAN_UNKNOWN, why)

    def _back_up(self, g: _Goal, now: float, why: str) -> bool:
        """Back up backup_distance and plan again, once a goal, if the scan shows room
        behind. Whether it does."""
        p = self.params
        if g.backups >= 1 or g.recoveries >= p.max_recoveries or not self._room_behind():
            return False
        assert g.pose is not None  # _tick has set it
        g.backups += 1
        g.recoveries += 1
        self.stats["recoveries"] += 1
        log.info("at (%.2f, %.2f) the robot %s: backing up", g.pose[0], g.pose[1], why)
        g.phase = "backup"
        g.backup_from = None
        g.deadline = now + 5.0 + 2 * p.backup_distance / p.backup_speed
        return True

    def _room_behind(self) -> bool:
        """No beam ends in the strip the base sweeps backing up backup_distance."""
        pts = self._scan_pts
        g = self._goal
        if pts is None or not len(pts) or g is None or g.pose is None:
            return True
        x, y, yaw = g.pose
        c, s = math.cos(yaw), math.sin(yaw)
        dx, dy = pts[:, 0] - x, pts[:, 1] - y
        fwd, side = c * dx + s * dy, -s * dx + c * dy
        x0 = self.params.self_box[0]
        behind = (
            (fwd < x0 + 0.02)
            & (fwd > x0 - self.params.backup_distance - 0.05)
            & (np.abs(side) < self.params.collision_radius)
        )
        return not behind.any()

    # -- goals -------------------------------------------------------------------------
    def _on_goal(self, handle) -> None:
        req = handle.request.pose
        q = req.pose.orientation
        yaw = math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))
        pose = (req.pose.position.x, req.pose.position.y, yaw)
        frame = req.header.frame_id.lstrip("/")
        if frame not in ("", GLOBAL_FRAME):
            try:
                T = self.tf.buffer.lookup(GLOBAL_FRAME, frame) @ planar(*pose)
            except TransformError as e:
                handle.abort(self._result(PLAN_TF_ERROR, f"goal in frame {frame!r}: {e}"))
                return
            pose = (T[0, 3], T[1, 3], math.atan2(T[1, 0], T[0, 0]))
        if not all(math.isfinite(v) for v in pose):
            handle.abort(self._result(PLAN_UNKNOWN, f"goal pose {pose} is not finite"))
            return
        if self._goal is not None:
            old = self._goal
            self._end(old)
            old.handle.abort(self._result(PLAN_UNKNOWN, "preempted by a newer goal"))
        g = self._goal = _Goal(handle, pose, self.runtime.now())
        self._watch_depth(True)
        self.stats["goals"] += 1
        handle.on_cancel(lambda: self._cancel(g))
        self.runtime.call_later(self.params.tf_timeout, self._check_started, g)

    def _check_started(self, g: _Goal) -> None:
        if self._goal is g and g.pose is None:
            self._abort(g, FOLLOW_TF_ERROR, self._no_pose_reason())

    def _no_pose_reason(self) -> str:
        if self._grid is None:
            return "no map received on /map"
        try:
            self.tf.buffer.lookup(GLOBAL_FRAME, BASE_FRAME)
        except TransformError as e:
            return f"no map -> base_footprint transform (is the robot localised? /initialpose): {e}"
        return "no odometry on /tf"

    def _cancel(self, g: _Goal) -> None:
        if self._goal is g:
            self._end(g)
        self.stats["canceled"] += 1
        g.handle.canceled(self._result(NONE, ""))

    def _end(self, g: _Goal) -> None:
        """Stop the base; the goal is no longer run."""
        self._cmd.publish(_twist())
        if self._goal is g:
            self._goal = None
            self._watch_depth(False)

    def _abort(self, g: _Goal, code: int, msg: str) -> None:
        self._end(g)
        self.stats["aborted"] += 1
        self.stats["last_error"] = msg
        log.info("goal (%.2f, %.2f) aborted: %s", g.goal[0], g.goal[1], msg)
        g.handle.abort(self._result(code, msg))

    def _succeed(self, g: _Goal) -> None:
        self._end(g)
        self.stats["succeeded"] += 1
        g.handle.succeed(self._result(NONE, ""))

    @staticmethod
    def _result(code: int, msg: str):
        return NavigateToPose.Result(error_code=code, error_msg=msg)

    # -- control -----------------------------------------------------------------------
    def _tick(self) -> None:
        g = self._goal
        assert g is not None  # _on_tf ticks only while a goal runs
        p = self.params
        now = self.runtime.now()
        try:
            g.pose = self.tf.pose(GLOBAL_FRAME, BASE_FRAME)
        except TransformError:
            if now - g.started > p.tf_timeout:
                self._abort(g, FOLLOW_TF_ERROR, self._no_pose_reason())
            return
        if self._grid is None:
            if now - g.started > p.tf_timeout:
                self._abort(g, PLAN_UNKNOWN, "no map received on /map")
            return
        if g.phase == "plan":
            self._plan(g)
            if self._goal is not g:
                return
        if g.phase == "backup":
            self._backup(g, now)
        elif g.phase == "follow":
            self._follow(g, now)
        elif g.phase == "turn":
            self._turn(g, now)
        if self._goal is g and now - g.feedback_at >= p.feedback_period:
            g.feedback_at = now
            self._feedback(g, now)

    def _backup(self, g: _Goal, now: float) -> None:
        assert g.pose is not None  # _tick has set it
        try:
            odom = self.tf.pose(ODOM_FRAME, BASE_FRAME)
        except TransformError:
            odom = g.pose
        if g.backup_from is None:
            g.backup_from = odom
        x0, y0, yaw0 = g.backup_from
        driven = -((odom[0] - x0) * math.cos(yaw0) + (odom[1] - y0) * math.sin(yaw0))
        if driven >= self.params.backup_distance or now > g.deadline:
            self._cmd.publish(_twist())
            g.phase = "plan"
            return
        self._cmd.publish(_twist(-self.params.backup_speed, 2.0 * _wrap(yaw0 - odom[2])))

    def _follow(self, g: _Goal, now: float) -> None:
        p = self.params
        assert g.pose is not None and g.progress is not None  # _tick's, and _plan's with the path
        x, y, yaw = g.pose
        gx, gy = g.goal[:2]
        dist_goal = math.hypot(gx - x, gy - y)
        if dist_goal < p.xy_goal_tolerance:
            g.phase = "turn"
            g.deadline = now + 10.0 + math.pi / 0.3
            self._turn(g, now)
            return
        if now > g.deadline:
            self._abort(g, CONTROLLER_TIMED_OUT, f"timed out {dist_goal:.2f} m from ({gx:.2f}, {gy:.2f})")
            return
        ref, t_ref = g.progress
        if math.hypot(x - ref[0], y - ref[1]) >= p.progress_radius:
            g.progress = (g.pose, now)
        elif now - t_ref > p.progress_time and g.blocked_since is None:
            # caught on something under the scan (a pallet's corner) while it turned, the
            # base stays put however the wheels spin; backing off frees it
            if self._back_up(g, now, f"made no progress for {p.progress_time:g} s"):
                return
            self._abort(
                g,
                FAILED_TO_MAKE_PROGRESS,
                f"no progress for {p.progress_time:g} s, {dist_goal:.2f} m from ({gx:.2f}, {gy:.2f})",
            )
            return
        g.seg, (tx, ty) = lookahead_point(g.path, g.seg, (x, y), p.lookahead)
        if self._blocked(g, now):
            return
        heading = _wrap(math.atan2(ty - y, tx - x) - yaw)
        if abs(heading) > math.radians(50):
            v = 0.0  # face the path first
        else:
            v = min(p.max_speed, 0.8 * dist_goal + 0.03) * math.cos(heading)
        w = max(-p.max_turn, min(p.max_turn, 2.5 * heading))
        self._drive(g, now, v, w, turn=heading if v == 0.0 else None)

    def _drive(self, g: _Goal, now: float, v: float, w: float, turn: float | None = None, creep: bool = True) -> None:
        """Command (v, w), unless it would sweep the footprint into something the scan or
        the depth camera saw. A turn in place (``turn``: the angle still to turn [rad]) is
        checked whole, and goes the other way round if only that is clear (and keeps to
        it); an arc is checked over sweep_horizon. Blocked, the base drives straight ahead
        or back (up to creep_limit a goal, if ``creep``) until the turn is clear; with no
        clear way, (v, w) as it is."""
        p = self.params
        dt = min(max(now - g.commanded_at, 0.0), 0.5)
        g.commanded_at = now
        if w == 0.0:
            self._cmd.publish(_twist(v, w))
            return
        assert g.pose is not None  # _tick has set it
        pose, pts = g.pose, self._near(g, 0.5)  # what the turning base could hit
        if turn is None:
            g.turn_way = 0.0
            if not sweep_hits(pts, pose, v, w, p.sweep_horizon, p.footprint, pad=p.sweep_pad):
                self._cmd.publish(_twist(v, w))
                return
        else:
            ways = [turn, turn - math.copysign(2 * math.pi, turn)]
            if g.turn_way and math.copysign(1.0, ways[1]) == g.turn_way:
                ways.reverse()  # keep to the way round taken
            for angle in ways:
                if not turn_hits(pts, pose, angle, p.footprint, pad=p.sweep_pad):
                    g.turn_way = math.copysign(1.0, angle)
                    if angle != turn:
                        self._swept(g, "turning the other way round")
                        w = math.copysign(p.max_turn, angle)
                    self._cmd.publish(_twist(0.0, w))
                    return
        if creep and g.crept < p.creep_limit:
            for cv in (p.creep_speed, -p.creep_speed):
                if not sweep_hits(pts, pose, cv, 0.0, p.sweep_horizon, p.footprint, pad=p.sweep_pad):
                    self._swept(g, "driving straight first")
                    g.crept += abs(cv) * dt
                    self._cmd.publish(_twist(cv, 0.0))
                    return
        self._cmd.publish(_twist(v, w))

    def _swept(self, g: _Goal, how: str) -> None:
        if not g.swept:
            g.swept = True
            assert g.pose is not None  # _tick has set it
            log.info("at (%.2f, %.2f) a turn would sweep the base into something: %s", *g.pose[:2], how)

    def _blocked(self, g: _Goal, now: float) -> bool:
        """Is something the map does not show on the path ahead? Stops the base, and
        plans around it once it has stayed there for obstacle_wait."""
        p = self.params
        key = (self._scan_seq, id(g.path))
        if g.checked != key:  # once a scan: the robot moves 4 cm meanwhile
            g.checked, g.obstacle = key, self._obstacle_points(g)
        pts = g.obstacle
        if len(pts) < p.collision_min_points:
            g.blocked_since = None
            return False
        self._cmd.publish(_twist())
        if g.blocked_since is None:
            g.blocked_since = now
            cx, cy = pts.mean(axis=0)
            g.blocked_at = (float(cx), float(cy))
            self.stats["obstacle_stops"] += 1
            log.info("stopped: an obstacle the map does not show at (%.2f, %.2f)", *g.blocked_at)
            return True
        if now - g.blocked_since < p.obstacle_wait:
            return True
        cx, cy = pts.mean(axis=0)
        g.blocked_at = (float(cx), float(cy))
        if g.recoveries >= p.max_recoveries:
            self._abort(
                g,
                PATIENCE_EXCEEDED,
                f"blocked by an obstacle that is not on the map, near "
                f"({g.blocked_at[0]:.2f}, {g.blocked_at[1]:.2f}), after {g.recoveries} recoveries",
            )
            return True
        g.recoveries += 1
        self.stats["recoveries"] += 1
        near = self._unmapped(g, self._near(g, 3.0))
        g.marks = np.vstack([g.marks, near]) if len(g.marks) else near
        g.phase = "plan"
        g.blocked_since = None
        self._plan(g)
        return True

    def _remembered(self) -> np.ndarray:
        """The remembered depth obstacle points, map frame (none without map -> odom)."""
        mem = self._depth_memory.points()
        if not len(mem):
            return mem
        try:
            T = self.tf.buffer.lookup(GLOBAL_FRAME, ODOM_FRAME)
        except TransformError:
            return mem[:0]
        return mem @ T[:2, :2].T + T[:2, 3]

    def _near(self, g: _Goal, radius: float) -> np.ndarray:
        """The newest scan's points, and the depth camera's obstacle points (the newest
        image's and the remembered ones: near the base, below the camera's view, a can is
        seen no more), within ``radius`` of the robot (map frame)."""
        pts = self._scan_pts if self._scan_pts is not None else np.zeros((0, 2))
        pts = np.vstack([pts, self._depth_pts, self._remembered()])
        if not len(pts):
            return np.zeros((0, 2))
        assert g.pose is not None  # _tick has set it
        x, y, _ = g.pose
        return pts[np.hypot(pts[:, 0] - x, pts[:, 1] - y) < radius]

    def _unmapped(self, g: _Goal, pts: np.ndarray) -> np.ndarray:
        """The points that the map (with the perceived obstacles and the goal's marks)
        does not explain: farther than mapped_distance from every obstacle on it."""
        if not len(pts):
            return pts
        cm = self._planner(g.marks).costmap
        grid = cm.grid
        cols = np.floor((pts[:, 0] - grid.origin[0]) / grid.resolution).astype(int)
        rows = np.floor((pts[:, 1] - grid.origin[1]) / grid.resolution).astype(int)
        h, w = cm.clearance.shape
        inside = (rows >= 0) & (rows < h) & (cols >= 0) & (cols < w)
        far = np.zeros(len(pts), dtype=bool)
        far[inside] = cm.clearance[rows[inside], cols[inside]] >= self.params.mapped_distance
        return pts[far]

    def _obstacle_points(self, g: _Goal) -> np.ndarray:
        """The newest scan's unmapped points in the corridor of the path ahead."""
        p = self.params
        near = self._near(g, p.collision_lookahead + p.collision_radius)
        if len(near) < p.collision_min_points:
            return near[:0]
        assert g.pose is not None  # _tick has set it
        line = path_ahead(g.path, g.seg, g.pose[:2], p.collision_lookahead)
        hits = near[distance_to_polyline(near, line) < p.collision_radius]
        if len(hits) < p.collision_min_points:
            return hits[:0]
        return self._unmapped(g, hits)

    def _turn(self, g: _Goal, now: float) -> None:
        p = self.params
        assert g.pose is not None  # _tick has set it
        err = _wrap(g.goal[2] - g.pose[2])
        if abs(err) < p.yaw_goal_tolerance:
            self._succeed(g)
            return
        if now > g.deadline:
            self._abort(g, CONTROLLER_TIMED_OUT, f"turn timed out {math.degrees(err):.1f} deg short")
            return
        w = math.copysign(min(p.max_turn, max(0.05, 2.0 * abs(err))), err)
        self._drive(g, now, 0.0, w, turn=err, creep=False)  # creeping would leave the goal

    def _feedback(self, g: _Goal, now: float) -> None:
        fb = NavigateToPose.Feedback()
        assert g.pose is not None  # _tick has set it
        x, y, yaw = g.pose
        fb.current_pose.header.frame_id = GLOBAL_FRAME
        to_stamp(now, fb.current_pose.header.stamp)
        fb.current_pose.pose.position.x, fb.current_pose.pose.position.y = float(x), float(y)
        fb.current_pose.pose.orientation.z = math.sin(yaw / 2)
        fb.current_pose.pose.orientation.w = math.cos(yaw / 2)
        if g.phase == "follow" and g.path:
            rest = path_ahead(g.path, g.seg, (x, y), math.inf)
            remaining = sum(math.dist(a, b) for a, b in zip(rest[1:], rest[2:])) + math.dist(rest[0], rest[1])
        else:
            remaining = math.hypot(g.goal[0] - x, g.goal[1] - y)
        fb.distance_remaining = float(remaining)
        fb.navigation_time = _duration(now - g.started)
        fb.estimated_time_remaining = _duration(remaining / self.params.max_speed)
        fb.number_of_recoveries = int(g.recoveries)
        g.handle.publish_feedback(fb)


__all__ = ["ACTION", "PERCEIVED", "Navigator", "NavigatorParams", "cloud_points", "lookahead_point"]
