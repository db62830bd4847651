"""The simulated gripper's close (sim/robot.py), in the bare world: the open hand around an
upright carton, then the fingers close.

The close was a torque with no speed limit, held for a whole control period (1/60 s, four
physics substeps): after the first period the fingers were already 1-2 cm inside the
carton, and the solver pushed them apart again. On the floor that settled into a grip; on
a table it threw the carton off (house_hard 2044 and 2040: upright cartons on tables,
misses at 0 mm with the hand around them). The gripper is now a speed- and force-limited
position servo, as the real one in current-based position control: no finger sinks more
than a few millimetres."""
from __future__ import annotations

import math

import pybullet as p
import pytest

from planning import ArmKinematics
from sim import SimWorld

REACH = 0.27
PENETRATION = 0.003     # [m] how far a finger may sink into what it closes on


@pytest.mark.parametrize("off", [0.0, 0.007])
def test_closing_fingers_do_not_sink_into_the_object(off):
    sim = SimWorld(None, "house_hard", seed=2044)
    try:
        x, y, heading = 7.5, 5.0, math.pi                 # an open spot of that world
        sim.set_object_pose("carton_1", x, y, math.radians(174.8))
        body, carton = sim.robot.body, sim.scene.objects["carton_1"]
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
        sim.robot.set_gripper(0.0)
        deepest = 0.0
        for _ in range(30):                               # half a second
            sim.step()
            contacts = p.getContactPoints(body, carton, physicsClientId=sim.cid)
            deepest = min([deepest] + [c[8] for c in contacts])
        assert deepest > -PENETRATION, f"a finger sank {-1000 * deepest:.1f} mm into the carton"
    finally:
        sim.close()
