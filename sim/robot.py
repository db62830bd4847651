"""The mobile manipulator in a pybullet client: loading, joint maps, low-level actuation."""

from __future__ import annotations

import math
from pathlib import Path

from common.quiet_pybullet import pybullet as p


def _clamp(x: float, lo: float, hi: float) -> float:
    """x within [lo, hi], as a float (numpy's clip costs microseconds a call on a scalar,
    and these run every control tick)."""
    return float(min(max(x, lo), hi))


URDF = Path(__file__).resolve().parent / "models" / "mobile_manipulator.urdf"

WHEEL_RADIUS = 0.033
WHEEL_SEPARATION = 0.287
# TurtleBot3 Waffle Pi limits (turtlebot3_teleop / firmware)
MAX_LINEAR = 0.26  # m/s
MAX_ANGULAR = 1.82  # rad/s
WHEEL_TORQUE = 1.5  # N m per wheel motor (XM430-W210 continuous; stall is ~3 N m)
WHEEL_ACCEL = 1.0 / WHEEL_RADIUS  # rad/s^2: 1 m/s^2 at the rim, like the firmware's velocity profile

WHEELS = ("wheel_left_joint", "wheel_right_joint")
ARM = ("joint1", "joint2", "joint3", "joint4")
GRIPPER = ("gripper_left_joint", "gripper_right_joint")
JOINT_STATE_NAMES = WHEELS + ARM + GRIPPER
# The robot's links form their own collision group (they still collide with everything), so
# the lidar's rays can leave the robot's body out (sim/lidar.py). Bullet's defaults are
# group 1 for dynamic bodies and 2 for static ones.
ROBOT_COLLISION_GROUP = 1 << 6
# OpenManipulator-X "home": folded up, out of the camera's view
ARM_HOME = (0.0, -1.0, 0.3, 0.7)
# The gripper: one XM430-W350 in current-based position control (operating mode 5) drives
# both fingers through a rack and pinion. It moves toward the goal at the profile velocity
# and pushes with at most the goal current: a speed-limited, force-limited position servo.
# ROBOTIS' TurtleBot3 manipulation bring-up (Jazzy, turtlebot3_manipulation_system.ros2_control
# .xacro) sets dxl_gripper_profile_velocity 200 (x 0.229 rpm = 0.76 rev/s; the finger moves
# 0.0722 m per revolution, 1.76e-5 m per tick: 0.055 m/s).
# As on the servo, the profile moves the setpoint, not the finger: a finger stopped by what
# it closes on falls behind its setpoint, and the position error drives the push up to the
# current limit, which then holds the object with that force.
GRIPPER_FORCE = 10.0  # N per finger: what the current limit pushes with at the fingertips
GRIPPER_SPEED = 0.05  # m/s per finger: the profile velocity above
GRIPPER_GAIN = 0.3  # the servo's position gain (pybullet's positionGain)
# pybullet's position motor pushes a blocked joint only in proportion to the velocity it
# asks for (about 55 N per m/s on a stalled finger at 50 solver iterations): capped at
# GRIPPER_SPEED it squeezed 2.8 N, whatever the force limit. The cap is the speed a finger
# may catch up with its setpoint after what it pushed on gave way; high enough that a
# stalled finger asks for more than GRIPPER_FORCE.
GRIPPER_CATCH_UP = 0.5  # m/s
# The pads' contact is a spring and damper (pybullet's contactStiffness and contactDamping):
# with the solver's default, an edge of a box that stands askew between the pads sank
# 6.5 mm under the full squeeze (2.5 mm under 2.8 N), and a sunk finger holds by interlock.
# A rubber pad against a carton's wall yields about 0.2 mm under GRIPPER_FORCE.
PAD_STIFFNESS = 5.0e4  # N/m
PAD_DAMPING = 200.0  # N s/m: no bounce when a pad meets a 60 g carton
GRIPPER_MAX_OPENING = 0.09
# The fingers' linkage: stiff against what a held object pushes sideways with (its weight
# and the base's accelerations, a few newtons), and a positional drift of the two fingers
# corrected over a few substeps
FINGER_COUPLING_FORCE = 200.0  # N
FINGER_COUPLING_ERP = 0.2


class Robot:
    def __init__(self, cid: int, start=(0.0, 0.0, 0.0), arm_home=ARM_HOME):
        self.cid = cid
        x, y, yaw = start
        flags = (
            p.URDF_USE_INERTIA_FROM_FILE
            | p.URDF_USE_IMPLICIT_CYLINDER
            | p.URDF_USE_SELF_COLLISION
            | p.URDF_USE_SELF_COLLISION_EXCLUDE_PARENT
        )
        self.body = p.loadURDF(
            str(URDF), [x, y, 0.0], p.getQuaternionFromEuler([0, 0, yaw]), flags=flags, physicsClientId=cid
        )
        self.joint: dict[str, int] = {}
        self.link: dict[str, int] = {"base_footprint": -1}
        self.limits: dict[str, tuple] = {}
        for j in range(p.getNumJoints(self.body, physicsClientId=cid)):
            info = p.getJointInfo(self.body, j, physicsClientId=cid)
            name = info[1].decode()
            self.joint[name] = j
            self.link[info[12].decode()] = j
            self.limits[name] = (info[8], info[9], info[10], info[11])  # lower, upper, effort, vel
        b = self.body
        for link in range(-1, p.getNumJoints(b, physicsClientId=cid)):
            p.setCollisionFilterGroupMask(b, link, ROBOT_COLLISION_GROUP, -1, physicsClientId=cid)
        # fingers are siblings: their inner faces touch when closed, they must not collide
        p.setCollisionFilterPair(
            b, b, self.joint["gripper_left_joint"], self.joint["gripper_right_joint"], 0, physicsClientId=cid
        )
        self.state_idx = [self.joint[n] for n in JOINT_STATE_NAMES]
        self.wheel_idx = [self.joint[n] for n in WHEELS]
        self.arm_idx = [self.joint[n] for n in ARM]
        self.grip_idx = [self.joint[n] for n in GRIPPER]
        # every non-fixed joint starts with a default velocity motor; we set our own below
        for n, q in zip(ARM, arm_home):
            p.resetJointState(b, self.joint[n], q, physicsClientId=cid)
        self.arm_target = list(arm_home)
        self.arm_target_vel = [0.0] * 4
        self.gripper_width = GRIPPER_MAX_OPENING
        for j in self.grip_idx:
            p.resetJointState(b, j, self.gripper_width / 2, physicsClientId=cid)
        self.grip_setpoint = [self.gripper_width / 2] * 2  # per finger, the profile's [m]
        for j in self.grip_idx:
            p.changeDynamics(b, j, contactStiffness=PAD_STIFFNESS, contactDamping=PAD_DAMPING, physicsClientId=cid)
        self._couple_fingers()
        self.wheel_target = [0.0, 0.0]
        self.wheel_setpoint = [0.0, 0.0]
        self.apply(0.0)

    def _couple_fingers(self) -> None:
        """One servo drives both fingers through a linkage (ROBOTIS' URDF:
        gripper_right_joint mimics gripper_left_joint, multiplier 1), so they always stand
        symmetric about the tool's axis. Independent fingers, each pushing with the same
        force limit, would leave what they hold free to slide sideways between them with
        every jolt of the base, until one finger reaches its end stop."""
        left, right = self.grip_idx
        coupling = p.createConstraint(
            self.body, left, self.body, right, p.JOINT_GEAR, [0, 1, 0], [0, 0, 0], [0, 0, 0], physicsClientId=self.cid
        )
        # joint velocities: left - right = 0; the erp pulls a drift of the positions back
        p.changeConstraint(
            coupling, gearRatio=-1, erp=FINGER_COUPLING_ERP, maxForce=FINGER_COUPLING_FORCE, physicsClientId=self.cid
        )

    # ---------------- commands ----------------
    def set_base_velocity(self, v: float, w: float):
        """Twist -> wheel speeds, clamped to the TurtleBot3 Waffle Pi limits."""
        v = _clamp(v, -MAX_LINEAR, MAX_LINEAR)
        w = _clamp(w, -MAX_ANGULAR, MAX_ANGULAR)
        wl = (v - w * WHEEL_SEPARATION / 2) / WHEEL_RADIUS
        wr = (v + w * WHEEL_SEPARATION / 2) / WHEEL_RADIUS
        self.wheel_target = [wl, wr]

    def set_arm(self, positions, velocities=None):
        lo_hi = [self.limits[n][:2] for n in ARM]
        self.arm_target = [_clamp(q, lo, hi) for q, (lo, hi) in zip(positions, lo_hi)]
        self.arm_target_vel = list(velocities) if velocities is not None else [0.0] * 4

    def set_gripper(self, width: float):
        """A new goal opening [m]: the fingers' profile starts from where they are (a goal
        repeated while they squeeze leaves it be, and the squeeze with it)."""
        width = _clamp(width, 0.0, GRIPPER_MAX_OPENING)
        if width != self.gripper_width:
            self.grip_setpoint = [s[0] for s in p.getJointStates(self.body, self.grip_idx, physicsClientId=self.cid)]
        self.gripper_width = width

    def apply(self, dt: float):
        """Push the current targets into pybullet's joint motors (they run every substep).
        Wheel speeds ramp towards their targets at WHEEL_ACCEL, so the tyres do not skid."""
        cid, b = self.cid, self.body
        step = WHEEL_ACCEL * dt
        self.wheel_setpoint = [
            sp + _clamp(tg - sp, -step, step) for sp, tg in zip(self.wheel_setpoint, self.wheel_target)
        ]
        p.setJointMotorControlArray(
            b,
            self.wheel_idx,
            p.VELOCITY_CONTROL,
            targetVelocities=self.wheel_setpoint,
            forces=[WHEEL_TORQUE] * 2,
            physicsClientId=cid,
        )
        p.setJointMotorControlArray(
            b,
            self.arm_idx,
            p.POSITION_CONTROL,
            targetPositions=self.arm_target,
            targetVelocities=self.arm_target_vel,
            forces=[self.limits[n][2] for n in ARM],
            positionGains=[0.3] * 4,
            velocityGains=[1.0] * 4,
            physicsClientId=cid,
        )
        # pybullet's position motor is that servo, solved with the contacts every substep,
        # its setpoint moving to the goal at GRIPPER_SPEED: the fingers approach at that
        # speed and stop on what they close on, then push harder as the setpoint runs on,
        # up to GRIPPER_FORCE (a torque held for a whole control period would push them
        # into it first). The setpoint moves once a control period, the motor runs every
        # substep: it is where the profile is at the period's end.
        goal, step = self.gripper_width / 2, GRIPPER_SPEED * dt
        for i, j in enumerate(self.grip_idx):  # (setJointMotorControlArray takes no speed limit)
            sp = self.grip_setpoint[i]
            sp = self.grip_setpoint[i] = sp + _clamp(goal - sp, -step, step)
            speed = 0.0 if sp == goal else math.copysign(GRIPPER_SPEED, goal - sp)
            p.setJointMotorControl2(
                b,
                j,
                p.POSITION_CONTROL,
                targetPosition=sp,
                targetVelocity=speed,
                force=GRIPPER_FORCE,
                maxVelocity=GRIPPER_CATCH_UP,
                positionGain=GRIPPER_GAIN,
                physicsClientId=cid,
            )

    def gripper_moving(self) -> bool:
        """Whether the servo's setpoint is still on its way to the goal (the fingers open
        or close; once there, a finger that stands short of it squeezes what it holds)."""
        goal = self.gripper_width / 2
        return any(sp != goal for sp in self.grip_setpoint)

    def holding(self, finger_positions) -> bool:
        """Whether the servo's setpoint has reached its goal and a finger stands short of
        it: the fingers have closed on something and hold it."""
        goal = self.gripper_width / 2
        return all(sp == goal for sp in self.grip_setpoint) and self.squeezing(finger_positions)

    def squeezing(self, finger_positions) -> bool:
        """Whether a finger stands more than a millimetre short of its setpoint: it pushes
        against something between the fingers."""
        return any(q - sp > 0.001 for sp, q in zip(self.grip_setpoint, finger_positions))

    # ---------------- state ----------------
    def joint_states(self):
        """(positions, velocities, efforts) in JOINT_STATE_NAMES order."""
        st = p.getJointStates(self.body, self.state_idx, physicsClientId=self.cid)
        return [s[0] for s in st], [s[1] for s in st], [s[3] for s in st]

    def base_pose(self):
        """(x, y, yaw) of base_footprint in the world (map) frame, plus the full 3-D pose."""
        pos, orn = p.getBasePositionAndOrientation(self.body, physicsClientId=self.cid)
        yaw = p.getEulerFromQuaternion(orn)[2]
        return (pos[0], pos[1], yaw), pos, orn

    def base_twist(self):
        lin, ang = p.getBaseVelocity(self.body, physicsClientId=self.cid)
        return lin, ang

    def link_pose(self, name):
        """World pose (pos, quat) of a named link's frame."""
        if name == "base_footprint":
            _, pos, orn = self.base_pose()
            return pos, orn
        s = p.getLinkState(self.body, self.link[name], computeForwardKinematics=True, physicsClientId=self.cid)
        return s[4], s[5]

    def arm_positions(self):
        return [s[0] for s in p.getJointStates(self.body, self.arm_idx, physicsClientId=self.cid)]

    def gripper_opening(self):
        return sum(s[0] for s in p.getJointStates(self.body, self.grip_idx, physicsClientId=self.cid))
