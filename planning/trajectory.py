"""Time parameterisation with ruckig: jerk-limited, rest to rest, segment by segment.

Each straight segment of a planned path becomes one offline ruckig trajectory
from rest to rest with ``Synchronization.Phase``: all joints share the same
normalised profile, so the timed motion stays on the straight joint-space
segment that the planner collision-checked. The arm stops at every waypoint;
the simplifier leaves few of them.

ruckig's ``intermediate_positions`` is never used: the free build computes
those trajectories on a remote server.

:func:`stop_trajectory` is ruckig's velocity-control stop (its ``06_stop``
example): from the current position, velocity and acceleration to zero velocity
and acceleration, under the acceleration and jerk limits. It is what cancelling
a motion commands instead of a freeze.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from ruckig import ControlInterface, InputParameter, Result, Ruckig, RuckigError, Synchronization, Trajectory

from .errors import InvalidInputError, TrajectoryError
from .kinematics import ArmKinematics

__all__ = ["JointLimits", "SampledTrajectory", "TimedTrajectory", "time_trajectory", "stop_trajectory"]


@dataclass(frozen=True)
class JointLimits:
    """Per-joint kinematic limits, all positive.

    Attributes:
        velocity: maximum speed per joint [rad/s].
        acceleration: maximum acceleration per joint [rad/s^2].
        jerk: maximum jerk per joint [rad/s^3].
    """

    velocity: tuple[float, ...]
    acceleration: tuple[float, ...]
    jerk: tuple[float, ...]

    def __post_init__(self) -> None:
        n = len(self.velocity)
        for name in ("velocity", "acceleration", "jerk"):
            values = getattr(self, name)
            if len(values) != n or n == 0:
                raise InvalidInputError(f"JointLimits.{name} has {len(values)} values, velocity has {n}")
            if not all(math.isfinite(v) and v > 0 for v in values):
                raise InvalidInputError(f"JointLimits.{name} must be finite and > 0, got {values}")
            object.__setattr__(self, name, tuple(float(v) for v in values))

    @property
    def dofs(self) -> int:
        """Number of joints."""
        return len(self.velocity)

    @classmethod
    def uniform(cls, dofs: int, velocity: float, acceleration: float, jerk: float) -> JointLimits:
        """The same limits for every joint ([rad/s], [rad/s^2], [rad/s^3])."""
        return cls((velocity,) * dofs, (acceleration,) * dofs, (jerk,) * dofs)

    @classmethod
    def from_kinematics(
        cls,
        kinematics: ArmKinematics,
        *,
        acceleration: float | Sequence[float],
        jerk: float | Sequence[float],
        velocity_scale: float = 1.0,
    ) -> JointLimits:
        """Velocity limits from the URDF (scaled by ``velocity_scale``), with the
        given acceleration [rad/s^2] and jerk [rad/s^3] (URDF has neither)."""
        n = len(kinematics.joint_names)
        acc = (acceleration,) * n if isinstance(acceleration, (int, float)) else tuple(acceleration)
        jrk = (jerk,) * n if isinstance(jerk, (int, float)) else tuple(jerk)
        if not (0 < velocity_scale <= 1):
            raise InvalidInputError(f"velocity_scale must be in (0, 1], got {velocity_scale!r}")
        vel = tuple(float(v) * velocity_scale for v in kinematics.max_velocity)
        return cls(vel, acc, jrk)

    def scaled(self, velocity_scale: float = 1.0, acceleration_scale: float = 1.0) -> JointLimits:
        """Limits scaled like MoveIt's scaling factors (each in (0, 1]); jerk
        scales with acceleration."""
        for name, s in (("velocity_scale", velocity_scale), ("acceleration_scale", acceleration_scale)):
            if not (0 < s <= 1):
                raise InvalidInputError(f"{name} must be in (0, 1], got {s!r}")
        return JointLimits(
            tuple(v * velocity_scale for v in self.velocity),
            tuple(a * acceleration_scale for a in self.acceleration),
            tuple(j * acceleration_scale for j in self.jerk),
        )


@dataclass(frozen=True, eq=False)  # holds arrays: compared by identity
class SampledTrajectory:
    """A trajectory sampled at a fixed step.

    Attributes:
        times: sample times from the start (N,) [s]; the last one is the duration.
        positions: (N, dofs) [rad].
        velocities: (N, dofs) [rad/s].
        accelerations: (N, dofs) [rad/s^2].
    """

    times: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    accelerations: np.ndarray


@dataclass(frozen=True)
class TimedTrajectory:
    """A chain of rest-to-rest ruckig segments along straight joint-space lines.

    Attributes:
        waypoints: the path the segments join, start first [rad].
        start_times: start time of each segment from the trajectory start [s].
        durations: duration of each segment [s].
        duration: total duration [s].
        limits: the limits it was timed with.
    """

    waypoints: tuple[tuple[float, ...], ...]
    start_times: tuple[float, ...]
    durations: tuple[float, ...]
    duration: float
    limits: JointLimits
    _segments: tuple[Trajectory, ...] = field(repr=False, compare=False)  # objects with at_time(t)

    @property
    def dofs(self) -> int:
        """Number of joints."""
        return len(self.waypoints[0])

    @property
    def final_position(self) -> tuple[float, ...]:
        """Position at the end [rad]."""
        if not self._segments:
            return self.waypoints[-1]
        return tuple(float(v) for v in self._segments[-1].at_time(self.durations[-1])[0])

    def at(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Position [rad], velocity [rad/s] and acceleration [rad/s^2] at time ``t``
        [s] from the start; clamped to the start and the end."""
        if not self._segments:
            return np.array(self.waypoints[-1]), np.zeros(self.dofs), np.zeros(self.dofs)
        t = min(max(t, 0.0), self.duration)
        i = int(np.searchsorted(self.start_times, t, side="right") - 1)
        i = min(max(i, 0), len(self._segments) - 1)
        local = min(t - self.start_times[i], self.durations[i])
        q, qd, qdd = self._segments[i].at_time(local)
        return np.asarray(q), np.asarray(qd), np.asarray(qdd)

    def sample(self, dt: float) -> SampledTrajectory:
        """Samples every ``dt`` [s] from 0, plus the end point."""
        if not (math.isfinite(dt) and dt > 0):
            raise InvalidInputError(f"dt must be > 0 s, got {dt!r}")
        n = int(math.floor(self.duration / dt + 1e-9))
        times = np.arange(n + 1) * dt
        if times[-1] < self.duration - 1e-12:
            times = np.append(times, self.duration)
        q = np.empty((len(times), self.dofs))
        qd = np.empty_like(q)
        qdd = np.empty_like(q)
        for k, t in enumerate(times):
            q[k], qd[k], qdd[k] = self.at(float(t))
        return SampledTrajectory(times, q, qd, qdd)


def _check_limits(limits: JointLimits, dofs: int) -> None:
    if limits.dofs != dofs:
        raise InvalidInputError(f"limits are for {limits.dofs} joints, the path has {dofs}")


def _input(limits: JointLimits) -> InputParameter:
    inp = InputParameter(limits.dofs)
    inp.max_velocity = list(limits.velocity)
    inp.max_acceleration = list(limits.acceleration)
    inp.max_jerk = list(limits.jerk)
    inp.synchronization = Synchronization.Phase
    return inp


def _calculate(otg: Ruckig, inp: InputParameter, what: str) -> Trajectory:
    traj = Trajectory(inp.degrees_of_freedom)
    try:
        result = otg.calculate(inp, traj)
    except (RuckigError, RuntimeError) as exc:  # ruckig raises on invalid input
        raise TrajectoryError(f"ruckig rejected {what}: {exc}") from exc
    if result not in (Result.Working, Result.Finished):
        raise TrajectoryError(f"ruckig failed on {what}: {result}")
    return traj


def time_trajectory(path: Sequence[Sequence[float]], limits: JointLimits) -> TimedTrajectory:
    """Time a piecewise-straight joint path, rest to rest at every waypoint.

    Args:
        path: waypoints (N, dofs) [rad]; consecutive duplicates are skipped.
        limits: velocity, acceleration and jerk limits per joint.

    Returns:
        A :class:`TimedTrajectory` whose motion stays on the path's segments.

    Raises:
        InvalidInputError: empty or ragged path, non-finite values, wrong dofs.
        TrajectoryError: ruckig could not compute a segment.
    """
    try:
        pts = np.asarray(path, dtype=float)
    except (TypeError, ValueError):
        raise InvalidInputError("path must be a sequence of equal-length joint vectors") from None
    if pts.ndim != 2 or len(pts) == 0 or not np.all(np.isfinite(pts)):
        raise InvalidInputError(f"path must be a non-empty (N, dofs) array of finite values, got shape {pts.shape}")
    _check_limits(limits, pts.shape[1])
    keep = [pts[0]]
    for p in pts[1:]:
        if np.max(np.abs(p - keep[-1])) > 1e-12:
            keep.append(p)
    otg = Ruckig(limits.dofs)
    inp = _input(limits)
    zeros = [0.0] * limits.dofs
    inp.current_velocity = inp.current_acceleration = zeros
    inp.target_velocity = inp.target_acceleration = zeros
    segments, starts, durations = [], [], []
    t = 0.0
    for i, (a, b) in enumerate(zip(keep[:-1], keep[1:])):
        inp.current_position = a.tolist()
        inp.target_position = b.tolist()
        traj = _calculate(otg, inp, f"segment {i}")
        segments.append(traj)
        starts.append(t)
        durations.append(traj.duration)
        t += traj.duration
    return TimedTrajectory(
        waypoints=tuple(tuple(float(v) for v in p) for p in keep),
        start_times=tuple(starts),
        durations=tuple(durations),
        duration=t,
        limits=limits,
        _segments=tuple(segments),
    )


class _OnLine:
    """A 1-DOF ruckig trajectory s(t) mapped onto the line q0 + u s."""

    def __init__(self, q0: np.ndarray, u: np.ndarray, traj: Trajectory) -> None:
        self.q0, self.u, self.traj = q0, u, traj
        self.duration = traj.duration

    def at_time(self, t: float) -> tuple[list[float], list[float], list[float]]:
        s, sd, sdd = (v[0] for v in self.traj.at_time(t))
        return (self.q0 + self.u * s).tolist(), (self.u * sd).tolist(), (self.u * sdd).tolist()


def stop_trajectory(
    q: Sequence[float],
    qd: Sequence[float],
    qdd: Sequence[float],
    limits: JointLimits,
) -> TimedTrajectory:
    """The jerk-limited stop from state (``q`` [rad], ``qd`` [rad/s], ``qdd``
    [rad/s^2]) to rest, under the acceleration and jerk limits.

    When velocity and acceleration are parallel, as anywhere on a trajectory
    from :func:`time_trajectory`, the stop brakes along that straight line (a
    1-DOF ruckig stop along the direction, under the tightest per-joint limits
    projected on it), so it stays on the collision-checked segment. Otherwise
    every joint brakes with ruckig's velocity interface, phase-synchronised
    where ruckig can. Joint position limits are not enforced: the stopping
    distance is the physics of braking.
    """
    state = []
    for name, v in (("q", q), ("qd", qd), ("qdd", qdd)):
        arr = np.asarray(v, dtype=float)
        if arr.shape != (limits.dofs,) or not np.all(np.isfinite(arr)):
            raise InvalidInputError(f"{name} must be {limits.dofs} finite values, got {v!r}")
        state.append(arr)
    q0, v0, a0 = state
    speed = float(np.linalg.norm(v0))
    if speed > 1e-12:
        u = v0 / speed
        along = float(a0 @ u)
        if np.linalg.norm(a0 - along * u) <= 1e-9 * (1.0 + float(np.linalg.norm(a0))):
            return _stop_on_line(q0, u, speed, along, limits)
    otg = Ruckig(limits.dofs)
    inp = _input(limits)
    inp.control_interface = ControlInterface.Velocity
    inp.current_position, inp.current_velocity, inp.current_acceleration = (x.tolist() for x in state)
    inp.target_velocity = [0.0] * limits.dofs
    inp.target_acceleration = [0.0] * limits.dofs
    traj = _calculate(otg, inp, "the stop")
    end = tuple(float(v) for v in traj.at_time(traj.duration)[0])
    return TimedTrajectory(
        waypoints=(tuple(float(v) for v in q0), end),
        start_times=(0.0,),
        durations=(traj.duration,),
        duration=traj.duration,
        limits=limits,
        _segments=(traj,),
    )


def _stop_on_line(q0: np.ndarray, u: np.ndarray, speed: float, acc: float, limits: JointLimits) -> TimedTrajectory:
    nz = np.abs(u) > 1e-12
    a_max = float(np.min(np.array(limits.acceleration)[nz] / np.abs(u[nz])))
    j_max = float(np.min(np.array(limits.jerk)[nz] / np.abs(u[nz])))
    v_max = float(np.min(np.array(limits.velocity)[nz] / np.abs(u[nz])))
    otg = Ruckig(1)
    inp = InputParameter(1)
    inp.control_interface = ControlInterface.Velocity
    inp.current_position, inp.current_velocity, inp.current_acceleration = [0.0], [speed], [acc]
    inp.target_velocity, inp.target_acceleration = [0.0], [0.0]
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = [max(v_max, speed)], [a_max], [j_max]
    traj = _calculate(otg, inp, "the stop")
    seg = _OnLine(q0, u, traj)
    end = tuple(float(v) for v in seg.at_time(traj.duration)[0])
    return TimedTrajectory(
        waypoints=(tuple(float(v) for v in q0), end),
        start_times=(0.0,),
        durations=(traj.duration,),
        duration=traj.duration,
        limits=limits,
        _segments=(seg,),
    )
