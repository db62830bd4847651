"""The arm's and the gripper's controllers, as ros2_control runs them on a TurtleBot3 with an
OpenManipulator-X (turtlebot3_manipulation_bringup's hardware_controller_manager.yaml),
served as actions on the runtime's bus (``bus.action_server``: the same code serves them
on every transport that serves actions).

``/arm_controller/follow_joint_trajectory`` (control_msgs/action/FollowJointTrajectory),
joints joint1..joint4, like ``joint_trajectory_controller``:

* a goal is validated first and aborted with ``error_code`` INVALID_JOINTS (no joint
  names, a joint named twice, not the arm's, or not all four: ``allow_partial_joints_goal``
  is false), INVALID_GOAL (no points, sizes that do not match, times that do not increase,
  a last point that still moves, a multi-DOF trajectory) or OLD_HEADER_TIMESTAMP, with an
  ``error_string`` that says what is wrong (the real controller rejects such goals; the
  bus's goals are accepted on arrival, so here they end aborted at once);
* an accepted goal preempts the running one, which ends canceled with INVALID_GOAL and
  "Current goal cancelled due to new incoming action." (a trajectory on the
  ``/arm_controller/joint_trajectory`` topic preempts it alike);
* feedback (``desired``, ``actual``, ``error`` = desired - actual) at
  ``action_monitor_rate``;
* the goal succeeds (SUCCESSFUL) once the last point's time has come and every joint is
  within its goal tolerance: position (``goal_tolerance`` of the goal; the server's default
  is 0, unchecked, as the TurtleBot3 configures it) and velocity (default
  ``stopped_velocity_tolerance`` 0.01 rad/s). Past ``goal_time_tolerance`` (the goal's, or
  the server's ``goal_time``; 0: no limit) it aborts with GOAL_TOLERANCE_VIOLATED. A
  ``path_tolerance`` the goal sets is checked on the way (PATH_TOLERANCE_VIOLATED, then
  the arm stops). Tolerances follow JointTolerance: > 0 a limit, 0 the default, -1 none;
  a tolerance naming an unknown joint leaves the defaults, as the real controller does;
* a cancel stops the arm smoothly, every joint decelerating at ``stop_deceleration``
  from the desired state (the real controller holds its last command, which on a
  position-controlled arm is an abrupt stop) and ends the goal canceled.

``/gripper_controller/gripper_cmd`` (control_msgs/action/GripperCommand), like
``position_controllers/GripperActionController`` on joint ``gripper_left_joint``:
``command.position`` [m] runs from -0.010 (closed) to 0.019 (open), the real gripper's
range, mapped onto the simulated fingers by :func:`sim.actuators.gripper_opening`;
``max_effort`` is not used (a position-controlled gripper ignores it; the fingers squeeze
with their 10 N each). The goal succeeds with ``reached_goal`` once the position is within
``goal_tolerance`` of the command; when the fingers stop short of it (for ``stall_timeout``
they move less than ``stall_velocity_threshold * stall_timeout``: their average speed
stays below the threshold) the goal ends with ``stalled``, aborted
as the real controller does (``allow_stalling`` false) or succeeded with
``allow_stalling``. The result carries the position, so closing on an object (stalled,
position above the closed end) is told apart from closing on nothing (reached_goal at
-0.010). A new goal preempts the running one (canceled, empty result); a cancel holds the
fingers where they are.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

from builtin_interfaces.msg import Time
from control_msgs.action import FollowJointTrajectory, GripperCommand
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from bt_engine.bus.actions import ServerGoal
from bt_engine.errors import ActorbtError

from .actuators import (
    ArmTrajectory,
    TrajectoryError,
    duration_to_sec,
    gripper_opening,
    gripper_position,
    gripper_speed,
    stop_trajectory,
    trajectory_from_msg,
)
from .robot import ARM, GRIPPER_FORCE, JOINT_STATE_NAMES

log = logging.getLogger("sim.controllers")

ARM_ACTION = "/arm_controller/follow_joint_trajectory"
ARM_TRAJECTORY = "/arm_controller/joint_trajectory"
GRIPPER_ACTION = "/gripper_controller/gripper_cmd"

ArmResult = FollowJointTrajectory.Result
GripperResult = GripperCommand.Result
PREEMPTED = "Current goal cancelled due to new incoming action."

_ARM_IDX = [JOINT_STATE_NAMES.index(n) for n in ARM]
_FINGER_IDX = [JOINT_STATE_NAMES.index(n) for n in ("gripper_left_joint", "gripper_right_joint")]


@dataclass(frozen=True)
class ArmControllerConfig:
    """The arm controller's parameters (joint_trajectory_controller's names)."""

    #: constraints.goal_time [s]: how long past the last point the goal may take to
    #: come within tolerance; 0: no limit (the TurtleBot3's setting)
    goal_time: float = 0.0
    #: constraints.stopped_velocity_tolerance [rad/s]: the default goal velocity tolerance
    stopped_velocity_tolerance: float = 0.01
    #: constraints.<joint>.goal [rad]: the default goal position tolerance; 0: unchecked
    goal_position_tolerance: float = 0.0
    #: constraints.<joint>.trajectory [rad]: the default path tolerance; 0: unchecked
    path_position_tolerance: float = 0.0
    allow_partial_joints_goal: bool = False
    #: feedback rate [Hz]
    action_monitor_rate: float = 20.0
    #: the simulator's smooth stop on a cancel or a path violation [rad/s^2]
    stop_deceleration: float = 2.0


@dataclass(frozen=True)
class GripperControllerConfig:
    """The gripper controller's parameters (gripper_action_controller's names). The
    defaults are ros2_control's except ``goal_tolerance`` (0.01 there: a third of the
    OpenManipulator-X's stroke, which would call a half-open gripper open) and
    ``stall_timeout`` (1 s there)."""

    goal_tolerance: float = 0.0003  # [m] of position (about 1 mm of opening here)
    stall_velocity_threshold: float = 0.001  # [m/s] of position
    stall_timeout: float = 0.5  # [s]
    allow_stalling: bool = False
    action_monitor_rate: float = 20.0  # feedback [Hz]


def _stamp(t: float) -> Time:
    sec, nsec = divmod(int(round(t * 1e9)), 1_000_000_000)
    return Time(sec=sec, nanosec=nsec)


def _serve(bus, name, action_type, on_goal):
    """The action server, or None (with a warning) on a transport that serves none yet."""
    try:
        return bus.action_server(name, action_type, on_goal)
    except ActorbtError as e:
        log.warning("%s is not offered: %s", name, e)
        return None


def _point(positions, velocities=None) -> JointTrajectoryPoint:
    pt = JointTrajectoryPoint()
    pt.positions = [float(x) for x in positions]
    if velocities is not None:
        pt.velocities = [float(x) for x in velocities]
    return pt


@dataclass
class _ArmGoal:
    handle: ServerGoal
    traj: ArmTrajectory
    goal_position: list[float]
    goal_velocity: list[float]
    path_position: list[float]
    goal_time: float
    ticks: int = 0
    number: int = 0  # 1 for the first goal this controller took


class ArmController:
    """joint_trajectory_controller for joint1..joint4 (see the module docstring)."""

    def __init__(self, sim, bus, config: ArmControllerConfig | None = None):
        self.sim = sim
        self.config = config or ArmControllerConfig()
        self.active: _ArmGoal | None = None
        self.goals = 0  # goals taken so far
        #: goal numbers to abort half way (a fault injected by ``actorbt robot --fault``)
        self.abort_goals: set[int] = set()
        self._feedback_every = max(1, round(1.0 / (sim.dt * self.config.action_monitor_rate)))
        self.server = _serve(bus, ARM_ACTION, FollowJointTrajectory, self._on_goal)
        self.sub = bus.subscribe(ARM_TRAJECTORY, JointTrajectory, self.on_trajectory)

    def close(self):
        self.sub.close()
        if self.server is not None:
            self.server.close()  # aborts a running goal
        self.active = None

    # ---------------------------------------------------------------- commands
    def _start_state(self, now):
        """Where a new trajectory starts: the running one's desired state while it moves
        (open-loop, as the TurtleBot3's controller), else the measured positions."""
        traj = self.sim.arm_trajectory
        if traj is not None and now < traj.end_time:
            return traj.sample(now)
        return self.sim.robot.arm_positions(), None

    def _build(self, msg, now):
        pos, vel = self._start_state(now)
        return trajectory_from_msg(
            msg,
            ARM,
            now,
            pos,
            vel,
            allow_partial=self.config.allow_partial_joints_goal,
            stamp_offset=self.sim.stamp_offset,
        )

    def on_trajectory(self, msg: JointTrajectory) -> bool:
        """A trajectory on the topic: replaces the running one (and preempts a goal)."""
        now = self.sim.now()
        try:
            traj = self._build(msg, now)
        except TrajectoryError as e:
            log.warning("ignored %s: %s", ARM_TRAJECTORY, e)
            return False
        self._preempt()
        self.sim.set_arm_trajectory(traj)
        return True

    def _on_goal(self, goal) -> None:
        req = goal.request
        now = self.sim.now()
        if req.multi_dof_trajectory.joint_names or req.multi_dof_trajectory.points:
            goal.abort(
                ArmResult(error_code=ArmResult.INVALID_GOAL, error_string="multi-DOF trajectories are not supported")
            )
            return
        try:
            traj = self._build(req.trajectory, now)
        except TrajectoryError as e:
            goal.abort(ArmResult(error_code=e.code, error_string=str(e)))
            return
        self._preempt()
        self.goals += 1
        active = self.active = _ArmGoal(goal, traj, *self._tolerances(req), number=self.goals)
        self.sim.set_arm_trajectory(traj)
        goal.on_cancel(lambda: self._cancel(active))

    def _tolerances(self, req) -> tuple[list[float], list[float], list[float], float]:
        c = self.config
        n = len(ARM)
        goal_pos, goal_vel = [c.goal_position_tolerance] * n, [c.stopped_velocity_tolerance] * n
        path_pos = [c.path_position_tolerance] * n
        try:
            for tolerances, pos_row, vel_row in (
                (req.goal_tolerance, goal_pos, goal_vel),
                (req.path_tolerance, path_pos, None),
            ):
                for tol in tolerances:
                    if tol.name not in ARM:
                        raise ValueError(f"tolerance for an unknown joint {tol.name!r}")
                    i = ARM.index(tol.name)
                    pos_row[i] = _resolve(pos_row[i], tol.position)
                    if vel_row is not None:
                        vel_row[i] = _resolve(vel_row[i], tol.velocity)
        except ValueError as e:  # as the real controller: the defaults, and a word in the log
            log.warning("%s: %s; using the default tolerances", ARM_ACTION, e)
            goal_pos, goal_vel = [c.goal_position_tolerance] * n, [c.stopped_velocity_tolerance] * n
            path_pos = [c.path_position_tolerance] * n
        goal_time = duration_to_sec(req.goal_time_tolerance)
        goal_time = c.goal_time if goal_time == 0.0 else max(goal_time, 0.0)
        return goal_pos, goal_vel, path_pos, goal_time

    def _preempt(self) -> None:
        if self.active is not None:
            old, self.active = self.active, None
            old.handle.canceled(ArmResult(error_code=ArmResult.INVALID_GOAL, error_string=PREEMPTED))

    def _stop(self, now) -> None:
        """Decelerate to rest from the desired state."""
        traj = self.sim.arm_trajectory
        if traj is None:
            return
        pos, vel = traj.sample(now)
        self.sim.set_arm_trajectory(stop_trajectory(ARM, now, pos, vel, self.config.stop_deceleration))

    def _cancel(self, active: _ArmGoal) -> None:
        if self.active is not active:
            active.handle.canceled(ArmResult())
            return
        self.active = None
        self._stop(self.sim.now())
        active.handle.canceled(
            ArmResult(error_code=ArmResult.SUCCESSFUL, error_string="canceled: the arm decelerates to rest")
        )

    # ---------------------------------------------------------------- monitoring
    def update(self, now: float, joint_states=None) -> None:
        """After each physics step: feedback, tolerances, the goal's end."""
        g = self.active
        if g is None:
            return
        q, v, _ = joint_states or self.sim.robot.joint_states()
        actual = [q[i] for i in _ARM_IDX]
        actual_vel = [v[i] for i in _ARM_IDX]
        desired, desired_vel = g.traj.sample(now)
        error = [d - a for d, a in zip(desired, actual)]
        if g.ticks % self._feedback_every == 0:
            fb = FollowJointTrajectory.Feedback()
            fb.header.stamp = _stamp(self.sim.ros_time(now))
            fb.joint_names = list(ARM)
            fb.desired = _point(desired, desired_vel)
            fb.actual = _point(actual, actual_vel)
            fb.error = _point(error, [d - a for d, a in zip(desired_vel, actual_vel)])
            g.handle.publish_feedback(fb)
        g.ticks += 1
        if g.number in self.abort_goals and now >= (g.traj.t0 + g.traj.end_time) / 2:
            log.warning("%s: goal %d aborted half way (a fault injected on the robot side)", ARM_ACTION, g.number)
            self.active = None
            self._stop(now)
            g.handle.abort(
                ArmResult(
                    error_code=ArmResult.PATH_TOLERANCE_VIOLATED,
                    error_string="Aborted due to path tolerance violation (a fault injected on the robot side)",
                )
            )
            return
        if now < g.traj.end_time:
            bad = [
                f"{n} {abs(e):.3f} rad (tolerance {t:g})"
                for n, e, t in zip(ARM, error, g.path_position)
                if t > 0 and abs(e) > t
            ]
            if bad:
                self.active = None
                self._stop(now)
                g.handle.abort(
                    ArmResult(
                        error_code=ArmResult.PATH_TOLERANCE_VIOLATED,
                        error_string="Aborted due to path tolerance violation: " + ", ".join(bad),
                    )
                )
            return
        bad = [
            f"{n} {abs(e):.4f} rad off (tolerance {t:g})"
            for n, e, t in zip(ARM, error, g.goal_position)
            if t > 0 and abs(e) > t
        ]
        bad += [
            f"{n} still moving at {abs(w):.4f} rad/s (tolerance {t:g})"
            for n, w, t in zip(ARM, actual_vel, g.goal_velocity)
            if t > 0 and abs(w) > t
        ]
        if not bad:
            self.active = None
            g.handle.succeed(ArmResult(error_code=ArmResult.SUCCESSFUL, error_string="Goal successfully reached!"))
        elif g.goal_time > 0 and now - g.traj.end_time > g.goal_time:
            self.active = None  # the last point stays commanded: the arm holds there
            late = now - g.traj.end_time - g.goal_time
            g.handle.abort(
                ArmResult(
                    error_code=ArmResult.GOAL_TOLERANCE_VIOLATED,
                    error_string=f"Aborted due to goal_time_tolerance exceeding by "
                    f"{late:.3f} seconds: " + ", ".join(bad),
                )
            )


def _resolve(default: float, value: float) -> float:
    """JointTolerance: > 0 the limit, 0 the default, -1 none (0 internally: unchecked)."""
    if value > 0:
        return float(value)
    if value == 0:
        return default
    if value == -1:
        return 0.0
    raise ValueError(f"illegal tolerance {value:g}")


@dataclass
class _GripperGoal:
    handle: ServerGoal
    position: float
    last_movement: float
    anchor: float  # the position when the fingers last counted as moving
    ticks: int = field(default=0)


class GripperController:
    """position_controllers/GripperActionController (see the module docstring)."""

    def __init__(self, sim, bus, config: GripperControllerConfig | None = None):
        self.sim = sim
        self.config = config or GripperControllerConfig()
        self.active: _GripperGoal | None = None
        self._feedback_every = max(1, round(1.0 / (sim.dt * self.config.action_monitor_rate)))
        self.server = _serve(bus, GRIPPER_ACTION, GripperCommand, self._on_goal)

    def close(self):
        if self.server is not None:
            self.server.close()
        self.active = None

    def state(self, joint_states=None):
        """(position [m], velocity [m/s], effort [N]) on the controller's scale."""
        q, v, e = joint_states or self.sim.robot.joint_states()
        opening = sum(q[i] for i in _FINGER_IDX)
        rate = sum(v[i] for i in _FINGER_IDX)
        squeezing = q[_FINGER_IDX[0]] > self.sim.robot.gripper_width / 2 + 1e-3
        effort = GRIPPER_FORCE if squeezing else abs(e[_FINGER_IDX[0]])
        return gripper_position(opening), gripper_speed(rate), effort

    def _on_goal(self, goal) -> None:
        if self.active is not None:
            old, self.active = self.active, None
            old.handle.canceled(GripperResult())
        position = float(goal.request.command.position)
        self.sim.set_gripper(gripper_opening(position))
        active = self.active = _GripperGoal(goal, position, self.sim.now(), self.state()[0])
        goal.on_cancel(lambda: self._cancel(active))

    def _cancel(self, active: _GripperGoal) -> None:
        if self.active is active:
            self.active = None
            position, _, _ = self.state()
            self.sim.set_gripper(gripper_opening(position))  # hold where they are
        active.handle.canceled(GripperResult())

    def update(self, now: float, joint_states=None) -> None:
        g = self.active
        if g is None:
            return
        c = self.config
        position, _, effort = self.state(joint_states)
        if g.ticks % self._feedback_every == 0:
            g.handle.publish_feedback(GripperCommand.Feedback(position=position, effort=effort))
        g.ticks += 1
        if abs(g.position - position) < c.goal_tolerance:
            self.active = None
            g.handle.succeed(GripperResult(position=position, effort=effort, reached_goal=True))
        elif abs(position - g.anchor) > c.stall_velocity_threshold * c.stall_timeout:
            # moving: judged by the distance covered, not the joint velocity of the moment,
            # which chatters while the fingers squeeze an object (a servo's velocity reading
            # is smoothed; pybullet's is not)
            g.last_movement, g.anchor = now, position
        elif now - g.last_movement > c.stall_timeout:
            self.active = None
            result = GripperResult(position=position, effort=effort, stalled=True)
            (g.handle.succeed if c.allow_stalling else g.handle.abort)(result)
