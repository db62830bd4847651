"""planning.trajectory: ruckig timing of paths and the jerk-limited stop."""

from __future__ import annotations

import numpy as np
import pytest

from planning import (
    ArmKinematics,
    InvalidInputError,
    JointLimits,
    PlanningScene,
    plan_joint_motion,
    seed_planners,
    stop_trajectory,
    time_trajectory,
)

LIMITS = JointLimits((1.0, 1.2, 1.5, 2.0), (2.0, 2.5, 3.0, 4.0), (10.0, 12.0, 15.0, 20.0))
PATH = [(0, 0, 0, 0), (0.5, -0.3, 0.2, 0.1), (1.0, 0.4, -0.5, 0.7), (0.0, 0.0, 0.0, 0.0)]
DT = 0.001  # 1 kHz
TOL = 1e-6


def _check_limits(samples, limits: JointLimits) -> None:
    v = np.abs(samples.velocities).max(axis=0)
    a = np.abs(samples.accelerations).max(axis=0)
    jerk = np.abs(np.diff(samples.accelerations, axis=0) / np.diff(samples.times)[:, None]).max(axis=0)
    assert np.all(v <= np.array(limits.velocity) * (1 + TOL) + TOL), v
    assert np.all(a <= np.array(limits.acceleration) * (1 + TOL) + TOL), a
    # finite differences of a piecewise-linear acceleration never exceed the jerk bound
    assert np.all(jerk <= np.array(limits.jerk) * (1 + 1e-4) + 1e-4), jerk
    # velocity is the derivative of position (1 kHz central differences)
    fd = np.gradient(samples.positions, samples.times, axis=0)[1:-1]
    assert np.allclose(fd, samples.velocities[1:-1], atol=5e-3)


def test_timed_trajectory_respects_limits_at_1khz():
    traj = time_trajectory(PATH, LIMITS)
    samples = traj.sample(DT)
    assert samples.times[0] == 0 and samples.times[-1] == pytest.approx(traj.duration)
    assert np.all(np.diff(samples.times) <= DT + 1e-12)
    _check_limits(samples, LIMITS)
    # rest to rest at every waypoint, and it ends on the goal
    for t, w in zip(list(traj.start_times) + [traj.duration], traj.waypoints):
        q, qd, qdd = traj.at(t)
        assert np.allclose(q, w, atol=1e-9) and np.allclose(qd, 0, atol=1e-9) and np.allclose(qdd, 0, atol=1e-9)
    assert np.allclose(traj.final_position, PATH[-1], atol=1e-9)
    # each segment is limited by its slowest joint, so some joint reaches a limit
    assert any(np.isclose(np.abs(samples.velocities).max(axis=0), LIMITS.velocity, rtol=1e-3))


def test_phase_synchronisation_stays_on_the_straight_segments():
    traj = time_trajectory(PATH, LIMITS)
    samples = traj.sample(DT)
    waypoints = np.array(traj.waypoints)
    for t, q in zip(samples.times, samples.positions):
        i = min(int(np.searchsorted(traj.start_times, t, side="right") - 1), len(traj.durations) - 1)
        a, b = waypoints[i], waypoints[i + 1]
        d = b - a
        u = float(np.dot(q - a, d) / np.dot(d, d))
        assert -1e-9 <= u <= 1 + 1e-9
        assert np.linalg.norm(a + u * d - q) < 1e-9


def test_a_planned_arm_path_is_timed_within_the_urdf_limits():
    kin = ArmKinematics.from_urdf()
    limits = JointLimits.from_kinematics(kin, acceleration=3.0, jerk=30.0, velocity_scale=0.5)
    assert limits.velocity == pytest.approx(tuple(0.5 * v for v in kin.max_velocity))
    seed_planners(11)
    scene = PlanningScene()
    try:
        start = kin.ik(0.2, -0.15, 0.12, 0.6).best
        goal = kin.ik(0.2, 0.15, 0.12, 0.6).best
        scene.add_box("wall", (0.04, 0.1, 0.22), (0.25, 0.0, 0.11))
        plan = plan_joint_motion(start, goal, scene, timeout=2.0)
        assert plan.ok, plan.message
        traj = time_trajectory(plan.path, limits)
        samples = traj.sample(DT)
        _check_limits(samples, limits)
        # every 1 kHz sample of the timed motion is collision-free
        assert all(scene.is_valid(q) for q in samples.positions[::5])
    finally:
        scene.close()


def test_stop_is_jerk_limited_and_ends_at_rest():
    traj = time_trajectory(PATH, LIMITS)
    t = traj.start_times[1] + 0.3 * traj.durations[1]  # mid-motion on segment 1
    q, qd, qdd = traj.at(t)
    assert np.linalg.norm(qd) > 0.1
    stop = stop_trajectory(q, qd, qdd, LIMITS)
    samples = stop.sample(DT)
    assert np.allclose(samples.positions[0], q) and np.allclose(samples.velocities[0], qd)
    assert np.allclose(samples.velocities[-1], 0, atol=1e-9)
    assert np.allclose(samples.accelerations[-1], 0, atol=1e-9)
    acc = np.abs(samples.accelerations).max(axis=0)
    jerk = np.abs(np.diff(samples.accelerations, axis=0) / DT).max(axis=0)
    assert np.all(acc <= np.array(LIMITS.acceleration) + 1e-6)
    assert np.all(jerk <= np.array(LIMITS.jerk) * (1 + 1e-4) + 1e-4)
    # the stop is not a freeze, and it brakes along the segment it was on
    assert stop.duration > 0.05
    travel = np.array(stop.final_position) - q
    seg = np.subtract(traj.waypoints[2], traj.waypoints[1])
    cos = float(travel @ seg / (np.linalg.norm(travel) * np.linalg.norm(seg)))
    assert cos == pytest.approx(1.0, abs=1e-6)
    # from rest, the stop is immediate
    assert stop_trajectory(q, np.zeros(4), np.zeros(4), LIMITS).duration == pytest.approx(0.0, abs=1e-9)


def test_stop_from_an_arbitrary_state_uses_every_joint():
    q, qd, qdd = np.zeros(4), np.array([0.8, -0.5, 0.2, 1.0]), np.array([-1.0, 1.5, 0.5, 0.0])
    stop = stop_trajectory(q, qd, qdd, LIMITS)
    samples = stop.sample(DT)
    assert np.allclose(samples.velocities[-1], 0, atol=1e-9)
    jerk = np.abs(np.diff(samples.accelerations, axis=0) / DT).max(axis=0)
    assert np.all(jerk <= np.array(LIMITS.jerk) * (1 + 1e-4) + 1e-4)


def test_degenerate_and_bad_inputs():
    single = time_trajectory([(0.1, 0.2, 0.3, 0.4)], LIMITS)
    assert single.duration == 0 and np.allclose(single.at(1.0)[0], (0.1, 0.2, 0.3, 0.4))
    dup = time_trajectory([(0, 0, 0, 0), (0, 0, 0, 0), (1, 0, 0, 0)], LIMITS)
    assert len(dup.durations) == 1
    with pytest.raises(InvalidInputError):
        time_trajectory([], LIMITS)
    with pytest.raises(InvalidInputError):
        time_trajectory([(0, 0, 0)], LIMITS)
    with pytest.raises(InvalidInputError):
        time_trajectory([(0, 0, 0, float("nan"))], LIMITS)
    with pytest.raises(InvalidInputError, match="acceleration"):
        JointLimits((1.0,) * 4, (1.0,) * 3, (1.0,) * 4)
    with pytest.raises(InvalidInputError, match="jerk"):
        JointLimits((1.0,) * 4, (1.0,) * 4, (0.0,) * 4)
    with pytest.raises(InvalidInputError):
        stop_trajectory((0, 0, 0, 0), (0, 0, 0), (0, 0, 0, 0), LIMITS)
    with pytest.raises(InvalidInputError):
        time_trajectory(PATH, LIMITS).sample(0.0)
