"""The bodies of objects: every registered category (``categories``) plus the simulator's
own distractors, which perception is not meant to recognise.

Every object's frame is at the centre of its bounding box (so a can standing on the floor
has its frame 0.061 m above the floor) with z up.  ``parts`` are primitives given in that
frame: ("cylinder", radius, length, z_offset) or ("box", (sx, sy, sz), z_offset).
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
    radius: float        # footprint radius (for placement and the top view)
    mass: float
    rgba: tuple
    friction: float = 0.9
    description: str = ""


def _from_category(cat: registry.Category) -> ObjectModel:
    rgba = tuple(cat.rgba) + (1.0,) * (4 - len(cat.rgba))
    return ObjectModel(name=cat.name, parts=cat.shape.parts(), height=cat.height,
                       radius=cat.footprint_radius, mass=cat.mass, rgba=rgba,
                       friction=cat.friction, description=cat.description)


#: objects of no category: perception should call them ``unknown``
DISTRACTORS: dict[str, ObjectModel] = {
    "box": ObjectModel(
        name="box", parts=(("box", (0.06, 0.06, 0.10), 0.0),), height=0.10, radius=0.0425,
        mass=0.060, rgba=(0.10, 0.25, 0.85, 1.0), friction=0.9,
        description="distractor: blue box 60 x 60 x 100 mm, 60 g"),
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
            raise KeyError(name) from None

    def __iter__(self) -> Iterator[str]:
        yield from registry.names()
        yield from (n for n in DISTRACTORS if n not in registry.names())

    def __len__(self) -> int:
        return len(list(iter(self)))


CATEGORIES: Mapping[str, ObjectModel] = _Models()
