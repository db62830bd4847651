"""The bodies of objects: every registered category (``categories``) plus the simulator's
own distractors, which perception is not meant to recognise.

Every object's frame is at the centre of its bounding box (so a can standing on the floor
has its frame 0.061 m above the floor) with z up.  ``parts`` are primitives given in that
frame: ("cylinder", radius, length, z_offset) or ("box", (sx, sy, sz), z_offset).

``DECOYS`` are more distractors for worlds that ask for them (``distractors:`` in a world
description, e.g. house_hard): meshes from pybullet_data (a mug, a duck, lego and jenga
bricks, a ball...) scaled to table-top size, and boxes and cylinders of other sizes than
the categories'; a world recolours them with hues near the categories'. They are looked
up like the others (``CATEGORIES["mug"]``) but not listed.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass

import categories as registry


@dataclass(frozen=True)
class ObjectModel:
    name: str
    parts: tuple
    height: float
    radius: float  # footprint radius (for placement and the top view)
    mass: float
    rgba: tuple
    friction: float = 0.9
    description: str = ""
    label: object = None  # categories.Label of a category (worlds with labels draw it)
    shape: object = None  # the category's shape (Revolution or Box), None for a distractor
    urdf: str | None = None  # a mesh distractor: pybullet_data URDF (parts only approximate it)
    scale: float = 1.0  # its globalScaling


def _from_category(cat: registry.Category) -> ObjectModel:
    rgba = tuple(cat.rgba) + (1.0,) * (4 - len(cat.rgba))
    return ObjectModel(
        name=cat.name,
        parts=cat.shape.parts(),
        height=cat.height,
        radius=cat.footprint_radius,
        mass=cat.mass,
        rgba=rgba,
        friction=cat.friction,
        description=cat.description,
        label=cat.label,
        shape=cat.shape,
    )


#: objects of no category: perception should call them ``unknown``
DISTRACTORS: dict[str, ObjectModel] = {
    "box": ObjectModel(
        name="box",
        parts=(("box", (0.06, 0.06, 0.10), 0.0),),
        height=0.10,
        radius=0.0425,
        mass=0.060,
        rgba=(0.10, 0.25, 0.85, 1.0),
        friction=0.9,
        description="distractor: blue box 60 x 60 x 100 mm, 60 g",
    ),
}


def _cyl(name, r, h, mass, what):
    return ObjectModel(
        name=name,
        parts=(("cylinder", r, h, 0.0),),
        height=h,
        radius=r,
        mass=mass,
        rgba=(0.5, 0.5, 0.5, 1.0),
        description=f"decoy: {what}",
    )


def _box(name, sx, sy, sz, mass, what):
    return ObjectModel(
        name=name,
        parts=(("box", (sx, sy, sz), 0.0),),
        height=sz,
        radius=0.5 * (sx * sx + sy * sy) ** 0.5,
        mass=mass,
        rgba=(0.5, 0.5, 0.5, 1.0),
        description=f"decoy: {what}",
    )


def _mesh(name, urdf, scale, size, mass, what):
    sx, sy, sz = size
    return ObjectModel(
        name=name,
        parts=(("box", (sx, sy, sz), 0.0),),
        height=sz,
        radius=0.5 * (sx * sx + sy * sy) ** 0.5,
        mass=mass,
        rgba=(0.5, 0.5, 0.5, 1.0),
        description=f"decoy: {what} (pybullet_data {urdf} x {scale:g})",
        urdf=urdf,
        scale=scale,
    )


#: distractors for worlds that ask for them: not listed by ``CATEGORIES``; sizes [m] are
#: the scaled meshes' bounding boxes (approximate)
DECOYS: dict[str, ObjectModel] = {
    m.name: m
    for m in (
        _mesh("mug", "objects/mug.urdf", 0.9, (0.08, 0.115, 0.095), 0.12, "mug"),
        _mesh("duck", "duck_vhacd.urdf", 1.2, (0.11, 0.10, 0.08), 0.08, "rubber duck"),
        _mesh("lego", "lego/lego.urdf", 2.5, (0.085, 0.085, 0.06), 0.05, "lego brick"),
        _mesh("jenga", "jenga/jenga.urdf", 0.8, (0.12, 0.04, 0.024), 0.04, "jenga block"),
        _mesh("domino", "domino/domino.urdf", 2.0, (0.012, 0.05, 0.10), 0.03, "domino"),
        _mesh("ball", "sphere_small.urdf", 1.0, (0.06, 0.06, 0.06), 0.05, "ball"),
        _mesh("soccerball", "soccerball.urdf", 0.09, (0.09, 0.09, 0.09), 0.06, "soccer ball"),
        _mesh("teddy", "teddy_vhacd.urdf", 1.3, (0.11, 0.13, 0.09), 0.08, "teddy bear"),
        _mesh("shape_a", "random_urdfs/003/003.urdf", 1.0, (0.04, 0.10, 0.10), 0.06, "random shape"),
        _mesh("shape_b", "random_urdfs/008/008.urdf", 1.0, (0.10, 0.10, 0.10), 0.06, "random shape"),
        _cyl("tin", 0.045, 0.07, 0.05, "short wide tin 90 x 70 mm"),
        _cyl("tube", 0.02, 0.16, 0.03, "slim tube 40 x 160 mm"),
        _cyl("jar", 0.055, 0.13, 0.08, "wide jar 110 x 130 mm"),
        _box("flat_box", 0.14, 0.10, 0.04, 0.05, "flat box 140 x 100 x 40 mm"),
        _box("tall_box", 0.05, 0.05, 0.20, 0.05, "tall box 50 x 50 x 200 mm"),
        _box("cube", 0.08, 0.08, 0.08, 0.05, "cube 80 mm"),
    )
}


class _Models(Mapping):
    """Name -> :class:`ObjectModel`, read live from the category registry (a category
    loaded after import is known) and then the distractors."""

    def __getitem__(self, name: str) -> ObjectModel:
        if name in DISTRACTORS:
            return DISTRACTORS[name]
        try:
            return _from_category(registry.get(name))
        except registry.UnknownCategoryError:
            if name in DECOYS:
                return DECOYS[name]
            raise KeyError(name) from None

    def __iter__(self) -> Iterator[str]:
        yield from registry.names()
        yield from (n for n in DISTRACTORS if n not in registry.names())

    def __len__(self) -> int:
        return len(list(iter(self)))


CATEGORIES: Mapping[str, ObjectModel] = _Models()
