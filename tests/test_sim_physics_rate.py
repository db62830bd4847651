"""The physics rate follows the hand (sim/simworld.py): the full rate while the arm or the
gripper moves, and what it touched settles; the still hand's rate otherwise (driving,
looking, standing, carrying), with more solver iterations while the fingers hold something."""

from __future__ import annotations

import math

import pytest

from planning import ArmKinematics
from sim import SimWorld
from sim.simworld import HAND_SETTLE, HOLDING_SOLVER_ITERATIONS, PHYSICS_HZ

STILL_HAND_PHYSICS_HZ = 120


def _steps_until(sim: SimWorld, hz: int, seconds: float) -> float | None:
    """[s] until the physics runs at ``hz``, None if not within ``seconds``."""
    for i in range(round(seconds / sim.dt)):
        sim.step()
        if sim.physics_hz == hz:
            return i * sim.dt
    return None


def test_the_still_hand_rate_is_on_by_default(monkeypatch):
    monkeypatch.delenv("ACTORBT_SIM_STILL_HAND_HZ", raising=False)
    sim = SimWorld(None, "house", seed=0, camera=False)
    try:
        assert _steps_until(sim, STILL_HAND_PHYSICS_HZ, 2.0) is not None
    finally:
        sim.close()


def test_the_rate_from_the_environment_reaches_every_world(monkeypatch):
    monkeypatch.setenv("ACTORBT_SIM_STILL_HAND_HZ", "120")
    sim = SimWorld(None, "house", seed=0, camera=False)
    try:
        assert _steps_until(sim, STILL_HAND_PHYSICS_HZ, 2.0) is not None
    finally:
        sim.close()


def test_the_hand_moving_runs_the_full_rate_and_a_still_one_the_lower_also_holding():
    sim = SimWorld(None, "house_hard", seed=2044, camera=False, still_hand_physics_hz=STILL_HAND_PHYSICS_HZ)
    try:
        # standing and driving with the arm folded
        assert _steps_until(sim, STILL_HAND_PHYSICS_HZ, 2.0) is not None
        sim.robot.set_base_velocity(0.2, 0.0)
        sim.advance(1.0)
        assert sim.physics_hz == STILL_HAND_PHYSICS_HZ
        sim.robot.set_base_velocity(0.0, 0.0)
        # the arm unfolds: at once the full rate, the lower one again once it settled
        sim.robot.set_arm(ArmKinematics.from_urdf().ik(0.27, 0.0, 0.06, 0.0).best)
        assert _steps_until(sim, PHYSICS_HZ, 0.1) is not None
        settled = _steps_until(sim, STILL_HAND_PHYSICS_HZ, 5.0)
        assert settled is not None and settled >= HAND_SETTLE
        # the carton between the fingers: closing on it runs the full rate; held with the
        # arm still, the lower one with the holding solver iterations; lifted, the full one
        x, y, yaw = sim.robot.base_pose()[0]
        sim.set_object_pose("carton_1", x + 0.27 * math.cos(yaw), y + 0.27 * math.sin(yaw), yaw)
        sim.advance(1.0)
        sim.robot.set_gripper(0.0)
        assert _steps_until(sim, PHYSICS_HZ, 0.1) is not None
        sim.advance(1.0)
        assert sim.physics_hz == PHYSICS_HZ, "the fingers still closing, yet at the lower rate"
        settled = _steps_until(sim, STILL_HAND_PHYSICS_HZ, 3.0)
        assert settled is not None and sim.in_gripper("carton_1")
        assert sim.solver_iterations_now == HOLDING_SOLVER_ITERATIONS
        sim.set_arm_positions(ArmKinematics.from_urdf().ik(0.27, 0.0, 0.16, 0.0).best, 2.0)
        assert _steps_until(sim, PHYSICS_HZ, 0.1) is not None
    finally:
        sim.close()


@pytest.mark.parametrize("how", ["argument", "environment"])
def test_one_rate_when_the_still_hand_rate_is_none(how, monkeypatch):
    if how == "environment":
        monkeypatch.setenv("ACTORBT_SIM_STILL_HAND_HZ", "none")
        sim = SimWorld(None, "house", seed=0, camera=False)
    else:
        monkeypatch.setenv("ACTORBT_SIM_STILL_HAND_HZ", "120")
        sim = SimWorld(None, "house", seed=0, camera=False, still_hand_physics_hz=None)
    try:
        assert _steps_until(sim, STILL_HAND_PHYSICS_HZ, 2.0) is None
        assert sim.physics_hz == PHYSICS_HZ
    finally:
        sim.close()


def test_a_bad_still_hand_rate_in_the_environment_is_a_clear_error(monkeypatch):
    monkeypatch.setenv("ACTORBT_SIM_STILL_HAND_HZ", "fast")
    with pytest.raises(ValueError, match="ACTORBT_SIM_STILL_HAND_HZ='fast': a rate in Hz or none"):
        SimWorld(None, "house", seed=0, camera=False)
    monkeypatch.setenv("ACTORBT_SIM_STILL_HAND_HZ", "100")
    with pytest.raises(ValueError, match=r"still_hand_physics_hz \(100\) must be a multiple of control_hz"):
        SimWorld(None, "house", seed=0, camera=False)
