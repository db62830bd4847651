"""Build a WorldSpec into a pybullet client: floor, static geometry, place location, objects.

Worlds with varied poses (``poses:``) start objects lying or leaning (``PlacedObject.quat``,
``z``) and let them settle (:meth:`Scene.settle`); worlds with ``appearance: {labels:
true}`` give a labelled category a textured mesh as its visual (sim/textures.py);
distractors from pybullet_data are loaded from their URDFs.
"""

from __future__ import annotations

import colorsys
import math
import os
from dataclasses import replace
from pathlib import Path

from common.quiet_pybullet import pybullet as p

from .objects import CATEGORIES
from .world_spec import Box, PlacedObject, WorldSpec

FLOOR_RGBA = (0.93, 0.91, 0.86, 1.0)
FLOOR_FRICTION = 1.0
ROLLING_FRICTION = 0.002  # worlds with varied poses (lying bodies stay put)


def _shift_like(src, dst, colour):
    """``colour`` moved in hue, saturation and value as ``src`` moved to ``dst``."""
    hs, ss, vs = colorsys.rgb_to_hsv(*src[:3])
    hd, sd, vd = colorsys.rgb_to_hsv(*dst[:3])
    h, s, v = colorsys.rgb_to_hsv(*colour[:3])
    h = (h + hd - hs) % 1.0
    s = min(1.0, s * (sd / ss if ss > 1e-6 else 1.0))
    v = min(1.0, v * (vd / vs if vs > 1e-6 else 1.0))
    return tuple(colorsys.hsv_to_rgb(h, s, v)) + tuple(colour[3:4] or (1.0,))


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
        vis = p.createVisualShape(
            p.GEOM_BOX, halfExtents=half, rgbaColor=list(b.rgba), specularColor=[0.05, 0.05, 0.05], physicsClientId=cid
        )
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
        self.floor = p.createMultiBody(0.0, col, vis, [(x0 + x1) / 2, (y0 + y1) / 2, -0.05], physicsClientId=cid)
        p.changeDynamics(self.floor, -1, lateralFriction=FLOOR_FRICTION, physicsClientId=cid)
        p.changeVisualShape(self.floor, -1, specularColor=[0, 0, 0], physicsClientId=cid)
        statics = list(spec.walls) + list(spec.furniture)
        self.statics = _static_boxes(cid, statics)
        self.place = _static_boxes(cid, [spec.place])[0] if spec.place else None
        self.objects: dict[str, int] = {}
        self.categories: dict[str, str] = {}
        self._textures: dict[str, int] = {}
        for obj in spec.objects:
            self.add_object(obj)

    def add_object(self, obj: PlacedObject) -> int:
        if obj.name in self.objects:
            raise ValueError(f"object '{obj.name}' already exists")
        cat = CATEGORIES[obj.category]
        body = self._add_urdf(obj, cat) if cat.urdf else self._add_primitives(obj, cat)
        # A body at rest leaves the contact solver until something touches it: a house's
        # resting objects were a quarter of a driving robot's physics time.
        p.changeDynamics(body, -1, activationState=p.ACTIVATION_STATE_ENABLE_SLEEPING, physicsClientId=self.cid)
        self.objects[obj.name] = body
        self.categories[obj.name] = obj.category
        return body

    def _add_primitives(self, obj: PlacedObject, cat) -> int:
        """An object built from its category's primitive parts."""
        cid = self.cid
        rgba = list(obj.rgba) if obj.rgba is not None else list(cat.rgba)
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
        texture = None
        if self.spec.appearance.labels and cat.label is not None and cat.shape is not None:
            vis, texture = self._labelled_visual(obj, cat, rgba)
        else:
            vis = p.createVisualShapeArray(visualFramePositions=frames, rgbaColors=[rgba] * len(types), **kw)
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
        z = cat.height / 2 + 1e-4 if obj.z is None else obj.z
        orn = _quat_yaw(obj.yaw) if obj.quat is None else list(obj.quat)
        # createMultiBody's position is the link frame's (the inertial frame is offset)
        body = p.createMultiBody(
            cat.mass, col, vis, [obj.x, obj.y, z], orn, baseInertialFramePosition=[0, 0, com_z], physicsClientId=cid
        )
        if texture is not None:
            p.changeVisualShape(body, -1, textureUniqueId=texture, rgbaColor=[1, 1, 1, 1], physicsClientId=cid)
        if self.spec.poses is None:
            p.changeDynamics(
                body,
                -1,
                lateralFriction=cat.friction,
                spinningFriction=0.001,
                rollingFriction=0.0001,
                physicsClientId=cid,
            )
        else:
            # lying bodies must not roll away: a little rolling resistance, as on a rug
            p.changeDynamics(
                body,
                -1,
                lateralFriction=cat.friction,
                spinningFriction=0.002,
                rollingFriction=ROLLING_FRICTION,
                physicsClientId=cid,
            )
        return body

    def _labelled_visual(self, obj, cat, rgba):
        """(visual shape, texture id): the category's mesh with its label printed on."""
        from . import textures

        label = cat.label
        if obj.rgba is not None and label is not None:  # jittered: the label too
            label = replace(
                label,
                rgba=_shift_like(cat.rgba, obj.rgba, label.rgba),
                print_rgba=_shift_like(cat.rgba, obj.rgba, label.print_rgba),
            )
        img = textures.label_texture(rgba, label, cat.height, cat.name)
        path = str(textures.texture_file(img))
        tex = self._textures.get(path)
        if tex is None:
            tex = self._textures[path] = p.loadTexture(path, physicsClientId=self.cid)
        mesh = str(textures.shape_obj(cat.shape, tag=f"{obj.name} {Path(path).name}"))
        vis = p.createVisualShape(
            p.GEOM_MESH,
            fileName=mesh,
            meshScale=[1, 1, 1],
            rgbaColor=[1, 1, 1, 1],
            specularColor=[0.2, 0.2, 0.2],
            physicsClientId=self.cid,
        )
        return vis, tex

    def _add_urdf(self, obj, model) -> int:
        """A distractor from pybullet_data, recoloured, resting on its support."""
        import pybullet_data

        cid = self.cid
        path = os.path.join(pybullet_data.getDataPath(), model.urdf)
        orn = _quat_yaw(obj.yaw) if obj.quat is None else list(obj.quat)
        body = p.loadURDF(path, [obj.x, obj.y, 1.0], orn, globalScaling=model.scale, physicsClientId=cid)
        lo, hi = p.getAABB(body, -1, physicsClientId=cid)
        base = (obj.z - model.height / 2) if obj.z is not None else 0.0
        pos, _ = p.getBasePositionAndOrientation(body, physicsClientId=cid)
        # centre its bounding box on (x, y), its bottom 0.1 mm above its support
        p.resetBasePositionAndOrientation(
            body,
            [pos[0] + obj.x - (lo[0] + hi[0]) / 2, pos[1] + obj.y - (lo[1] + hi[1]) / 2, pos[2] - lo[2] + base + 1e-4],
            orn,
            physicsClientId=cid,
        )
        rgba = list(obj.rgba) if obj.rgba is not None else list(model.rgba)
        for link in range(-1, p.getNumJoints(body, physicsClientId=cid)):
            p.changeVisualShape(body, link, rgbaColor=rgba, specularColor=[0.1, 0.1, 0.1], physicsClientId=cid)
            p.changeDynamics(
                body,
                link,
                mass=model.mass,
                lateralFriction=model.friction,
                spinningFriction=0.002,
                rollingFriction=ROLLING_FRICTION,
                physicsClientId=cid,
            )
        return body

    def settle(self, steps: int, still: float = 2e-3) -> int:
        """Step the physics (``steps`` at least, twice that at most) until every object is at
        rest (speeds under ``still`` m/s and 10 ``still`` rad/s); returns the steps taken."""
        n = 0
        while n < 2 * steps:
            p.stepSimulation(physicsClientId=self.cid)
            n += 1
            if n >= steps and n % 10 == 0 and all(self._still(b, still) for b in self.objects.values()):
                break
        return n

    def _still(self, body, still):
        lin, ang = p.getBaseVelocity(body, physicsClientId=self.cid)
        return math.hypot(*lin) < still and math.hypot(*ang) < 10 * still

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
        p.changeDynamics(body, -1, activationState=p.ACTIVATION_STATE_WAKE_UP, physicsClientId=self.cid)
