"""A held object stays as the fingers took it (sim/simworld.py HOLDING_SOLVER_ITERATIONS).

pybullet's friction is solved iteratively; stopped short of converging, it lets a body
held by friction alone creep about the line between the pads. At the contact solver's
usual 50 iterations a bottle or a can turned up to 17 degrees over this 21 s carry; in a
map-world episode a bottle turned 23 degrees and, let go askew, toppled off the pallet
(actor_demo_house seed 3). While the fingers hold something, the solver runs
HOLDING_SOLVER_ITERATIONS.
"""

from __future__ import annotations

import math
import statistics

import numpy as np
import pybullet as p
import pytest

from planning import ArmKinematics
from sim import SimWorld
from sim.robot import ARM_HOME
from sim.simworld import HOLDING_SOLVER_ITERATIONS

REACH = 0.26
#: the base's moves over the carry: (v [m/s], w [rad/s]) for 1.5 s each, twice
DRIVE = ((0.26, 0.0), (0.0, 0.0), (-0.26, 0.0), (0.0, 1.8), (0.0, 0.0), (0.26, 0.5), (0.0, 0.0)) * 2


def _axis_in_hand(sim: SimWorld, body: int) -> np.ndarray:
    ee_pos, ee_orn = sim.link_pose("end_effector_link")
    inv = p.invertTransform(ee_pos, ee_orn)
    _, orn = p.getBasePositionAndOrientation(body, physicsClientId=sim.cid)
    q = p.multiplyTransforms(inv[0], inv[1], [0, 0, 0], orn)[1]
    return np.array(p.getMatrixFromQuaternion(q)).reshape(3, 3)[:, 2]


def _worst_turn(category: str, grip_z: float, **world) -> tuple[float, set]:
    """[deg] the most the object's axis turned in the hand, from the grasp over a lift, a
    fold and a carry; and the solver iterations seen while it was held."""
    sim = SimWorld(None, "house_hard", seed=2000, camera=False, cmd_vel_timeout=0, **world)
    try:
        name = next(n for n in sim.object_names() if sim.object_category(n) == category)
        body = sim.scene.objects[name]
        kin = ArmKinematics.from_urdf()
        x, y = 7.5, 5.0  # open floor in that world
        z0 = p.getBasePositionAndOrientation(sim.robot.body, physicsClientId=sim.cid)[0][2]
        p.resetBasePositionAndOrientation(sim.robot.body, [x - REACH, y, z0], [0, 0, 0, 1], physicsClientId=sim.cid)
        sim.set_object_pose(name, x + 0.3, y)  # out of the way while the arm unfolds
        sim.robot.set_gripper(0.09)
        sim.robot.set_arm(kin.ik(REACH, 0.0, grip_z, 0.0).best)
        sim.advance(2.0)
        assert sim.solver_iterations_now == sim.solver_iterations  # nothing held yet
        ee = sim.link_pose("end_effector_link")[0]
        sim.set_object_pose(name, ee[0], ee[1])
        sim.advance(0.5)
        sim.robot.set_gripper(0.0)
        sim.advance(1.5)
        before = _axis_in_hand(sim, body)
        sim.set_arm_positions(kin.ik(REACH, 0.0, grip_z + 0.10, 0.0).best, 2.0)
        sim.advance(2.5)
        sim.set_arm_positions(ARM_HOME, 2.0)
        sim.advance(2.5)
        worst, iterations = 0.0, set()
        for v, w in DRIVE:
            sim.robot.set_base_velocity(v, w)
            for _ in range(6):
                sim.advance(0.25)
                iterations.add(sim.solver_iterations_now)
                c = float(np.clip(np.dot(_axis_in_hand(sim, body), before), -1.0, 1.0))
                worst = max(worst, math.degrees(math.acos(c)))
        assert sim.in_gripper(name)
        return worst, iterations
    finally:
        sim.close()


@pytest.mark.parametrize(
    "category, heights",
    [("bottle", (0.045, 0.055, 0.065)), ("can", (0.045, 0.055, 0.065)), ("carton", (0.045, 0.05, 0.055))],
)
def test_a_held_object_does_not_turn_in_the_hand_over_a_fold_and_a_carry(category, heights):
    """Which grasp creeps most is chaotic (a different physics rate before the grasp moves
    the worst case between heights), so the judge is several grasps: the worst of 9 went
    from 17.4 degrees at 50 iterations to about 3.5 here, the median to about 1."""
    turns = []
    for grip_z in heights:
        worst, iterations = _worst_turn(category, grip_z)
        assert iterations == {HOLDING_SOLVER_ITERATIONS}
        turns.append(worst)
    assert max(turns) < 5.0, turns
    assert statistics.median(turns) < 3.0, turns


def test_at_the_usual_solver_iterations_held_objects_creep():
    """What the holding iterations are for: the same carries without them turn a bottle and
    a can several times as far (a median of about 10 degrees against about 2)."""
    turns = [
        _worst_turn(category, grip_z, holding_solver_iterations=50)[0]
        for category in ("bottle", "can")
        for grip_z in (0.045, 0.055, 0.065)
    ]
    assert statistics.median(turns) > 3.0, turns
