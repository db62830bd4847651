"""Build a WorldSpec into a pybullet client: floor, static geometry, place location, objects."""
from __future__ import annotations

import math

from ._pybullet import pybullet as p

from .description import Box, PlacedObject, WorldSpec
from .objects import CATEGORIES

FLOOR_RGBA = (0.93, 0.91, 0.86, 1.0)
FLOOR_FRICTION = 1.0


def _quat_yaw(yaw):
    return (0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))


def _static_boxes(cid, boxes: list[Box]) -> list[int]:
    """One fixed body per box. (A single compound would be one body id, but pybullet draws a
    visual-less body's collision shapes, and createVisualShapeArray overflows beyond 16
    shapes and mangles colours; single bodies are the reliable path.)"""
    out = []
    for b in boxes:
        half = [b.sx / 2, b.sy / 2, b.sz / 2]
        col = p.createCollisionShape(p.GEOM_BOX, halfExtents=half, physicsClientId=cid)
        vis = p.createVisualShape(p.GEOM_BOX, halfExtents=half, rgbaColor=list(b.rgba),
                                  specularColor=[0.05, 0.05, 0.05], physicsClientId=cid)
        body = p.createMultiBody(0.0, col, vis, [b.x, b.y, b.sz / 2], _quat_yaw(b.yaw), physicsClientId=cid)
        p.changeDynamics(body, -1, lateralFriction=0.6, physicsClientId=cid)
        out.append(body)
    return out


class Scene:
    """The static world and the movable objects of one pybullet client."""

    def __init__(self, cid: int, spec: WorldSpec):
        self.cid = cid
        self.spec = spec
        x0, y0, x1, y1 = spec.bounds
        half = [(x1 - x0) / 2 + 1.0, (y1 - y0) / 2 + 1.0, 0.05]
        col = p.createCollisionShape(p.GEOM_BOX, halfExtents=half, physicsClientId=cid)
        vis = p.createVisualShape(p.GEOM_BOX, halfExtents=half, rgbaColor=FLOOR_RGBA, physicsClientId=cid)
        self.floor = p.createMultiBody(0.0, col, vis, [(x0 + x1) / 2, (y0 + y1) / 2, -0.05],
                                       physicsClientId=cid)
        p.changeDynamics(self.floor, -1, lateralFriction=FLOOR_FRICTION, physicsClientId=cid)
        p.changeVisualShape(self.floor, -1, specularColor=[0, 0, 0], physicsClientId=cid)
        statics = list(spec.walls) + list(spec.furniture)
        self.statics = _static_boxes(cid, statics)
        self.place = _static_boxes(cid, [spec.place])[0] if spec.place else None
        self.objects: dict[str, int] = {}
        self.categories: dict[str, str] = {}
        for obj in spec.objects:
            self.add_object(obj)

    def add_object(self, obj: PlacedObject) -> int:
        if obj.name in self.objects:
            raise ValueError(f"object '{obj.name}' already exists")
        cat = CATEGORIES[obj.category]
        cid = self.cid
        types = []
        half, radii, lengths, frames = [], [], [], []
        for part in cat.parts:
            if part[0] == "cylinder":
                types.append(p.GEOM_CYLINDER)
                radii.append(part[1])
                lengths.append(part[2])
                half.append([0, 0, 0])
                frames.append([0, 0, part[3]])
            elif part[0] == "box":
                types.append(p.GEOM_BOX)
                radii.append(0)
                lengths.append(0)
                half.append([s / 2 for s in part[1]])
                frames.append([0, 0, part[2]])
            elif part[0] == "sphere":
                types.append(p.GEOM_SPHERE)
                radii.append(part[1])
                lengths.append(0)
                half.append([0, 0, 0])
                frames.append([0, 0, part[2]])
        kw = dict(shapeTypes=types, radii=radii, halfExtents=half, lengths=lengths, physicsClientId=cid)
        col = p.createCollisionShapeArray(collisionFramePositions=frames, **kw)
        vis = p.createVisualShapeArray(visualFramePositions=frames, rgbaColors=[list(cat.rgba)] * len(types),
                                       **kw)
        # centre of mass: volume-weighted over the parts (the bottle is bottom-heavy)
        vols = []
        for part in cat.parts:
            if part[0] == "cylinder":
                vols.append(math.pi * part[1] ** 2 * part[2])
            elif part[0] == "box":
                vols.append(part[1][0] * part[1][1] * part[1][2])
            else:
                vols.append(4 / 3 * math.pi * part[1] ** 3)
        com_z = sum(v * f[2] for v, f in zip(vols, frames)) / sum(vols)
        body = p.createMultiBody(cat.mass, col, vis, [obj.x, obj.y, cat.height / 2 + 1e-4],
                                 _quat_yaw(obj.yaw), baseInertialFramePosition=[0, 0, com_z],
                                 physicsClientId=cid)
        p.changeDynamics(body, -1, lateralFriction=cat.friction, spinningFriction=0.001,
                         rollingFriction=0.0001, physicsClientId=cid)
        self.objects[obj.name] = body
        self.categories[obj.name] = obj.category
        return body

    def object_pose(self, name):
        """(x, y, z, qx, qy, qz, qw) of the object's frame (centre of its bounding box)."""
        body = self.objects[name]
        pos, orn = p.getBasePositionAndOrientation(body, physicsClientId=self.cid)
        # getBasePositionAndOrientation reports the inertial frame; convert to the link frame
        dyn = p.getDynamicsInfo(body, -1, physicsClientId=self.cid)
        inv_pos, inv_orn = p.invertTransform(dyn[3], dyn[4])
        pos, orn = p.multiplyTransforms(pos, orn, inv_pos, inv_orn)
        return tuple(pos) + tuple(orn)

    def set_object_pose(self, name, x, y, yaw=0.0, z=None):
        """Teleport an object (z defaults to standing on the floor) and zero its velocity."""
        body = self.objects[name]
        cat = CATEGORIES[self.categories[name]]
        z = cat.height / 2 + 1e-4 if z is None else z
        dyn = p.getDynamicsInfo(body, -1, physicsClientId=self.cid)
        pos, orn = p.multiplyTransforms([x, y, z], _quat_yaw(yaw), dyn[3], dyn[4])
        p.resetBasePositionAndOrientation(body, pos, orn, physicsClientId=self.cid)
        p.resetBaseVelocity(body, [0, 0, 0], [0, 0, 0], physicsClientId=self.cid)
