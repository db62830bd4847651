"""The simulated gripper's close (sim/robot.py), in the bare world: the open hand around an
upright carton, then the fingers close.

The close was a torque with no speed limit, held for a whole control period (1/60 s, four
physics substeps): after the first period the fingers were already 1-2 cm inside the
carton, and the solver pushed them apart again. On the floor that settled into a grip; on
a table it threw the carton off (house_hard 2044 and 2040: upright cartons on tables,
misses at 0 mm with the hand around them). The gripper is now a speed- and force-limited
position servo, as the real one in current-based position control: no finger sinks more
than a few millimetres, also once it squeezes with the servo's full force."""

from __future__ import annotations

import math

import pybullet as p
import pytest

from planning import ArmKinematics
from sim import SimWorld

REACH = 0.27
PENETRATION = 0.003  # [m] how far a finger may sink into what it closes on


def _hand_around_carton(yaw_deg: float, off: float = 0.0) -> SimWorld:
    """house_hard 2044's bare world with its carton upright on open floor (its yaw
    ``yaw_deg``) and the open hand around it, ``off`` [m] to its side."""
    sim = SimWorld(None, "house_hard", seed=2044)
    x, y, heading = 7.5, 5.0, math.pi  # an open spot of that world
    sim.set_object_pose("carton_1", x, y, math.radians(yaw_deg))
    body = sim.robot.body
    # the base REACH behind the carton, the hand ``off`` to its side
    bx, by = x - REACH * math.cos(heading), y - REACH * math.sin(heading) - off
    z0 = p.getBasePositionAndOrientation(body, physicsClientId=sim.cid)[0][2]
    quat = p.getQuaternionFromEuler([0, 0, heading])
    # the arm unfolds 0.3 m back, clear of the carton; then the base is put in place
    p.resetBasePositionAndOrientation(body, [bx + 0.3, by, z0], quat, physicsClientId=sim.cid)
    sim.robot.set_gripper(0.085)
    sim.robot.set_arm(ArmKinematics.from_urdf().ik(REACH, 0.0, 0.06, 0.0).best)
    sim.advance(3.0)
    p.resetBasePositionAndOrientation(body, [bx, by, z0], quat, physicsClientId=sim.cid)
    sim.advance(0.5)
    return sim


def _finger_forces(sim) -> list[float]:
    """The contact force [N] of each finger on the carton."""
    body, carton = sim.robot.body, sim.scene.objects["carton_1"]
    contacts = p.getContactPoints(body, carton, physicsClientId=sim.cid)
    return [sum(c[9] for c in contacts if c[3] == j) for j in sim.robot.grip_idx]


@pytest.mark.parametrize("off, yaw", [(0.0, 174.8), (0.007, 174.8), (0.0, 165.0)])
def test_closing_fingers_do_not_sink_into_the_object(off, yaw):
    """Also under the full squeeze, on a carton standing askew between the pads (its
    edges, not its faces, meet them)."""
    sim = _hand_around_carton(yaw, off)
    try:
        body, carton = sim.robot.body, sim.scene.objects["carton_1"]
        sim.robot.set_gripper(0.0)
        deepest = 0.0
        for _ in range(60):  # a second: closed and squeezing
            sim.step()
            contacts = p.getContactPoints(body, carton, physicsClientId=sim.cid)
            deepest = min([deepest] + [c[8] for c in contacts])
        assert deepest > -PENETRATION, f"a finger sank {-1000 * deepest:.1f} mm into the carton"
    finally:
        sim.close()


def test_stalled_fingers_squeeze_with_the_servo_force_and_let_go_at_once():
    """The servo's setpoint runs on past a finger that the object stops, and the position
    error pushes up to the current limit: each finger squeezes with GRIPPER_FORCE. With
    the setpoint held at the finger (the speed limit capping pybullet's motor), a stalled
    finger pushed 2.8 N whatever the limit, and a carton lying in the hand slid out of the
    fingertips over a carry (house_hard 2004 and 2006: dropped beside the pallet). A grip
    check (the same goal again) keeps the squeeze; opening lets go within a control
    period, the carton left where it stands."""
    from sim.robot import GRIPPER_FORCE

    sim = _hand_around_carton(180.0)
    try:
        sim.robot.set_gripper(0.0)
        sim.advance(1.0)
        assert _finger_forces(sim) == [pytest.approx(GRIPPER_FORCE, rel=0.1)] * 2
        sim.robot.set_gripper(0.0)  # a grip check closes again
        sim.step()
        assert _finger_forces(sim) == [pytest.approx(GRIPPER_FORCE, rel=0.1)] * 2
        before = sim.object_pose("carton_1")
        sim.robot.set_gripper(0.085)
        sim.step()
        assert max(_finger_forces(sim)) < 1.0
        sim.advance(0.5)
        assert sim.robot.gripper_opening() > 0.08
        assert math.dist(before[:3], sim.object_pose("carton_1")[:3]) < 0.002
    finally:
        sim.close()
