"""The arm and gripper as actors: plan with OMPL, time with ruckig, execute through the
robot's ros2_control controllers' actions.

The arm moves through ``/arm_controller/follow_joint_trajectory``
(control_msgs/FollowJointTrajectory): the timed trajectory is the goal, with a goal
tolerance per joint and a time to settle, and the controller's result says whether the
arm got there. Cancelling a motion cancels the goal; the controller brings the arm to
rest. The gripper moves through ``/gripper_controller/gripper_cmd``
(control_msgs/GripperCommand): its result's ``stalled`` and ``position`` tell a grasp on
something from fingers that closed on nothing.
"""

from __future__ import annotations

import logging
import math
from typing import Any

from control_msgs.action import FollowJointTrajectory, GripperCommand
from control_msgs.msg import JointTolerance
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from bt_engine import ActorbtError, ActorTimeout, SubSystem, actor
from planning import (
    ArmKinematics,
    JointLimits,
    MotionPlan,
    PlanningScene,
    TimedTrajectory,
    plan_joint_motion,
    plan_pose_motion,
    time_trajectory,
)

from .ros_conv import duration_msg, named

log = logging.getLogger("actors.manipulator")

#: Joint positions of the folded "home" pose [rad] (joint1..joint4).
HOME = (0.0, -1.05, 0.35, 0.70)
GRIPPER_OPEN = 0.085  # finger opening [m]
GRIPPER_CLOSED = 0.0
FINGERS = ("gripper_left_joint", "gripper_right_joint")
SAMPLE_DT = 0.02  # spacing of the trajectory's points [s]
CONVERGED = 0.01  # goal tolerance of each joint at the end of a motion [rad]
SETTLE_TIME = 2.0  # how long past the trajectory's end the arm may take to settle [s]
#: [rad] a motion whose goal the controller gave up on (GOAL_TOLERANCE_VIOLATED: not
#: settled within CONVERGED in SETTLE_TIME) still counts as arrived when every joint is
#: this near its goal: an arm that carries something sags under it, or rocks a little
#: with it, by about a hundredth of a radian (3 mm at the tool)
ARRIVED = 0.03
GRIPPER_TIMEOUT = 5.0  # how long a gripper command may take to end [s]
ARM_ACTION = "/arm_controller/follow_joint_trajectory"
GRIPPER_ACTION = "/gripper_controller/gripper_cmd"

#: The gripper controller's position scale [m] (the OpenManipulator-X's gripper_left_joint:
#: -0.010 closed .. 0.019 open) and the finger opening it spans on this robot [m]: the
#: simulated robot's widened gripper opens 0 .. 90 mm over that range (sim/actuators.py,
#: ``gripper_opening``, is the definition; tests/test_sim_controllers.py keeps the two
#: equal). A real OpenManipulator-X would be calibrated here.
GRIPPER_POSITIONS = (-0.010, 0.019)
GRIPPER_OPENINGS = (0.0, 0.090)


def gripper_command_position(width: float) -> float:
    """The gripper controller's position [m] for a finger opening ``width`` [m]."""
    (p0, p1), (w0, w1) = GRIPPER_POSITIONS, GRIPPER_OPENINGS
    f = min(max((width - w0) / (w1 - w0), 0.0), 1.0)
    return p0 + f * (p1 - p0)


def gripper_width(position: float) -> float:
    """The finger opening [m] at a gripper controller position [m]."""
    (p0, p1), (w0, w1) = GRIPPER_POSITIONS, GRIPPER_OPENINGS
    f = min(max((position - p0) / (p1 - p0), 0.0), 1.0)
    return w0 + f * (w1 - w0)


def goal_result(error: BaseException | None) -> Any:
    """The result an action goal ended with, from a failed call's exception chain (an
    aborted or canceled goal fails the call with it), or None."""
    seen = set()
    while error is not None and id(error) not in seen:
        seen.add(id(error))
        result = getattr(error, "result", None)
        if result is not None and hasattr(result, "get_fields_and_field_types"):
            return result
        error = error.__cause__ or error.__context__
    return None


class MotionError(ActorbtError):
    """An arm motion could not be planned or did not reach its goal."""


class Manipulator(SubSystem):
    """OpenManipulator-X-like 4-DOF arm and parallel gripper.

    Poses are in the robot's ``base_footprint`` frame: x forward, z up [m]; ``pitch``
    is the tool's angle below the horizontal [rad] (pi/2 points straight down).
    """

    def __init__(self, velocity_scale: float = 0.35, acceleration: float = 2.0, jerk: float = 15.0) -> None:
        super().__init__()
        self.kinematics = ArmKinematics.from_urdf()
        self.scene = PlanningScene(self.kinematics, fixed_joints={f: GRIPPER_OPEN / 2 for f in FINGERS})
        self.limits = JointLimits.from_kinematics(
            self.kinematics, acceleration=acceleration, jerk=jerk, velocity_scale=velocity_scale
        )
        self.joints = tuple(self.kinematics.joint_names)
        self.register_action("follow_joint_trajectory", FollowJointTrajectory, ARM_ACTION, moves=True)
        self.register_action("gripper_cmd", GripperCommand, GRIPPER_ACTION, moves=True)
        self.register_subscriber("joint_states", JointState, "/joint_states", 1)
        self.set_value("last_plan", None)
        self.set_value("gripper", None)

    # -- state -------------------------------------------------------------------------
    def _state(self) -> tuple[list[float], list[float]]:
        msg = self.run_actor("joint_states")
        q = named(msg.name, msg.position, self.joints)
        qd = named(msg.name, msg.velocity, self.joints)
        return q, qd

    @actor(read_only=True)
    def get_status(self) -> dict:
        """Current arm joints [rad], joint speeds [rad/s], tool pose, and the gripper as its
        last command left it (see ``close``; None before the first)."""
        q, qd = self._state()
        pose = self.kinematics.fk_pose(q)
        return {
            "joints": q,
            "velocities": qd,
            "gripper": self.get_value("gripper"),
            "pose": {"x": pose.x, "y": pose.y, "z": pose.z, "pitch": pose.pitch},
        }

    # -- motions -----------------------------------------------------------------------
    @actor(moves=True)
    def home(self) -> list[float]:
        """Fold the arm into its home pose."""
        return self.run_actor("move_joint", *HOME)

    @actor(moves=True, limits={"q": (-math.pi, math.pi)})
    def move_joint(self, *q: float) -> list[float]:
        """Plan and move to joint positions ``q`` (joint1..joint4) [rad]; returns where it ended.

        Args:
            *q: the four joint positions, joint1 (base yaw) to joint4 (wrist) [rad]
        """
        if len(q) != len(self.joints):
            raise MotionError(f"move_joint needs {len(self.joints)} joint values, got {len(q)}")
        start, _ = self._state()
        return self._run_plan(plan_joint_motion(start, q, self.scene))

    @actor(moves=True, limits={"deg": (-180.0, 180.0)})
    def move_joint_degree(self, *deg: float) -> list[float]:
        """As move_joint, in degrees; returns where it ended [rad].

        Args:
            *deg: the four joint positions, joint1 (base yaw) to joint4 (wrist) [deg]
        """
        return self.run_actor("move_joint", *(math.radians(d) for d in deg))

    @actor(moves=True, limits={"delta_deg": (-90.0, 90.0)})
    def adjust_joint(self, *delta_deg: float) -> list[float]:
        """Move every joint by ``delta_deg`` [deg] from where it is; returns where it ended [rad].

        Args:
            *delta_deg: the change of each of the four joints, joint1 to joint4 [deg]
        """
        q, _ = self._state()
        if len(delta_deg) != len(q):
            raise MotionError(f"adjust_joint needs {len(q)} deltas, got {len(delta_deg)}")
        return self.run_actor("move_joint", *(a + math.radians(d) for a, d in zip(q, delta_deg)))

    @actor(moves=True, limits={"x": (-0.6, 0.6), "y": (-0.6, 0.6), "z": (-0.1, 0.8), "pitch": (-math.pi, math.pi)})
    def move_to_pose(self, x: float, y: float, z: float, pitch: float) -> list[float]:
        """Plan and move the tool to (x, y, z) [m] in base_footprint with ``pitch`` [rad];
        returns the joint positions reached [rad].

        Args:
            x: tool position forward of the base, base_footprint frame [m]
            y: tool position to the left of the base, base_footprint frame [m]
            z: tool height above the floor [m]
            pitch: tool angle below the horizontal; pi/2 points straight down [rad]
        """
        start, _ = self._state()
        return self._run_plan(plan_pose_motion(start, (x, y, z, pitch), self.scene))

    @actor(read_only=True)
    def reachable(self, x: float, y: float, z: float, pitch: float) -> bool:
        """Can the tool be at (x, y, z) [m] in base_footprint with ``pitch`` [rad]? (Its
        inverse kinematics only: nothing moves.)

        Args:
            x: tool position forward of the base, base_footprint frame [m]
            y: tool position to the left of the base, base_footprint frame [m]
            z: tool height above the floor [m]
            pitch: tool angle below the horizontal; pi/2 points straight down [rad]
        """
        return bool(self.kinematics.ik(x, y, z, pitch).ok)

    @actor(moves=True, limits={"width": (0.0, GRIPPER_OPENINGS[1])})
    def open(self, width: float = GRIPPER_OPEN) -> dict:
        """Open the gripper to ``width`` [m]; returns the gripper's state as ``close`` does.

        Args:
            width: finger opening to reach [m]
        """
        return self._gripper(width)

    @actor(moves=True, limits={"width": (0.0, GRIPPER_OPENINGS[1])})
    def close(self, width: float = GRIPPER_CLOSED) -> dict:
        """Close the gripper; on an object the fingers stall at its width. Returns the
        controller's result: ``width`` (the finger opening) [m], ``position`` (on the
        controller's scale) [m], ``effort`` [N], ``stalled`` (stopped short of ``width``:
        something is between the fingers), ``reached_goal`` and ``centre`` (the middle
        between the fingers, to the left of the tool's axis [m]).

        Args:
            width: finger opening to close to; 0 closes fully [m]
        """
        return self._gripper(width)

    # -- execution ---------------------------------------------------------------------
    def _gripper(self, width: float) -> dict:
        goal = GripperCommand.Goal()
        goal.command.position = gripper_command_position(float(width))
        try:
            result = self.run_actor_mode("gripper_cmd", "timed", GRIPPER_TIMEOUT, goal)
        except ActorTimeout as e:  # the goal is canceled: the fingers hold where they are
            raise MotionError(f"the gripper did not settle within {GRIPPER_TIMEOUT:g} s") from e
        except ActorbtError as e:
            # the controller aborts a goal on which the fingers stalled (allow_stalling
            # false, as on the TurtleBot3): a grasp, which its result reports
            result = goal_result(e)
            if result is None or not result.stalled:
                raise
        state = {
            "width": gripper_width(result.position),
            "position": float(result.position),
            "effort": float(result.effort),
            "stalled": bool(result.stalled),
            "reached_goal": bool(result.reached_goal),
            "centre": self._finger_centre(),
        }
        self.set_value("gripper", state)
        return state

    def _finger_centre(self) -> float:
        """Where the middle between the fingers is [m], to the left of the tool's axis
        (gripper_left_joint and gripper_right_joint in /joint_states; 0 when the fingers
        are coupled, as on a real OpenManipulator-X, or not reported). Closed on an object,
        each finger stops where it meets it: the middle says where the object is."""
        msg = self.run_actor("joint_states")
        q = dict(zip(msg.name, msg.position))
        if not all(f in q for f in FINGERS):
            return 0.0
        return 0.5 * (float(q[FINGERS[0]]) - float(q[FINGERS[1]]))

    def _run_plan(self, plan: MotionPlan) -> list[float]:
        self.set_value("last_plan", plan)
        if not plan.ok:
            raise MotionError(f"no arm motion: {plan.message}")
        traj = time_trajectory(plan.path, self.limits)
        return self._execute(traj)

    def _trajectory_msg(self, traj: TimedTrajectory) -> JointTrajectory:
        sampled = traj.sample(SAMPLE_DT)
        msg = JointTrajectory()
        msg.joint_names = list(self.joints)
        for t, p, v in zip(sampled.times, sampled.positions, sampled.velocities):
            pt = JointTrajectoryPoint()
            pt.positions = [float(a) for a in p]
            pt.velocities = [float(a) for a in v]
            pt.time_from_start = duration_msg(float(t))
            msg.points.append(pt)
        msg.points[-1].velocities = [0.0] * len(self.joints)  # the controller wants it at rest
        return msg

    def _execute(self, traj: TimedTrajectory) -> list[float]:
        goal = FollowJointTrajectory.Goal()
        goal.trajectory = self._trajectory_msg(traj)
        goal.goal_tolerance = [JointTolerance(name=j, position=CONVERGED) for j in self.joints]
        goal.goal_time_tolerance = duration_msg(SETTLE_TIME)
        try:
            self.run_actor("follow_joint_trajectory", goal)
        except ActorbtError as e:
            result = goal_result(e)
            if result is None:
                raise
            q, _ = self._state()
            target = goal.trajectory.points[-1].positions
            off = max(abs(a - b) for a, b in zip(q, target))
            if result.error_code == FollowJointTrajectory.Result.GOAL_TOLERANCE_VIOLATED and off <= ARRIVED:
                log.info(
                    "the arm arrived %.3f rad from its goal, not settled within %.2f rad: %s",
                    off,
                    CONVERGED,
                    result.error_string,
                )
                return q
            raise MotionError(
                f"the arm did not reach its goal: {result.error_string} (error_code {result.error_code})"
            ) from e
        q, _ = self._state()
        return q

    def _last_plan(self) -> Any:
        return self.get_value("last_plan")
