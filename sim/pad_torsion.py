"""The finger pads' torsional friction, which pybullet's point contacts lack.

A body held between the pads touches each one at a point, and the two points lie on the
line between the pads. Turning about that line moves neither point, so pybullet's
(lateral) friction cannot resist it, and its spinning friction, a velocity constraint,
lets the body creep: a 90 g vase held 23 mm below its centre of mass tilted from 3 to 30
degrees over 15 s of driving, and fell over when it was put down. A real pad presses on a
patch, not a point, and friction over the patch resists turning about the pad's normal,
up to ``mu * F * L / 4`` for a strip of length ``L`` pressed with ``F`` (uniform pressure
along a line: the least of the shapes a pad meets).

:class:`PadTorsion` adds that torque once per control period: while the body is pressed
by both pads and the torque that would stop its turning relative to the hand is within
the patches' limit, the body keeps the angle about the pad axis it had relative to the
hand (it sticks); beyond the limit it turns freely and sticks again at its new angle.
The limit follows the pads' normal force, so a body the fingers let go of is free.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ._pybullet import pybullet as p

#: [m] the length of the strip a pad presses on a body: the pad's height (30 mm)
PAD_STRIP = 0.030


@dataclass
class _Anchor:
    body: int
    rel_twist: float      # [rad] the body's angle about the pad axis relative to the hand


def _twist(q, axis) -> float:
    """The angle [rad] of rotation ``q`` (x, y, z, w) about the unit ``axis``."""
    return 2.0 * math.atan2(float(np.dot(q[:3], axis)), q[3])


def _qmul(a, b) -> np.ndarray:
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return np.array([aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw,
                     aw * bw - ax * bx - ay * by - az * bz])


def _qinv(q) -> np.ndarray:
    return np.array([-q[0], -q[1], -q[2], q[3]])


def _axis_angle(axis, angle) -> np.ndarray:
    s = math.sin(angle / 2)
    return np.array([axis[0] * s, axis[1] * s, axis[2] * s, math.cos(angle / 2)])


def _rotate(q, v) -> np.ndarray:
    return np.array(p.multiplyTransforms((0, 0, 0), q, v, (0, 0, 0, 1))[0])


class PadTorsion:
    """Torsional friction between the two finger links ``pads`` of ``robot`` and the
    bodies ``objects`` they press, applied by :meth:`apply` after each control period."""

    def __init__(self, cid: int, robot: int, pads: tuple[int, int], objects: dict[str, int]):
        self.cid, self.robot, self.pads = cid, robot, pads
        self.objects = objects          # name -> body, the scene's (objects may be added)
        self.anchor: _Anchor | None = None
        self._inertia: dict[int, tuple] = {}

    def apply(self, dt: float) -> None:
        held = self._pressed()
        if held is None:
            self.anchor = None
            return
        body, pivot, force, mu = held
        cid = self.cid
        hand = p.getLinkState(self.robot, self.pads[0], computeLinkVelocity=1, physicsClientId=cid)
        q_hand, w_hand = np.array(hand[5]), np.array(hand[7])
        axis = _rotate(q_hand, (0.0, 1.0, 0.0))       # the fingers close along their y axis
        pos, q_obj = (np.array(v) for v in p.getBasePositionAndOrientation(body, physicsClientId=cid))
        v_obj, w_obj = (np.array(v) for v in p.getBaseVelocity(body, physicsClientId=cid))
        rel_twist = _twist(_qmul(_qinv(q_hand), q_obj), _rotate(_qinv(q_hand), axis))
        if self.anchor is None or self.anchor.body != body:
            self.anchor = _Anchor(body, rel_twist)
            return
        spin = float(np.dot(w_obj - w_hand, axis))     # turning relative to the hand [rad/s]
        needed = self._inertia_about(body, q_obj, pos, pivot, axis) * abs(spin) / dt
        if needed > 2 * mu * force * PAD_STRIP / 4:     # two pads: it slips
            self.anchor.rel_twist = rel_twist
            return
        back = -math.remainder(rel_twist - self.anchor.rel_twist, 2 * math.pi)
        turn = _axis_angle(axis, back)
        new_pos = pivot + _rotate(turn, pos - pivot)
        new_q = _qmul(turn, q_obj)
        new_w = w_obj - spin * axis
        new_v = v_obj + np.cross(new_w - w_obj, new_pos - pivot)
        p.resetBasePositionAndOrientation(body, new_pos.tolist(), new_q.tolist(), physicsClientId=cid)
        p.resetBaseVelocity(body, new_v.tolist(), new_w.tolist(), physicsClientId=cid)

    def _pressed(self):
        """(body, the middle of its contacts, the pads' mean normal force [N], friction) of
        the object pressed by both pads, or None."""
        per_pad, ids = [], set(self.objects.values())
        for link in self.pads:
            touching: dict[int, list] = {}
            for c in p.getContactPoints(bodyA=self.robot, linkIndexA=link, physicsClientId=self.cid):
                if c[2] in ids and c[9] > 0.0:
                    touching.setdefault(c[2], []).append(c)
            per_pad.append(touching)
        both = set(per_pad[0]) & set(per_pad[1])
        if not both:
            return None
        body = min(both)
        contacts = per_pad[0][body] + per_pad[1][body]
        pivot = np.mean([c[5] for c in contacts], axis=0)
        force = min(sum(c[9] for c in pad[body]) for pad in per_pad)
        mu = (p.getDynamicsInfo(self.robot, self.pads[0], physicsClientId=self.cid)[1]
              * p.getDynamicsInfo(body, -1, physicsClientId=self.cid)[1])
        return body, pivot, force, mu

    def _inertia_about(self, body, q_obj, com, pivot, axis) -> float:
        """[kg m^2] the body's moment of inertia about the pad axis through ``pivot``
        (pybullet's base pose is its centre of mass and principal axes)."""
        if body not in self._inertia:
            info = p.getDynamicsInfo(body, -1, physicsClientId=self.cid)
            self._inertia[body] = (info[0], np.array(info[2]))
        mass, diag = self._inertia[body]
        u = _rotate(_qinv(q_obj), axis)
        offset = com - pivot
        d2 = float(np.dot(offset, offset) - np.dot(offset, axis) ** 2)
        return float(np.dot(diag, u * u)) + mass * d2
