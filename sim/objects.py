"""Object categories: shape, size, mass, colour, friction.

Every object's frame is at the centre of its bounding box (so a can standing on the floor
has its frame 0.061 m above the floor) with z up.  ``parts`` are primitives given in that
frame: ("cylinder", radius, length, z_offset) or ("box", (sx, sy, sz), z_offset).
"""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Category:
    name: str
    parts: tuple
    height: float
    radius: float        # footprint radius (for placement and the top view)
    mass: float
    rgba: tuple
    friction: float = 0.9
    description: str = ""


def _bottle():
    body_r, body_h = 0.035, 0.200
    sh_r, sh_h = 0.024, 0.030
    neck_r, neck_h = 0.0135, 0.075
    total = body_h + sh_h + neck_h
    z0 = -total / 2
    return Category(
        name="bottle",
        parts=(("cylinder", body_r, body_h, z0 + body_h / 2),
               ("cylinder", sh_r, sh_h, z0 + body_h + sh_h / 2),
               ("cylinder", neck_r, neck_h, z0 + body_h + sh_h + neck_h / 2)),
        # 80 g: an empty PET wine bottle. Much heavier and the extended arm tips the robot
        # onto its nose (its centre of mass is only ~25 mm behind the wheel axle).
        height=total, radius=body_r, mass=0.08, rgba=(0.05, 0.32, 0.12, 1.0), friction=0.9,
        description="wine-bottle shape: body 70 mm x 200 mm, shoulder, neck 27 mm; 0.305 m, 80 g (empty PET)")


CATEGORIES: dict[str, Category] = {
    "can": Category(
        name="can", parts=(("cylinder", 0.033, 0.122, 0.0),), height=0.122, radius=0.033,
        mass=0.040, rgba=(0.85, 0.07, 0.07, 1.0), friction=0.9,
        description="soda can 66 mm x 122 mm, 40 g (empty), red"),
    "bottle": _bottle(),
    "box": Category(
        name="box", parts=(("box", (0.06, 0.06, 0.10), 0.0),), height=0.10, radius=0.0425,
        mass=0.060, rgba=(0.10, 0.25, 0.85, 1.0), friction=0.9,
        description="distractor: blue box 60 x 60 x 100 mm, 60 g"),
}
