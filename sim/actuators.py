"""The arm's trajectories and the gripper's position scale: the controllers' arithmetic.

Arm (``joint_trajectory_controller``): trajectory_msgs/JointTrajectory points interpolated
over time_from_start. A new trajectory replaces the old one from its start time; the
segment before the first point starts at the state the caller gives (the controller passes
the running trajectory's desired state: ``open_loop_control`` as on the TurtleBot3); cubic
Hermite interpolation where both ends of a segment carry velocities, linear otherwise;
after the last point the last positions are held. :func:`trajectory_from_msg` validates a
message as the controller does and says why it refuses one (:class:`TrajectoryError`,
with the FollowJointTrajectory error code). :func:`stop_trajectory` is the smooth stop
the simulated controller makes on a cancel.

Gripper (``gripper_action_controller``): the one place that maps the real
OpenManipulator-X's gripper position onto the simulated fingers, see
:func:`gripper_opening`.
"""

from __future__ import annotations

import bisect
import math

from .robot import GRIPPER_MAX_OPENING

#: control_msgs/action/FollowJointTrajectory Result error codes (the subset validation gives)
INVALID_GOAL = -1
INVALID_JOINTS = -2
OLD_HEADER_TIMESTAMP = -3


class TrajectoryError(ValueError):
    """A trajectory the controller refuses; ``code`` is the FollowJointTrajectory
    error_code that says why (INVALID_GOAL, INVALID_JOINTS, OLD_HEADER_TIMESTAMP)."""

    def __init__(self, message: str, code: int = INVALID_GOAL):
        super().__init__(message)
        self.code = code


class ArmTrajectory:
    def __init__(self, joint_names, start_time, start_positions, points, start_velocities=None):
        """joint_names: the arm joints, in the robot's order.
        start_positions / start_velocities: the state the first segment starts from
        (velocities None: at rest, and the first segment is linear unless its end has
        velocities). points: list of (t_from_start, {name: pos}, {name: vel} or None),
        t increasing."""
        self.names = list(joint_names)
        self.t0 = start_time
        self.times = [0.0]
        self.pos = [list(start_positions)]
        self.vel = [list(start_velocities) if start_velocities is not None else [0.0] * len(self.names)]
        have_vel = [True]
        for t, pos, vel in points:
            if t < self.times[-1] or (t == self.times[-1] and len(self.times) > 1):
                raise TrajectoryError("time_from_start must increase from point to point")
            row = [pos.get(n, self.pos[-1][i]) for i, n in enumerate(self.names)]
            vrow = [vel.get(n, 0.0) for n in self.names] if vel is not None else [0.0] * len(self.names)
            if t == 0.0:  # a point at t=0 replaces the start
                self.pos[0], self.vel[0] = row, vrow
                have_vel[0] = vel is not None
                continue
            self.times.append(t)
            self.pos.append(row)
            self.vel.append(vrow)
            have_vel.append(vel is not None)
        self.have_vel = have_vel

    @property
    def end_time(self):
        return self.t0 + self.times[-1]

    @property
    def final_positions(self):
        return list(self.pos[-1])

    def sample(self, now):
        """(positions, velocities) at absolute time ``now``."""
        t = now - self.t0
        if t <= 0.0:
            return list(self.pos[0]), [0.0] * len(self.names)
        if t >= self.times[-1]:
            return list(self.pos[-1]), [0.0] * len(self.names)
        k = bisect.bisect_right(self.times, t) - 1
        ta, tb = self.times[k], self.times[k + 1]
        h = tb - ta
        s = (t - ta) / h
        pa, pb = self.pos[k], self.pos[k + 1]
        if self.have_vel[k] and self.have_vel[k + 1]:
            va, vb = self.vel[k], self.vel[k + 1]
            h00, h10 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s
            h01, h11 = -2 * s**3 + 3 * s**2, s**3 - s**2
            d00, d10 = (6 * s**2 - 6 * s) / h, 3 * s**2 - 4 * s + 1
            d01, d11 = (-6 * s**2 + 6 * s) / h, 3 * s**2 - 2 * s
            pos = [h00 * a + h10 * h * ua + h01 * b + h11 * h * ub for a, b, ua, ub in zip(pa, pb, va, vb)]
            vel = [d00 * a + d10 * ua + d01 * b + d11 * ub for a, b, ua, ub in zip(pa, pb, va, vb)]
            return pos, vel
        pos = [a + s * (b - a) for a, b in zip(pa, pb)]
        vel = [(b - a) / h for a, b in zip(pa, pb)]
        return pos, vel


def stop_trajectory(joint_names, now, positions, velocities, deceleration):
    """Come to rest from (positions, velocities) at ``now`` with every joint decelerating
    uniformly, all ending together after ``max |v| / deceleration`` seconds: the velocity
    ramps down linearly (a cubic Hermite segment with the end velocity 0 is exactly that)."""
    duration = max((abs(v) for v in velocities), default=0.0) / deceleration
    if duration < 1e-3:
        return ArmTrajectory(joint_names, now, positions, [])
    end = {n: p + v * duration / 2 for n, p, v in zip(joint_names, positions, velocities)}
    return ArmTrajectory(
        joint_names, now, positions, [(duration, end, {n: 0.0 for n in joint_names})], start_velocities=velocities
    )


def duration_to_sec(d) -> float:
    return float(d.sec) + float(d.nanosec) * 1e-9


def trajectory_from_msg(
    msg, arm_names, now, start_positions, start_velocities=None, *, allow_partial=False, stamp_offset=0.0
):
    """Build an ArmTrajectory from a trajectory_msgs/JointTrajectory, or raise
    :class:`TrajectoryError` for what joint_trajectory_controller refuses: no joint
    names, a joint named twice or not the arm's, only some of the arm's joints (unless
    ``allow_partial``), no points, a point whose sizes do not match the joints or that
    holds a NaN, times that do not increase, a last point with a velocity, a header stamp
    so old that the whole trajectory lies in the past. ``now`` is on the runtime clock; a
    header stamp is that plus ``stamp_offset`` (ROS time)."""
    names = list(msg.joint_names)
    if not names:
        raise TrajectoryError("empty joint names on incoming trajectory", INVALID_JOINTS)
    if len(set(names)) != len(names):
        raise TrajectoryError(f"joints named twice on incoming trajectory: {names}", INVALID_JOINTS)
    unknown = [n for n in names if n not in arm_names]
    if unknown:
        raise TrajectoryError(
            f"incoming joints {unknown} are not the controller's (arm joints: {list(arm_names)})", INVALID_JOINTS
        )
    if not allow_partial and len(names) != len(arm_names):
        missing = [n for n in arm_names if n not in names]
        raise TrajectoryError(
            f"the trajectory leaves out joints {missing}; this controller "
            "takes all of its joints (allow_partial_joints_goal false)",
            INVALID_JOINTS,
        )
    if not msg.points:
        raise TrajectoryError("empty trajectory: no points")
    pts = []
    last_t = -1.0
    for i, pt in enumerate(msg.points):
        if len(pt.positions) != len(names):
            raise TrajectoryError(f"point {i}: {len(pt.positions)} positions for {len(names)} joints")
        if any(not math.isfinite(x) for x in pt.positions):
            raise TrajectoryError(f"point {i}: a position is not a number")
        for field in ("velocities", "accelerations"):
            n = len(getattr(pt, field))
            if n and n != len(names):
                raise TrajectoryError(f"point {i}: {n} {field} for {len(names)} joints")
        t = duration_to_sec(pt.time_from_start)
        if t < 0.0 or (t <= last_t):
            raise TrajectoryError(
                f"time_from_start of point {i} ({t:g} s) does not increase from the point before ({last_t:g} s)"
                if i
                else f"time_from_start of point 0 is negative ({t:g} s)"
            )
        last_t = t
        vel = dict(zip(names, pt.velocities)) if len(pt.velocities) else None
        pts.append((t, dict(zip(names, pt.positions)), vel))
    last = msg.points[-1]
    if any(v != 0.0 for v in last.velocities):
        raise TrajectoryError("the velocity of the last trajectory point is not zero")
    stamp = float(msg.header.stamp.sec) + float(msg.header.stamp.nanosec) * 1e-9
    stamped = stamp > 0.0  # a zero stamp means "start now"
    stamp -= stamp_offset
    if stamped and stamp + last_t < now:
        raise TrajectoryError(
            f"the trajectory (header stamp {stamp + stamp_offset:.3f} s) ended {now - stamp - last_t:.3f} s ago",
            OLD_HEADER_TIMESTAMP,
        )
    start = stamp if stamped and stamp > now else now
    return ArmTrajectory(arm_names, start, start_positions, pts, start_velocities)


# ---------------------------------------------------------------------------- gripper
#: The OpenManipulator-X's gripper as its ros2_control ``gripper_controller`` takes it
#: (``/gripper_controller/gripper_cmd``, joint ``gripper_left_joint``): position [m] from
#: closed to open, the real robot's joint range.
GRIPPER_POSITION_CLOSED = -0.010
GRIPPER_POSITION_OPEN = 0.019


def gripper_opening(position: float) -> float:
    """The simulated fingers' opening [m] (gap between their inner faces, = the sum of
    gripper_left_joint and gripper_right_joint in /joint_states) for a gripper
    controller ``position`` [m].

    This is the only place the two scales meet. The simulated gripper is wider than the
    real one (each finger strokes 0..45 mm, see sim/models/build_urdf.py), so the real
    robot's position range GRIPPER_POSITION_CLOSED .. GRIPPER_POSITION_OPEN
    (-0.010 .. 0.019, 29 mm) is stretched linearly onto the opening 0 .. 0.090 m:

        opening = (position + 0.010) / 0.029 * 0.090      (about 3.1 mm of opening per mm)

    Monotonic (increasing); positions outside the range clamp to the stroke's ends."""
    span = GRIPPER_POSITION_OPEN - GRIPPER_POSITION_CLOSED
    f = (position - GRIPPER_POSITION_CLOSED) / span
    return min(max(f, 0.0), 1.0) * GRIPPER_MAX_OPENING


def gripper_position(opening: float) -> float:
    """Inverse of :func:`gripper_opening`: the controller position [m] of an opening [m]."""
    f = min(max(opening / GRIPPER_MAX_OPENING, 0.0), 1.0)
    return GRIPPER_POSITION_CLOSED + f * (GRIPPER_POSITION_OPEN - GRIPPER_POSITION_CLOSED)


def gripper_speed(opening_rate: float) -> float:
    """A rate of the opening [m/s] on the controller's position scale [m/s]."""
    return opening_rate * (GRIPPER_POSITION_OPEN - GRIPPER_POSITION_CLOSED) / GRIPPER_MAX_OPENING
