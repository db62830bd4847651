"""The simulated robot started with no /initialpose: the localiser (navstack) finds it on
the map by itself or says that it has not, and is never sure of a wrong pose.

A rehearsal on the real robot, started at (1, 1, 0) with no initial pose, had the
localiser say "localised" (std 4 cm) at (0.00, 0.00, -0.15): its global localisation had
converged to (1.04, 1.00), but map -> odom stayed at the identity it held before anything
was known (tests/test_navstack_localiser.py has the same on the synthetic robot)."""

from __future__ import annotations

import math

import pytest

from bt_engine import ActorError, Runtime

sim_mod = pytest.importorskip("sim")

SECONDS = 10.0  # the localiser searches 2 s after the first scan (NavStack's global_after)
WRONG = 0.3  # [m] and [rad]: "localised" this far from the truth is a wrong pose


def _errors(pose, truth):
    return (math.hypot(pose[0] - truth[0], pose[1] - truth[1]), abs(math.remainder(pose[2] - truth[2], 2 * math.pi)))


def _start_without_initial_pose(world: str, seed: int = 0):
    """Start the world (its and the localiser's ``seed``) with nothing said of the pose.
    Returns samples (localisation_status, true pose) every 0.25 s for SECONDS, then the
    map -> base_footprint pose from tf (None: not there), the true pose, and
    require_localised's refusal (None: it accepted)."""
    from actors.navigation import Navigation
    from navstack import NavStack

    rt = Runtime()
    # initial_pose=False: the simulator must not give /initialpose as a user would
    sim = sim_mod.SimWorld(rt, world=world, seed=seed, camera=False, initial_pose=False).start()
    try:
        rt.add_subsystem("navigation", Navigation)
        rt.add_subsystem("navstack", NavStack, seed=seed)
        samples = []
        while len(samples) * 0.25 < SECONDS:
            rt.call("sleep", 0.25)
            samples.append((rt.call("localisation_status"), sim.robot_pose()))
        truth = sim.robot_pose()
        try:
            tf_pose = rt.call("get_pose")
        except ActorError:
            tf_pose = None
        try:
            rt.call("require_localised", wait=0.5)
            refusal = None
        except ActorError as e:
            refusal = str(e)
    finally:
        sim.close()
        rt.close()
    return samples, tf_pose, truth, refusal


def _check(samples, tf_pose, truth, refusal):
    for st, true_pose in samples:
        if st["state"] == "localised":
            e, eyaw = _errors(st["pose"], true_pose)
            assert e <= WRONG and eyaw <= WRONG, f"localised, {e:.2f} m and {eyaw:.2f} rad off: {st}"
    st = samples[-1][0]
    if st["state"] == "localised":
        e, eyaw = _errors(st["pose"], truth)
        assert e < 0.10 and eyaw < 0.10, st
        assert tf_pose is not None, "localised, so map -> base_footprint is on /tf"
        e, eyaw = _errors(tf_pose, truth)
        assert e < 0.10 and eyaw < 0.10, tf_pose
        assert refusal is None
    else:
        assert st["pose"] is None, st  # says it does not know
        assert tf_pose is None, "not localised, so nothing on /tf"
        assert refusal is not None and "delocalised" in refusal
    return st


def test_started_away_from_the_origin_with_no_initial_pose():
    """The house: the robot starts at (1, 1, 0), its odometry at (0, 0, 0)."""
    samples, tf_pose, truth, refusal = _start_without_initial_pose("house")
    assert math.hypot(truth[0], truth[1]) > 1.0
    st = _check(samples, tf_pose, truth, refusal)
    assert st["state"] in ("localised", "uncertain"), st


def test_started_in_a_square_room_with_no_initial_pose():
    """open_floor: the robot at the centre of a walled square, which looks the same turned
    by any quarter turn: four poses fit the scan alike, so it must not say localised at
    one of the three wrong ones (with this seed the filter's weights alone pick the pose
    turned half round)."""
    samples, tf_pose, truth, refusal = _start_without_initial_pose("open_floor", seed=3)
    _check(samples, tf_pose, truth, refusal)
