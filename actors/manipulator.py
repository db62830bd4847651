"""The arm and gripper as actors: plan with OMPL, time with ruckig, execute on topics.

Execution publishes the timed trajectory on ``/arm_controller/joint_trajectory`` and
follows ``/joint_states`` until the arm converges or a deadline passes. Cancelling a
motion sends a jerk-limited stop computed with ruckig, not a freeze.
"""
from __future__ import annotations

import math
from typing import Any

from sensor_msgs.msg import JointState
from std_msgs.msg import Float64
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from bt_engine import ActorbtError, Cancelled, SubSystem, actor
from planning import (ArmKinematics, JointLimits, MotionPlan, PlanningScene, TimedTrajectory,
                      plan_joint_motion, plan_pose_motion, stop_trajectory, time_trajectory)

from .ros_conv import duration_msg, named

#: Joint positions of the folded "home" pose [rad] (joint1..joint4).
HOME = (0.0, -1.05, 0.35, 0.70)
GRIPPER_OPEN = 0.085    # finger opening [m]
GRIPPER_CLOSED = 0.0
FINGERS = ("gripper_left_joint", "gripper_right_joint")
SAMPLE_DT = 0.02        # spacing of published trajectory points [s]
CONVERGED = 0.01        # joint position tolerance at the end of a motion [rad]
SETTLE_TIME = 2.0       # how long past the trajectory's end the arm may take to settle [s]


class MotionError(ActorbtError):
    """An arm motion could not be planned or did not reach its goal."""


class Manipulator(SubSystem):
    """OpenManipulator-X-like 4-DOF arm and parallel gripper.

    Poses are in the robot's ``base_footprint`` frame: x forward, z up [m]; ``pitch``
    is the tool's angle below the horizontal [rad] (pi/2 points straight down).
    """

    def __init__(self, velocity_scale: float = 0.35, acceleration: float = 2.0,
                 jerk: float = 15.0) -> None:
        super().__init__()
        self.kinematics = ArmKinematics.from_urdf()
        self.scene = PlanningScene(self.kinematics, fixed_joints={f: GRIPPER_OPEN / 2 for f in FINGERS})
        self.limits = JointLimits.from_kinematics(
            self.kinematics, acceleration=acceleration, jerk=jerk, velocity_scale=velocity_scale)
        self.joints = tuple(self.kinematics.joint_names)
        self.register_publisher("arm_command", JointTrajectory, "/arm_controller/joint_trajectory")
        self.register_publisher("gripper_command", Float64, "/gripper/command")
        self.register_subscriber("joint_states", JointState, "/joint_states", 1)
        self.set_value("last_plan", None)

    # -- state -------------------------------------------------------------------------
    def _state(self) -> tuple[list[float], list[float], float]:
        msg = self.run_actor("joint_states")
        q = named(msg.name, msg.position, self.joints)
        qd = named(msg.name, msg.velocity, self.joints)
        width = sum(named(msg.name, msg.position, FINGERS))
        return q, qd, width

    @actor
    def get_status(self) -> dict:
        """Current arm joints [rad], joint speeds [rad/s], gripper opening [m] and tool pose."""
        q, qd, width = self._state()
        pose = self.kinematics.fk_pose(q)
        return {"joints": q, "velocities": qd, "gripper": width,
                "pose": {"x": pose.x, "y": pose.y, "z": pose.z, "pitch": pose.pitch}}

    # -- motions -----------------------------------------------------------------------
    @actor
    def home(self) -> list[float]:
        """Fold the arm into its home pose."""
        return self.run_actor("move_joint", *HOME)

    @actor
    def move_joint(self, *q: float) -> list[float]:
        """Plan and move to joint positions ``q`` (joint1..joint4) [rad]; returns where it ended.

        Args:
            *q: the four joint positions, joint1 (base yaw) to joint4 (wrist) [rad]
        """
        if len(q) != len(self.joints):
            raise MotionError(f"move_joint needs {len(self.joints)} joint values, got {len(q)}")
        start, _, _ = self._state()
        return self._run_plan(plan_joint_motion(start, q, self.scene))

    @actor
    def move_joint_degree(self, *deg: float) -> list[float]:
        """As move_joint, in degrees; returns where it ended [rad].

        Args:
            *deg: the four joint positions, joint1 (base yaw) to joint4 (wrist) [deg]
        """
        return self.run_actor("move_joint", *(math.radians(d) for d in deg))

    @actor
    def adjust_joint(self, *delta_deg: float) -> list[float]:
        """Move every joint by ``delta_deg`` [deg] from where it is; returns where it ended [rad].

        Args:
            *delta_deg: the change of each of the four joints, joint1 to joint4 [deg]
        """
        q, _, _ = self._state()
        if len(delta_deg) != len(q):
            raise MotionError(f"adjust_joint needs {len(q)} deltas, got {len(delta_deg)}")
        return self.run_actor("move_joint", *(a + math.radians(d) for a, d in zip(q, delta_deg)))

    @actor
    def move_to_pose(self, x: float, y: float, z: float, pitch: float) -> list[float]:
        """Plan and move the tool to (x, y, z) [m] in base_footprint with ``pitch`` [rad];
        returns the joint positions reached [rad].

        Args:
            x: tool position forward of the base, base_footprint frame [m]
            y: tool position to the left of the base, base_footprint frame [m]
            z: tool height above the floor [m]
            pitch: tool angle below the horizontal; pi/2 points straight down [rad]
        """
        start, _, _ = self._state()
        return self._run_plan(plan_pose_motion(start, (x, y, z, pitch), self.scene))

    @actor
    def open(self, width: float = GRIPPER_OPEN) -> float:
        """Open the gripper to ``width`` [m]; returns the opening reached [m].

        Args:
            width: finger opening to reach [m]
        """
        return self._gripper(width)

    @actor
    def close(self, width: float = GRIPPER_CLOSED) -> float:
        """Close the gripper (on an object it stops at the object's width); returns the opening [m].

        Args:
            width: finger opening to close to; 0 closes fully [m]
        """
        return self._gripper(width)

    # -- execution ---------------------------------------------------------------------
    def _gripper(self, width: float) -> float:
        self.run_actor("gripper_command", Float64(data=float(width)))
        last = None
        for _ in range(40):  # settle: the opening stops changing (or reaches the target)
            self.run_actor("sleep", 0.05)
            _, _, w = self._state()
            if last is not None and abs(w - last) < 2e-4:
                break
            last = w
        return self._state()[2]

    def _run_plan(self, plan: MotionPlan) -> list[float]:
        self.set_value("last_plan", plan)
        if not plan.ok:
            raise MotionError(f"no arm motion: {plan.message}")
        traj = time_trajectory(plan.path, self.limits)
        return self._execute(traj)

    def _publish(self, traj: TimedTrajectory) -> None:
        sampled = traj.sample(SAMPLE_DT)
        msg = JointTrajectory()
        msg.joint_names = list(self.joints)
        for t, p, v in zip(sampled.times, sampled.positions, sampled.velocities):
            pt = JointTrajectoryPoint()
            pt.positions = [float(a) for a in p]
            pt.velocities = [float(a) for a in v]
            pt.time_from_start = duration_msg(float(t))
            msg.points.append(pt)
        self.run_actor("arm_command", msg)

    def _execute(self, traj: TimedTrajectory) -> list[float]:
        rt = self.runtime
        goal = traj.final_position
        t0 = rt.now()
        self._publish(traj)
        try:
            deadline = t0 + traj.duration + SETTLE_TIME
            with self.run_actor_mode("joint_states", "iterator") as states:
                for msg in states:
                    q = named(msg.name, msg.position, self.joints)
                    err = max(abs(a - b) for a, b in zip(q, goal))
                    if rt.now() - t0 >= traj.duration and err < CONVERGED:
                        return q
                    if rt.now() > deadline:
                        raise MotionError(f"arm did not converge: {err:.4f} rad from the goal "
                                          f"{SETTLE_TIME} s after the trajectory ended")
        except Cancelled:
            self._stop_along(traj, rt.now() - t0)
            raise
        raise MotionError("joint states stopped arriving")

    def _stop_along(self, traj: TimedTrajectory, elapsed: float) -> None:
        """Replace the running trajectory by ruckig's jerk-limited stop from its current state."""
        if elapsed >= traj.duration:
            return
        q, qd, qdd = traj.at(max(0.0, elapsed))
        self._publish(stop_trajectory(q, qd, qdd, self.limits))

    def _last_plan(self) -> Any:
        return self.get_value("last_plan")
