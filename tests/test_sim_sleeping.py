"""Objects at rest sleep (sim/scene.py): they leave the contact solver, yet anything that
touches them, or the simulator moving them, wakes them as before."""

from __future__ import annotations

import math

import pybullet as p

from sim import SimWorld


def _position(sim: SimWorld, name: str):
    return p.getBasePositionAndOrientation(sim.scene.objects[name], physicsClientId=sim.cid)[0]


def test_a_sleeping_object_is_pushed_by_the_base_that_drives_into_it():
    sim = SimWorld(None, "open_floor", seed=0, camera=False, cmd_vel_timeout=0)
    try:
        x, y, _ = sim.robot_pose()
        name = sim.add_object("can", x + 0.45, y)
        sim.advance(4.0)  # long enough at rest to fall asleep
        before = _position(sim, name)
        sim.robot.set_base_velocity(0.2, 0.0)
        sim.advance(3.0)
        after = _position(sim, name)
        assert after[0] - before[0] > 0.1, "the base drove through a sleeping can"
    finally:
        sim.close()


def test_a_sleeping_object_put_in_the_air_falls():
    sim = SimWorld(None, "open_floor", seed=0, camera=False, cmd_vel_timeout=0)
    try:
        x, y, _ = sim.robot_pose()
        name = sim.add_object("bottle", x + 1.0, y)
        sim.advance(4.0)
        sim.set_object_pose(name, x + 1.0, y, z=0.5)
        sim.advance(1.0)
        pos = _position(sim, name)
        assert pos[2] < 0.2, f"a woken bottle hung in the air at z {pos[2]:.2f}"
        lo, hi = p.getAABB(sim.scene.objects[name], physicsClientId=sim.cid)
        assert lo[2] > -0.01 and math.isfinite(hi[2])
    finally:
        sim.close()
