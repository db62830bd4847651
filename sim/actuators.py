"""Arm trajectory tracking: JointTrajectory points interpolated over time_from_start.

Like ros2_control's joint_trajectory_controller: a new trajectory replaces the old one from
its start time; the segment before the first point starts at the current position; cubic
Hermite interpolation where both ends of a segment carry velocities, linear otherwise; after
the last point the last positions are held.
"""
from __future__ import annotations

import bisect


class TrajectoryError(ValueError):
    pass


class ArmTrajectory:
    def __init__(self, joint_names, start_time, start_positions, points):
        """joint_names: the arm joints, in the robot's order.
        points: list of (t_from_start, {name: pos}, {name: vel} or None), t increasing."""
        self.names = list(joint_names)
        self.t0 = start_time
        self.times = [0.0]
        self.pos = [list(start_positions)]
        self.vel = [[0.0] * len(self.names)]
        have_vel = [True]
        for t, pos, vel in points:
            if t < self.times[-1] or (t == self.times[-1] and len(self.times) > 1):
                raise TrajectoryError("time_from_start must increase from point to point")
            row = [pos.get(n, self.pos[-1][i]) for i, n in enumerate(self.names)]
            vrow = [vel.get(n, 0.0) for n in self.names] if vel is not None else [0.0] * len(self.names)
            if t == 0.0:      # a point at t=0 replaces the start
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


def duration_to_sec(d) -> float:
    return float(d.sec) + float(d.nanosec) * 1e-9


def trajectory_from_msg(msg, arm_names, now, current_positions):
    """Build an ArmTrajectory from a trajectory_msgs/JointTrajectory."""
    names = list(msg.joint_names)
    unknown = [n for n in names if n not in arm_names]
    if unknown:
        raise TrajectoryError(f"unknown joints {unknown} (arm joints: {list(arm_names)})")
    if not msg.points:
        raise TrajectoryError("trajectory has no points")
    pts = []
    for i, pt in enumerate(msg.points):
        if len(pt.positions) != len(names):
            raise TrajectoryError(f"point {i}: {len(pt.positions)} positions for {len(names)} joints")
        vel = None
        if len(pt.velocities):
            if len(pt.velocities) != len(names):
                raise TrajectoryError(f"point {i}: {len(pt.velocities)} velocities for {len(names)} joints")
            vel = dict(zip(names, pt.velocities))
        pts.append((duration_to_sec(pt.time_from_start), dict(zip(names, pt.positions)), vel))
    stamp = float(msg.header.stamp.sec) + float(msg.header.stamp.nanosec) * 1e-9
    start = stamp if stamp > now else now
    return ArmTrajectory(arm_names, start, current_positions, pts)
